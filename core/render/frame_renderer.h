// One frame of a render, whichever method: place the scene at the frame's time, run the
// method's stages, and return the layers with per-frame stats (DESIGN.md "Stats").
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "accel/ray_scene.h"
#include "base/job.h"
#include "freq/env_bandwidth.h"
#include "image/layers.h"
#include "render/cache_pass.h"
#include "render/method.h"
#include "render/radiance_point.h"
#include "render/reconstruction.h"
#include "render/reference_cache.h"
#include "render/shading_memo.h"
#include "settings/cache_settings.h"
#include "settings/render_settings.h"
#include "settings/settings_group.h"
#include "settings/shading_settings.h"
#include "settings/sparse_settings.h"

namespace freqlab {

// The built-in methods (render/method.h registers them, in this order); a registered method
// has an id past Cache.
enum class RenderMethod { GBuffer, Mis, Reference, Points, Sparse, Cache };

struct RenderConfig {
    RenderMethod method = RenderMethod::GBuffer;
    FrameSettings frame;
    GBufferSettings gbuffer;
    ShadingSettings shading;
    MisSettings mis;
    ReferenceSettings reference;
    PointsSettings points;
    SparseSettings sparse;
    CacheSettings cache;
    int spp() const;  // the sample count of the chosen method (0 for gbuffer)
    // The samples of the chosen method's estimates (mis / reference / radiance points).
    SampleSequence sequence() const;
    // Methods with state across frames (method A's cache) must render frames in order.
    // (Not method cache with cache.cold_start: each of its frames starts from an empty cache.)
    bool needs_previous_frames() const {
        return render_method_info(method).stateful &&
               !(method == RenderMethod::Cache && cache.cold_start);
    }
    // All settings of this render under their "prefix.key" names (for --set, JSON, stats).
    SettingsGroup settings_group();
};

struct FrameResult {
    int frame = 0;
    // Not a frame of the animation but the environment's bandwidth hierarchy (the workbench's
    // environment view); `frame` is then -1.
    bool environment_view = false;
    float time_s = 0.0f;
    LayerSet layers;
    nlohmann::json stats;  // frame, time_s, time_ms, stages, rays, pixels_*, nonfinite
    // Method cache: every entry's decision this frame (the inspector explains them).
    std::shared_ptr<const std::vector<CacheRecord>> cache_records;
    std::shared_ptr<const RadianceCache> cache_snapshot;  // entries before this frame's changes
    // Method cache: the reused samples' positions (SparsePassOutput::moved_samples).
    std::shared_ptr<const std::vector<std::pair<int, vec3>>> sample_positions;
    // A first image of the frame, shown while the frame renders (never recorded).
    bool preview = false;
    // Read back with only some of its layers (render/frame_store.h: what a timeline jump shows
    // first): the layers left out, by name; no cache records or sample positions either.
    bool partial = false;
    std::vector<std::string> unread_layers;
};

class FrameRenderer {
  public:
    FrameRenderer(const Scene& scene, const RenderConfig& config, const EmbreeDevice& device);
    FrameResult render(int frame, Progress& progress);
    const RayScene& ray_scene() const { return ray_scene_; }
    // What the method keeps across frames (method A's cache, and the frame it last rendered) as
    // bytes, and back: rendering on from a restored state gives the bytes the renderer that
    // saved it would have (render/frame_checkpoint.h). Stateless methods: empty / refused.
    bool has_state() const { return method_state_ != nullptr; }
    std::string save_state() const;
    void restore_state(const std::string& bytes, const std::string& source);
    // Method cache: also return a copy of the cache as it was before each frame (for the
    // inspector; costs a copy of the cache per frame).
    void keep_cache_details(bool on) { keep_cache_details_ = on; }
    // Methods sparse and cache hand a first image of each frame to `sink` while it renders
    // (render/sparse_pass.h); called on the rendering thread. Empty: none.
    void set_preview_sink(std::function<void(LayerSet&&)> sink) { preview_ = std::move(sink); }
    // Methods sparse and cache recall radiance points from `memo` where an earlier run shaded
    // the same ones, and add theirs (render/shading_memo.h). The owner keys the memo
    // (ShadingMemo::key_of); null: every point is shaded.
    void set_shading_memo(std::shared_ptr<ShadingMemo> memo) { memo_ = std::move(memo); }
    // Methods that reconstruct record pixel (record->x, record->y)'s contributions into
    // *record during the next renders (null: none).
    void record_reconstruction(ReconstructionRecord* record) { record_ = record; }
    // The contributions the pixel trace prints for pixel (x, y) of `result` (sparse, cache).
    ReconstructionRecord reconstruction_weights(const FrameResult& result, int x, int y);
    // The estimate of pixel (x, y) of `result` re-run with every sample traced, as text lines
    // (render/pixel_trace.cpp). Not while render() runs on another thread.
    // For method points, `point` (when given) receives the pixel's radiance point.
    std::vector<std::string> trace_pixel(const FrameResult& result, int x, int y,
                                         size_t max_samples = 48, RadiancePoint* point = nullptr);

  private:
    const Scene& scene_;
    RenderConfig config_;
    RayScene ray_scene_;
    ReferenceCache cache_;
    std::unique_ptr<EnvBandwidthHierarchy> bandwidth_;  // method A: built on first use
    std::unique_ptr<MethodState> method_state_;         // the method's across frames
    bool keep_cache_details_ = false;
    std::function<void(LayerSet&&)> preview_;
    std::shared_ptr<ShadingMemo> memo_;
    ReconstructionRecord* record_ = nullptr;
    const EnvBandwidthHierarchy* bandwidth();
};

// Counts NaN/Inf values over all layers (they are reported, never silently kept).
long count_nonfinite(const LayerSet& layers);

}  // namespace freqlab
