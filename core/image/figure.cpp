#include "image/figure.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/error.h"
#include "image/image_io.h"

namespace freqlab {

OIIO_NAMESPACE_USING

namespace {

constexpr int kMargin = 12, kBarHeight = 16, kTextSize = 14;

struct Canvas {
    int w, h;
    std::vector<unsigned char> rgb;
    void fill(int x0, int y0, int x1, int y1, vec3 c) {
        for (int y = std::max(0, y0); y < std::min(h, y1); ++y)
            for (int x = std::max(0, x0); x < std::min(w, x1); ++x)
                for (int k = 0; k < 3; ++k)
                    rgb[(size_t(y) * w + x) * 3 + k] = (unsigned char)std::lround(c[k] * 255.0f);
    }
    void frame(int x0, int y0, int x1, int y1, vec3 c, int t = 2) {
        fill(x0 - t, y0 - t, x1 + t, y0, c);
        fill(x0 - t, y1, x1 + t, y1 + t, c);
        fill(x0 - t, y0, x0, y1, c);
        fill(x1, y0, x1 + t, y1, c);
    }
    // Nearest-neighbour copy of src's rectangle (sx, sy, sw, sh) into (dx, dy, dw, dh).
    void blit(const std::vector<unsigned char>& src, int src_w, int sx, int sy, int sw, int sh,
              int dx, int dy, int dw, int dh) {
        for (int y = 0; y < dh; ++y)
            for (int x = 0; x < dw; ++x) {
                const int u = sx + x * sw / dw, v = sy + y * sh / dh;
                for (int k = 0; k < 3; ++k)
                    rgb[(size_t(dy + y) * w + dx + x) * 3 + k] =
                        src[(size_t(v) * src_w + u) * 3 + k];
            }
    }
};

void draw_text(Canvas& c, int x, int y, const std::string& text, const std::string& font) {
    ImageBuf buf(ImageSpec(c.w, c.h, 3, TypeDesc::UINT8), c.rgb.data());
    const float white[] = {0.92f, 0.92f, 0.92f};
    if (!ImageBufAlgo::render_text(buf, x, y, text, kTextSize, font, white))
        throw Error(font, "font",
                    "cannot render text with this font (" + buf.geterror() +
                        "); expected a TrueType file, e.g. from fonts-dejavu-core");
}

}  // namespace

FigureImage compose_figure(const LayerSet& set, const FigureSpec& spec) {
    const Layer* layer = set.find(spec.layer);
    if (!layer)
        throw Error("figure", "layer",
                    "no layer \"" + spec.layer + "\"; layers are: " + set.names());
    if (spec.insets.size() > 4)
        throw Error("figure", "insets",
                    "at most 4 insets, got " + std::to_string(spec.insets.size()));
    if (spec.scale < 1 || spec.scale > 16) throw Error("figure", "scale", "expected 1 to 16");
    const int lw = set.width(), lh = set.height();
    for (size_t i = 0; i < spec.insets.size(); ++i) {
        const FigureInset& in = spec.insets[i];
        if (in.width < 2 || in.height < 2 || in.x < 0 || in.y < 0 || in.x + in.width > lw ||
            in.y + in.height > lh)
            throw Error("figure", "insets[" + std::to_string(i) + "]",
                        "expected a rectangle of at least 2x2 inside the " + std::to_string(lw) +
                            "x" + std::to_string(lh) + " image");
    }
    const std::vector<unsigned char> src = layer_to_rgb8(set, *layer, spec.display);
    const DisplayRange range = spec.display.auto_range ? auto_range(*layer) : spec.display.range;

    const int main_w = lw * spec.scale, main_h = lh * spec.scale;
    const int title_h = spec.title.empty() ? 0 : kTextSize + 8;
    const bool has_bar = layer->kind != LayerKind::Color && layer->channels == 1;
    const int n = int(spec.insets.size());
    const int panel_h = n ? (main_h - (n - 1) * kMargin) / n : 0;
    // Inset panels keep their aspect ratio at the height each gets.
    int panel_w = 0;
    for (const FigureInset& in : spec.insets)
        panel_w = std::max(panel_w, panel_h * in.width / in.height);

    FigureImage fig;
    fig.width = kMargin + main_w + (n ? kMargin + panel_w : 0) + kMargin;
    // A categorical legend: every entry, in rows as wide as the figure (a narrow image wraps
    // its legend instead of dropping the classes past the edge).
    struct LegendEntry {
        int x, row;
    };
    std::vector<LegendEntry> legend;
    if (has_bar && layer->kind == LayerKind::Categorical) {
        int x = kMargin, row = 0;
        for (const std::string& name : layer->legend) {
            const int entry_w = 18 + 9 * int(name.size()) + 14;
            if (x > kMargin && x + entry_w > fig.width - kMargin) x = kMargin, ++row;
            legend.push_back({x, row});
            x += entry_w;
        }
    }
    const int legend_rows = legend.empty() ? 1 : legend.back().row + 1;
    const int bar_h =
        has_bar ? kBarHeight + kTextSize + 14 + (legend_rows - 1) * (kTextSize + 8) : 0;
    fig.height = kMargin + title_h + main_h + bar_h + kMargin;
    Canvas c{fig.width, fig.height,
             std::vector<unsigned char>(size_t(fig.width) * fig.height * 3, 24)};
    const int mx = kMargin, my = kMargin + title_h;
    c.blit(src, lw, 0, 0, lw, lh, mx, my, main_w, main_h);
    fig.main = {mx, my, mx + main_w, my + main_h};

    for (int i = 0; i < n; ++i) {
        const FigureInset& in = spec.insets[size_t(i)];
        const vec3 colour = categorical(i + 1);
        const int px = mx + main_w + kMargin, py = my + i * (panel_h + kMargin);
        const int pw = panel_h * in.width / in.height;
        c.blit(src, lw, in.x, in.y, in.width, in.height, px, py, pw, panel_h);
        c.frame(px, py, px + pw, py + panel_h, colour);
        c.frame(mx + in.x * spec.scale, my + in.y * spec.scale, mx + (in.x + in.width) * spec.scale,
                my + (in.y + in.height) * spec.scale, colour);
        fig.inset_panels.push_back({px, py, px + pw, py + panel_h});
    }

    if (has_bar) {
        const int by = my + main_h + 8, bw = std::min(main_w, 480);
        if (layer->kind == LayerKind::Categorical) {
            for (size_t i = 0; i < legend.size(); ++i) {
                const int x = legend[i].x, y = by + legend[i].row * (kTextSize + 8);
                // The colours the pixels were drawn in: the layer's own palette.
                c.fill(x, y, x + 14, y + 14, category_colour(*layer, int(i)));
                fig.legend_swatches.push_back({x, y, x + 14, y + 14});
                draw_text(c, x + 18, y + 13, layer->legend[i], spec.font);
            }
        } else {
            for (int x = 0; x < bw; ++x) {
                const float t = (x + 0.5f) / bw;
                c.fill(mx + x, by, mx + x + 1, by + kBarHeight,
                       layer->kind == LayerKind::Signed ? diverging(2 * t - 1) : viridis(t));
            }
            for (double t : colorbar_ticks(range.lo, range.hi)) {
                const int x =
                    mx + int(std::floor((t - range.lo) / (range.hi - range.lo) * (bw - 1)));
                c.fill(x, by + kBarHeight, x + 1, by + kBarHeight + 4, vec3(0.92f));
                char label[32];
                std::snprintf(label, sizeof label, "%g", t);
                draw_text(c, std::min(x, mx + bw - 8 * int(std::string(label).size())),
                          by + kBarHeight + 4 + kTextSize, label, spec.font);
            }
        }
    }
    if (!spec.title.empty()) draw_text(c, kMargin, kMargin + kTextSize, spec.title, spec.font);
    fig.rgb = std::move(c.rgb);
    return fig;
}

void write_figure(const std::filesystem::path& path, const LayerSet& set, const FigureSpec& spec,
                  const nlohmann::json& provenance) {
    const FigureImage fig = compose_figure(set, spec);
    write_png(path, fig.width, fig.height, fig.rgb, provenance);
}

}  // namespace freqlab
