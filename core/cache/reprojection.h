// Method A's per-frame cache pass (seed, Premier article Algorithm 1 "cache point verification
// and reprojection", §5.2, §5.3): move every entry with its object, project it, run the
// validity tests, then resolve pixels hit by several survivors (merge rule, Fig. 13) and
// remove discards in one batch.
//
// | step     | rule                                                                          |
// |----------|-------------------------------------------------------------------------------|
// | project  | x = T_object(now) x_object; pixel = floor of the pinhole projection            |
// | depth    | |distance - surface distance| <= depth_tolerance x distance + the pixel's      |
// |          | footprint (a sub-pixel offset on a grazing surface moves the depth that much)  |
// | mirrors  | the pixel's reflection is re-traced (by the caller): same reflected object,    |
// |          | spatial test on the reflected point                                             |
// | keeper   | per pixel the youngest survivor (then the heaviest); the others merge into it  |
// |          | when each lies within the other's r_x and r_theta and their creation times    |
// |          | within both lifespans (seed Fig. 13, extended in time), else stay unused     |
// | merge    | value = (w_k L_k + w_o L_o) / (w_k + w_o), weight w_k + w_o (the keeper's      |
// |          | bandwidths and creation time stay)                                              |
#pragma once

#include <vector>

#include "accel/ray_scene.h"
#include "cache/cache_decision.h"
#include "cache/radiance_cache.h"
#include "scene/camera.h"

namespace freqlab {

// What the reprojection needs of the current frame.
struct CacheFrameView {
    int width = 0, height = 0;
    const CameraRayGenerator* camera = nullptr;
    const std::vector<SurfaceHit>* hits = nullptr;  // the G-buffer's pixel-centre hits
    const std::vector<float>* footprint = nullptr;  // world size of each pixel on its surface
    // Mirror pixels: the first non-mirror hit of the pixel's reflection chain (else invalid).
    const std::vector<SurfaceHit>* reflected = nullptr;
    std::vector<mat4> to_world;  // per object, at `time`
    float time = 0.0f;
};

struct CacheRecord {
    int object = -1, slot = -1;
    int pixel = -1;  // the pixel it lands on (-1 outside the image)
    CacheDecision decision = CacheDecision::Reused;
    CacheTestValues tests;
    vec3 world_position{0.0f};  // moved with its object to this frame
};

// Every live entry's geometric tests (all but occlusion), in a deterministic order.
std::vector<CacheRecord> reproject_entries(const RadianceCache& cache, const CacheFrameView& view,
                                           const CacheSettings& settings);

// The tests of the entries still kept against this frame's upsampled per-pixel occlusion ratio
// and log shading (`known[pixel]` false, or a NaN shading: no statistic there, they pass).
void apply_field_tests(std::vector<CacheRecord>& records, const std::vector<float>& occlusion,
                       const std::vector<float>& shading, const std::vector<char>& known,
                       const CacheSettings& settings);

// Per pixel, the record whose value the pixel uses (-1: none). Applies the merge rule to
// several survivors on one pixel (updates the keeper's value in the cache).
std::vector<int> resolve_pixels(std::vector<CacheRecord>& records, RadianceCache& cache,
                                const CacheFrameView& view, const CacheSettings& settings);

// Removes discarded and merged entries, one batch per object. Returns discards per reason
// (indexed by CacheDecision).
std::vector<long> commit_decisions(const std::vector<CacheRecord>& records, RadianceCache& cache);

}  // namespace freqlab
