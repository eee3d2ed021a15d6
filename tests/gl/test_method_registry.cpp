// A method registered from this file alone (render/method.h) renders through the CLI's code
// path (run_render: --method, --spp, --debug-pixel, the frame's files) and the workbench's
// (its method name in the options, a frame shown), and its declared layers are checked.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "commands.h"
#include "gl_session.h"
#include "render/frame_renderer.h"
#include "render/method.h"
#include "scene/scene_loader.h"

using namespace freqlab;
using namespace freqlab::ui;
using namespace freqlab::ui::test;
namespace fs = std::filesystem;

namespace {

const vec3 kConstant(0.25f, 0.5f, 0.75f);

RenderMethodInfo constant_method() {
    RenderMethodInfo m;
    m.name = "constant_test";
    m.summary = "every pixel the same colour (a registry test)";
    m.setting_groups = {"frame", "gbuffer"};
    m.spp_refusal = "takes no samples";
    m.layers = {{"constant_marker", LayerKind::Categorical}};
    m.render = [](MethodContext& c) {
        Layer& color = *c.result.layers.find("color");
        for (size_t i = 0; i < c.result.layers.pixel_count(); ++i)
            for (int k = 0; k < 3; ++k) color.data[i * 3 + size_t(k)] = kConstant[k];
        Layer& marker = c.result.layers.add("constant_marker", LayerKind::Categorical, 1);
        std::fill(marker.data.begin(), marker.data.end(), 1.0f);
        MethodOutput out;
        out.stats["constant"] = true;
        return out;
    };
    m.trace = [](const PixelTraceContext& c, TraceLines& out) {
        out.push_back("constant colour at (" + std::to_string(c.x) + ", " + std::to_string(c.y) +
                      ")");
    };
    return m;
}

const RenderMethod kConstantMethod = register_render_method(constant_method());

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("freqlab_registry_" + name);
    fs::remove_all(dir);
    return dir;
}

}  // namespace

TEST(MethodRegistry, ARegisteredMethodIsListedAndParsed) {
    EXPECT_EQ(parse_render_method("constant_test"), kConstantMethod);
    EXPECT_NE(render_method_list().find("|constant_test"), std::string::npos);
    EXPECT_THROW(register_render_method(constant_method()), Error);  // the name is taken
    try {
        parse_render_method("constant");
        ADD_FAILURE() << "an unknown method parsed";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("constant_test"), std::string::npos) << e.what();
    }
}

TEST(MethodRegistry, ARegisteredMethodRendersThroughTheCommandLine) {
    RenderArgs args;
    args.method = "constant_test";
    args.size = "32x18";
    args.frames = "0:2";
    args.quiet = true;
    args.debug_pixel = "16,12";
    args.out = fresh_dir("cli").string();
    testing::internal::CaptureStdout();
    EXPECT_EQ(run_render(args), 0);
    const std::string printed = testing::internal::GetCapturedStdout();
    EXPECT_NE(printed.find("constant colour at (16, 12)"), std::string::npos) << printed;
    EXPECT_NE(printed.find("constant_marker"), std::string::npos) << printed;

    auto in = OIIO::ImageInput::open((fs::path(args.out) / "frame_0001.exr").string());
    ASSERT_TRUE(in) << OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    ASSERT_EQ(spec.width, 32);
    std::vector<float> px(size_t(spec.width) * spec.height * spec.nchannels);
    ASSERT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data()));
    const int r = spec.channelindex("R"), g = spec.channelindex("G"), b = spec.channelindex("B");
    ASSERT_GE(r, 0);
    for (int i : {0, 100, 32 * 18 - 1}) {
        EXPECT_FLOAT_EQ(px[size_t(i * spec.nchannels + r)], kConstant.x);
        EXPECT_FLOAT_EQ(px[size_t(i * spec.nchannels + g)], kConstant.y);
        EXPECT_FLOAT_EQ(px[size_t(i * spec.nchannels + b)], kConstant.z);
    }
    std::ifstream stats(fs::path(args.out) / "stats.json");
    const nlohmann::json j = nlohmann::json::parse(stats);
    EXPECT_EQ(j.at("frames").at(1).at("constant"), true);

    // --spp is the registry's: refused with the method's own reason.
    args.spp = 4;
    args.out = fresh_dir("cli_spp").string();
    try {
        run_render(args);
        ADD_FAILURE() << "--spp was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("takes no samples"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(fs::path(args.out) / "frame_0000.exr"));
}

TEST(MethodRegistry, ARegisteredMethodRendersInTheWorkbench) {
    GlSession gl;
    WorkbenchOptions o = small_scene("constant_marker");
    o.method = "constant_test";
    Workbench wb(o);
    run_until_shown(gl, wb);
    ASSERT_NE(wb.layers(), nullptr);
    const Layer& color = wb.layers()->get("color");
    EXPECT_FLOAT_EQ(color.data[0], kConstant.x);
    EXPECT_FLOAT_EQ(color.data[color.data.size() - 1], kConstant.z);
    EXPECT_NE(wb.layers()->find("constant_marker"), nullptr);
}

TEST(MethodRegistry, AMethodThatDoesNotWriteADeclaredLayerIsRefusedByName) {
    RenderMethodInfo broken = constant_method();
    broken.name = "broken_test";
    broken.layers.push_back({"never_written", LayerKind::Continuous});
    const RenderMethod id = register_render_method(broken);
    const Scene scene = load_scene("builtin:default");
    RenderConfig config;
    config.method = id;
    config.frame.width = 16;
    config.frame.height = 9;
    EmbreeDevice device(1);
    FrameRenderer renderer(scene, config, device);
    Progress progress;
    try {
        renderer.render(0, progress);
        ADD_FAILURE() << "a missing declared layer passed";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("never_written"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("broken_test"), std::string::npos) << e.what();
    }
}
