// `--method sparse`: method A's frame pipeline without the cache (seed, Premier article
// Algorithm 1 minus its cache steps, §5.1, §6):
//   G-buffer -> uniform initial radiance points (sparse.initial_stride) -> bilateral upsampling of
//   their visibility statistics {occluded, log t_min, mu_v, sigma_v} -> per-pixel B_S from the
//   covariance chain with the pixel's own geometry -> density -> rejection sampling -> adaptive
//   radiance points at the chosen pixels -> cross-bilateral reconstruction of the demodulated
//   shading -> texture x shading.
// Perfect mirrors are always sampled (density 1): their reflections are followed, not filtered.
// Pixels d px from an object's edge get a density of at least (2 / d)^2: the reconstruction
// only looks inwards there, and without samples near the edge it extrapolates (measured: +3.1 %
// on sphere_on_plane's lower sphere at 320 x 180, tests/test_sparse.cpp).
#pragma once

#include <nlohmann/json.hpp>

#include "freq/env_bandwidth.h"
#include "render/cache_pass.h"
#include "render/gbuffer.h"
#include "render/radiance_point.h"
#include "render/reconstruction.h"
#include "render/shading_memo.h"
#include "settings/sparse_settings.h"

namespace freqlab {

struct SparsePassOutput {
    long rays = 0;
    long nonfinite = 0;
    nlohmann::json
        stats;  // pixels_initial, pixels_adaptive, pixels_shaded, fallback_pixels, stage ms
    std::vector<CacheRecord> cache_records;  // with the cache: every entry's decision
    // With the cache: the reused samples (pixel, position) whose position is their entry's,
    // not their pixel's (what the reconstruction weighed them at).
    std::vector<std::pair<int, vec3>> moved_samples;
};

// With a cache (`--method cache`) the pipeline reuses, discards and inserts entries at the
// steps of Algorithm 1 (render/cache_pass.h); without, it is the no-cache baseline.
struct CacheHook {
    CacheState& state;
    const CacheSettings& settings;
};

// A first image of the frame (issue "The timeline as a recorded run": a progressive first
// image): once the initial grid is shaded (or stood in for by cache entries), its colour from
// those points alone, each pixel the bilinear blend of the grid points around it on its own
// object times its albedo; the background as rendered. A `color` layer, handed over while the
// adaptive points render.
using PreviewSink = std::function<void(LayerSet&&)>;

// What a run attaches to a frame of the pipeline (all optional).
struct SparseHooks {
    const CacheHook* cache = nullptr;        // method A's cache (`--method cache`)
    ReconstructionRecord* record = nullptr;  // a pixel's reconstruction contributions
    const PreviewSink* preview = nullptr;    // the first image
    // Points shaded by an earlier run with the same shading inputs (render/shading_memo.h):
    // recalled instead of shaded, and this frame's new points added.
    ShadingMemo* memo = nullptr;
};

SparsePassOutput render_sparse(const RayScene& scene, const GBuffer& gbuffer, int frame,
                               const FrameSettings& frame_settings, const ShadingSettings& shading,
                               const PointsSettings& points, const SparseSettings& sparse,
                               const EnvBandwidthHierarchy* bandwidth, LayerSet& layers,
                               Progress& progress, const SparseHooks& hooks = {});

// The `sampled` layer's categories.
// (The layer adds 4 = reused for the cache's entries.)
enum class SampleKind : int { None = 0, Initial = 1, Adaptive = 2, Fallback = 3 };

constexpr uint64_t kSparseStream = 0x5350415253ULL;  // "SPARS": rejection sampling

}  // namespace freqlab
