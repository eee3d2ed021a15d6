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
    const RenderMethodInfo& info = render_method_info(method);
    return info.sequence ? info.sequence(*this) : SampleSequence::Independent;
}

int RenderConfig::spp() const {
    const RenderMethodInfo& info = render_method_info(method);
    return info.spp ? info.spp(*this) : 0;
}

long count_nonfinite(const LayerSet& layers) {
    long n = 0;
    for (const Layer& l : layers.layers())
        for (float v : l.data) n += !std::isfinite(v);
    return n;
}

namespace {

// A method's output layers are its declaration's (method.h): a missing one or one of another
// kind is a bug of the method, said with its name.
void check_declared_layers(const RenderMethodInfo& method, const LayerSet& layers) {
    for (const LayerDeclaration& d : method.layers) {
        const Layer* l = layers.find(d.name);
        if (!l || l->kind != d.kind)
            throw Error("", "method " + method.name,
                        "declares layer '" + d.name + "' (" + to_string(d.kind) + ") but " +
                            (l ? std::string("wrote it as ") + to_string(l->kind)
                               : "did not write it; it wrote " + layers.names()));
    }
}

}  // namespace

FrameRenderer::FrameRenderer(const Scene& scene, const RenderConfig& config,
                             const EmbreeDevice& device)
    : scene_(scene), config_(config), ray_scene_(scene, device) {
    const RenderMethodInfo& info = render_method_info(config.method);
    if (info.make_state) method_state_ = info.make_state();
}

const EnvBandwidthHierarchy* FrameRenderer::bandwidth() {
    const EnvironmentMap* env = scene_.environment();
    if (!env) return nullptr;  // no environment: B_L = 0, nothing to build
    if (!bandwidth_)
        bandwidth_ = std::make_unique<EnvBandwidthHierarchy>(EnvBandwidthHierarchy::cached(*env));
    return bandwidth_.get();
}

std::string FrameRenderer::save_state() const {
    if (!method_state_) return {};
    ByteWriter w;
    method_state_->encode(w);
    return std::move(w.bytes());
}

void FrameRenderer::restore_state(const std::string& bytes, const std::string& source) {
    if (!method_state_)
        throw Error(source, "method",
                    "method " + render_method_info(config_.method).name +
                        " keeps nothing across frames: there is no state to restore");
    ByteReader r(bytes, source, "state");
    method_state_->decode(r, source);
    if (r.remaining() != 0)
        throw Error(source, "state", std::to_string(r.remaining()) + " bytes left over");
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
        for (const std::string& group : render_method_info(config_.method).setting_groups)
            settings[group] = all.at(group);
        settings["reference"].erase("use_cache");
        settings["reference"].erase("cache_megabytes");
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
    const RenderMethodInfo& method = render_method_info(config_.method);
    GBufferOutput gb = render_gbuffer(ray_scene_, frame, config_.frame, config_.gbuffer, progress,
                                      method.antialiased_gbuffer);
    stages["gbuffer"] = ms_since(t0);
    result.layers = std::move(gb.layers);
    long rays = gb.rays, guarded = 0;
    nlohmann::json method_stats;
    // Method A's environment bandwidth hierarchy: built (or loaded) once, timed when used.
    const EnvBandwidthHierarchy* bw = nullptr;
    if (method.env_bandwidth) {
        t0 = Clock::now();
        bw = bandwidth();
        stages["env_bandwidth"] = ms_since(t0);
    }
    if (method.render) {
        MethodContext context{ray_scene_,
                              gb.gbuffer,
                              frame,
                              config_,
                              bw,
                              method_state_.get(),
                              keep_cache_details_,
                              record_,
                              result,
                              progress,
                              preview_ ? &preview_ : nullptr,
                              memo_.get()};
        MethodOutput out = method.render(context);
        rays += out.rays;
        guarded = out.nonfinite;
        if (out.stats.contains("stages")) {
            for (const auto& [key, value] : out.stats["stages"].items()) stages[key] = value;
            out.stats.erase("stages");
        }
        method_stats = std::move(out.stats);
    }
    check_declared_layers(method, result.layers);

    const long nonfinite = count_nonfinite(result.layers) + guarded;
    long cache_removed = 0;
    if (!cache_key.empty())
        cache_removed =
            cache_.store(cache_key, result.layers,
                         {{"scene", scene_.source}, {"frame", frame}, {"method", "reference"}},
                         double(config_.reference.cache_megabytes) * 1e6);
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
    if (!cache_key.empty()) result.stats["reference_cache_removed"] = cache_removed;
    for (const auto& [key, value] : method_stats.items()) result.stats[key] = value;
    return result;
}

}  // namespace freqlab
