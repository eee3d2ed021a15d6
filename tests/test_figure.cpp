// Figures: the main image and the insets are nearest-neighbour copies of the layer's display
// colours, insets are framed in their colour, bad insets are errors.
#include <gtest/gtest.h>

#include "base/error.h"
#include "image/figure.h"
#include "image/image_io.h"
#include "image/line_plot.h"

#include <array>
#include <filesystem>

using namespace freqlab;

namespace {

LayerSet gradient(int w, int h) {
    LayerSet s(w, h);
    Layer& d = s.add("depth", LayerKind::Continuous, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) d.at(w, x, y) = float(x + 3 * y);
    return s;
}

}  // namespace

TEST(Figure, MainImageAndInsetsAreExactCopies) {
    const LayerSet set = gradient(64, 40);
    FigureSpec spec;
    spec.layer = "depth";
    spec.scale = 3;
    spec.title = "depth, frame 0";
    spec.insets = {{5, 6, 10, 8}, {40, 20, 16, 16}};
    const FigureImage fig = compose_figure(set, spec);
    const std::vector<unsigned char> src = layer_to_rgb8(set, set.get("depth"), spec.display);
    auto fig_px = [&](int x, int y) { return &fig.rgb[(size_t(y) * fig.width + x) * 3]; };
    auto src_px = [&](int x, int y) { return &src[(size_t(y) * 64 + x) * 3]; };
    EXPECT_EQ(fig.main.x1 - fig.main.x0, 192);
    EXPECT_EQ(fig.main.y1 - fig.main.y0, 120);
    // Main image: pixel (x, y) of the layer covers a 3x3 block.
    for (auto [x, y] : {std::pair{0, 0}, {17, 3}, {63, 39}}) {
        // Avoid the inset frames drawn on the main image.
        const unsigned char* f = fig_px(fig.main.x0 + 3 * x + 1, fig.main.y0 + 3 * y + 1);
        const unsigned char* s = src_px(x, y);
        EXPECT_TRUE(f[0] == s[0] && f[1] == s[1] && f[2] == s[2]) << x << "," << y;
    }
    ASSERT_EQ(fig.inset_panels.size(), 2u);
    // Second inset: 16x16 layer pixels shown in a panel; its centre shows layer pixel (48, 28).
    const auto& p = fig.inset_panels[1];
    const int cx = p.x0 + (p.x1 - p.x0) * 17 / 32, cy = p.y0 + (p.y1 - p.y0) * 17 / 32;
    const unsigned char* f = fig_px(cx, cy);
    const unsigned char* s = src_px(40 + 8, 20 + 8);
    EXPECT_TRUE(f[0] == s[0] && f[1] == s[1] && f[2] == s[2]);
    // Its frame has the inset's colour, on the panel and on the main image.
    const vec3 c = categorical(2);
    const unsigned char* frame_px = fig_px(p.x0 - 1, cy);
    EXPECT_EQ(int(frame_px[0]), int(std::lround(c.r * 255)));
    const unsigned char* on_main = fig_px(fig.main.x0 + 40 * 3 - 1, fig.main.y0 + 25 * 3);
    EXPECT_EQ(int(on_main[1]), int(std::lround(c.g * 255)));
}

// A categorical layer with its own palette (method A's decision colours, say), written to EXR
// and read back as `freqlab figure` reads it: each class's legend swatch has the colour of that
// class's pixels. (Before: the EXR dropped the palette and the legend drew the default one.)
TEST(Figure, CategoricalLegendSwatchesHaveTheColoursOfTheirPixels) {
    const int w = 12, h = 6;
    LayerSet set(w, h);
    Layer& d = set.add("decision", LayerKind::Categorical, 1, "a decision per pixel");
    d.legend = {"none", "reused", "temporal", "spatial"};
    d.palette = {vec3(0.0f), vec3(1.0f), vec3(1.0f, 0.6f, 0.0f), vec3(0.2f, 0.45f, 1.0f)};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) d.at(w, x, y) = float(x / 3);  // columns of 3: classes 0..3
    const std::filesystem::path file =
        std::filesystem::temp_directory_path() / "freqlab_test_figure_palette.exr";
    write_exr(file, set, {{"test", "palette"}});
    const ExrFile read = read_exr(file);
    std::filesystem::remove(file);
    ASSERT_EQ(read.layers.get("decision").palette.size(), d.palette.size());
    for (size_t i = 0; i < d.palette.size(); ++i)
        EXPECT_EQ(read.layers.get("decision").palette[i], d.palette[i]) << "palette[" << i << "]";

    // The workbench's export composes from its layers; `freqlab figure` from the EXR.
    for (const LayerSet* layers : std::vector<const LayerSet*>{&set, &read.layers}) {
        FigureSpec spec;
        spec.layer = "decision";
        spec.scale = 4;
        const FigureImage fig = compose_figure(*layers, spec);
        ASSERT_EQ(fig.legend_swatches.size(), d.legend.size()) << "every class has a swatch";
        auto px = [&](int x, int y) {
            const unsigned char* p = &fig.rgb[(size_t(y) * fig.width + x) * 3];
            return std::array<int, 3>{p[0], p[1], p[2]};
        };
        for (int k = 0; k < 4; ++k) {
            const FigureImage::Box& b = fig.legend_swatches[size_t(k)];
            const auto swatch = px((b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2);
            const auto pixel = px(fig.main.x0 + (3 * k + 1) * spec.scale + 1, fig.main.y0 + 5);
            EXPECT_EQ(swatch, pixel) << "class " << k << " (" << d.legend[size_t(k)] << ")"
                                     << (layers == &set ? " in memory" : " read from EXR");
        }
    }
}

TEST(Figure, BadInsetsAndLayersAreErrors) {
    const LayerSet set = gradient(32, 32);
    FigureSpec spec;
    spec.layer = "depth";
    spec.insets = {{30, 30, 8, 8}};
    try {
        compose_figure(set, spec);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "insets[0]");
    }
    spec.insets.clear();
    spec.layer = "nope";
    EXPECT_THROW(compose_figure(set, spec), Error);
    spec.layer = "depth";
    spec.font = "/nonexistent/font.ttf";
    spec.title = "x";
    EXPECT_THROW(compose_figure(set, spec), Error);
}

// The plot's legend sits in the top corner its curves cross least: a rising curve leaves the
// top left free, a falling one the top right (where a swatch of the series colour must be).
TEST(LinePlot, LegendGoesToTheTopCornerTheCurvesLeaveFree) {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / "freqlab_test_line_plot";
    std::filesystem::create_directories(dir);
    for (bool rising : {true, false}) {
        LinePlot plot;
        plot.series = {
            {"a", vec3(1.0f, 0.0f, 0.0f), {0.0, 1.0}, {rising ? 0.0 : 1.0, rising ? 1.0 : 0.0}}};
        const std::filesystem::path png = dir / (rising ? "rising.png" : "falling.png");
        write_line_plot(png, plot);
        const RgbImage img = read_rgb_image(png);
        // Swatch centres of the two candidate places (line_plot.cpp's layout for a one-letter
        // name on the default 900 x 520 plot).
        auto red = [](const vec3& c) { return c.x > 0.9f && c.y < 0.05f && c.z < 0.05f; };
        const bool left = red(img.at(113, 86)), right = red(img.at(835, 86));
        EXPECT_EQ(left, rising) << (rising ? "rising" : "falling");
        EXPECT_EQ(right, !rising) << (rising ? "rising" : "falling");
    }
}
