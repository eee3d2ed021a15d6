// Recorded runs (render/frame_store.h; issue "The timeline as a recorded run"): a frame read
// back from the run store is the frame that was rendered, bit for bit; a file of another run or
// a damaged one is refused naming the field; the run store and the decoded frames in memory
// stay under their caps, dropping what was used least lately.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "base/error.h"
#include "base/file_io.h"
#include "render/background_frame_reader.h"
#include "render/frame_checkpoint.h"
#include "render/frame_store.h"
#include "render/shading_memo_store.h"

using namespace freqlab;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json run_key(const std::string& method) {
    return {{"freqlab", "test"},
            {"scene_hash", "abc"},
            {"method", method},
            {"settings", {{"cache", {{"q_eps_x", 0.5}}}}},
            {"seed", 7}};
}

// A frame with every kind of content: colour, a categorical layer with legend and palette, a
// sparse layer, stats, cache records with each decision, reused samples' positions. `megabytes`
// of colour data when given.
FrameResult test_frame(int frame, double megabytes = 0.0) {
    const int w = megabytes > 0 ? 512 : 7,
              h = megabytes > 0 ? int(megabytes * 1048576 / (512 * 12)) : 5;
    FrameResult r;
    r.frame = frame;
    r.time_s = 0.25f * frame;
    r.layers = LayerSet(w, h);
    Layer& c = r.layers.add("color", LayerKind::Color, 3, "radiance");
    for (size_t i = 0; i < c.data.size(); ++i) c.data[i] = float(i % 97) * 0.37f + frame;
    Layer& d = r.layers.add("decision", LayerKind::Categorical, 1, "per pixel");
    d.legend = {"reused", "new"};
    d.palette = {vec3(1, 0, 0), vec3(0, 1, 0)};
    d.data.assign(d.data.size(), 1.0f);
    Layer& s = r.layers.add("samples", LayerKind::Continuous, 1);
    s.sparse = true;
    s.data[3] = -0.0f;
    s.data[4] = 1e-38f;
    r.stats = {{"frame", frame}, {"time_ms", 12.5}, {"discards", {{"Angular", 3}}}};
    auto records = std::make_shared<std::vector<CacheRecord>>();
    for (int k = 0; k < kCacheDecisionCount; ++k) {
        CacheRecord rec;
        rec.object = k;
        rec.slot = 2 * k;
        rec.pixel = 3 * k;
        rec.decision = CacheDecision(k);
        rec.tests.angular_distance = 0.1 * k;
        rec.world_position = vec3(float(k), 2.0f, -1.0f);
        records->push_back(rec);
    }
    CacheRecord outside;  // lands outside the image: not stored (the inspector never lists it)
    outside.pixel = -1;
    records->push_back(outside);
    r.cache_records = records;
    r.sample_positions = std::make_shared<const std::vector<std::pair<int, vec3>>>(
        std::vector<std::pair<int, vec3>>{{4, vec3(1, 2, 3)}, {9, vec3(-1, 0, 0.5f)}});
    return r;
}

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("freqlab_frame_store_" + name);
    fs::remove_all(dir);
    return dir;
}

std::string field_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.field();
    }
    return "(no error)";
}

uint64_t folder_bytes(const fs::path& dir) {
    uint64_t bytes = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file()) bytes += e.file_size();
    return bytes;
}

}  // namespace

TEST(RecordedFrames, ReadBackIsTheFrameWrittenBitForBit) {
    const fs::path dir = fresh_dir("roundtrip");
    const FrameResult f = test_frame(3);
    write_recorded_frame(dir, run_key("cache"), f);
    const FrameResult back = read_recorded_frame(dir, run_key("cache"), 3);
    EXPECT_EQ(back.frame, 3);
    EXPECT_EQ(back.time_s, f.time_s);
    EXPECT_EQ(back.stats, f.stats);
    ASSERT_EQ(back.layers.layers().size(), f.layers.layers().size());
    for (size_t i = 0; i < f.layers.layers().size(); ++i) {
        const Layer &a = f.layers.layers()[i], &b = back.layers.layers()[i];
        EXPECT_EQ(b.name, a.name);
        EXPECT_EQ(b.kind, a.kind);
        EXPECT_EQ(b.legend, a.legend);
        EXPECT_EQ(b.palette, a.palette);
        EXPECT_EQ(b.sparse, a.sparse);
        ASSERT_EQ(b.data.size(), a.data.size());
        EXPECT_EQ(std::memcmp(b.data.data(), a.data.data(), a.data.size() * sizeof(float)), 0)
            << a.name << ": bits differ (-0, denormals)";
    }
    ASSERT_TRUE(back.cache_records);
    ASSERT_EQ(back.cache_records->size(), size_t(kCacheDecisionCount));
    for (size_t k = 0; k < back.cache_records->size(); ++k) {
        EXPECT_EQ((*back.cache_records)[k].decision, (*f.cache_records)[k].decision);
        EXPECT_EQ((*back.cache_records)[k].tests.angular_distance,
                  (*f.cache_records)[k].tests.angular_distance);
        EXPECT_EQ((*back.cache_records)[k].world_position, (*f.cache_records)[k].world_position);
    }
    ASSERT_TRUE(back.sample_positions);
    EXPECT_EQ(*back.sample_positions, *f.sample_positions);
    // The stats the timeline reads without the layers.
    const auto stats = recorded_frame_stats(dir);
    ASSERT_EQ(stats.size(), 1u);
    EXPECT_EQ(stats.at(3), f.stats);
    fs::remove_all(dir);
}

// A timeline jump reads the layers on screen first (~5 % of a frame), the rest later.
TEST(RecordedFrames, OnlyTheLayersAskedForAreReadAndTheOthersNamed) {
    const fs::path dir = fresh_dir("partial");
    const FrameResult f = test_frame(3);
    write_recorded_frame(dir, run_key("cache"), f);
    const FrameResult part = read_recorded_frame(dir, run_key("cache"), 3, {"samples", "nope"});
    EXPECT_TRUE(part.partial);
    EXPECT_EQ(part.unread_layers, (std::vector<std::string>{"color", "decision"}));
    ASSERT_EQ(part.layers.layers().size(), 1u);
    const Layer& s = part.layers.get("samples");
    EXPECT_TRUE(s.sparse);
    EXPECT_EQ(std::memcmp(s.data.data(), f.layers.get("samples").data.data(),
                          s.data.size() * sizeof(float)),
              0);
    EXPECT_EQ(part.stats, f.stats);
    EXPECT_EQ(part.time_s, f.time_s);
    EXPECT_FALSE(part.cache_records);
    EXPECT_FALSE(part.sample_positions);
    EXPECT_FALSE(read_recorded_frame(dir, run_key("cache"), 3).partial);
    // A layer left out is still checked: a damaged kind is refused naming it either way.
    std::string bytes = read_text_file(recorded_frame_path(dir, 3));
    const size_t at = bytes.find("decision");
    ASSERT_NE(at, std::string::npos);
    const int32_t bad_kind = 99;
    std::memcpy(&bytes[at + 8], &bad_kind, sizeof bad_kind);
    write_text_atomically(recorded_frame_path(dir, 3), bytes);
    EXPECT_EQ(field_of([&] { read_recorded_frame(dir, run_key("cache"), 3, {"color"}); }),
              "layers.decision");
    EXPECT_EQ(field_of([&] { read_recorded_frame(dir, run_key("cache"), 3); }), "layers.decision");
    fs::remove_all(dir);
}

// The whole frame after the jump: read on the reader's thread, the same bytes as a read here;
// a frame gone from the store comes back as an error naming its file.
TEST(RecordedFrames, BackgroundReaderReadsWholeFramesAndNamesMissingOnes) {
    const fs::path dir = fresh_dir("background");
    for (int frame : {1, 2}) write_recorded_frame(dir, run_key("cache"), test_frame(frame));
    BackgroundFrameReader reader;
    EXPECT_TRUE(reader.idle());
    std::vector<BackgroundFrameReader::Read> reads;
    auto wait_for = [&](int frame) {
        for (int i = 0; i < 1000; ++i) {
            for (auto& r : reader.take()) reads.push_back(std::move(r));
            if (!reads.empty() && reads.back().frame == frame) return;
            reader.wait_until_idle_or_done();
        }
        FAIL() << "frame " << frame << " never read";
    };
    reader.request(dir, run_key("cache"), 1);
    reader.request(dir, run_key("cache"), 2);  // replaces 1 unless 1 is being read
    wait_for(2);
    const BackgroundFrameReader::Read& two = reads.back();
    ASSERT_TRUE(two.result) << two.error;
    EXPECT_EQ(two.dir, dir);
    EXPECT_FALSE(two.result->partial);
    const FrameResult here = read_recorded_frame(dir, run_key("cache"), 2);
    ASSERT_EQ(two.result->layers.layers().size(), here.layers.layers().size());
    for (size_t i = 0; i < here.layers.layers().size(); ++i)
        EXPECT_EQ(two.result->layers.layers()[i].data, here.layers.layers()[i].data);
    ASSERT_TRUE(two.result->cache_records);
    EXPECT_EQ(two.result->cache_records->size(), here.cache_records->size());
    EXPECT_LE(reads.size(), 2u);
    reads.clear();
    reader.request(dir, run_key("cache"), 9);
    wait_for(9);
    EXPECT_FALSE(reads.back().result);
    EXPECT_NE(reads.back().error.find("frame_0009.bin"), std::string::npos) << reads.back().error;
    EXPECT_TRUE(reader.idle());
    fs::remove_all(dir);
}

// A display setting re-renders nothing (issue "The timeline as a recorded run"): the run key
// leaves out every setting whose flags are nothing or display only, so a run reopened at
// another exposure (or checkpoint period) finds its frames; any other setting is another run.
TEST(RecordedFrames, RunKeyLeavesOutSettingsThatChangeNoResult) {
    RenderConfig config;
    auto key = [&] {
        return frame_checkpoint_key({{"freqlab", "test"},
                                     {"scene_hash", "abc"},
                                     {"scene", "/some/path.json"},
                                     {"method", "cache"},
                                     {"settings", config.settings_group().to_json()},
                                     {"seed", 0}});
    };
    const json base = key();
    EXPECT_FALSE(base.contains("scene"));
    EXPECT_FALSE(base["settings"]["frame"].contains("exposure"));
    EXPECT_FALSE(base["settings"]["cache"].contains("checkpoint_every"));
    EXPECT_TRUE(base["settings"]["cache"].contains("q_eps_x"));
    config.frame.exposure = 3.0f;
    config.cache.checkpoint_every = 7;
    config.reference.use_cache = !config.reference.use_cache;
    EXPECT_EQ(key(), base);
    config.cache.q_eps_x *= 2.0f;
    EXPECT_NE(key(), base);
}

TEST(RecordedFrames, AnotherRunsOrADamagedFileIsRefusedNamingTheField) {
    const fs::path dir = fresh_dir("damage");
    write_recorded_frame(dir, run_key("cache"), test_frame(1));
    EXPECT_EQ(field_of([&] { read_recorded_frame(dir, run_key("sparse"), 1); }), "key.method");
    const fs::path file = recorded_frame_path(dir, 1);
    std::string bytes = read_text_file(file);
    // A frame renamed to another number is not that frame.
    write_text_atomically(recorded_frame_path(dir, 2), bytes);
    EXPECT_EQ(field_of([&] { read_recorded_frame(dir, run_key("cache"), 2); }), "frame");
    for (size_t cut : {bytes.size() / 3, bytes.size() - 1}) {
        write_text_atomically(file, bytes.substr(0, cut));
        EXPECT_EQ(field_of([&] { read_recorded_frame(dir, run_key("cache"), 1); }), "size");
    }
    write_text_atomically(file, "FLFR");
    EXPECT_EQ(field_of([&] { read_recorded_frame(dir, run_key("cache"), 1); }), "header");
    fs::remove_all(dir);
}

// Acceptance 4's cap: other runs go first (least recently used first), then the run's own
// frames least recently used first; its checkpoints stay; what is left fits the cap.
TEST(RecordedFrames, RunStoreObeysItsCap) {
    const fs::path store = fresh_dir("cap") / "runs";
    const fs::path old_run = store / "old", other = store / "other", mine = store / "mine";
    for (int f = 0; f < 3; ++f) write_recorded_frame(old_run, run_key("mis"), test_frame(f, 1.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    write_recorded_frame(other, run_key("mis"), test_frame(0, 1.0));
    write_frame_checkpoint(frame_checkpoint_path(mine, 10), run_key("cache"), 10,
                           std::string(500000, 'x'));
    ShadingMemo::FrameTable points;  // a frame's shading memo goes with the frame
    points.entries.resize(2);
    points.keys = {4, 8};
    points.entries[1].pixel = 2;
    for (int f = 0; f < 8; ++f) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        write_recorded_frame(mine, run_key("cache"), test_frame(f, 1.0));
        write_memo_frame(mine, {{"memo", 1}}, f, points);
    }
    touch_recorded_frame(mine, 0);  // looked at last: stays
    setenv("FREQLAB_RUN_STORE_MB", "4.8", 1);
    const RunStoreTrim removed = trim_run_store(mine);
    unsetenv("FREQLAB_RUN_STORE_MB");
    EXPECT_EQ(removed.runs, 2);
    EXPECT_FALSE(fs::exists(old_run));
    EXPECT_FALSE(fs::exists(other));
    EXPECT_LE(folder_bytes(store), uint64_t(4.8 * 1048576));
    EXPECT_TRUE(fs::exists(frame_checkpoint_path(mine, 10)));
    const auto kept = recorded_frame_stats(mine);
    EXPECT_GT(removed.frames, 0);
    EXPECT_EQ(int(kept.size()), 8 - removed.frames);
    EXPECT_TRUE(kept.count(0)) << "the frame used last was dropped";
    EXPECT_TRUE(kept.count(7)) << "the newest frame was dropped";
    EXPECT_FALSE(kept.count(1)) << "the least recently used frame was kept";
    for (int f = 0; f < 8; ++f) {
        EXPECT_EQ(fs::exists(recorded_frame_path(mine, f)), kept.count(f) > 0) << f;
        EXPECT_EQ(fs::exists(memo_frame_path(mine, f)), kept.count(f) > 0) << f;
    }
    EXPECT_EQ(recorded_frame_stats(mine).size(), kept.size()) << "memo/key.json is no frame";
    fs::remove_all(store.parent_path());
}

TEST(RecordedFrames, DecodedFramesStayUnderTheirCapLeastRecentlyUsedFirst) {
    const size_t one = frame_result_bytes(test_frame(0, 1.0));
    DecodedFrames frames(size_t(3.5 * double(one)));
    for (int f = 0; f < 3; ++f) frames.keep(std::make_shared<FrameResult>(test_frame(f, 1.0)));
    EXPECT_TRUE(frames.find(0));  // 0 used after 1 and 2
    const std::shared_ptr<FrameResult> held = frames.find(1);
    frames.keep(std::make_shared<FrameResult>(test_frame(3, 1.0)));
    EXPECT_EQ(frames.frames(), (std::vector<int>{0, 1, 3}));  // 2: least recently used
    EXPECT_LE(frames.bytes(), frames.cap());
    frames.keep(std::make_shared<FrameResult>(test_frame(4, 1.0)));
    frames.keep(std::make_shared<FrameResult>(test_frame(5, 1.0)));
    EXPECT_EQ(frames.frames(), (std::vector<int>{3, 4, 5}));
    EXPECT_EQ(held->frame, 1) << "a frame handed out outlives its eviction";
    DecodedFrames tiny(1);
    tiny.keep(std::make_shared<FrameResult>(test_frame(9)));
    EXPECT_EQ(tiny.frames(), (std::vector<int>{9})) << "the frame kept last always stays";
}

TEST(RecordedFrames, CapsFromTheEnvironmentAreNumbersOrRefused) {
    setenv("FREQLAB_FRAME_MEMORY_MB", "64", 1);
    EXPECT_EQ(decoded_frames_cap(), size_t(64) << 20);
    setenv("FREQLAB_FRAME_MEMORY_MB", "lots", 1);
    try {
        decoded_frames_cap();
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("FREQLAB_FRAME_MEMORY_MB"), std::string::npos);
    }
    unsetenv("FREQLAB_FRAME_MEMORY_MB");
}
