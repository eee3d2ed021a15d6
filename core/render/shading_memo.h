// Radiance points a run has shaded, recalled by a later run that shades the same points
// (issue "The timeline as a recorded run": a cache.* change re-runs method A's cache from frame 0
// without shading again what both runs shade).
//
// Why a recalled point is exact: SparseFrame::shade draws its random numbers from (seed, frame,
// pixel, pass) alone, and its other inputs are the G-buffer, the shading / points / sparse
// settings and, for adaptive points, the visibility plan upsampled from the initial grid. The
// owner keys a memo by everything but the plan (scene, size, seed, method, every setting outside
// `cache.*`: ShadingMemo::key_of); a point is recalled only for the same frame, pixel, pass and
// the same plan bit for bit, so a recalled point is the point shading would compute, and a run
// fed from a memo renders the bytes a run from scratch renders (test_shading_memo.cpp). On a
// moving scene the initial grid is always shaded (no stand-ins), so plans do not depend on the
// cache and every point both runs shade is recalled; on a still one, cache entries stand in on
// the grid and a plan that changed is shaded again.
//
// | parameter        | default | meaning                                                   |
// |------------------|---------|-----------------------------------------------------------|
// | max_bytes        | 512 MB  | $FREQLAB_SHADING_MEMO_MB; past it the latest frames go     |
//
// Why the latest frames go first: a cache.* change renders the run again from frame 0 up to
// the frame shown, so frames 0..K recalled save what 0..K cost; a memo with holes early on
// would save as much only if every later frame were still there.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/radiance_point.h"

namespace freqlab {

class ShadingMemo {
  public:
    // One shaded point: where, which pass, the plan it followed (none: no plan), the point.
    struct Entry {
        uint32_t pixel = 0;
        uint8_t pass = 0;
        bool planned = false;
        VisibilityPlan plan;
        RadiancePoint point;
    };
    // A frame's points, sorted by (pixel, pass); shared read-only with the passes using it.
    struct FrameTable {
        std::vector<uint64_t> keys;  // pixel * 4 + pass, ascending
        std::vector<Entry> entries;  // same order
        // The point shaded for (pixel, pass) with this plan, or null.
        const RadiancePoint* find(uint32_t pixel, uint8_t pass, const VisibilityPlan* plan) const;
        size_t bytes() const;
    };
    struct Counts {
        long recalled = 0, stored = 0, frames = 0, evicted_frames = 0, loaded_frames = 0;
        size_t bytes = 0, max_bytes = 0;
    };

    explicit ShadingMemo(size_t max_bytes = default_max_bytes());
    // $FREQLAB_SHADING_MEMO_MB (default 512; 0 keeps nothing), refused when not a number.
    static size_t default_max_bytes();
    // What a memo's points depend on, from a run key (frame_checkpoint_key): the key without
    // the cache's settings (the run key has no setting that changes no result).
    static nlohmann::json key_of(const nlohmann::json& run_key);

    // The frame's table (null when none); the memo may drop it meanwhile, the pointer stays.
    // A frame not in memory is asked of the loader once (render/shading_memo_store.h: the
    // points earlier runs wrote to the run store) and kept like added points.
    std::shared_ptr<const FrameTable> frame(int frame);
    using Loader = std::function<std::shared_ptr<const FrameTable>(int frame)>;
    void set_loader(Loader loader);
    // Adds the frame's new points (pixels and passes not in its table yet); the table is
    // replaced, so tables handed out are never written. Then drops the latest frames (this
    // one too, when it is the latest) until the memo is within max_bytes.
    void add(int frame, std::vector<Entry> entries);
    void count_recalled(long n);
    Counts counts() const;

  private:
    void fit_within_cap();  // drops the latest frames until within max_bytes (mutex_ held)
    mutable std::mutex mutex_;
    size_t max_bytes_ = 0;
    std::map<int, std::shared_ptr<const FrameTable>> frames_;
    Loader loader_;
    std::set<int> asked_;  // frames the loader was asked for
    size_t bytes_ = 0;
    Counts counts_;  // recalled, stored, evicted_frames (the rest is filled in by counts())
};

}  // namespace freqlab
