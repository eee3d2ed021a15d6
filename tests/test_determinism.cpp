// A render is identical for any thread count (DESIGN.md "Determinism").
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cstring>

#include "render/frame_renderer.h"
#include "scene/scene_loader.h"

using namespace freqlab;

namespace {

LayerSet render_with_threads(int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    const Scene scene = load_scene("builtin:default");
    RenderConfig config;
    config.frame.width = 97;  // not a multiple of the tile or packet size
    config.frame.height = 41;
    config.gbuffer.aa_samples = 11;
    EmbreeDevice device(threads);
    FrameRenderer renderer(scene, config, device);
    Progress progress;
    return renderer.render(5, progress).layers;
}

}  // namespace

TEST(Determinism, OneAndTwoThreadsGiveTheSameBytes) {
    const LayerSet a = render_with_threads(1), b = render_with_threads(2);
    ASSERT_EQ(a.layers().size(), b.layers().size());
    for (size_t i = 0; i < a.layers().size(); ++i) {
        const Layer &la = a.layers()[i], &lb = b.layers()[i];
        ASSERT_EQ(la.data.size(), lb.data.size());
        EXPECT_EQ(std::memcmp(la.data.data(), lb.data.data(), la.data.size() * sizeof(float)), 0)
            << la.name;
    }
}

TEST(Determinism, SeedChangesTheJitterButNotTheCentreLayers) {
    const Scene scene = load_scene("builtin:default");
    EmbreeDevice device(1);
    RenderConfig c1, c2;
    c1.frame.width = c2.frame.width = 48;
    c1.frame.height = c2.frame.height = 32;
    c2.frame.seed = 99;
    FrameRenderer r1(scene, c1, device), r2(scene, c2, device);
    Progress p;
    const LayerSet a = r1.render(0, p).layers, b = r2.render(0, p).layers;
    EXPECT_EQ(a.get("depth").data, b.get("depth").data);
    EXPECT_NE(a.get("albedo").data, b.get("albedo").data);
}

// The shading methods shade the pixel-centre hits and cast no jittered G-buffer rays: their
// albedo layer is the centre's (the one their textures multiply), the same for any seed, while
// the gbuffer preview averages jittered rays.
TEST(Determinism, ShadingMethodsTakeTheAlbedoOfTheCentreRay) {
    const Scene scene = load_scene("builtin:default");
    EmbreeDevice device(1);
    auto render = [&](RenderMethod method, int seed) {
        RenderConfig c;
        c.method = method;
        c.frame.width = 48;
        c.frame.height = 32;
        c.frame.seed = seed;
        c.mis.spp = 2;
        FrameRenderer r(scene, c, device);
        Progress p;
        return r.render(0, p);
    };
    const FrameResult a = render(RenderMethod::Mis, 0), b = render(RenderMethod::Mis, 99);
    EXPECT_EQ(a.layers.get("albedo").data, b.layers.get("albedo").data);
    const FrameResult g = render(RenderMethod::GBuffer, 0);
    EXPECT_EQ(g.stats["rays"].get<long>(), 48L * 32L * (1 + RenderConfig{}.gbuffer.aa_samples));
    EXPECT_NE(g.layers.get("albedo").data, a.layers.get("albedo").data);
}
