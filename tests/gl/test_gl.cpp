// The workbench's GL path under OSMesa (no display): colormaps on the GPU against the CPU
// colormaps, colorbar ticks, categorical legend, the inspector through a simulated click, and
// the headless screenshot. Label `gl`; DISPLAY is unset before anything runs.
#include <gtest/gtest.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include <unistd.h>

#include "base/error.h"

#include "gl_host.h"
#include "gl_session.h"
#include "image/colormap.h"
#include "image/image_io.h"
#include "layer_view.h"
#include "osmesa_host.h"
#include "render/frame_store.h"
#include "render/shading_memo_store.h"
#include "workbench.h"

using namespace freqlab;
using namespace freqlab::ui;
using namespace freqlab::ui::test;
namespace fs = std::filesystem;

namespace {

void expect_colour(const unsigned char* px, const vec3& expected, const std::string& where) {
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(int(px[c]), int(std::lround(expected[c] * 255.0f)), 2)
            << where << " channel " << c;
}

LayerSet ramp_layers() {
    LayerSet set(256, 2);
    Layer& cont = set.add("cont", LayerKind::Continuous, 1);
    Layer& sig = set.add("sig", LayerKind::Signed, 1);
    Layer& cat = set.add("cat", LayerKind::Categorical, 1);
    Layer& col = set.add("color", LayerKind::Color, 3);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 256; ++x) {
            const float t = x / 255.0f;
            cont.at(256, x, y) = 10.0f + 20.0f * t;  // range [10, 30]
            sig.at(256, x, y) = -4.0f + 8.0f * t;    // range [-4, 4]
            cat.at(256, x, y) = float(x % 13);
            for (int c = 0; c < 3; ++c) col.at(256, x, y, c) = t * (c + 1) / 3.0f;
        }
    cont.at(256, 7, 1) = NAN;
    return set;
}

}  // namespace

TEST(GlColormap, EachKindMatchesTheCpuColormap) {
    GlSession gl;
    LayerView view;
    const LayerSet set = ramp_layers();
    DisplayParams fixed;
    fixed.auto_range = false;

    fixed.range = {10.0f, 30.0f};
    view.render(set, set.get("cont"), fixed);
    std::vector<unsigned char> px = view.read_rgba();
    for (int x : {0, 37, 128, 200, 255})
        expect_colour(&px[size_t(x) * 4], viridis(x / 255.0f), "viridis x=" + std::to_string(x));
    expect_colour(&px[(256 + 7) * 4], vec3(1, 0, 1), "NaN shows magenta");

    const DisplayRange r = view.render(set, set.get("sig"), DisplayParams{});  // auto: [-4, 4]
    EXPECT_FLOAT_EQ(r.lo, -4.0f);
    EXPECT_FLOAT_EQ(r.hi, 4.0f);
    px = view.read_rgba();
    for (int x : {0, 64, 128, 191, 255})
        expect_colour(&px[size_t(x) * 4], diverging((-4.0f + 8.0f * x / 255.0f) / 4.0f),
                      "diverging x=" + std::to_string(x));

    view.render(set, set.get("cat"), DisplayParams{});
    px = view.read_rgba();
    for (int x : {0, 3, 9, 12, 25})
        expect_colour(&px[size_t(x) * 4], categorical(x % 13), "category x=" + std::to_string(x));

    DisplayParams exposure;
    exposure.exposure_ev = 1.0f;
    view.render(set, set.get("color"), exposure);
    px = view.read_rgba();
    for (int x : {0, 40, 100, 255})
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(int(px[size_t(x) * 4 + c]),
                        int(std::lround(linear_to_srgb(2.0f * x / 255.0f * (c + 1) / 3.0f) * 255)),
                        2)
                << "colour x=" << x;
}

// A sparse layer (values only where a sample is) draws its no-data pixels transparent: over
// colour they showed the colormap's 0 (issue "The workbench tells the truth"); a dense layer's
// 0 is a value and stays opaque.
TEST(GlColormap, SparseLayersNoDataIsTransparent) {
    GlSession gl;
    LayerView view;
    LayerSet set(4, 1);
    Layer& sparse = set.add("sampled", LayerKind::Categorical, 1);
    sparse.sparse = true;
    sparse.data = {0.0f, 1.0f, 0.0f, 2.0f};
    Layer& dense = set.add("dense", LayerKind::Continuous, 1);
    dense.data = {0.0f, 1.0f, 0.0f, 2.0f};
    view.render(set, sparse, DisplayParams{});
    std::vector<unsigned char> px = view.read_rgba();
    EXPECT_EQ(px[0 * 4 + 3], 0);
    EXPECT_EQ(px[2 * 4 + 3], 0);
    EXPECT_EQ(px[1 * 4 + 3], 255);
    EXPECT_EQ(px[3 * 4 + 3], 255);
    view.render(set, dense, DisplayParams{});
    px = view.read_rgba();
    for (int x = 0; x < 4; ++x) EXPECT_EQ(px[size_t(x) * 4 + 3], 255) << x;
}

TEST(GlWorkbench, ColorbarHasTheColormapAndItsTicks) {
    GlSession gl;
    Workbench wb(small_scene("depth"));
    run_until_shown(gl, wb);
    const ScreenRect bar = wb.colorbar_rect();
    ASSERT_GT(bar.x1 - bar.x0, 100.0f);
    const std::vector<unsigned char> rgb = gl.host->read_rgb();
    int w, h;
    gl.host->framebuffer_size(&w, &h);
    auto at = [&](float x, float y) { return &rgb[(size_t(y) * w + size_t(x)) * 3]; };
    const float ymid = 0.5f * (bar.y0 + bar.y1);
    for (float t : {0.05f, 0.3f, 0.5f, 0.8f, 0.95f})
        expect_colour(at(bar.x0 + t * (bar.x1 - bar.x0), ymid), viridis(t),
                      "colorbar t=" + std::to_string(t));
    const DisplayRange r = wb.shown_range();
    const std::vector<double> ticks = colorbar_ticks(r.lo, r.hi);
    ASSERT_GE(ticks.size(), 3u);
    for (double t : ticks) {
        const float x = bar.x0 + float((t - r.lo) / (r.hi - r.lo)) * (bar.x1 - bar.x0);
        // A one-pixel line: look at the pixel columns either side of its position.
        int brightest = 0;
        for (float dx : {-1.0f, 0.0f, 1.0f}) {
            const unsigned char* p = at(std::clamp(x + dx, bar.x0, bar.x1 - 1), bar.y1 + 2);
            brightest = std::max(brightest, int(p[0]) + p[1] + p[2]);
        }
        EXPECT_GT(brightest, 3 * 150) << "tick mark at " << t;
    }
}

TEST(GlWorkbench, CategoricalLayerHasOneColourPerCategoryAndALegend) {
    GlSession gl;
    Workbench wb(small_scene("object"));
    run_until_shown(gl, wb);
    const auto swatches = wb.legend_swatches();
    ASSERT_EQ(swatches.size(), 6u);  // background + the built-in scene's 5 objects
    EXPECT_EQ(swatches[0].first, "background");
    EXPECT_EQ(swatches[5].first, "torus");
    const std::vector<unsigned char> rgb = gl.host->read_rgb();
    int w, h;
    gl.host->framebuffer_size(&w, &h);
    for (size_t i = 0; i < swatches.size(); ++i) {
        const ScreenRect& r = swatches[i].second;
        const size_t p = (size_t((r.y0 + r.y1) / 2) * w + size_t((r.x0 + r.x1) / 2)) * 3;
        expect_colour(&rgb[p], categorical(int(i)), "legend " + swatches[i].first);
    }
}

TEST(GlWorkbench, InspectorReturnsTheExactValuesOfTheClickedPixel) {
    GlSession gl;
    Workbench wb(small_scene("color"));
    run_until_shown(gl, wb);
    const ScreenRect img = wb.image_rect();
    const LayerSet* L = wb.layers();
    ASSERT_NE(L, nullptr);
    const int px = 101, py = 67;  // a pixel on the ground
    const float sx = img.x0 + (px + 0.5f) / L->width() * (img.x1 - img.x0);
    const float sy = img.y0 + (py + 0.5f) / L->height() * (img.y1 - img.y0);
    gl.host->set_mouse(sx, sy, false);
    render_ui_frame(*gl.host, wb);
    gl.host->set_mouse(sx, sy, true);  // press
    render_ui_frame(*gl.host, wb);
    gl.host->set_mouse(sx, sy, false);  // release
    render_ui_frame(*gl.host, wb);
    const std::vector<InspectorRow> rows = wb.inspect();
    ASSERT_EQ(rows.size(), L->layers().size());
    for (const InspectorRow& row : rows) {
        const Layer& l = L->get(row.layer);
        ASSERT_EQ(int(row.values.size()), l.channels);
        for (int c = 0; c < l.channels; ++c)
            EXPECT_EQ(row.values[size_t(c)], l.at(L->width(), px, py, c)) << row.layer;
    }
    EXPECT_EQ(rows.back().layer, "object");
    EXPECT_EQ(rows.back().note, "ground");
}

TEST(GlWorkbench, HeadlessScreenshotHasTheRequestedSizeAndContent) {
    const fs::path out = fs::temp_directory_path() / "freqlab_headless.png";
    fs::remove(out);
    WorkbenchOptions o = small_scene("");
    o.screenshot = out.string();
    o.width = 800;
    o.height = 500;
    ASSERT_EQ(run_headless(o), 0);
    auto in = OIIO::ImageInput::open(out.string());
    ASSERT_TRUE(in);
    const OIIO::ImageSpec spec = in->spec();
    EXPECT_EQ(spec.width, 800);
    EXPECT_EQ(spec.height, 500);
    std::vector<unsigned char> px(size_t(spec.width) * spec.height * spec.nchannels);
    in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, px.data());
    // Not blank: many distinct grey levels (panels, text, the rendered image).
    std::vector<int> seen(256, 0);
    for (size_t i = 0; i < px.size(); i += size_t(spec.nchannels)) seen[px[i]] = 1;
    int distinct = 0;
    for (int v : seen) distinct += v;
    EXPECT_GT(distinct, 64);
}

TEST(GlWorkbench, CompareAddsErrorLayersAndMetrics) {
    setenv("FREQLAB_CACHE_DIR", (fs::temp_directory_path() / "freqlab_gl_cache").c_str(), 1);
    GlSession gl;
    WorkbenchOptions o = small_scene("color");
    o.method = "mis";
    o.settings.push_back("mis.spp=2");
    o.settings.push_back("reference.spp=64");
    Workbench wb(o);
    run_until_shown(gl, wb);
    wb.request_reference();
    for (int i = 0; i < 2000 && (wb.reference_busy() || !wb.metrics()); ++i)
        render_ui_frame(*gl.host, wb);
    ASSERT_NE(wb.metrics(), nullptr) << wb.error();
    const LayerSet* L = wb.layers();
    ASSERT_NE(L->find("reference"), nullptr);
    ASSERT_NE(L->find("error"), nullptr);
    // The error layer is luminance(colour) - luminance(reference), pixel by pixel.
    const Layer &c = L->get("color"), &r = L->get("reference"), &e = L->get("error");
    for (size_t p : {size_t(0), size_t(5000), L->pixel_count() - 1}) {
        const vec3 cv(c.data[3 * p], c.data[3 * p + 1], c.data[3 * p + 2]);
        const vec3 rv(r.data[3 * p], r.data[3 * p + 1], r.data[3 * p + 2]);
        EXPECT_FLOAT_EQ(e.data[p], luminance(cv) - luminance(rv));
    }
    // The metrics shown are those of compare on the two colour layers; 2 spp is noisy.
    LayerSet test(L->width(), L->height()), ref(L->width(), L->height());
    test.add("color", LayerKind::Color, 3).data = c.data;
    ref.add("color", LayerKind::Color, 3).data = r.data;
    const ImageMetrics m = compare_layers(test, ref);
    EXPECT_DOUBLE_EQ(wb.metrics()->rmse, m.rmse);
    EXPECT_DOUBLE_EQ(wb.metrics()->ssim, m.ssim);
    EXPECT_GT(m.rmse, 0.0);
    EXPECT_LT(m.ssim, 1.0);
}

TEST(GlWorkbench, SessionRoundTrip) {
    const fs::path path = fs::temp_directory_path() / "freqlab_session.json";
    GlSession gl;
    {
        WorkbenchOptions o = small_scene("depth");
        o.frame = 3;
        o.settings.push_back("frame.exposure=-1.5");
        Workbench wb(o);
        run_until_shown(gl, wb);
        wb.select_pixel(20, 30);
        wb.save_session(path.string());
    }
    Workbench wb(WorkbenchOptions{});
    wb.load_session(path.string());
    run_until_shown(gl, wb);
    EXPECT_EQ(wb.frame(), 3);
    ASSERT_NE(wb.layers(), nullptr);
    EXPECT_EQ(wb.layers()->width(), 160);  // frame.width came back from the session
    const auto rows = wb.inspect();
    ASSERT_FALSE(rows.empty());
    EXPECT_EQ(rows[0].values[0], wb.layers()->get("color").at(160, 20, 30, 0));
    // A damaged session names the field and leaves the workbench as it was.
    {
        std::ofstream(path)
            << R"({"freqlab_session": 1, "scene": "builtin:default", "method": "mis",
          "frame": 0, "layer": "color", "overlay_on_color": false, "overlay_opacity": 0.5,
          "fixed_range": false, "range": [0, 1], "zoom": 1, "centre": [0.5, 0.5], "inspect": [-1, -1],
          "insets": [], "settings": {"frame": {"width": "wide"}}})";
    }
    try {
        wb.load_session(path.string());
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "settings.frame.width");
    }
    EXPECT_EQ(wb.frame(), 3);
}

int main(int argc, char** argv) {
    unsetenv("DISPLAY");  // the gl label must never need a display
    // A run store of this process's own: frames recorded by an earlier test run would be shown
    // instead of rendered. (The cache of tables and references stays shared.)
    const fs::path cache =
        fs::temp_directory_path() / ("freqlab_gl_run_store_" + std::to_string(getpid()));
    setenv("FREQLAB_RUN_STORE_DIR", cache.c_str(), 1);
    ::testing::InitGoogleTest(&argc, argv);
    const int status = RUN_ALL_TESTS();
    std::error_code ec;
    fs::remove_all(cache, ec);
    return status;
}

// Method B in the workbench: a surface bake of a plane under a constant environment of
// radiance 1 shows E = pi on the plane (away from the sphere) in the lightmapped preview, and
// the sphere (no lightmap) has no texel.
TEST(GlWorkbench, BakePreviewShowsTheAnalyticIrradiance) {
    GlSession gl;
    WorkbenchOptions o;
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/analytic/sphere_on_plane.json";
    o.method = "surface";
    o.layer = "lm_irradiance";
    o.settings = {"frame.width=160", "frame.height=90",  "bake.spp=512",
                  "bake.bounces=0",  "bake.max_size=64", "bake.probes_x=0"};
    Workbench wb(o);
    run_until_shown(gl, wb);
    const LayerSet* L = wb.layers();
    ASSERT_NE(L, nullptr);
    const Layer& e = L->get("lm_irradiance");
    const Layer& texel = L->get("lightmap_texel");
    // Bottom corners see the plane; the centre sees the sphere.
    for (auto [x, y] : {std::pair{5, 85}, std::pair{154, 85}}) {
        EXPECT_GE(texel.at(160, x, y, 2), 0.0f);
        EXPECT_NEAR(e.at(160, x, y, 0), 3.14159f, 0.05f * 3.14159f) << x << "," << y;
    }
    EXPECT_EQ(texel.at(160, 80, 40, 2), -1.0f);
    EXPECT_EQ(L->find("texel_mc_window"), nullptr) << "a surface bake has no Monte Carlo terms";
}

namespace {

nlohmann::json read_json(const fs::path& p) {
    std::ifstream in(p);
    return nlohmann::json::parse(in);
}

void write_json(const fs::path& p, const nlohmann::json& j) {
    std::ofstream(p) << j.dump(2);
}

LayerSet shown_layers(GlSession& gl, Workbench& wb) {
    run_until_shown(gl, wb);
    EXPECT_NE(wb.layers(), nullptr);
    return wb.layers() ? *wb.layers() : LayerSet(0, 0);
}

}  // namespace

// An export says what made it: after the media sliders moved (a session carrying sigma_s 1.4 and
// g 0.5), the EXR's provenance holds those coefficients, the method, the bake settings, the seed,
// the scene's hash and freqlab's version; a render's holds its settings and frame.
TEST(GlWorkbench, ExportsCarryTheValuesUsed) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_export_provenance";
    fs::create_directories(dir);
    GlSession gl;
    WorkbenchOptions o;
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json";
    o.method = "extinction";
    o.settings = {"frame.width=96",       "frame.height=72", "bake.spp=2",
                  "bake.texel_density=4", "bake.probes_x=0", "bake.seed=17"};
    {
        Workbench wb(o);
        run_until_shown(gl, wb);
        wb.save_session((dir / "saved.json").string());
    }
    nlohmann::json session = read_json(dir / "saved.json");
    session["bake"]["media"][0]["sigma_s"] = 1.4;
    session["bake"]["media"][0]["g"] = 0.5;
    write_json(dir / "moved.json", session);
    Workbench wb(WorkbenchOptions{});
    wb.load_session((dir / "moved.json").string());
    shown_layers(gl, wb);
    wb.export_exr((dir / "bake.exr").string());
    const ExrFile bake = read_exr(dir / "bake.exr");
    const nlohmann::json& p = bake.provenance;
    EXPECT_EQ(p["method"], "extinction");
    EXPECT_EQ(p["seed"], 17);
    EXPECT_EQ(p["settings"]["bake"]["spp"], 2);
    ASSERT_EQ(p["media"].size(), 1u);
    EXPECT_DOUBLE_EQ(p["media"][0]["sigma_s"].get<double>(), 1.4);
    EXPECT_DOUBLE_EQ(p["media"][0]["g"].get<double>(), 0.5);
    EXPECT_EQ(p["scene_hash"].get<std::string>().size(), 16u);
    EXPECT_EQ(p["freqlab"].get<std::string>().rfind("0.1+", 0), 0u) << p["freqlab"];

    WorkbenchOptions r;
    r.scene = "builtin:default";
    r.settings = {"frame.width=64", "frame.height=36", "frame.exposure=1.5"};
    Workbench render(r);
    run_until_shown(gl, render);
    render.export_exr((dir / "render.exr").string());
    const nlohmann::json q = read_exr(dir / "render.exr").provenance;
    EXPECT_EQ(q["method"], "gbuffer");
    EXPECT_EQ(q["frame"], 0);
    EXPECT_DOUBLE_EQ(q["settings"]["frame"]["exposure"].get<double>(), 1.5);
    EXPECT_EQ(q["media"].size(), 0u);
    fs::remove_all(dir);
}

// A bake's session keeps its method, bake settings and media coefficients: loading a session
// whose fog has sigma_s 1.4 bakes exactly what a scene file with that fog bakes, a bad
// coefficient names its field and changes nothing, and every render method's session loads.
TEST(GlWorkbench, BakeSessionKeepsMethodSettingsAndMedia) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_bake_session";
    fs::create_directories(dir);
    const std::string cornell = std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json";
    GlSession gl;
    WorkbenchOptions o;
    o.scene = cornell;
    o.method = "extinction";
    o.layer = "lm_irradiance";
    o.settings = {"frame.width=96", "frame.height=72", "bake.spp=4", "bake.texel_density=4",
                  "bake.probes_x=0"};
    {
        Workbench wb(o);
        run_until_shown(gl, wb);
        wb.save_session((dir / "saved.json").string());
    }
    nlohmann::json session = read_json(dir / "saved.json");
    EXPECT_EQ(session["method"], "extinction");
    EXPECT_EQ(session["bake"]["settings"]["bake"]["spp"], 4);
    ASSERT_EQ(session["bake"]["media"].size(), 1u);
    EXPECT_EQ(session["bake"]["media"][0]["name"], "fog");
    EXPECT_DOUBLE_EQ(session["bake"]["media"][0]["sigma_s"].get<double>(), 0.35);
    session["bake"]["media"][0]["sigma_s"] = 1.4;
    write_json(dir / "thick.json", session);

    Workbench loaded(WorkbenchOptions{});
    loaded.load_session((dir / "thick.json").string());
    const LayerSet from_session = shown_layers(gl, loaded);
    loaded.save_session((dir / "again.json").string());
    EXPECT_EQ(read_json(dir / "again.json")["bake"], session["bake"]);

    nlohmann::json scene = read_json(cornell);
    scene["media"][0]["sigma_s"] = 1.4;
    write_json(dir / "cornell_thick.json", scene);
    o.scene = (dir / "cornell_thick.json").string();
    Workbench direct(o);
    const LayerSet from_scene = shown_layers(gl, direct);
    const Layer& a = from_session.get("lm_irradiance");
    const Layer& b = from_scene.get("lm_irradiance");
    ASSERT_EQ(a.data.size(), b.data.size());
    EXPECT_EQ(a.data, b.data);
    // The default fog would give other values: the coefficients did reach the bake.
    Workbench thin(WorkbenchOptions{});
    thin.load_session((dir / "saved.json").string());
    EXPECT_NE(shown_layers(gl, thin).get("lm_irradiance").data, a.data);

    session["bake"]["media"][0]["g"] = 1.0;
    write_json(dir / "bad.json", session);
    try {
        loaded.load_session((dir / "bad.json").string());
        FAIL() << "g = 1 was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "bake.media[0].g");
    }
    loaded.save_session((dir / "after_bad.json").string());
    EXPECT_EQ(read_json(dir / "after_bad.json")["bake"]["media"][0]["sigma_s"], 1.4);
    // bake.* settings reach a bake workbench's bake.
    loaded.apply_setting("bake.spp=8");
    run_until_shown(gl, loaded);
    loaded.save_session((dir / "after_set.json").string());
    EXPECT_EQ(read_json(dir / "after_set.json")["bake"]["settings"]["bake"]["spp"], 8);

    for (const char* method : {"gbuffer", "mis", "reference", "points", "sparse", "cache"}) {
        nlohmann::json s = read_json(dir / "saved.json");
        s.erase("bake");
        s["scene"] = "builtin:default";
        s["method"] = method;
        s["layer"] = "color";
        write_json(dir / "render.json", s);
        Workbench wb(WorkbenchOptions{});
        EXPECT_NO_THROW(wb.load_session((dir / "render.json").string())) << method;
        EXPECT_EQ(read_json(dir / "render.json")["method"], method);
    }
}

// File > Open scene: a missing file is an error naming it, shown in the UI, the workbench as it
// was; a good one renders with the method and settings chosen in the GUI (not only --set's:
// the panels edit the state, and Open scene went back to the start's options, cache ->
// gbuffer, sliders to their defaults).
TEST(GlWorkbench, OpenSceneKeepsMethodAndSettings) {
    GlSession gl;
    Workbench wb(small_scene("depth"));
    run_until_shown(gl, wb);
    // GUI-side: the method menu, then a slider's setting.
    wb.set_method("mis");
    wb.apply_setting("mis.spp=3");
    wb.apply_setting("frame.width=144");
    run_until_shown(gl, wb);
    EXPECT_EQ(wb.method(), "mis");
    wb.open_scene("no_such_scene.json");
    render_ui_frame(*gl.host, wb);
    EXPECT_NE(wb.error().find("no_such_scene.json"), std::string::npos) << wb.error();
    EXPECT_EQ(wb.method(), "mis");
    ASSERT_NE(wb.layers(), nullptr) << "the shown frame stays";
    wb.open_scene(std::string(FREQLAB_SOURCE_DIR) + "/scenes/analytic/sphere_on_plane.json");
    run_until_shown(gl, wb);
    EXPECT_TRUE(wb.error().empty()) << wb.error();
    EXPECT_EQ(wb.method(), "mis");
    ASSERT_NE(wb.layers(), nullptr);
    EXPECT_EQ(wb.layers()->width(), 144);  // the GUI's frame.width
    const nlohmann::json p = wb.export_provenance();
    EXPECT_EQ(p["method"], "mis");
    EXPECT_EQ(p["settings"]["mis"]["spp"], 3) << p.dump();
}

// The method menu holds the bake methods too: switching opens the bake session with the
// settings kept, another bake method keeps the session (its media sliders), and back.
TEST(GlWorkbench, MethodMenuReachesTheBakes) {
    GlSession gl;
    WorkbenchOptions o = small_scene("");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json";
    Workbench wb(o);
    run_until_shown(gl, wb);
    EXPECT_TRUE(wb.error().empty()) << wb.error();
    wb.set_method("extinction");
    wb.apply_setting("bake.spp=2");
    wb.apply_setting("bake.texel_density=4");
    run_until_shown(gl, wb);
    EXPECT_EQ(wb.method(), "extinction");
    ASSERT_NE(wb.layers(), nullptr);
    EXPECT_NE(wb.layers()->find("lm_irradiance"), nullptr) << "the bake's preview";
    EXPECT_EQ(wb.layers()->width(), 160);  // frame.* kept: the preview's size
    EXPECT_EQ(wb.export_provenance()["settings"]["bake"]["spp"], 2);
    wb.set_method("surface");
    run_until_shown(gl, wb);
    EXPECT_EQ(wb.method(), "surface");
    EXPECT_EQ(wb.export_provenance()["settings"]["bake"]["spp"], 2);
    wb.set_method("gbuffer");
    run_until_shown(gl, wb);
    EXPECT_EQ(wb.method(), "gbuffer");
    EXPECT_NE(wb.layers()->find("depth"), nullptr);
    EXPECT_THROW(wb.set_method("no_such_method"), Error);
}

// `gui SCENE --method impulse --tables --headless --screenshot F` waited for a tables panel a
// bake session never drew (> 10 minutes at 100 % CPU): the panel is in bake sessions now, its
// sliders on the scene's medium.
TEST(GlWorkbench, TablesPanelInABakeSession) {
    const fs::path out = fs::temp_directory_path() / "freqlab_bake_tables.png";
    fs::remove(out);
    WorkbenchOptions o;
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json";
    o.method = "impulse";
    o.settings = {"frame.width=96", "frame.height=72", "bake.spp=2", "bake.texel_density=4",
                  "bake.probes_x=0"};
    o.show_tables = true;
    o.screenshot = out.string();
    o.width = 900;
    o.height = 600;
    ASSERT_EQ(run_headless(o), 0);
    EXPECT_TRUE(fs::exists(out));
    GlSession gl;
    Workbench wb(o);
    for (int i = 0; i < 2000 && !wb.tables_ready(); ++i) render_ui_frame(*gl.host, wb);
    EXPECT_TRUE(wb.tables_ready());
}

// The inspector's "why" for the cache: re-run when the renderer is free; while a job renders
// the next frames, the decisions the shown frame recorded when it ran (it showed nothing then).
TEST(GlWorkbench, CacheTraceExistsWhileAJobRuns) {
    GlSession gl(1280, 760);
    WorkbenchOptions o = small_scene("cache_decisions");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json";
    o.method = "cache";
    o.frame = 2;
    o.warm_from = 0;
    o.inspect_trace = true;
    Workbench wb(o);
    for (int f = 0; f <= 2; ++f) {
        wb.set_frame(f);
        run_until_shown(gl, wb);
    }
    wb.select_pixel(80, 45);
    render_ui_frame(*gl.host, wb);
    ASSERT_FALSE(wb.trace_lines().empty());
    const std::string full = wb.trace_lines()[0];
    EXPECT_EQ(full.find("is rendering"), std::string::npos) << full;
    wb.set_frame(8);                // frames 3 .. 8 in order: a job of several frames
    wb.select_pixel(81, 46);        // another pixel while it runs
    render_ui_frame(*gl.host, wb);  // the job started in this frame; it cannot have ended
    ASSERT_GE(wb.trace_lines().size(), 2u);
    EXPECT_NE(wb.trace_lines()[0].find("is rendering"), std::string::npos) << wb.trace_lines()[0];
    EXPECT_NE(wb.trace_lines()[1].find("entries land within 1 px of (81, 46)"), std::string::npos)
        << wb.trace_lines()[1];
    bool decided = false;  // each entry's decision, e.g. "reused" or "discard_temporal"
    for (const std::string& l : wb.trace_lines())
        decided |=
            l.find(": reused") != std::string::npos || l.find(": discard") != std::string::npos;
    EXPECT_TRUE(decided);
    wb.wait_for_render();
    run_until_shown(gl, wb);
    render_ui_frame(*gl.host, wb);
    EXPECT_EQ(wb.trace_lines()[0].find("is rendering"), std::string::npos) << "the full trace";
}

// Probe lobes follow the viewport's zoom and pan (they stayed where the fitted image had them).
TEST(GlWorkbench, ProbeLobesFollowZoomAndPan) {
    GlSession gl;
    WorkbenchOptions o;
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json";
    o.method = "extinction";
    o.settings = {"frame.width=160", "frame.height=120", "bake.spp=2",     "bake.texel_density=4",
                  "bake.probes_x=2", "bake.probes_y=2",  "bake.probes_z=2"};
    Workbench wb(o);
    run_until_shown(gl, wb);
    for (int i = 0; i < 400 && wb.probe_marks().empty(); ++i) {
        wb.wait_for_render();
        render_ui_frame(*gl.host, wb);
    }
    render_ui_frame(*gl.host, wb);
    const auto fitted = wb.probe_marks();
    ASSERT_GE(fitted.size(), 4u);  // of 8: those the camera sees
    const ScreenRect r = wb.image_rect();
    const float cx = 0.5f * (r.x0 + r.x1), cy = 0.5f * (r.y0 + r.y1);
    // Twice as large about uv (0.45, 0.55): a probe at screen p goes to c + 2 (p - q), q where
    // that uv was on the fitted image.
    wb.set_view(2.0f, 0.45f, 0.55f);
    render_ui_frame(*gl.host, wb);
    render_ui_frame(*gl.host, wb);
    const float qx = r.x0 + 0.45f * (r.x1 - r.x0), qy = r.y0 + 0.55f * (r.y1 - r.y0);
    int inside = 0;
    for (const auto& [x, y] : fitted) {
        const float ex = cx + 2.0f * (x - qx), ey = cy + 2.0f * (y - qy);
        if (!wb.image_rect().contains(ex, ey)) continue;
        ++inside;
        bool found = false;
        for (const auto& [zx, zy] : wb.probe_marks())
            found |= std::abs(zx - ex) < 1.0f && std::abs(zy - ey) < 1.0f;
        EXPECT_TRUE(found) << "probe at " << x << ", " << y << " expected at " << ex << ", " << ey;
    }
    EXPECT_GT(inside, 0);
    EXPECT_EQ(size_t(inside), wb.probe_marks().size()) << "probes outside the image are not drawn";
}

// A cache.* setting applied from outside the panel (sessions, scripts) re-renders like the
// panel does: it used to only redraw, so the frame kept the old cache's decisions.
TEST(GlWorkbench, ApplySettingRerendersOnACacheSetting) {
    GlSession gl;
    WorkbenchOptions o = small_scene("decision");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json";
    o.method = "cache";
    o.frame = 2;
    o.warm_from = 0;
    Workbench wb(o);
    run_until_shown(gl, wb);
    ASSERT_NE(wb.layers(), nullptr);
    const std::vector<float> before = wb.layers()->get("decision").data;
    long reused = 0;
    for (float d : before) reused += d == 1.0f;  // decision 1: reused from the cache
    ASSERT_GT(reused, 0) << "frame 2 after 0 and 1 reuses some radiance points";
    wb.apply_setting("cache.q_eps_x=0.5");
    EXPECT_FALSE(wb.frame_shown());
    run_until_shown(gl, wb);
    const std::vector<float> after = wb.layers()->get("decision").data;
    ASSERT_EQ(after.size(), before.size());
    EXPECT_NE(after, before) << "the frame was not rendered again with the new cache setting";
}

// Compare for a bake: the VPT reference's own noise is measured (two independent halves) and
// kept below a quarter of the error it measures (at 4 x the samples it was as large as the
// error: the metrics measured the reference).
TEST(GlWorkbench, BakeReferenceNoiseIsBelowTheMeasuredError) {
    GlSession gl;
    WorkbenchOptions o;
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json";
    o.method = "impulse";
    o.settings = {"frame.width=96", "frame.height=72", "bake.spp=4", "bake.texel_density=4",
                  "bake.probes_x=0"};
    Workbench wb(o);
    run_until_shown(gl, wb);
    wb.wait_for_render();
    run_until_shown(gl, wb);
    wb.request_reference();
    for (int i = 0; i < 100000 && (wb.reference_busy() || !wb.metrics()); ++i)
        render_ui_frame(*gl.host, wb);
    ASSERT_NE(wb.metrics(), nullptr) << wb.error();
    const std::string note = wb.reference_note();
    int spp = 0;
    double noise = 0, percent = 0, error = 0;
    ASSERT_EQ(std::sscanf(note.c_str(),
                          "VPT reference: %d spp (two halves, seeds +7919 / +15838); its noise "
                          "relMSE %lf = %lf%% of the measured %lf",
                          &spp, &noise, &percent, &error),
              4)
        << note;
    std::printf("%s\n", note.c_str());
    EXPECT_GE(spp, 16);
    EXPECT_GT(noise, 0.0);
    const bool capped = note.find("stopped at 64") != std::string::npos;
    EXPECT_TRUE(noise <= 0.25 * error || capped) << note;
    // The note prints three significant digits: half of the last one apart at most.
    const double last_digit = std::pow(10.0, std::floor(std::log10(error)) - 2.0);
    EXPECT_NEAR(wb.metrics()->relmse, error, 0.5 * last_digit * (1.0 + 1e-9))
        << "the metrics are this error";
}

// The environment bandwidth view is not a frame of the animation (it was flagged by the magic
// frame -100, then -1): its exports say what they hold and it has no reference to render (a
// request used to start a reference render of the non-existent frame).
TEST(GlWorkbench, EnvironmentViewIsNoFrame) {
    GlSession gl;
    WorkbenchOptions o = small_scene("");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json";
    Workbench wb(o);
    run_until_shown(gl, wb);
    EXPECT_NE(wb.export_stem().find("_frame0000_"), std::string::npos) << wb.export_stem();
    wb.show_env_bandwidth();
    run_until_shown(gl, wb);
    ASSERT_NE(wb.layers(), nullptr);
    const std::string stem = wb.export_stem();
    EXPECT_EQ(stem.find("frame"), std::string::npos) << stem;
    EXPECT_NE(stem.find("environment_bandwidth"), std::string::npos) << stem;
    wb.request_reference();
    EXPECT_FALSE(wb.reference_busy()) << "a reference render of the environment view started";
    EXPECT_NE(wb.status().find("no reference"), std::string::npos) << wb.status();
}

// Cache checkpoints in the workbench (issue "The timeline as a recorded run", acceptance 2): a
// first session renders rotor's frames 0..6 in order and leaves checkpoints before frames 3 and
// 6 in the run store; a second session (same scene and settings) jumping to frame 6 renders only
// frame 6, from the checkpoint, and shows the first session's bytes; a jump to 5 renders 3, 4, 5.
TEST(GlWorkbench, JumpsResumeFromTheRunsCheckpointsWithTheSameBytes) {
    const ScopedRunStore scoped("freqlab_gl_run_store");
    const fs::path& store = scoped.dir();
    GlSession gl;
    WorkbenchOptions o = small_scene("color");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json";
    o.method = "cache";
    o.settings.push_back("cache.checkpoint_every=3");
    std::map<int, std::vector<float>> first;
    {
        Workbench wb(o);
        for (int f = 0; f <= 6; ++f) {
            wb.set_frame(f);
            run_until_shown(gl, wb);
            first[f] = wb.layers()->get("color").data;
        }
    }
    size_t checkpoints = 0, frames = 0;
    for (const auto& e : fs::recursive_directory_iterator(store)) {
        checkpoints += e.path().filename().string().rfind("state_before_", 0) == 0;
        frames += e.path().extension() == ".json" && e.path().parent_path().filename() == "frames";
    }
    EXPECT_EQ(checkpoints, 2u) << "before frames 3 and 6";
    EXPECT_EQ(frames, 7u) << "every frame recorded in the run store";
    {  // the run opened again: every frame from the store, nothing rendered
        Workbench wb(o);
        EXPECT_EQ(wb.recorded_frames(), (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
        wb.set_frame(5);
        run_until_shown(gl, wb);
        EXPECT_EQ(wb.resumed_from(), -1);
        EXPECT_EQ(wb.layers()->get("color").data, first[5]);
    }
    // Without the recorded frames (trimmed from the store), a jump resumes from a checkpoint.
    for (const auto& run : fs::directory_iterator(store)) fs::remove_all(run.path() / "frames");
    {
        Workbench wb(o);
        run_until_shown(gl, wb);  // frame 0
        wb.set_frame(6);
        run_until_shown(gl, wb);
        EXPECT_EQ(wb.resumed_from(), 6);
        EXPECT_EQ(wb.recorded_frames(), (std::vector<int>{0, 6}));
        EXPECT_EQ(wb.layers()->get("color").data, first[6]);
        wb.set_frame(5);
        run_until_shown(gl, wb);
        EXPECT_EQ(wb.resumed_from(), 3);
        EXPECT_EQ(wb.recorded_frames(), (std::vector<int>{0, 3, 4, 5, 6}));
        EXPECT_EQ(wb.layers()->get("color").data, first[5]);
    }
}

// A jump to a recorded frame shows the layers on screen first (a read of ~5 % of the frame: issue
// "The timeline as a recorded run", acceptance 1) and the rest a UI frame or more later, read in
// the background; whoever needs every layer at once (exports, the inspector, tests) waits for
// it. Both are the recorded bytes.
TEST(GlWorkbench, ARecordedFrameShowsItsLayerFirstAndTheRestFollows) {
    const ScopedRunStore store("freqlab_gl_partial_store");
    GlSession gl;
    WorkbenchOptions o = small_scene("object");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json";
    o.method = "cache";
    std::map<int, LayerSet> first;
    {
        Workbench wb(o);
        for (int f = 0; f <= 2; ++f) {
            wb.set_frame(f);
            run_until_shown(gl, wb);
            first[f] = *wb.layers();
        }
    }
    auto same = [&](const LayerSet& got, int frame) {
        ASSERT_EQ(got.names(), first[frame].names());
        for (const Layer& l : first[frame].layers())
            EXPECT_EQ(got.get(l.name).data, l.data) << l.name << " of frame " << frame;
    };
    auto until_shown = [&](Workbench& wb) {  // no UI frame after it: that one may complete it
        for (int i = 0; i < 400 && !wb.frame_shown(); ++i) render_ui_frame(*gl.host, wb);
        ASSERT_TRUE(wb.frame_shown()) << wb.error();
    };
    Workbench wb(o);  // the run opened again: its frames come from the run store
    until_shown(wb);
    wb.set_frame(2);
    until_shown(wb);
    EXPECT_FALSE(wb.frame_complete()) << "the jump read the layer on screen only";
    for (int i = 0; i < 400 && !wb.frame_complete(); ++i) render_ui_frame(*gl.host, wb);
    EXPECT_TRUE(wb.frame_complete());
    same(*wb.layers(), 2);
    wb.set_frame(1);
    until_shown(wb);
    EXPECT_FALSE(wb.frame_complete());
    same(*wb.layers(), 1);  // asked at once: waits for the rest
    EXPECT_TRUE(wb.frame_complete());
}

// A cache.* change in a later session (a new workbench on a recorded run) recalls the radiance
// points the first session shaded: each frame's points go to the run store with the frame
// (render/shading_memo_store.h), and a memo empty in memory reads them from there.
TEST(GlWorkbench, ACacheChangeInALaterSessionRecallsThePointsOfTheRunStore) {
    const ScopedRunStore store("freqlab_gl_memo_store");
    GlSession gl;
    WorkbenchOptions o = small_scene("color");
    o.scene = std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json";
    o.method = "cache";
    {
        Workbench wb(o);
        wb.set_frame(2);
        run_until_shown(gl, wb);
        EXPECT_TRUE(fs::exists(memo_frame_path(wb.run_directory(), 2)));
    }
    Workbench wb(o);
    wb.set_frame(2);
    run_until_shown(gl, wb);  // from the run store, nothing rendered
    wb.apply_setting("cache.q_eps_x=0.0004");
    run_until_shown(gl, wb);
    const auto stats = recorded_frame_stats(wb.run_directory());
    ASSERT_EQ(stats.size(), 3u);
    for (const auto& [frame, st] : stats) {
        ASSERT_TRUE(st.contains("shading_memo")) << frame;
        EXPECT_GT(st["shading_memo"]["recalled"].get<long>(),
                  4 * st["shading_memo"]["shaded"].get<long>())
            << "frame " << frame;
    }
}

// A/B of two recorded runs (issue "The timeline as a recorded run"): the run kept as A, a
// setting changed, the frame B shows gains A's recorded colour bit for bit (layer run_a), its
// error layers and metrics against it; forgetting A drops the comparison.
TEST(GlWorkbench, ABComparesTheShownRunWithRunAsRecording) {
    GlSession gl;
    WorkbenchOptions o = small_scene("color");
    o.method = "mis";
    o.settings.push_back("mis.spp=2");
    Workbench wb(o);
    run_until_shown(gl, wb);
    const std::vector<float> a = wb.layers()->get("color").data;
    wb.keep_run_as_a();
    EXPECT_FALSE(wb.comparing_runs()) << "A is the run shown until a setting changes";
    wb.apply_setting("mis.spp=16");
    run_until_shown(gl, wb);
    for (int i = 0; i < 5 && !wb.metrics(); ++i) render_ui_frame(*gl.host, wb);
    EXPECT_TRUE(wb.comparing_runs());
    ASSERT_NE(wb.metrics(), nullptr);
    const Layer* run_a = wb.layers()->find("run_a");
    ASSERT_NE(run_a, nullptr);
    EXPECT_EQ(run_a->data, a);
    EXPECT_NE(wb.layers()->get("color").data, a) << "B renders 16 samples, A 2";
    EXPECT_GT(wb.metrics()->rmse, 0.0);
    EXPECT_EQ(wb.layers()->find("reference"), nullptr);
    wb.forget_run_a();
    EXPECT_FALSE(wb.comparing_runs());
    EXPECT_EQ(wb.metrics(), nullptr);
}

// Cancel cancels (issue "The timeline as a recorded run", acceptance 5): the job stops, and no
// job for that frame starts again by itself (it restarted on the next UI frame); the window may
// sleep. Another frame, or "render", renders again.
TEST(GlWorkbench, CancelledRenderStaysCancelledUntilAsked) {
    GlSession gl;
    WorkbenchOptions o = small_scene("color");
    o.method = "mis";
    o.settings.push_back("mis.spp=4096");
    Workbench wb(o);
    render_ui_frame(*gl.host, wb);  // starts frame 0's job
    ASSERT_TRUE(wb.busy());
    wb.cancel_render();
    wb.wait_for_render();
    for (int i = 0; i < 5; ++i) render_ui_frame(*gl.host, wb);
    EXPECT_FALSE(wb.frame_shown());
    EXPECT_FALSE(wb.busy()) << "a job started again after the cancel";
    EXPECT_TRUE(wb.recorded_frames().empty());
    EXPECT_TRUE(wb.error().empty()) << wb.error();
    wb.apply_setting("mis.spp=2");
    run_until_shown(gl, wb);
    EXPECT_EQ(wb.recorded_frames(), std::vector<int>{0});
}
