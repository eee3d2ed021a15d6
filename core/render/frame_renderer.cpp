#include "render/frame_renderer.h"

#include <chrono>
#include <cmath>

#include "base/error.h"
#include "base/stopwatch.h"
#include "render/gbuffer.h"
#include "render/points_pass.h"
#include "render/shading_pass.h"
#include "render/sparse_pass.h"

namespace freqlab {

const std::vector<std::string>& render_method_names() {
    static const std::vector<std::string> names = {"gbuffer", "mis",    "reference",
                                                   "points",  "sparse", "cache"};
    return names;
}

RenderMethod parse_render_method(const std::string& name) {
    const auto& names = render_method_names();
    for (size_t i = 0; i < names.size(); ++i)
        if (name == names[i]) return RenderMethod(i);
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw Error("--method", name, "unknown method; expected one of: " + list);
}

SettingsGroup RenderConfig::settings_group() {
    SettingsGroup g;
    g.bind(FrameSettings::schema(), &frame);
    g.bind(GBufferSettings::schema(), &gbuffer);
    g.bind(ShadingSettings::schema(), &shading);
    g.bind(MisSettings::schema(), &mis);
    g.bind(ReferenceSettings::schema(), &reference);
    g.bind(PointsSettings::schema(), &points);
    g.bind(SparseSettings::schema(), &sparse);
    g.bind(CacheSettings::schema(), &cache);
    return g;
}

SampleSequence RenderConfig::sequence() const {
    if (method == RenderMethod::Mis) return sample_sequence(mis.stratified);
    if (method == RenderMethod::Reference) return sample_sequence(reference.stratified);
    return sample_sequence(points.stratified);
}

int RenderConfig::spp() const {
    switch (method) {
        case RenderMethod::Mis:
            return mis.spp;
        case RenderMethod::Reference:
            return reference.spp;
        case RenderMethod::Points:
        case RenderMethod::Sparse:
        case RenderMethod::Cache:
            return points.max_samples;
        default:
            return 0;
    }
}

long count_nonfinite(const LayerSet& layers) {
    long n = 0;
    for (const Layer& l : layers.layers())
        for (float v : l.data) n += !std::isfinite(v);
    return n;
}

FrameRenderer::FrameRenderer(const Scene& scene, const RenderConfig& config,
                             const EmbreeDevice& device)
    : scene_(scene), config_(config), ray_scene_(scene, device) {}

const EnvBandwidthHierarchy* FrameRenderer::bandwidth() {
    const EnvironmentMap* env = scene_.environment();
    if (!env) return nullptr;  // no environment: B_L = 0, nothing to build
    if (!bandwidth_)
        bandwidth_ = std::make_unique<EnvBandwidthHierarchy>(EnvBandwidthHierarchy::cached(*env));
    return bandwidth_.get();
}

FrameResult FrameRenderer::render(int frame, Progress& progress) {
    const auto t_start = Clock::now();
    FrameResult result;
    result.frame = frame;
    result.time_s = scene_.time_of_frame(frame);
    nlohmann::json stages = nlohmann::json::object();

    std::string cache_key;
    if (config_.method == RenderMethod::Reference && config_.reference.use_cache) {
        RenderConfig copy = config_;
        // Only what the reference depends on: other methods' settings must not re-render it.
        const nlohmann::json all = copy.settings_group().to_json();
        nlohmann::json settings;
        for (const char* group : {"frame", "gbuffer", "shading", "reference"})
            settings[group] = all.at(group);
        settings["reference"].erase("use_cache");
        // Absent when off, so that references cached before the setting existed still match.
        if (!settings["reference"].value("stratified", false))
            settings["reference"].erase("stratified");
        settings["frame"].erase("exposure");  // display only
        cache_key = cache_.key(scene_.content_hash, settings, frame);
        if (std::optional<LayerSet> cached = cache_.load(cache_key)) {
            result.layers = std::move(*cached);
            result.stats = {{"frame", frame},
                            {"time_s", result.time_s},
                            {"time_ms", ms_since(t_start)},
                            {"stages", {{"reference_cache_load", ms_since(t_start)}}},
                            {"rays", 0},
                            {"spp", config_.spp()},
                            {"pixels_total", long(result.layers.pixel_count())},
                            {"pixels_shaded", 0},
                            {"nonfinite", count_nonfinite(result.layers)},
                            {"reference_cache", cache_key}};
            return result;
        }
    }

    auto t0 = Clock::now();
    ray_scene_.update(result.time_s);
    stages["accel_update"] = ms_since(t0);

    t0 = Clock::now();
    // Only `gbuffer` shows the AA preview; the shading methods shade the centre hits and replace
    // its colour, so their albedo layer is the centre's (the one their textures multiply) and
    // the AA rays are not cast. The reference keeps them (its cached files carry that layer).
    const bool antialiased =
        config_.method == RenderMethod::GBuffer || config_.method == RenderMethod::Reference;
    GBufferOutput gb =
        render_gbuffer(ray_scene_, frame, config_.frame, config_.gbuffer, progress, antialiased);
    stages["gbuffer"] = ms_since(t0);
    result.layers = std::move(gb.layers);
    long rays = gb.rays, guarded = 0;
    nlohmann::json sparse_stats;
    // Method A's environment bandwidth hierarchy: built (or loaded) once, timed when used.
    const EnvBandwidthHierarchy* bw = nullptr;
    if (config_.method == RenderMethod::Points || config_.method == RenderMethod::Sparse ||
        config_.method == RenderMethod::Cache) {
        t0 = Clock::now();
        bw = bandwidth();
        stages["env_bandwidth"] = ms_since(t0);
    }

    if (config_.method == RenderMethod::Mis || config_.method == RenderMethod::Reference) {
        t0 = Clock::now();
        const ShadingPassOutput out =
            shade_pixels(ray_scene_, gb.gbuffer, frame, config_.frame, config_.spp(),
                         config_.shading, config_.sequence(), result.layers, progress);
        stages["shading"] = ms_since(t0);
        rays += out.rays;
        guarded = out.nonfinite;
    } else if (config_.method == RenderMethod::Points) {
        t0 = Clock::now();
        const PointsPassOutput out =
            render_points(ray_scene_, gb.gbuffer, frame, config_.frame, config_.shading,
                          config_.points, bw, result.layers, progress);
        stages["radiance_points"] = ms_since(t0);
        rays += out.rays;
        guarded = out.nonfinite;
        sparse_stats["pixels_shaded"] = out.pixels_shaded;
    } else if (config_.method == RenderMethod::Sparse || config_.method == RenderMethod::Cache) {
        const bool use_cache = config_.method == RenderMethod::Cache;
        bool reset = false;
        if (use_cache && frame != cache_state_.last_frame + 1) {
            // Out of order (a scrub, a re-render): the cache starts afresh at this frame.
            cache_state_.cache.reset(scene_.objects.size());
            reset = cache_state_.last_frame >= 0;
        }
        if (use_cache && cache_state_.cache.object_count() != scene_.objects.size())
            cache_state_.cache.reset(scene_.objects.size());
        if (use_cache && keep_cache_details_)
            result.cache_snapshot = std::make_shared<const RadianceCache>(cache_state_.cache);
        const CacheHook hook{cache_state_, config_.cache};
        SparsePassOutput out = render_sparse(ray_scene_, gb.gbuffer, frame, config_.frame,
                                             config_.shading, config_.points, config_.sparse, bw,
                                             result.layers, progress, use_cache ? &hook : nullptr);
        if (use_cache) {
            cache_state_.last_frame = frame;
            out.stats["cache_reset"] = reset;
            result.cache_records =
                std::make_shared<const std::vector<CacheRecord>>(std::move(out.cache_records));
        }
        for (const auto& [key, value] : out.stats["stages"].items()) stages[key] = value;
        out.stats.erase("stages");
        sparse_stats = std::move(out.stats);
        rays += out.rays;
        guarded = out.nonfinite;
    }

    const long nonfinite = count_nonfinite(result.layers) + guarded;
    if (!cache_key.empty())
        cache_.store(cache_key, result.layers,
                     {{"scene", scene_.source}, {"frame", frame}, {"method", "reference"}});
    result.stats = {
        {"frame", frame},
        {"time_s", result.time_s},
        {"time_ms", ms_since(t_start)},
        {"stages", stages},
        {"rays", rays},
        {"spp", config_.spp()},
        {"pixels_total", long(result.layers.pixel_count())},
        {"pixels_shaded", long(result.layers.pixel_count())},
        {"nonfinite", nonfinite},
    };
    for (const auto& [key, value] : sparse_stats.items()) result.stats[key] = value;
    return result;
}

}  // namespace freqlab
