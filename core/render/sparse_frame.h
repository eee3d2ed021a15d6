// One frame of method A's sparse pipeline (render_sparse, sparse_pass.h) as the state its
// stages share, one member function per stage of the seed's Algorithm 1 (Premier article §5,
// §6): features -> [cache: reproject] -> initial points -> upsampled statistics -> [cache:
// occlusion test, one entry per pixel] -> density -> adaptive points -> reconstruction (with
// fallbacks) -> [cache: discard, insert] -> layers. The cache's stages live in
// sparse_cache_stages.cpp; the rest in sparse_pass.cpp. Internal to those two files.
#pragma once

#include <array>
#include <atomic>
#include <vector>

#include "render/cache_pass.h"
#include "render/key_lights.h"
#include "render/radiance_point.h"
#include "render/reconstruction.h"
#include "render/sparse_pass.h"
#include "render/sparse_sampling.h"

namespace freqlab {

struct SparseFrame {
    SparseFrame(const RayScene& rs, const GBuffer& gb, int frame, const FrameSettings& fs,
                const ShadingSettings& shading, const PointsSettings& points,
                const SparseSettings& sparse, const EnvBandwidthHierarchy* bandwidth,
                LayerSet& layers, Progress& progress, const CacheHook* cache,
                ReconstructionRecord* record);

    // The stages, in order.
    void cache_reproject();          // 0. move, project and test every entry (all but occlusion)
    void initial_points();           // 1. uniform points, or the kept entries standing in for them
    LayerSet preview_image() const;  // 1b. the colour from the initial grid alone
    void upsample();                 // 2. upsampled visibility statistics and features
    void cache_resolve();            // 2b. occlusion and key-light tests, one entry per pixel
    void compute_density();          // 3. density from the per-pixel screen-space bandwidth
    void adaptive_points();          // 4. rejection sampling and the adaptive points
    void reconstruct_image();        // 5. cross-bilateral reconstruction, fallbacks shaded
    void cache_insert();             // 6. batch discard, then every new point becomes an entry
    void write_layers();
    SparsePassOutput finish();

    // A fresh radiance point at pixel i (pass 0 initial, 1 adaptive, 2 fallback): recalled
    // from `table` when an earlier run shaded it with the same plan, else shaded (then, with a
    // memo, *added describes it for the memo). Returns true when recalled.
    bool shade(size_t i, uint64_t pass, const ShadingMemo::FrameTable* table,
               ShadingMemo::Entry* added);
    void shade_all(const std::vector<int>& pixels, uint64_t pass);
    RadiancePoint& point_at(size_t i) { return shaded_points[size_t(point_slot[i])]; }
    // Adaptive and fallback points keep the upsampled statistics as their features; only
    // where none reached do they use their own.
    void own_features_where_unknown(const std::vector<int>& pixels);

    const RayScene& rs;
    const GBuffer& gb;
    const int frame;
    const FrameSettings& fs;
    const SparseSettings& sparse;
    LayerSet& layers;
    Progress& progress;
    const CacheHook* cache;
    ReconstructionRecord* record;
    const int w, h;
    const size_t n;
    const Scene& scene;
    const RadiancePointIntegrator integrator;
    const CameraRayGenerator camera;
    const double pixel_angle;
    SparsePassOutput result;

    // Features of every pixel.
    std::vector<PixelFeature> features;
    std::vector<ShadingPoint> shading_points;
    std::vector<char> mirror;
    // Per pixel: the fresh radiance point, or the reused cache record, and the value the
    // reconstruction reads (demodulated by the texture; mirrors: the radiance itself).
    // Radiance points are kept only where shaded: a frame-sized array of them (~170 MB at
    // 1280x720) took half a second to build and free.
    std::vector<int> point_slot;
    std::vector<RadiancePoint> shaded_points;
    std::vector<char> fresh, sampled;
    std::vector<vec3> value;
    std::vector<SampleKind> kind;
    std::atomic<long> rays{0};
    ShadingMemo* memo = nullptr;  // SparseHooks::memo
    std::atomic<long> recalled{0}, recalled_rays{0};
    std::atomic<long> nonfinite{0};  // colours that were NaN / Inf (written as 0)
    // The upsampled visibility statistics (step 2); adaptive points plan their sample count
    // from them.
    std::vector<VisibilityStats> stats;
    std::vector<char> found;

    // The cache's view of the frame.
    CacheFrameView view;
    std::vector<SurfaceHit> reflected;
    std::vector<float> footprint;
    std::vector<int> standin;  // initial pixels a kept entry stands in for
    bool moves = false;
    std::vector<KeyLight> keys;  // whose visibility entries record (render/key_lights.h)

    std::vector<int> initial, initial_shaded;
    std::vector<VisibilityStats> values;  // the initial points' statistics
    std::vector<char> own;  // the pixel's statistics are its own point's (or stand-in's)
    std::vector<int> initial_slot;
    std::vector<float> mu_v, sigma_v;

    std::vector<int> keeper, reused;
    // The reused entries' own radiance-point values, read when they are resolved (the insert
    // stage may move slots): the per-point layers show them on reused pixels.
    std::vector<std::array<float, 10>> reused_fields;  // radiance_point_layer_names() order
    std::vector<int> reused_field_slot;                // per pixel, -1: not reused
    // The upsampled occlusion ratio and log shading at every pixel: what the observed-change
    // tests compare between an entry's creation and now.
    std::vector<float> age, field, shading_field;

    std::vector<float> density, radius;
    std::vector<int> adaptive;
    ReconstructionOutput rec;
};

}  // namespace freqlab
