// The render side of method A's cache (`--method cache`; seed, Premier article Algorithm 1,
// §5.2): what the sparse frame pipeline (render/sparse_pass.cpp) calls at its cache steps.
//
// | step        | rule                                                                        |
// |-------------|-----------------------------------------------------------------------------|
// | stand-ins   | when nothing moves, a kept entry landing on an initial pixel stands in for   |
// |             | the initial radiance point (its statistics feed the upsampling): visibility |
// |             | cannot have changed; otherwise initial points are shaded (Algorithm 1)       |
// | coverage    | each reused entry splats its pixel's density d over a disk of area 1 / d    |
// |             | (at least its own pixel); the residual max(0, d - coverage) is what         |
// |             | rejection sampling sees                                                     |
// | rejection   | the uniform numbers are keyed by pixel, not frame: with nothing changed, the |
// |             | pixels drawn are those already covered, so a static frame shades nothing    |
// | insertion   | every newly shaded point (initial, adaptive, fallback) becomes an entry      |
// |             | after the batch discard (so freed slots are reused the same frame)           |
#pragma once

#include <nlohmann/json.hpp>

#include "cache/reprojection.h"
#include "image/layers.h"
#include "render/radiance_point.h"
#include "render/sparse_sampling.h"

namespace freqlab {

// Method A's cache across frames, owned by the FrameRenderer.
struct CacheState {
    RadianceCache cache;
    int last_frame = -1;  // frames must come in order; anything else starts afresh
};

// The per-pixel categories of the `decision` layer.
enum class PixelDecision : int { None = 0, Reused, NewInitial, NewAdaptive, NewFallback };

// Whether any object of the scene moves or its environment turns (stand-ins, and the observed
// half of the temporal test, only matter when something does).
bool scene_has_motion(const Scene& scene);

// For each pixel, the youngest kept record landing on it (-1: none); no merging.
std::vector<int> first_survivors(const std::vector<CacheRecord>& records, int pixel_count,
                                 const RadianceCache& cache);

// The density already covered by the reused entries at `reused` pixels (see the table).
std::vector<float> splat_coverage(int width, int height, const std::vector<int>& reused,
                                  const std::vector<float>& density,
                                  const std::vector<PixelFeature>& features);

// A newly shaded point as a cache entry. `shading` is the demodulated value (mirrors: the
// radiance); `reflected` the first non-mirror hit of a mirror pixel's reflection.
CacheEntry make_cache_entry(const SurfaceHit& hit, const vec3& view_dir, const mat4& to_world,
                            const RadiancePoint& point, const vec3& shading, float occlusion_field,
                            float shading_field, bool mirror, const SurfaceHit& reflected,
                            const mat4* reflected_to_world, bool moving, float time);

// `decision` (per pixel), `age` and `cache_decisions` (the previous frame's entries where they
// land, coloured by decision: the seed's Fig. 12(a)).
void add_cache_layers(LayerSet& layers, const std::vector<PixelDecision>& decision,
                      const std::vector<float>& age, const std::vector<CacheRecord>& records);

// The inspector's text: the entries landing within `radius` px of (x, y) this frame, each with
// its tuple (when `snapshot`, the cache before the frame, is given) and a sentence per test.
std::vector<std::string> cache_entries_near(const std::vector<CacheRecord>& records,
                                            const RadianceCache* snapshot, int x, int y, int radius,
                                            int width, const CacheSettings& settings,
                                            size_t max_entries);

// Per-frame stats: pixels_reused, merged, discards {reason: count}, cache_points, cache_bytes.
nlohmann::json cache_stats(const std::vector<long>& decision_counts, const RadianceCache& cache);

}  // namespace freqlab
