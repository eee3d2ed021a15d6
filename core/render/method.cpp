#include "render/method.h"

#include <chrono>

#include "base/error.h"
#include "base/stopwatch.h"
#include "render/frame_renderer.h"
#include "render/pixel_trace.h"
#include "render/points_pass.h"
#include "render/shading_pass.h"
#include "render/sparse_pass.h"

namespace freqlab {

namespace {

const std::vector<LayerDeclaration> kEstimateLayers = {{"variance", LayerKind::Continuous},
                                                       {"rays", LayerKind::Continuous}};

std::vector<LayerDeclaration> radiance_point_layers() {
    std::vector<LayerDeclaration> out;
    for (const std::string& name : radiance_point_layer_names())
        out.push_back({name, LayerKind::Continuous});
    return out;
}

std::vector<LayerDeclaration> sparse_layers() {
    std::vector<LayerDeclaration> out = {
        {"density", LayerKind::Continuous},      {"sampled", LayerKind::Categorical},
        {"recon_weight", LayerKind::Continuous}, {"recon_radius", LayerKind::Continuous},
        {"samples", LayerKind::Color},           {"mu_v", LayerKind::Continuous},
        {"sigma_v", LayerKind::Continuous},      {"rays", LayerKind::Continuous}};
    const std::vector<LayerDeclaration> points = radiance_point_layers();
    out.insert(out.end(), points.begin(), points.end());
    return out;
}

const char* kAdaptiveSpp =
    "chooses its sample counts per radiance point (N_Omega); set gbuffer.aa_samples or "
    "points.* with --set";

MethodOutput shade(MethodContext& c, int spp, SampleSequence sequence) {
    const auto t0 = Clock::now();
    const ShadingPassOutput out =
        shade_pixels(c.rays, c.gbuffer, c.frame, c.config.frame, spp, c.config.shading, sequence,
                     c.result.layers, c.progress);
    MethodOutput m;
    m.rays = out.rays;
    m.nonfinite = out.nonfinite;
    m.stats["stages"]["shading"] = ms_since(t0);
    return m;
}

MethodOutput render_points_method(MethodContext& c) {
    const auto t0 = Clock::now();
    const PointsPassOutput out =
        render_points(c.rays, c.gbuffer, c.frame, c.config.frame, c.config.shading, c.config.points,
                      c.bandwidth, c.result.layers, c.progress);
    MethodOutput m;
    m.rays = out.rays;
    m.nonfinite = out.nonfinite;
    m.stats["stages"]["radiance_points"] = ms_since(t0);
    m.stats["pixels_shaded"] = out.pixels_shaded;
    return m;
}

MethodOutput sparse_output(SparsePassOutput&& out) {
    MethodOutput m;
    m.rays = out.rays;
    m.nonfinite = out.nonfinite;
    m.stats = std::move(out.stats);
    return m;
}

MethodOutput render_sparse_method(MethodContext& c) {
    return sparse_output(render_sparse(c.rays, c.gbuffer, c.frame, c.config.frame, c.config.shading,
                                       c.config.points, c.config.sparse, c.bandwidth,
                                       c.result.layers, c.progress,
                                       {nullptr, c.reconstruction_record, c.preview, c.memo}));
}

struct CacheMethodState : MethodState {
    CacheState cache;
    void encode(ByteWriter& w) const override {
        w.put<int32_t>(cache.last_frame);
        cache.cache.encode(w);
    }
    void decode(ByteReader& r, const std::string& source) override {
        cache.last_frame = r.get<int32_t>();
        cache.cache.decode(r, source);
    }
};

MethodOutput render_cache_method(MethodContext& c) {
    CacheState& state = static_cast<CacheMethodState*>(c.state)->cache;
    const size_t objects = c.rays.scene().objects.size();
    bool reset = false;
    if (c.config.cache.cold_start || c.frame != state.last_frame + 1) {
        // Out of order (a scrub, a re-render): the cache starts afresh at this frame.
        state.cache.reset(objects);
        reset = state.last_frame >= 0;
    }
    if (state.cache.object_count() != objects) state.cache.reset(objects);
    const bool started_empty = state.cache.live_count() == 0;
    if (c.keep_details)
        c.result.cache_snapshot = std::make_shared<const RadianceCache>(state.cache);
    const CacheHook hook{state, c.config.cache};
    SparsePassOutput out =
        render_sparse(c.rays, c.gbuffer, c.frame, c.config.frame, c.config.shading, c.config.points,
                      c.config.sparse, c.bandwidth, c.result.layers, c.progress,
                      {&hook, c.reconstruction_record, c.preview, c.memo});
    state.last_frame = c.frame;
    c.result.sample_positions =
        std::make_shared<const std::vector<std::pair<int, vec3>>>(std::move(out.moved_samples));
    c.result.cache_records =
        std::make_shared<const std::vector<CacheRecord>>(std::move(out.cache_records));
    MethodOutput m = sparse_output(std::move(out));
    m.stats["cache_reset"] = reset;
    // How the frame started, for the inspector: warm (the frame before's cache) or cold, and why.
    m.stats["cache_start"] = c.config.cache.cold_start ? "cold (cache.cold_start)"
                             : reset                   ? "cold (not after the frame before)"
                             : started_empty           ? "cold (empty cache)"
                                                       : "warm";
    return m;
}

std::vector<RenderMethodInfo> built_in_methods() {
    const std::vector<std::string> base = {"frame", "gbuffer"};
    auto groups = [&](std::initializer_list<const char*> more) {
        std::vector<std::string> g = base;
        g.insert(g.end(), more.begin(), more.end());
        return g;
    };
    std::vector<RenderMethodInfo> m(6);
    m[0].name = "gbuffer";
    m[0].summary = "primary rays only: the antialiased, unlit G-buffer";
    m[0].setting_groups = groups({});
    m[0].spp_setting = "gbuffer.aa_samples";
    m[0].antialiased_gbuffer = true;

    m[1].name = "mis";
    m[1].summary = "direct lighting, MIS of environment and BRDF samples, every pixel";
    m[1].setting_groups = groups({"shading", "mis"});
    m[1].spp_setting = "mis.spp";
    m[1].layers = kEstimateLayers;
    m[1].spp = [](const RenderConfig& c) { return c.mis.spp; };
    m[1].sequence = [](const RenderConfig& c) { return sample_sequence(c.mis.stratified); };
    m[1].render = [](MethodContext& c) {
        return shade(c, c.config.mis.spp, sample_sequence(c.config.mis.stratified));
    };
    m[1].trace = trace_direct_lighting;

    m[2] = m[1];
    m[2].name = "reference";
    m[2].summary = "the ground truth: mis at many samples, cached on disk";
    m[2].setting_groups = groups({"shading", "reference"});
    m[2].spp_setting = "reference.spp";
    m[2].antialiased_gbuffer = true;  // its cached files carry the AA albedo
    m[2].spp = [](const RenderConfig& c) { return c.reference.spp; };
    m[2].sequence = [](const RenderConfig& c) { return sample_sequence(c.reference.stratified); };
    m[2].render = [](MethodContext& c) {
        return shade(c, c.config.reference.spp, sample_sequence(c.config.reference.stratified));
    };

    m[3].name = "points";
    m[3].summary = "method A's radiance points (adaptive N_Omega) at every points.stride pixel";
    m[3].setting_groups = groups({"shading", "points"});
    m[3].spp_refusal = kAdaptiveSpp;
    m[3].env_bandwidth = true;
    m[3].layers = kEstimateLayers;
    const std::vector<LayerDeclaration> points = radiance_point_layers();
    m[3].layers.insert(m[3].layers.end(), points.begin(), points.end());
    m[3].spp = [](const RenderConfig& c) { return c.points.max_samples; };
    m[3].sequence = [](const RenderConfig& c) { return sample_sequence(c.points.stratified); };
    m[3].render = render_points_method;
    m[3].trace = trace_radiance_point;

    m[4] = m[3];
    m[4].name = "sparse";
    m[4].summary = "method A: frequency-chosen pixels, cross-bilateral reconstruction";
    m[4].setting_groups = groups({"shading", "points", "sparse"});
    m[4].layers = sparse_layers();
    m[4].render = render_sparse_method;
    m[4].trace = trace_reconstruction;

    m[5] = m[4];
    m[5].name = "cache";
    m[5].summary = "method A with its object-space radiance cache across frames";
    m[5].setting_groups = groups({"shading", "points", "sparse", "cache"});
    m[5].stateful = true;
    m[5].layers.insert(m[5].layers.begin(), {{"decision", LayerKind::Categorical},
                                             {"age", LayerKind::Continuous},
                                             {"cache_decisions", LayerKind::Categorical}});
    m[5].make_state = [] { return std::make_unique<CacheMethodState>(); };
    m[5].render = render_cache_method;
    m[5].trace = trace_cache;
    return m;
}

std::vector<RenderMethodInfo>& registry() {
    static std::vector<RenderMethodInfo> methods = built_in_methods();
    return methods;
}

}  // namespace

RenderMethod register_render_method(RenderMethodInfo info) {
    if (info.name.empty()) throw Error("", "method", "a method needs a name");
    for (const RenderMethodInfo& m : registry())
        if (m.name == info.name)
            throw Error("", "method", "a method named '" + info.name + "' is registered already");
    registry().push_back(std::move(info));
    return RenderMethod(registry().size() - 1);
}

const RenderMethodInfo& render_method_info(RenderMethod method) {
    const size_t i = size_t(method);
    if (i >= registry().size()) throw Error("", "method", "no method has id " + std::to_string(i));
    return registry()[i];
}

std::vector<std::string> render_method_names() {
    std::vector<std::string> names;
    for (const RenderMethodInfo& m : registry()) names.push_back(m.name);
    return names;
}

std::string render_method_list(const std::string& separator) {
    std::string list;
    for (const RenderMethodInfo& m : registry()) list += (list.empty() ? "" : separator) + m.name;
    return list;
}

RenderMethod parse_render_method(const std::string& name) {
    for (size_t i = 0; i < registry().size(); ++i)
        if (registry()[i].name == name) return RenderMethod(i);
    throw Error("--method", name, "unknown method; expected one of: " + render_method_list(", "));
}

}  // namespace freqlab
