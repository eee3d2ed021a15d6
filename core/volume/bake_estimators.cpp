#include "volume/bake_estimators.h"

#include <limits>

#include "base/error.h"
#include "math/sampling.h"
#include "math/sh.h"

namespace freqlab {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr float kBelowHorizonKeep = 0.25f;

// sin and cos of the area lobes' tilts (a few degrees, area_tables.h) by their Taylor series
// to the x^9 / x^8 terms: below 1e-7 up to 0.6 rad; sincosf beyond.
float small_angle_sin(float x) {
    if (std::abs(x) > 0.6f) return std::sin(x);
    const float x2 = x * x;
    return x * (1.0f + x2 * (-1.0f / 6 + x2 * (1.0f / 120 + x2 * (-1.0f / 5040 + x2 / 362880))));
}
float small_angle_cos(float x) {
    if (std::abs(x) > 0.6f) return std::cos(x);
    const float x2 = x * x;
    return 1.0f + x2 * (-0.5f + x2 * (1.0f / 24 + x2 * (-1.0f / 720 + x2 / 40320)));
}

bool finite(const vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

const char* to_string(BakeMethod m) {
    switch (m) {
        case BakeMethod::Surface:
            return "surface";
        case BakeMethod::Extinction:
            return "extinction";
        case BakeMethod::Impulse:
            return "impulse";
        case BakeMethod::Vpt:
            return "vpt";
    }
    return "?";
}

const std::vector<BakeMethod>& bake_methods() {
    static const std::vector<BakeMethod> all = {BakeMethod::Surface, BakeMethod::Extinction,
                                                BakeMethod::Impulse, BakeMethod::Vpt};
    return all;
}

std::string bake_method_list(const std::string& separator) {
    std::string list;
    for (BakeMethod m : bake_methods()) list += (list.empty() ? "" : separator) + to_string(m);
    return list;
}

bool is_bake_method(const std::string& name) {
    for (BakeMethod m : bake_methods())
        if (name == to_string(m)) return true;
    return false;
}

BakeMethod parse_bake_method(const std::string& text) {
    for (BakeMethod m : bake_methods())
        if (text == to_string(m)) return m;
    throw Error("--method", text, "expected one of: " + bake_method_list(", "));
}

BakeEstimator::BakeEstimator(const RayScene& scene, const Media& media, const ImpulseTables* tables,
                             BakeMethod method, const BakeSettings& settings)
    : scene_(scene), media_(media), tables_(tables), method_(method), settings_(settings) {
    if (method == BakeMethod::Impulse && !media.empty() && !tables)
        throw Error("", "--method", "impulse needs the impulse-response tables");
    if (tables) {
        table_bounces_ = tables->bounces();
        if (settings.tabulated_irradiance)
            irradiance_ = std::make_unique<ImpulseIrradianceCache>(*tables);
    }
    attenuates_ = method != BakeMethod::Surface && !media.empty();
    scatters_ = method == BakeMethod::Impulse && !media.empty();
    zh_clamped_cosine(kImpulseOrder, cosine_zh_);
}

vec3 BakeEstimator::origin(const vec3& p, const vec3& n) const {
    return spawn_point(p, n);
}

bool BakeEstimator::visible(const vec3& from, const vec3& n, const vec3& dir, double distance,
                            BakeCounters& counters) const {
    ++counters.rays;
    return !scene_.occluded(shadow_ray(origin(from, n), dir, distance));
}

void BakeEstimator::sample_emitters(const vec3& p, CounterRng& rng,
                                    std::vector<EmitterSample>& out) const {
    out.clear();
    const std::vector<Light>& lights = scene_.scene().lights;
    for (size_t index = 0; index < lights.size(); ++index) {
        const Light& light = lights[index];
        EmitterSample s;
        s.light = int(index);
        switch (light.type) {
            case LightType::Point:
            case LightType::Directional:
            case LightType::Quad: {
                vec2 u(0.0f);
                if (light_sample_dimensions(light) == 2) {
                    u.x = rng.next_float();
                    u.y = rng.next_float();
                }
                const LightSample ls = sample_light(light, p, u);
                if (!ls.valid) continue;
                s.kind = light.type == LightType::Point         ? EmitterKind::Point
                         : light.type == LightType::Directional ? EmitterKind::Directional
                                                                : EmitterKind::Area;
                s.dir = ls.direction;
                s.distance = ls.distance;
                s.irradiance = ls.irradiance;
                s.intensity = ls.intensity;
                s.fixed = light.type != LightType::Quad;
                if (light.type == LightType::Quad) {
                    s.emitter_normal = ls.emitter_normal;
                    s.shift = std::sqrt(std::max(0.0f, 1.0f - ls.emitter_cos * ls.emitter_cos));
                }
                break;
            }
            case LightType::Environment:
            case LightType::Sky: {
                const EnvironmentMap* env = scene_.environment();
                if (!env) continue;
                const vec4 u(rng.next_float(), rng.next_float(), rng.next_float(),
                             rng.next_float());
                float pdf = 0.0f;
                const vec3 radiance = env->sample(u, &s.dir, &pdf);
                if (!(pdf > 0.0f)) continue;
                s.kind = EmitterKind::Directional;
                s.irradiance = s.intensity = radiance / pdf;
                break;
            }
        }
        out.push_back(s);
    }
}

void BakeEstimator::add_scattered(EmitterKind kind, const vec3& intensity, const vec3& dir,
                                  double distance, double shift, const vec3& emitter_normal,
                                  const SegmentOptics& optics, const vec3& n, float albedo_lum,
                                  IrradianceParts& out, BakeCounters& counters) const {
    // The segment's effective medium (§4.4) without a chain of divisions: the lookup is
    // latency-bound (perf), so each quantity is one operation away from the optics.
    if (!(optics.tau_s > 0.0) || !(optics.length > 0.0) || !std::isfinite(distance) ||
        !(distance > 0.0))
        return;
    const double inv_length = 1.0 / optics.length;
    const double sigma_t = (optics.tau_s + optics.tau_a) * inv_length;
    const double albedo = optics.tau_s / (optics.tau_s + optics.tau_a);
    // Beyond the tables' last optical distance every path is attenuated by more than e^-40.
    const double optical_distance = sigma_t * distance;
    if (optical_distance > ZhDistanceTable::kMaxD) return;
    double w_surface = 0.0;
    switch (settings_.back_scatter) {
        case BackScatter::Off:
            w_surface = 0.0;
            break;
        case BackScatter::On:
            w_surface = 1.0;
            break;
        case BackScatter::Albedo:
            w_surface = std::clamp(double(albedo_lum), 0.0, 1.0);
            break;
    }
    // The surface variant is the infinite one at a receiver shifted kBackScatterShift optical
    // units towards the emitter (impulse_query.h); the albedo blend scales that shift, so one
    // lookup serves every mode and the two ends are exactly off and on.
    const double query_optical =
        std::max(optical_distance - w_surface * kBackScatterShift, ZhDistanceTable::kMinD);
    // The tables cover |g| <= kGRange; stronger anisotropy is clamped (stated in the header).
    const double g = std::clamp(optics.tau_gs / optics.tau_s, -kGRange, kGRange);
    const int last_bounce = std::min(settings_.media_bounces, table_bounces_);
    const double shift_q = std::clamp(shift, 0.0, 1.0);
    const float cos_light = glm::dot(dir, n);
    ++counters.impulse_queries;
    if (const ImpulseIrradiance* table = irradiance_table(g, albedo, last_bounce)) {
        // The tabulated double product (impulse_irradiance.h): one lookup per part.
        const ImpulseIrradiance::At D = ImpulseIrradiance::at(query_optical);
        const double scale = kind == EmitterKind::Directional ? 1.0 : sigma_t * sigma_t;
        ScatteredIrradiance e;
        if (kind == EmitterKind::Point) {
            e = table->point(D, cos_light);
        } else if (kind == EmitterKind::Directional) {
            e = table->directional(D, cos_light);
        } else {
            // The single lobe's axis is tilted from l towards the emitter normal's part
            // across l, t = (n_e - (n_e . l) l) / |...|, whose length is the shift itself.
            const float tilt = float(table->tilt(D, shift_q));
            float cos_single = cos_light;
            if (tilt != 0.0f && shift_q > 1e-6) {
                const float nl_l = glm::dot(emitter_normal, dir);
                const float t_n = (glm::dot(emitter_normal, n) - nl_l * cos_light) / float(shift_q);
                cos_single = small_angle_cos(tilt) * cos_light + small_angle_sin(tilt) * t_n;
            }
            e = table->area(D, shift_q, cos_single, cos_light);
        }
        out.single += intensity * float(std::max(0.0, e.single * scale));
        out.multiple += intensity * float(std::max(0.0, e.multiple * scale));
        return;
    }
    ImpulseQuery q;
    q.emitter = kind;
    q.distance = query_optical / sigma_t;
    q.shift = shift_q;
    q.medium = optics.effective();
    q.medium.g = g;
    q.last_bounce = last_bounce;
    q.collapsed = true;
    q.variant = TableVariant::Infinite;
    q.receiver = Receiver::OnSurface;
    const ImpulseResponse r = query_impulse(*tables_, q);
    const glm::dvec3 l(dir), nd(n);
    const glm::dvec3 axis =
        kind == EmitterKind::Area ? tilted_axis(l, emitter_normal, r.axis_tilt) : l;
    const double e_single = zh_double_product(kImpulseOrder, r.single.data(), axis, cosine_zh_, nd);
    const double e_multiple =
        zh_double_product(kImpulseOrder, r.multiple.data(), l, cosine_zh_, nd);
    // A truncated ZH lobe rings slightly negative far from its axis; irradiance cannot.
    out.single += intensity * float(std::max(0.0, e_single));
    out.multiple += intensity * float(std::max(0.0, e_multiple));
}

glm::dvec3 BakeEstimator::tilted_axis(const glm::dvec3& l, const vec3& emitter_normal,
                                      double tilt) {
    const glm::dvec3 nl(emitter_normal);
    const glm::dvec3 t = nl - glm::dot(nl, l) * l;
    const double len = glm::length(t);
    return len > 1e-9 && tilt != 0.0 ? std::cos(tilt) * l + std::sin(tilt) * (t / len) : l;
}

SegmentOptics BakeEstimator::segment_optics(const vec3& p, const vec3& dir, double length,
                                            CounterRng& rng) const {
    return settings_.tracking == Tracking::Ratio ? media_.track(p, dir, length, rng)
                                                 : media_.integrate(p, dir, length);
}

const ImpulseIrradiance* BakeEstimator::irradiance_table(double g, double albedo,
                                                         int last_bounce) const {
    if (!irradiance_) return nullptr;
    if (media_.size() != 1) return irradiance_->get(g, albedo, last_bounce);
    // One medium: every segment's effective g and albedo are its own (density scales both
    // coefficients alike), so the table is resolved once per version of the coefficients.
    const uint64_t version = media_.version();
    if (single_version_.load(std::memory_order_acquire) == version)
        return single_table_.load(std::memory_order_relaxed);
    const ImpulseIrradiance* table = irradiance_->get(g, albedo, last_bounce);
    single_table_.store(table, std::memory_order_relaxed);
    single_version_.store(version, std::memory_order_release);
    return table;
}

IrradianceParts BakeEstimator::estimate(const vec3& p, const vec3& n, const vec3& albedo,
                                        CounterRng& rng, BakeCounters& counters,
                                        FixedDirect* fixed) const {
    const bool reuse = fixed && settings_.tracking == Tracking::Exact;
    IrradianceParts parts =
        method_ == BakeMethod::Vpt
            ? volume_path(p, n, rng, counters)
            : surface_path(p, n, albedo, 0, rng, counters, reuse ? fixed : nullptr);
    if (!finite(parts.surface) || !finite(parts.single) || !finite(parts.multiple)) {
        ++counters.guarded;
        return {};
    }
    return parts;
}

bool BakeEstimator::direct_light(const EmitterSample& s, const vec3& p, const vec3& n,
                                 float albedo_lum, CounterRng& rng, BakeCounters& counters,
                                 IrradianceParts& parts, vec3* occluded_multiple) const {
    const float cos_x = glm::dot(n, s.dir);
    // Below the horizon the segment to the emitter enters the receiver's own surface at once:
    // no ray is cast, and like an occluded one the connection brings no direct light; the
    // light scattered by the lit medium around the receiver is lit_medium_single's.
    if (cos_x <= 0.0f || !visible(p, n, s.dir, s.distance, counters)) {
        if (scatters_ && occluded_multiple && settings_.media_bounces > 1)
            *occluded_multiple = unoccluded_scatter(s, p, n, albedo_lum, rng, counters).multiple;
        return false;
    }
    SegmentOptics optics;
    if (attenuates_) {
        const double length =
            std::isfinite(s.distance) ? s.distance : media_.exit_distance(p, s.dir);
        optics = segment_optics(p, s.dir, length, rng);
    }
    parts.surface += s.irradiance * cos_x * optics.transmittance_float();
    if (scatters_) {
        const double distance = std::isfinite(s.distance) ? s.distance : optics.length;
        add_scattered(s.kind, s.intensity, s.dir, distance, s.shift, s.emitter_normal, optics, n,
                      albedo_lum, parts, counters);
    }
    return true;
}

IrradianceParts BakeEstimator::unoccluded_scatter(const EmitterSample& s, const vec3& p,
                                                  const vec3& n, float albedo_lum, CounterRng& rng,
                                                  BakeCounters& counters) const {
    IrradianceParts out;
    const double length = std::isfinite(s.distance) ? s.distance : media_.exit_distance(p, s.dir);
    if (!(length > 0.0) || !std::isfinite(length)) return out;
    const SegmentOptics optics = segment_optics(p, s.dir, length, rng);
    add_scattered(s.kind, s.intensity, s.dir, length, s.shift, s.emitter_normal, optics, n,
                  albedo_lum, out, counters);
    return out;
}

void BakeEstimator::add_lit_medium(const EmitterSample& s, const vec3& p, const vec3& n,
                                   const vec3& unoccluded_multiple, CounterRng& rng,
                                   BakeCounters& counters, IrradianceParts& parts) const {
    // Environment samples below the horizon are half of a uniform sky's and bring little on
    // open ground (the medium they light lies beyond the ground's edge): Russian roulette,
    // one in kBelowHorizonKeep kept and weighted up, so that they cost a quarter.
    float weight = 1.0f;
    if (!s.fixed && s.kind == EmitterKind::Directional && glm::dot(n, s.dir) <= 0.0f) {
        if (rng.next_float() >= kBelowHorizonKeep) return;
        weight = 1.0f / kBelowHorizonKeep;
    }
    const LitMediumSample lit = lit_medium_single(s, p, n, rng, counters);
    parts.single += lit.single * weight;
    // Multiple scattering: the unoccluded response's where the point drawn is lit. Its mean
    // is the lit fraction of the medium the receiver sees (weighted by the cosine and the
    // transmittance), at most the unoccluded response: 0 in a closed gap, ~1/2 under a small
    // occluder. (Scaling by single's lit-medium estimate over the tables' single instead
    // diverged in thick media, where the tables' single is e^-12 and the real one is not.)
    if (lit.lit) parts.multiple += unoccluded_multiple * weight;
}

BakeEstimator::LitMediumSample BakeEstimator::lit_medium_single(const EmitterSample& s,
                                                                const vec3& p, const vec3& n,
                                                                CounterRng& rng,
                                                                BakeCounters& counters) const {
    LitMediumSample r;
    // Three numbers whatever happens: the streams of later vertices stay aligned.
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const double u3 = rng.next_double();
    const vec3 local_dir = sample_cosine_hemisphere(u1, u2);
    if (local_dir.z <= 1e-6f) return r;
    const vec3 w = Frame(n).to_world(local_dir);
    const vec3 o = origin(p, n);
    // The part of w's ray that can scatter: to the media's exit or, in a medium filling all
    // space, to the first surface (then nothing lies between p and the point).
    double t_end = media_.exit_distance(o, w);
    bool check_path = true;
    if (!std::isfinite(t_end)) {
        ++counters.rays;
        const SurfaceHit hit = scene_.intersect(Ray{o, w, 0.0f, INFINITY});
        t_end = hit.valid ? double(hit.distance) : kInfinity;
        check_path = false;
    }
    if (!(t_end > 0.0)) return r;
    const bool distant = !std::isfinite(s.distance);
    const vec3 emitter = distant ? vec3(0.0f) : p + s.dir * float(s.distance);
    double t = 0.0, pdf = 0.0;
    if (distant) {
        // Free flight at the segment's mean extinction (the exact optics below make any
        // positive pdf unbiased).
        double sigma;
        if (std::isfinite(t_end)) {
            const SegmentOptics along = media_.integrate(o, w, t_end);
            sigma = (along.tau_s + along.tau_a) / t_end;
        } else {
            sigma = media_.at(o).sigma_t();
        }
        if (!(sigma > 0.0)) return r;
        const TruncatedExponentialSample e = sample_truncated_exponential(sigma, t_end, u3);
        t = e.t;
        pdf = e.pdf;
    } else {
        const glm::dvec3 oc = glm::dvec3(emitter) - glm::dvec3(o);
        const double delta = glm::dot(oc, glm::dvec3(w));
        const double h = glm::length(oc - delta * glm::dvec3(w));
        EquiangularSample ea;
        if (h < 1e-9 || !sample_equiangular(delta, h, 0.0, t_end, u3, &ea)) return r;
        t = ea.t;
        pdf = ea.pdf;
    }
    if (!(pdf > 0.0) || !std::isfinite(t)) return r;
    const vec3 x = o + w * float(t);
    const HomogeneousMedium here = media_.at(x);
    if (!(here.sigma_s > 0.0)) return r;
    r.in_medium = true;
    vec3 l = s.dir;
    double dist = kInfinity;
    vec3 strength = s.irradiance;  // what reaches x from the emitter before the medium
    if (!distant) {
        const vec3 to = emitter - x;
        dist = glm::length(to);
        if (!(dist > 0.0)) return r;
        l = to / float(dist);
        float emission = 1.0f;
        if (s.kind == EmitterKind::Area) emission = std::max(0.0f, -glm::dot(l, s.emitter_normal));
        strength = s.intensity * float(emission / (dist * dist));
        if (emission <= 0.0f) return r;
    }
    ++counters.rays;
    if (scene_.occluded(shadow_ray(x, l, dist))) return r;
    if (check_path) {
        ++counters.rays;
        if (scene_.occluded(shadow_ray(o, w, t))) return r;
    }
    r.lit = true;
    const double to_emitter = distant ? media_.exit_distance(x, l) : dist;
    const double weight =
        media_.transmittance(o, w, t) * here.sigma_s * hg_phase(here.g, glm::dot(l, w)) *
        (std::isfinite(to_emitter) ? media_.transmittance(x, l, to_emitter) : 0.0) / pdf;
    r.single = strength * float(kPiD * weight);
    return r;
}

IrradianceParts BakeEstimator::surface_path(const vec3& p, const vec3& n, const vec3& albedo,
                                            int depth, CounterRng& rng, BakeCounters& counters,
                                            FixedDirect* fixed) const {
    IrradianceParts parts;
    const float albedo_lum = luminance(albedo);
    // One buffer per path depth and thread: no allocation per vertex.
    thread_local std::vector<std::vector<EmitterSample>> buffers;
    if (buffers.size() <= size_t(depth)) buffers.resize(size_t(depth) + 1);
    std::vector<EmitterSample> local = std::move(buffers[size_t(depth)]);
    sample_emitters(p, rng, local);
    IrradianceParts fixed_parts;
    const bool learn = fixed && !fixed->known;
    // Occluded connections' lit-medium estimates run after every connection is resolved, in
    // emitter order, whether or not the fixed lights were reused: the same random numbers
    // either way.
    thread_local std::vector<std::vector<OccludedConnection>> occluded_buffers;
    if (occluded_buffers.size() <= size_t(depth)) occluded_buffers.resize(size_t(depth) + 1);
    std::vector<OccludedConnection>& occluded = occluded_buffers[size_t(depth)];
    // Up to bake.lit_medium_depth (the texel itself by default: deeper vertices' shadows reach
    // it through a diffuse bounce, and cost as much).
    const bool lit_here = scatters_ && depth <= settings_.lit_medium_depth;
    occluded.assign(lit_here ? local.size() : 0, OccludedConnection{});
    for (size_t i = 0; i < local.size(); ++i) {
        const EmitterSample& s = local[i];
        vec3 multiple(0.0f);
        vec3* want = lit_here ? &multiple : nullptr;
        if (!fixed || !s.fixed) {
            if (!direct_light(s, p, n, albedo_lum, rng, counters, parts, want) && lit_here)
                occluded[i] = {true, multiple};
        } else if (learn) {
            if (!direct_light(s, p, n, albedo_lum, rng, counters, fixed_parts, want) && lit_here)
                fixed->occluded.emplace_back(s.light, multiple);
        }
    }
    if (fixed) {
        if (learn) {
            fixed->known = true;
            fixed->parts = fixed_parts;
        }
        parts += fixed->parts;
        for (const auto& [light, multiple] : fixed->occluded)
            for (size_t i = 0; i < local.size(); ++i)
                if (local[i].light == light && local[i].fixed) occluded[i] = {true, multiple};
    }
    for (size_t i = 0; i < occluded.size(); ++i)
        if (occluded[i].occluded)
            add_lit_medium(local[i], p, n, occluded[i].multiple, rng, counters, parts);
    buffers[size_t(depth)] = std::move(local);
    if (depth >= settings_.bounces) return parts;
    // One indirect segment, cosine-sampled: irradiance = pi x radiance on average.
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const vec3 local_dir = sample_cosine_hemisphere(u1, u2);
    if (local_dir.z <= 1e-6f) return parts;
    const vec3 dir = Frame(n).to_world(local_dir);
    ++counters.rays;
    const SurfaceHit hit = scene_.intersect(Ray{origin(p, n), dir, 0.0f, INFINITY});
    if (!hit.valid) return parts;  // environment light arrives by NEE only
    const Material& material = scene_.scene().materials[size_t(hit.material)];
    if (material.type == BrdfType::Mirror) return parts;
    const vec3 albedo_y = material.albedo.eval(hit.uv);
    if (glm::all(glm::equal(albedo_y, vec3(0.0f)))) return parts;
    const IrradianceParts sub =
        surface_path(hit.position, hit.shading_normal, albedo_y, depth + 1, rng, counters);
    const vec3 radiance = albedo_y * kInvPi * sub.total();  // L(y -> p), diffuse
    // A vertex that gathered nothing (its emitters hidden, its own path lost) sends nothing to
    // attenuate or scatter: no tracking, no table lookup.
    if (glm::all(glm::equal(radiance, vec3(0.0f)))) return parts;
    SegmentOptics optics;
    if (attenuates_) optics = segment_optics(p, dir, hit.distance, rng);
    parts.surface += kPi * radiance * optics.transmittance_float();
    if (scatters_) {
        // y as a differential-area emitter of intensity L dA cos_y max(n_y . u, 0) / cos_y: with
        // dA = d^2 domega / cos_y and domega = 1 / pdf, I0 = L d^2 / (cos_y pdf).
        const float cos_y = std::max(1e-3f, std::abs(glm::dot(hit.shading_normal, dir)));
        const float pdf = local_dir.z * kInvPi;
        const double d = hit.distance;
        const vec3 intensity = radiance * float(d * d / (double(cos_y) * pdf));
        add_scattered(EmitterKind::Area, intensity, dir, d,
                      std::sqrt(std::max(0.0f, 1.0f - cos_y * cos_y)), hit.shading_normal, optics,
                      n, albedo_lum, parts, counters);
    }
    return parts;
}

vec3 BakeEstimator::point_lights_along(const vec3& o, const vec3& d, double t_max, CounterRng& rng,
                                       BakeCounters& counters) const {
    vec3 sum(0.0f);
    const double t_end = std::min(t_max, media_.exit_distance(o, d));
    for (const Light& light : scene_.scene().lights) {
        if (light.type != LightType::Point) continue;
        const float u = rng.next_float();  // drawn for every point light: streams stay aligned
        if (!(t_end > 0.0)) continue;
        // Equiangular sampling: the 1/r^2 of the light along the segment.
        const glm::dvec3 oc = glm::dvec3(light.position) - glm::dvec3(o);
        const double delta = glm::dot(oc, glm::dvec3(d));
        const double h = glm::length(oc - delta * glm::dvec3(d));
        if (h < 1e-9) continue;  // the light on the ray's line: a set of measure zero
        EquiangularSample ea;
        if (!sample_equiangular(delta, h, 0.0, t_end, double(u), &ea)) continue;
        const double t = ea.t, pdf = ea.pdf;
        const double r2 = h * h + (t - delta) * (t - delta);
        const vec3 x = o + d * float(t);
        const HomogeneousMedium here = media_.at(x);
        if (!(here.sigma_s > 0.0)) continue;
        const vec3 to_light = light.position - x;
        const double dist = glm::length(to_light);
        const vec3 l = to_light / float(dist);
        ++counters.rays;
        if (scene_.occluded(shadow_ray(x, l, dist))) continue;
        const double w = media_.transmittance(o, d, t) * here.sigma_s *
                         hg_phase(here.g, glm::dot(l, d)) / r2 * media_.transmittance(x, l, dist) /
                         pdf;
        sum += light.intensity * float(w);
    }
    return sum;
}

IrradianceParts BakeEstimator::volume_path(const vec3& p, const vec3& n, CounterRng& rng,
                                           BakeCounters& counters) const {
    IrradianceParts parts;
    std::vector<EmitterSample> emitters;
    // Direct light at the receiver, attenuated exactly.
    sample_emitters(p, rng, emitters);
    for (const EmitterSample& s : emitters) {
        const float cos_x = glm::dot(n, s.dir);
        if (cos_x <= 0.0f || !visible(p, n, s.dir, s.distance, counters)) continue;
        const double length =
            std::isfinite(s.distance) ? s.distance : media_.exit_distance(p, s.dir);
        parts.surface += s.irradiance * cos_x * float(media_.transmittance(p, s.dir, length));
    }
    // The walk from a cosine-sampled direction: irradiance = pi x radiance.
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const vec3 local_dir = sample_cosine_hemisphere(u1, u2);
    if (local_dir.z <= 1e-6f) return parts;
    parts += walk(origin(p, n), Frame(n).to_world(local_dir), vec3(kPi), rng, counters);
    return parts;
}

IrradianceParts BakeEstimator::walk(vec3 pos, vec3 dir, vec3 throughput, CounterRng& rng,
                                    BakeCounters& counters) const {
    IrradianceParts parts;
    std::vector<EmitterSample> emitters;
    int chain = 0;      // scattering events since the last surface vertex
    int category = -1;  // fixed at the first surface vertex: 0 surface, 1 single, 2 multiple
    int surface_vertices = 0, events = 0;
    auto add = [&](int cat, const vec3& v) {
        (cat == 0 ? parts.surface : cat == 1 ? parts.single : parts.multiple) += v;
    };
    while (events < 1024) {
        ++counters.rays;
        const SurfaceHit hit = scene_.intersect(Ray{pos, dir, 0.0f, INFINITY});
        const double t_max = hit.valid ? double(hit.distance) : kInfinity;
        if (!media_.empty() && chain < settings_.media_bounces)
            add(category >= 0 ? category : (chain == 0 ? 1 : 2),
                throughput * point_lights_along(pos, dir, t_max, rng, counters));
        const MediumCollision c =
            media_.empty() ? MediumCollision{} : media_.sample_collision(pos, dir, t_max, rng);
        if (c.happened) {
            if (chain >= settings_.media_bounces) break;  // the walk ends in the medium
            ++chain;
            ++events;
            const vec3 x = pos + dir * float(c.t);
            throughput *= float(c.sigma_s / c.sigma_t);
            const int cat = category >= 0 ? category : (chain == 1 ? 1 : 2);
            sample_emitters(x, rng, emitters);
            for (const EmitterSample& s : emitters) {
                if (s.kind == EmitterKind::Point) continue;  // point_lights_along() has them
                // Light travels along -s.dir, then along -dir after scattering at x.
                const float phase = float(hg_phase(c.g, glm::dot(s.dir, dir)));
                ++counters.rays;
                if (scene_.occluded(shadow_ray(x, s.dir, s.distance))) continue;
                const double length =
                    std::isfinite(s.distance) ? s.distance : media_.exit_distance(x, s.dir);
                add(cat, throughput * s.irradiance * phase *
                             float(media_.transmittance(x, s.dir, length)));
            }
            dir = sample_hg_direction(float(c.g), dir, rng.next_float(), rng.next_float());
            pos = x;
            if (events >= 4) {
                const float survive = std::min(
                    1.0f, std::max(throughput.x, std::max(throughput.y, throughput.z)) / kPi);
                if (rng.next_float() >= survive) break;
                throughput /= survive;
            }
            continue;
        }
        if (!hit.valid) break;
        if (category < 0) category = chain == 0 ? 0 : (chain == 1 ? 1 : 2);
        if (++surface_vertices > settings_.bounces) break;
        const Material& material = scene_.scene().materials[size_t(hit.material)];
        if (material.type == BrdfType::Mirror) break;
        const vec3 albedo_y = material.albedo.eval(hit.uv);
        if (glm::all(glm::equal(albedo_y, vec3(0.0f)))) break;
        const vec3 ny = hit.shading_normal;
        // Radiance leaving y towards the walk: albedo / pi x irradiance at y (NEE part here).
        sample_emitters(hit.position, rng, emitters);
        for (const EmitterSample& s : emitters) {
            const float cos_y = glm::dot(ny, s.dir);
            if (cos_y <= 0.0f || !visible(hit.position, ny, s.dir, s.distance, counters)) continue;
            const double length =
                std::isfinite(s.distance) ? s.distance : media_.exit_distance(hit.position, s.dir);
            add(category, throughput * albedo_y * kInvPi * s.irradiance * cos_y *
                              float(media_.transmittance(hit.position, s.dir, length)));
        }
        // Continue: cosine sampling at y makes the throughput factor the albedo.
        throughput *= albedo_y;
        chain = 0;
        const vec3 ld = sample_cosine_hemisphere(rng.next_float(), rng.next_float());
        if (ld.z <= 1e-6f) break;
        dir = Frame(ny).to_world(ld);
        pos = origin(hit.position, ny);
    }
    return parts;
}

}  // namespace freqlab
