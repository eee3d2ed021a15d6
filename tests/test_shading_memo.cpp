// The shading memo (render/shading_memo.h; issue "The timeline as a recorded run", acceptance 3):
// a run with another cache.q_eps_x fed from the memo of a first run renders the same bytes as
// the same run from scratch, on a moving scene (every shared point recalled) and on a still one
// (cache entries stand in on the initial grid, so plans change and are shaded again); the table
// refuses a point shaded with another plan; the memo keeps under its cap.
#include <gtest/gtest.h>

#include <filesystem>

#include "base/error.h"
#include "base/file_io.h"

#include "render/frame_checkpoint.h"
#include "render/frame_renderer.h"
#include "render/shading_memo.h"
#include "render/shading_memo_store.h"
#include "scene/scene_loader.h"

using namespace freqlab;

namespace {

Scene rotor(bool spinning) {
    Scene scene = load_scene(std::string(FREQLAB_SOURCE_DIR) + "/scenes/rotor.json");
    if (!spinning)
        for (SceneObject& o : scene.objects) o.animation.spin_rad_per_s = 0.0f;
    return scene;
}

RenderConfig cache_config(float q_eps_x) {
    RenderConfig config;
    config.method = RenderMethod::Cache;
    config.frame.width = 160;
    config.frame.height = 90;
    config.points.max_samples = 64;
    config.cache.q_eps_x = q_eps_x;
    return config;
}

std::vector<FrameResult> render_frames(const Scene& scene, const RenderConfig& config, int frames,
                                       std::shared_ptr<ShadingMemo> memo) {
    EmbreeDevice device;
    FrameRenderer renderer(scene, config, device);
    renderer.set_shading_memo(std::move(memo));
    Progress progress;
    std::vector<FrameResult> out;
    for (int f = 0; f < frames; ++f) out.push_back(renderer.render(f, progress));
    return out;
}

// Runs q_eps_x = 1e-4 into a memo, then 4e-4 from it and from scratch: same layers, bit for bit.
void expect_memo_run_matches_scratch(bool spinning, long* recalled, long* shaded) {
    const Scene scene = rotor(spinning);
    const int frames = 4;
    auto memo = std::make_shared<ShadingMemo>(size_t(256) << 20);
    (void)render_frames(scene, cache_config(1e-4f), frames, memo);
    const std::vector<FrameResult> fed = render_frames(scene, cache_config(4e-4f), frames, memo);
    const std::vector<FrameResult> scratch =
        render_frames(scene, cache_config(4e-4f), frames, nullptr);
    *recalled = *shaded = 0;
    for (int f = 0; f < frames; ++f) {
        const LayerSet &a = fed[size_t(f)].layers, &b = scratch[size_t(f)].layers;
        ASSERT_EQ(a.names(), b.names());
        for (const Layer& l : b.layers())
            ASSERT_EQ(a.get(l.name).data, l.data) << "frame " << f << " layer " << l.name;
        EXPECT_EQ(fed[size_t(f)].stats["pixels_shaded"], scratch[size_t(f)].stats["pixels_shaded"]);
        const nlohmann::json& m = fed[size_t(f)].stats.at("shading_memo");
        *recalled += m["recalled"].get<long>();
        *shaded += m["shaded"].get<long>();
        EXPECT_FALSE(scratch[size_t(f)].stats.contains("shading_memo"));
    }
}

std::string field_of_memo(const std::filesystem::path& file, const nlohmann::json& key, int frame) {
    try {
        read_memo_frame(file, key, frame);
    } catch (const Error& e) {
        return e.field();
    }
    return "(accepted)";
}

}  // namespace

TEST(ShadingMemo, AnotherQEpsXFromTheMemoRendersTheBytesOfARunFromScratchOnAMovingScene) {
    long recalled = 0, shaded = 0;
    expect_memo_run_matches_scratch(true, &recalled, &shaded);
    // Moving: no stand-ins, plans do not depend on the cache; only points the first run did
    // not shade (it reused their pixels' entries) are shaded again.
    EXPECT_GT(recalled, 4 * shaded) << "recalled " << recalled << ", shaded " << shaded;
}

TEST(ShadingMemo, AnotherQEpsXFromTheMemoRendersTheBytesOfARunFromScratchOnAStillScene) {
    long recalled = 0, shaded = 0;
    expect_memo_run_matches_scratch(false, &recalled, &shaded);
    EXPECT_GT(recalled, 0);  // frame 0 at least: an empty cache, no stand-ins
}

TEST(ShadingMemo, ATableRecallsOnlyThePointOfTheSamePixelPassAndPlan) {
    ShadingMemo memo(size_t(1) << 20);
    VisibilityPlan plan;
    plan.occluded_fraction = 0.25;
    ShadingMemo::Entry planned{7, 1, true, plan, {}};
    planned.point.rays = 11;
    ShadingMemo::Entry unplanned{7, 0, false, {}, {}};
    unplanned.point.rays = 5;
    memo.add(3, {planned, unplanned});
    const auto table = memo.frame(3);
    ASSERT_TRUE(table);
    EXPECT_EQ(memo.frame(4), nullptr);
    ASSERT_NE(table->find(7, 1, &plan), nullptr);
    EXPECT_EQ(table->find(7, 1, &plan)->rays, 11);
    EXPECT_EQ(table->find(7, 0, nullptr)->rays, 5);
    EXPECT_EQ(table->find(7, 1, nullptr), nullptr);  // planned then, not now
    EXPECT_EQ(table->find(7, 0, &plan), nullptr);    // and the other way
    VisibilityPlan other = plan;
    other.occluded_fraction = std::nextafter(0.25, 1.0);
    EXPECT_EQ(table->find(7, 1, &other), nullptr);
    other = plan;
    other.own_distances = true;
    EXPECT_EQ(table->find(7, 1, &other), nullptr);
    EXPECT_EQ(table->find(8, 1, &plan), nullptr);
    // Adding the same key again keeps the first point (the table handed out is unchanged).
    ShadingMemo::Entry again = planned;
    again.point.rays = 99;
    memo.add(3, {again});
    EXPECT_EQ(memo.frame(3)->find(7, 1, &plan)->rays, 11);
    EXPECT_EQ(memo.frame(3)->keys.size(), 2u);
    EXPECT_EQ(memo.counts().stored, 2);
}

// A cache.* change renders from frame 0: the early frames are the ones worth keeping.
TEST(ShadingMemo, KeepsUnderItsCapDroppingTheLatestFrames) {
    const size_t per_frame = 1000 * sizeof(ShadingMemo::Entry) + 1000 * sizeof(uint64_t);
    ShadingMemo memo(3 * per_frame + per_frame / 2);
    auto frame_entries = [] {
        std::vector<ShadingMemo::Entry> e(1000);
        for (size_t k = 0; k < e.size(); ++k) e[k].pixel = uint32_t(k);
        return e;
    };
    for (int f : {0, 2, 5}) memo.add(f, frame_entries());
    EXPECT_EQ(memo.counts().frames, 3);
    memo.add(1, frame_entries());  // frame 5 goes
    ShadingMemo::Counts c = memo.counts();
    EXPECT_EQ(c.frames, 3);
    EXPECT_LE(c.bytes, c.max_bytes);
    EXPECT_EQ(c.evicted_frames, 1);
    EXPECT_EQ(memo.frame(5), nullptr);
    for (int f : {0, 1, 2}) EXPECT_NE(memo.frame(f), nullptr) << f;
    memo.add(9, frame_entries());  // the latest itself: not kept
    EXPECT_EQ(memo.frame(9), nullptr);
    EXPECT_EQ(memo.counts().evicted_frames, 2);
    // A cap of 0 keeps nothing.
    ShadingMemo none(0);
    none.add(0, frame_entries());
    EXPECT_EQ(none.frame(0), nullptr);
}

TEST(ShadingMemo, ItsKeyIsTheRunKeyWithoutTheCacheSettings) {
    RenderConfig config;
    auto run_key = [&] {
        return frame_checkpoint_key({{"freqlab", "test"},
                                     {"scene_hash", "abc"},
                                     {"method", "cache"},
                                     {"settings", config.settings_group().to_json()},
                                     {"seed", 0}});
    };
    const nlohmann::json run = run_key();
    config.cache.q_eps_x = 2e-4f;
    config.frame.exposure = 2.0f;
    EXPECT_EQ(ShadingMemo::key_of(run), ShadingMemo::key_of(run_key()));
    EXPECT_NE(run, run_key());
    config.frame.width = 320;
    EXPECT_NE(ShadingMemo::key_of(run), ShadingMemo::key_of(run_key()));
}

// The memo on disk (render/shading_memo_store.h): a run reopened in a later session (a new memo,
// fed by the files the first run wrote) renders another q_eps_x with the bytes of a run from
// scratch, recalling the first run's points; a damaged or foreign file is refused naming the
// field, and the loader skips it (those points are shaded again).
TEST(ShadingMemo, PointsWrittenToTheRunStoreFeedALaterSession) {
    const Scene scene = rotor(true);
    const int frames = 3;
    const std::filesystem::path store =
        std::filesystem::temp_directory_path() / "freqlab_memo_store_test";
    std::filesystem::remove_all(store);
    const std::filesystem::path run_a = store / "a", run_b = store / "b", other = store / "c";
    const nlohmann::json key = {{"scene_hash", "rotor"}, {"settings", {{"frame", {{"w", 160}}}}}};
    {
        auto memo = std::make_shared<ShadingMemo>(size_t(256) << 20);
        (void)render_frames(scene, cache_config(1e-4f), frames, memo);
        for (int f = 0; f < frames; ++f) write_memo_frame(run_a, key, f, *memo->frame(f));
        write_memo_frame(other, {{"scene_hash", "another"}}, 0, *memo->frame(0));
    }
    EXPECT_EQ(runs_sharing_memo(run_b, key), std::vector<std::filesystem::path>{run_a});
    auto memo = std::make_shared<ShadingMemo>(size_t(256) << 20);
    memo->set_loader(memo_loader(runs_sharing_memo(run_b, key), key));
    const std::vector<FrameResult> fed = render_frames(scene, cache_config(4e-4f), frames, memo);
    const std::vector<FrameResult> scratch =
        render_frames(scene, cache_config(4e-4f), frames, nullptr);
    long recalled = 0, shaded = 0;
    for (int f = 0; f < frames; ++f) {
        for (const Layer& l : scratch[size_t(f)].layers.layers())
            ASSERT_EQ(fed[size_t(f)].layers.get(l.name).data, l.data) << f << " " << l.name;
        recalled += fed[size_t(f)].stats["shading_memo"]["recalled"].get<long>();
        shaded += fed[size_t(f)].stats["shading_memo"]["shaded"].get<long>();
    }
    EXPECT_GT(recalled, 4 * shaded) << "recalled " << recalled << ", shaded " << shaded;
    EXPECT_EQ(memo->counts().loaded_frames, frames);

    // Damage: refused naming the field; the loader passes over it.
    const std::filesystem::path file = memo_frame_path(run_a, 1);
    std::string bytes = read_text_file(file);
    EXPECT_EQ(field_of_memo(file, {{"scene_hash", "another"}}, 1), "key");
    bytes[bytes.size() / 2] ^= 0x20;
    write_text_atomically(file, bytes);
    EXPECT_EQ(field_of_memo(file, key, 1), "checksum");
    write_text_atomically(file, bytes.substr(0, 6));
    EXPECT_EQ(field_of_memo(file, key, 1), "header");
    EXPECT_EQ(memo_loader({run_a}, key)(1), nullptr);
    ASSERT_NE(memo_loader({run_a}, key)(2), nullptr);
    // A table whose keys are out of order (written by hand, checksum valid) is refused too.
    ShadingMemo::FrameTable bad;
    bad.entries = {{9, 0, false, {}, {}}, {3, 0, false, {}, {}}};
    bad.keys = {36, 12};
    write_memo_frame(run_a, key, 5, bad);
    EXPECT_EQ(field_of_memo(memo_frame_path(run_a, 5), key, 5), "entries[1]");
    std::filesystem::remove_all(store);
}
