// Bounded memory (issue "Reliability"): method A's cache obeys cache.max_megabytes after every
// frame, the reference cache's folder obeys reference.cache_megabytes after every store, and a
// bake reports what it holds and the process's peak memory.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "cache/radiance_cache.h"
#include "render/frame_renderer.h"
#include "render/reference_cache.h"
#include "scene/scene_loader.h"
#include "volume/lightmap_baker.h"
#include "volume/media.h"

namespace fs = std::filesystem;
using namespace freqlab;

TEST(MemoryCaps, CacheKeepsItsLivePointsUnderTheCap) {
    const Scene scene = load_scene(std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json");
    EmbreeDevice device(2);
    auto run = [&](float megabytes, std::vector<nlohmann::json>& stats) {
        RenderConfig config;
        config.method = RenderMethod::Cache;
        config.frame.width = 240;
        config.frame.height = 135;
        config.cache.max_megabytes = megabytes;
        FrameRenderer renderer(scene, config, device);
        for (int f = 0; f < 12; ++f) {
            Progress progress;
            stats.push_back(renderer.render(f, progress).stats);
        }
    };
    std::vector<nlohmann::json> free_run, capped;
    run(65536.0f, free_run);
    const double per_point = double(ObjectCache::bytes_per_slot());
    const double grown = free_run.back()["cache_points"].get<double>() * per_point;
    // The cap at a third of what the cache holds after 12 frames uncapped: it must bind.
    const float cap_mb = std::max(0.1f, float(grown / 3e6));
    ASSERT_GT(grown, 2.0 * cap_mb * 1e6) << "the scene does not fill the cache enough to test";
    run(cap_mb, capped);
    long evicted = 0;
    for (const nlohmann::json& s : capped) {
        EXPECT_LE(s["cache_points"].get<double>() * per_point, cap_mb * 1e6) << s.dump();
        evicted += s["evicted"].get<long>();
    }
    EXPECT_GT(evicted, 0);
}

TEST(MemoryCaps, ReferenceCacheFolderStaysUnderItsCap) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_reference_cap";
    fs::remove_all(dir);
    setenv("FREQLAB_CACHE_DIR", dir.string().c_str(), 1);
    const Scene scene = load_scene("builtin:default");
    EmbreeDevice device(2);
    RenderConfig config;
    config.method = RenderMethod::Reference;
    config.frame.width = 32;
    config.frame.height = 18;
    config.reference.spp = 4;
    // One reference's size on disk, then a cap that holds two and a half of them.
    {
        FrameRenderer first(scene, config, device);
        Progress progress;
        first.render(0, progress);
    }
    const ReferenceCache cache;
    ASSERT_EQ(cache.directory(), dir / "reference");
    const double one = cache.bytes_on_disk();
    ASSERT_GT(one, 0.0);
    config.reference.cache_megabytes = float(2.5 * one / 1e6);
    FrameRenderer renderer(scene, config, device);
    long removed = 0;
    for (int f = 1; f <= 6; ++f) {
        Progress progress;
        const FrameResult r = renderer.render(f, progress);
        removed += r.stats["reference_cache_removed"].get<long>();
        EXPECT_LE(cache.bytes_on_disk(), 2.5 * one * 1.05) << "frame " << f;  // sizes vary a bit
    }
    EXPECT_GE(removed, 4);  // 7 stored, at most 2-3 kept
    // The newest is kept: rendering it again is a cache hit (nothing shaded).
    Progress progress;
    EXPECT_EQ(renderer.render(6, progress).stats["pixels_shaded"].get<long>(), 0);
    unsetenv("FREQLAB_CACHE_DIR");
    fs::remove_all(dir);
}

TEST(MemoryCaps, BakeReportsItsStorageAndPeakMemory) {
    const Scene scene = load_scene(std::string(FREQLAB_SOURCE_DIR) + "/scenes/cornell_fog.json");
    EmbreeDevice device(2);
    RayScene rays(scene, device);
    rays.update(0.0f);
    const Media media;  // surface bake: the atlas and sums are what is measured
    BakeSettings settings;
    settings.spp = 1;
    settings.max_size = 64;
    LightmapBaker baker(rays, media, nullptr, BakeMethod::Surface, settings);
    baker.run();
    const BakeStats& s = baker.stats();
    // Per texel at least the texel record and three RGB sums.
    EXPECT_GE(s.storage_mb * 1e6, double(s.texels_total) * (sizeof(LightmapTexel) + 36))
        << s.storage_mb;
    EXPECT_GT(s.peak_rss_mb, s.storage_mb);
    EXPECT_EQ(s.to_json()["peak_rss_mb"].get<double>(), s.peak_rss_mb);
}
