#include "image/line_plot.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "base/error.h"
#include "image/image_io.h"

namespace freqlab {

using namespace OIIO;

namespace {

// 1, 2 or 5 times a power of ten, about `count` steps over [lo, hi].
double nice_step(double lo, double hi, int count) {
    const double raw = (hi - lo) / count, p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * p >= raw) return m * p;
    return 10.0 * p;
}

// Tick positions on an axis spanning [lo, hi] (log10 units on a log axis): whole decades,
// and 2 x and 5 x each decade as well when fewer than three decades are spanned.
std::vector<double> ticks(double lo, double hi, bool log, int count) {
    std::vector<double> out;
    if (!log) {
        const double step = nice_step(lo, hi, count);
        for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step)
            out.push_back(v);
        return out;
    }
    const bool minor = hi - lo < 3.0;
    for (double d = std::floor(lo); d <= hi + 1e-9; d += 1.0)
        for (double m : {1.0, 2.0, 5.0}) {
            if (m > 1.0 && !minor) continue;
            const double v = d + std::log10(m);
            if (v >= lo - 1e-9 && v <= hi + 1e-9) out.push_back(v);
        }
    return out;
}

std::string tick_label(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

}  // namespace

void write_line_plot(const std::filesystem::path& path, const LinePlot& plot) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const PlotSeries& s : plot.series) {
        if (s.x.size() != s.y.size() || s.x.empty())
            throw Error(path.string(), "series " + s.name, "expected as many x as y values, > 0");
        for (size_t i = 0; i < s.x.size(); ++i) {
            const double x = plot.log_x ? std::log10(s.x[i]) : s.x[i];
            const double y = plot.log_y ? std::log10(s.y[i]) : s.y[i];
            if (!std::isfinite(x) || !std::isfinite(y))
                throw Error(path.string(), "series " + s.name,
                            "non-finite value (or <= 0 on a log axis)");
            x0 = std::min(x0, x), x1 = std::max(x1, x);
            y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
    }
    if (plot.series.empty()) throw Error(path.string(), "series", "nothing to plot");
    if (!plot.log_y) y0 = std::min(y0, 0.0);
    auto fx = [&](double x) { return plot.log_x ? std::log10(x) : x; };
    if (x1 <= x0) x1 = x0 + 1;
    if (y1 <= y0) y1 = y0 + 1;
    const int W = plot.width, H = plot.height, left = 90, right = 20, top = 64, bottom = 60;
    ImageBuf buf(ImageSpec(W, H, 3, TypeDesc::FLOAT));
    const float bg[] = {0.1f, 0.1f, 0.11f}, axis[] = {0.8f, 0.8f, 0.8f},
                grid[] = {0.25f, 0.25f, 0.27f};
    ImageBufAlgo::fill(buf, bg);
    auto px = [&](double x) {
        return left + int(std::lround((x - x0) / (x1 - x0) * (W - left - right)));
    };
    auto py = [&](double y) {
        return H - bottom - int(std::lround((y - y0) / (y1 - y0) * (H - top - bottom)));
    };
    auto text = [&](int x, int y, const std::string& t, int size, const float* colour) {
        if (!ImageBufAlgo::render_text(buf, x, y, t, size, plot.font, colour))
            throw Error(plot.font, "font",
                        "cannot render text with this font (" + buf.geterror() +
                            "); expected a TrueType file");
    };
    for (double x : ticks(x0, x1, plot.log_x, 8)) {
        ImageBufAlgo::render_line(buf, px(x), top, px(x), H - bottom, grid);
        text(px(x) - 10, H - bottom + 20, tick_label(plot.log_x ? std::pow(10.0, x) : x), 14, axis);
    }
    for (double y : ticks(y0, y1, plot.log_y, 6)) {
        ImageBufAlgo::render_line(buf, left, py(y), W - right, py(y), grid);
        text(8, py(y) + 5, tick_label(plot.log_y ? std::pow(10.0, y) : y), 14, axis);
    }
    ImageBufAlgo::render_line(buf, left, H - bottom, W - right, H - bottom, axis);
    ImageBufAlgo::render_line(buf, left, top, left, H - bottom, axis);
    text(left, 26, plot.title, 18, axis);
    text(W / 2 - 40, H - 15, plot.x_label, 14, axis);
    text(8, top - 14, plot.y_label, 14, axis);
    // The curves, and how many of their pixels fall in each candidate place of the legend.
    size_t longest = 0;
    for (const PlotSeries& s : plot.series) longest = std::max(longest, s.name.size());
    const int legend_w = 44 + 8 * int(longest), legend_h = 8 + 20 * int(plot.series.size());
    const int legend_y = top + 8, legend_x[2] = {left + 8, W - right - 8 - legend_w};
    long covered[2] = {0, 0};
    for (const PlotSeries& s : plot.series) {
        const float c[] = {s.colour.x, s.colour.y, s.colour.z};
        for (size_t i = 1; i < s.x.size(); ++i) {
            const double ya = plot.log_y ? std::log10(s.y[i - 1]) : s.y[i - 1];
            const double yb = plot.log_y ? std::log10(s.y[i]) : s.y[i];
            const int xa = px(fx(s.x[i - 1])), xb = px(fx(s.x[i]));
            for (int t = 0; t < 2; ++t)  // two pixels thick
                ImageBufAlgo::render_line(buf, xa, py(ya) + t, xb, py(yb) + t, c);
            for (int k = 0; k <= 32; ++k) {
                const double f = k / 32.0;
                const double x = xa + f * (xb - xa), y = py(ya) + f * (py(yb) - py(ya));
                for (int side = 0; side < 2; ++side)
                    covered[side] += x >= legend_x[side] && x <= legend_x[side] + legend_w &&
                                     y >= legend_y && y <= legend_y + legend_h;
            }
        }
    }
    // The legend on a box of its own, in the top corner the curves cross least.
    const int lx = legend_x[covered[1] < covered[0] ? 1 : 0];
    ImageBufAlgo::render_box(buf, lx, legend_y, lx + legend_w, legend_y + legend_h, bg, true);
    ImageBufAlgo::render_box(buf, lx, legend_y, lx + legend_w, legend_y + legend_h, grid, false);
    for (size_t k = 0; k < plot.series.size(); ++k) {
        const PlotSeries& s = plot.series[k];
        const float c[] = {s.colour.x, s.colour.y, s.colour.z};
        const int ly = legend_y + 20 + 20 * int(k);
        ImageBufAlgo::render_box(buf, lx + 8, ly - 12, lx + 22, ly, c, true);
        text(lx + 28, ly, s.name, 14, axis);
    }
    std::vector<unsigned char> rgb(size_t(W) * H * 3);
    std::vector<float> pixels(size_t(W) * H * 3);
    buf.get_pixels(ROI(0, W, 0, H, 0, 1, 0, 3), TypeDesc::FLOAT, pixels.data());
    for (size_t i = 0; i < pixels.size(); ++i)
        rgb[i] = (unsigned char)std::lround(std::clamp(pixels[i], 0.0f, 1.0f) * 255.0f);
    write_png(path, W, H, rgb);
}

}  // namespace freqlab
