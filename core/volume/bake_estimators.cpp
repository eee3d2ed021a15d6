#include "volume/bake_estimators.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "base/error.h"
#include "math/sampling.h"
#include "math/sh.h"
#include "volume/emitter_roulette.h"
#include "volume/vertex_corrections.h"

namespace freqlab {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr float kBelowHorizonKeep = 0.25f;
// Draws a texel walk's forced first collision tries (Media::sample_forced_collision).
constexpr int kForcedCollisionTries = 8;

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

const std::vector<BakeMethod>& bake_methods() {
    static const std::vector<BakeMethod> all = [] {
        std::vector<BakeMethod> v;
        for (const EnumName<BakeMethod>& e : kBakeMethodNames) v.push_back(e.value);
        return v;
    }();
    return all;
}

std::string bake_method_list(const std::string& separator) {
    return enum_name_list(kBakeMethodNames, separator);
}

bool is_bake_method(const std::string& name) {
    for (const EnumName<BakeMethod>& e : kBakeMethodNames)
        if (name == e.name) return true;
    return false;
}

BakeMethod parse_bake_method(const std::string& text) {
    return enum_from_name(kBakeMethodNames, text, "--method");
}

BakeEstimator::BakeEstimator(const RayScene& scene, const Media& media, const ImpulseTables* tables,
                             BakeMethod method, const BakeSettings& settings)
    : scene_(scene),
      media_(media),
      tables_(tables),
      method_(method),
      settings_(settings),
      near_lights_(scene.scene().lights, settings.near_light_fraction) {
    if (method == BakeMethod::Impulse && !media.empty() && !tables)
        throw Error("", "--method", "impulse needs the impulse-response tables");
    if (tables) {
        table_bounces_ = tables->bounces();
        if (settings.tabulated_irradiance)
            irradiance_ = std::make_unique<ImpulseIrradianceCache>(*tables);
    }
    for (const Light& light : scene.scene().lights)
        if (light.type == LightType::Point) ++point_lights_;
    attenuates_ = method != BakeMethod::Surface && !media.empty();
    scatters_ = method == BakeMethod::Impulse && !media.empty();
    zh_clamped_cosine(kImpulseOrder, cosine_zh_);
    check_media();
}

void BakeEstimator::check_media() const {
    if (!scatters_) return;
    for (size_t i = 0; i < media_.size(); ++i) {
        const MediumDesc& d = media_.desc(i);
        if (!(std::fabs(d.g) <= kGRange)) {
            char text[200];
            std::snprintf(text, sizeof text,
                          "g = %.4g: method B's impulse tables cover |g| <= %.2f (HG's response "
                          "is singular at |g| = 1); bake with --method vpt or lower |g|",
                          d.g, kGRange);
            throw Error("", "media[" + std::to_string(i) + "].g (" + d.name + ")", text);
        }
    }
}

bool BakeEstimator::texel_walk() const {
    return scatters_ && settings_.texel_multiple == TexelMultiple::Walk &&
           settings_.media_bounces > 1;
}

bool BakeEstimator::surface_light_walk() const {
    return scatters_ && settings_.texel_surface_light == TexelSurfaceLight::Walk;
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
                if (!ls.valid) {
                    // p behind a quad: no direct light, but the medium in front of the quad
                    // it sees is lit (smoke_room's ceiling: single 0.31x VPT's without it).
                    if (!scatters_ || light.type != LightType::Quad || !(ls.distance > 0.0f))
                        continue;
                    s.kind = EmitterKind::Area;
                    s.dir = ls.direction;
                    s.distance = ls.distance;
                    s.emitter_normal = ls.emitter_normal;
                    s.intensity = ls.intensity;
                    s.behind = true;
                    out.push_back(s);
                    continue;
                }
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
                                  IrradianceParts& out, BakeCounters& counters,
                                  int last_bounce_cap) const {
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
    // Within the tables' range: check_media() refused every medium beyond it, and a segment's
    // g is a mean of its media's.
    const double g = optics.tau_gs / optics.tau_s;
    int last_bounce = std::min(settings_.media_bounces, table_bounces_);
    if (last_bounce_cap > 0) last_bounce = std::min(last_bounce, last_bounce_cap);
    const double shift_q = std::clamp(shift, 0.0, 1.0);
    const float cos_light = glm::dot(dir, n);
    ++counters.impulse_queries;
    // One medium's segment: its own table; a mixture's: the blend of its cell's node tables.
    ImpulseIrradianceBlend tables;
    if (irradiance_ && optics.scattering_media > 1) {
        tables = irradiance_->blend(g, albedo, last_bounce);
    } else if (const ImpulseIrradiance* table = irradiance_table(g, albedo, last_bounce)) {
        tables.table[0] = table;
        tables.weight[0] = 1.0;
        tables.count = 1;
    }
    if (tables.count > 0) {
        // The tabulated double product (impulse_irradiance.h): one lookup per part and table.
        const ImpulseIrradiance::At D = ImpulseIrradiance::at(query_optical);
        const double scale = kind == EmitterKind::Directional ? 1.0 : sigma_t * sigma_t;
        ScatteredIrradiance sum;
        for (int k = 0; k < tables.count; ++k) {
            const ScatteredIrradiance e = tabulated_scattered(
                *tables.table[k], D, kind, dir, shift_q, emitter_normal, n, cos_light);
            sum.single += tables.weight[k] * e.single;
            sum.multiple += tables.weight[k] * e.multiple;
        }
        out.single += intensity * float(std::max(0.0, sum.single * scale));
        out.multiple += intensity * float(std::max(0.0, sum.multiple * scale));
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

ScatteredIrradiance BakeEstimator::tabulated_scattered(const ImpulseIrradiance& table,
                                                       const ImpulseIrradiance::At& D,
                                                       EmitterKind kind, const vec3& dir,
                                                       double shift, const vec3& emitter_normal,
                                                       const vec3& n, float cos_light) {
    if (kind == EmitterKind::Point) return table.point(D, cos_light);
    if (kind == EmitterKind::Directional) return table.directional(D, cos_light);
    // The single lobe's axis is tilted from l towards the emitter normal's part across l,
    // t = (n_e - (n_e . l) l) / |...|, whose length is the shift itself.
    const float tilt = float(table.tilt(D, shift));
    float cos_single = cos_light;
    if (tilt != 0.0f && shift > 1e-6) {
        const float nl_l = glm::dot(emitter_normal, dir);
        const float t_n = (glm::dot(emitter_normal, n) - nl_l * cos_light) / float(shift);
        cos_single = small_angle_cos(tilt) * cos_light + small_angle_sin(tilt) * t_n;
    }
    return table.area(D, shift, cos_single, cos_light);
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
    if (media_.size() != 1 || last_bounce != std::min(settings_.media_bounces, table_bounces_))
        return irradiance_->get(g, albedo, last_bounce);
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
                                        CounterRng& rng, BakeCounters& counters, FixedDirect* fixed,
                                        IrradianceParts* deferred, float mc_rate,
                                        UnoccludedSingle* unoccluded) const {
    const bool reuse = fixed && settings_.tracking == Tracking::Exact;
    IrradianceParts later;
    UnoccludedSingle single;
    IrradianceParts parts = method_ == BakeMethod::Vpt
                                ? volume_path(p, n, rng, counters)
                                : surface_path(p, n, albedo, 0, rng, counters,
                                               reuse ? fixed : nullptr, deferred ? &later : nullptr,
                                               false, mc_rate, unoccluded ? &single : nullptr);
    if (!finite(parts.total()) || !finite(later.total()) ||
        !finite(single.tables + single.correction)) {
        ++counters.guarded;
        return {};
    }
    if (deferred) *deferred += later;
    if (unoccluded) *unoccluded += single;
    return parts;
}

bool BakeEstimator::direct_light(const EmitterSample& s, const vec3& p, const vec3& n,
                                 float albedo_lum, CounterRng& rng, BakeCounters& counters,
                                 IrradianceParts& parts, OccludedConnection* occluded,
                                 bool no_multiple) const {
    const float cos_x = glm::dot(n, s.dir);
    const bool above = !s.behind && cos_x > 0.0f;
    // Below the horizon the segment to the emitter enters the receiver's own surface at once:
    // no ray is cast, and like an occluded one the connection brings no direct light; the
    // light scattered by the lit medium around the receiver is lit_medium_single's.
    if (!above || !visible(p, n, s.dir, s.distance, counters)) {
        if (!scatters_ || !occluded) return false;
        occluded->occluded = true;
        // Behind an area light the tables have no response (they are of its front).
        if (!no_multiple && !s.behind && settings_.media_bounces > 2)
            occluded->multiple = unoccluded_higher_orders(s, p, n, albedo_lum, rng, counters);
        return false;
    }
    SegmentOptics optics;
    // An infinite distance ends where the ray leaves the media (optics.length).
    if (attenuates_) optics = segment_optics(p, s.dir, s.distance, rng);
    parts.surface += s.irradiance * cos_x * optics.transmittance_float();
    if (scatters_) {
        const double distance = std::isfinite(s.distance) ? s.distance : optics.length;
        IrradianceParts scattered;
        add_scattered(s.kind, s.intensity, s.dir, distance, s.shift, s.emitter_normal, optics, n,
                      albedo_lum, scattered, counters);
        parts.single += scattered.single;
        if (!no_multiple) parts.multiple += scattered.multiple;
    }
    return true;
}

IrradianceParts BakeEstimator::unoccluded_scatter(const EmitterSample& s, const vec3& p,
                                                  const vec3& n, float albedo_lum, CounterRng& rng,
                                                  BakeCounters& counters) const {
    IrradianceParts out;
    const SegmentOptics optics = segment_optics(p, s.dir, s.distance, rng);
    const double length = optics.length;
    if (!(length > 0.0) || !std::isfinite(length)) return out;
    add_scattered(s.kind, s.intensity, s.dir, length, s.shift, s.emitter_normal, optics, n,
                  albedo_lum, out, counters);
    return out;
}

vec3 BakeEstimator::unoccluded_higher_orders(const EmitterSample& s, const vec3& p, const vec3& n,
                                             float albedo_lum, CounterRng& rng,
                                             BakeCounters& counters) const {
    const SegmentOptics optics = segment_optics(p, s.dir, s.distance, rng);
    const double length = optics.length;
    if (!(length > 0.0) || !std::isfinite(length)) return vec3(0.0f);
    IrradianceParts all, two;
    add_scattered(s.kind, s.intensity, s.dir, length, s.shift, s.emitter_normal, optics, n,
                  albedo_lum, all, counters);
    add_scattered(s.kind, s.intensity, s.dir, length, s.shift, s.emitter_normal, optics, n,
                  albedo_lum, two, counters, 2);
    return glm::max(all.multiple - two.multiple, vec3(0.0f));
}

void BakeEstimator::add_lit_medium(const EmitterSample& s, const vec3& p, const vec3& n,
                                   const vec3& higher_orders, CounterRng& rng,
                                   BakeCounters& counters, IrradianceParts& parts,
                                   bool no_multiple) const {
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
    // Multiple scattering: order 2 exactly through the lit medium (second_scatter); orders 3
    // and up the unoccluded tables' wherever the point drawn is medium the receiver sees (0 in
    // a closed gap, e.g. a box's face on the floor). They come from so far around that the
    // shadow itself barely changes them (haze_occluder's umbra, VPT: orders 3+ 0.092 there,
    // 0.079 on the open floor; weighting them by "the point drawn is lit" read 0.065).
    if (no_multiple) return;
    parts.multiple += lit.multiple * weight;
    if (lit.seen) parts.multiple += higher_orders * weight;
}

float BakeEstimator::emitter_strength(const EmitterSample& s) {
    if (!std::isfinite(s.distance)) return luminance(s.irradiance);
    const double d2 = std::max(s.distance * s.distance, 1e-12);
    return float(double(luminance(s.intensity)) / d2);
}

template <class Has>
void BakeEstimator::emitter_keep(const std::vector<EmitterSample>& emitters, Has has,
                                 std::vector<float>& keep) const {
    thread_local std::vector<float> strength;
    strength.assign(emitters.size(), 0.0f);
    size_t count = 0;
    for (size_t i = 0; i < emitters.size(); ++i)
        if (has(i)) {
            strength[i] = emitter_strength(emitters[i]);
            ++count;
        }
    // One emitter with a term is kept for sure, whatever the others (which have none).
    emitter_keep_probabilities(strength, count > 1 ? settings_.mc_emitter_budget : 0.0f, keep);
}

bool BakeEstimator::has_mc_term(const EmitterSample& s, const OccludedConnection& c,
                                const vec3& n) const {
    return c.occluded || (settings_.single_correction && glm::dot(n, s.dir) > 0.0f);
}

std::vector<float> BakeEstimator::mc_keep(const std::vector<EmitterSample>& emitters,
                                          const std::vector<OccludedConnection>& occluded,
                                          const vec3& n) const {
    std::vector<float> keep;
    emitter_keep(
        emitters,
        [&](size_t i) { return i < occluded.size() && has_mc_term(emitters[i], occluded[i], n); },
        keep);
    return keep;
}

BakeEstimator::MediumPoint BakeEstimator::draw_medium_point(
    const vec3& p, const vec3& n, const vec3* emitter, CounterRng& rng, BakeCounters& counters,
    bool whole_ray, const ReceiverDirections* directions) const {
    MediumPoint m;
    // Three numbers whatever happens: the streams of later vertices stay aligned.
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const double u3 = rng.next_double();
    if (directions) {
        vec3 w;
        if (!directions->sample(u1, u2, &w, &m.direction_weight)) return m;
        m.w = w;
    } else {
        const vec3 local_dir = sample_cosine_hemisphere(u1, u2);
        if (local_dir.z <= 1e-6f) return m;
        m.w = Frame(n).to_world(local_dir);
    }
    m.o = origin(p, n);
    // The part of w's ray that can scatter: to the media's exit or, in a medium filling all
    // space, to the first surface (then nothing lies between p and the point).
    double t_end = media_.exit_distance(m.o, m.w);
    if (!std::isfinite(t_end)) {
        ++counters.rays;
        const SurfaceHit hit = scene_.intersect(Ray{m.o, m.w, 0.0f, INFINITY});
        t_end = hit.valid ? double(hit.distance) : kInfinity;
        m.check_path = false;
    }
    if (!(t_end > 0.0) && !whole_ray) return m;
    m.t_end = std::max(t_end, 0.0);
    if (!emitter) {
        // Free flight at the segment's mean extinction (the exact optics of the estimates
        // make any positive pdf unbiased).
        double sigma;
        if (std::isfinite(t_end)) {
            const SegmentOptics along = media_.integrate(m.o, m.w, t_end);
            sigma = (along.tau_s + along.tau_a) / t_end;
        } else {
            sigma = media_.at(m.o).sigma_t();
        }
        if (!(sigma > 0.0)) return m;
        const TruncatedExponentialSample e = sample_truncated_exponential(sigma, t_end, u3);
        m.t = e.t;
        m.pdf = e.pdf;
    } else {
        const glm::dvec3 oc = glm::dvec3(*emitter) - glm::dvec3(m.o);
        const double delta = glm::dot(oc, glm::dvec3(m.w));
        const double h = glm::length(oc - delta * glm::dvec3(m.w));
        EquiangularSample ea;
        if (h < 1e-9 || !sample_equiangular(delta, h, 0.0, whole_ray ? kInfinity : t_end, u3, &ea))
            return m;
        m.t = ea.t;
        m.pdf = ea.pdf;
    }
    if (!(m.pdf > 0.0) || !std::isfinite(m.t)) return m;
    m.x = m.o + m.w * float(m.t);
    if (m.t < m.t_end) m.here = media_.at(m.x);  // beyond: no medium of the scene's
    m.valid = m.here.sigma_s > 0.0;
    return m;
}

bool BakeEstimator::sees_receiver(const MediumPoint& m, BakeCounters& counters) const {
    if (!m.check_path) return true;
    ++counters.rays;
    return !scene_.occluded(shadow_ray(m.o, m.w, m.t));
}

BakeEstimator::LitMediumSample BakeEstimator::lit_medium_single(const EmitterSample& s,
                                                                const vec3& p, const vec3& n,
                                                                CounterRng& rng,
                                                                BakeCounters& counters) const {
    LitMediumSample r;
    const bool distant = !std::isfinite(s.distance);
    const vec3 emitter = distant ? vec3(0.0f) : p + s.dir * float(s.distance);
    const MediumPoint m = draw_medium_point(p, n, distant ? nullptr : &emitter, rng, counters);
    const bool order_two = settings_.media_bounces > 1 && !texel_walk();
    if (order_two && !distant) {
        // Order 2 from a point of its own, by free flight: an equiangular point far from the
        // emitter weighs 1 / h (h the ray's distance to the emitter), which order 2 has no
        // 1 / r^2 to cancel (cornell_fog's floor: multiple relMSE 1.8e3 with the shared point).
        const MediumPoint m2 = draw_medium_point(p, n, nullptr, rng, counters);
        if (m2.valid && sees_receiver(m2, counters))
            add_second_scatter(s, emitter, m2, rng, counters, r);
    }
    if (!m.valid) return r;
    const vec3 &x = m.x, &w = m.w, &o = m.o;
    const double t = m.t, pdf = m.pdf;
    const HomogeneousMedium& here = m.here;
    r.in_medium = true;
    const EmitterSeen at = emitter_seen(s, emitter, x);
    if (!at.valid) return r;
    if (!sees_receiver(m, counters)) return r;
    r.seen = true;
    const double to_receiver = media_.transmittance(o, w, t);
    if (order_two && distant) add_second_scatter(s, emitter, m, rng, counters, r, to_receiver);
    ++counters.rays;
    if (scene_.occluded(shadow_ray(x, at.l, at.distance))) return r;
    r.lit = true;
    const double weight = to_receiver * here.sigma_s * hg_phase(here.g, glm::dot(at.l, w)) *
                          media_.transmittance(x, at.l, at.to_emitter) / pdf;
    r.single = at.strength * float(kPiD * weight);
    return r;
}

void BakeEstimator::add_second_scatter(const EmitterSample& s, const vec3& emitter,
                                       const MediumPoint& m, CounterRng& rng,
                                       BakeCounters& counters, LitMediumSample& r,
                                       double to_receiver) const {
    const SecondScatter second = second_scatter(s, emitter, m.x, m.w, m.here, rng, counters);
    if (to_receiver < 0.0) to_receiver = media_.transmittance(m.o, m.w, m.t);
    r.multiple = second.radiance * float(kPiD * to_receiver * m.here.sigma_s / m.pdf);
}

BakeEstimator::EmitterSeen BakeEstimator::emitter_seen(const EmitterSample& s, const vec3& emitter,
                                                       const vec3& x) const {
    EmitterSeen at;
    if (!std::isfinite(s.distance)) {
        at.l = s.dir;
        at.strength = s.irradiance;
        at.to_emitter = media_.exit_distance(x, s.dir);
        at.valid = std::isfinite(at.to_emitter);
        return at;
    }
    const vec3 to = emitter - x;
    at.distance = glm::length(to);
    if (!(at.distance > 0.0)) return at;
    at.l = to / float(at.distance);
    float emission = 1.0f;
    if (s.kind == EmitterKind::Area) emission = std::max(0.0f, -glm::dot(at.l, s.emitter_normal));
    if (emission <= 0.0f) return at;
    at.strength = s.intensity * float(emission / (at.distance * at.distance));
    at.to_emitter = at.distance;
    at.valid = true;
    return at;
}

BakeEstimator::SecondScatter BakeEstimator::second_scatter(
    const EmitterSample& s, const vec3& emitter, const vec3& x, const vec3& w,
    const HomogeneousMedium& here, CounterRng& rng, BakeCounters& counters) const {
    SecondScatter r;
    const float u1 = rng.next_float(), u2 = rng.next_float();
    // The walk continues from x as VPT's does: the phase sampled about w cancels f at x.
    const vec3 w2 = sample_hg_direction(float(here.g), w, u1, u2);
    ++counters.rays;
    const SurfaceHit hit = scene_.intersect(Ray{x, w2, 0.0f, INFINITY});
    const double t_max = hit.valid ? double(hit.distance) : kInfinity;
    vec3 x2;
    double along = 0.0;  // x2's weight: T(x, x2) sigma_s(x2) / pdf, or the albedo of a flight
    if (!std::isfinite(s.distance)) {
        const MediumCollision c = media_.sample_collision(x, w2, t_max, rng);
        if (!c.happened || !(c.sigma_t > 0.0)) return r;
        x2 = x + w2 * float(c.t);
        along = c.sigma_s / c.sigma_t;
    } else {
        // A point or area emitter: equiangular about it, since a collision's NEE to it has
        // the 1/r^2 of points near it (as VPT's point_lights_along).
        const float u = rng.next_float();
        const double t_end = std::min(t_max, media_.exit_distance(x, w2));
        const glm::dvec3 oc = glm::dvec3(emitter) - glm::dvec3(x);
        const double delta = glm::dot(oc, glm::dvec3(w2));
        const double h = glm::length(oc - delta * glm::dvec3(w2));
        EquiangularSample ea;
        if (!(t_end > 0.0) || h < 1e-9 || !sample_equiangular(delta, h, 0.0, t_end, u, &ea))
            return r;
        x2 = x + w2 * float(ea.t);
        along = media_.transmittance(x, w2, ea.t) * media_.at(x2).sigma_s / ea.pdf;
    }
    if (!(along > 0.0)) return r;
    const HomogeneousMedium there = media_.at(x2);
    const EmitterSeen at = emitter_seen(s, emitter, x2);
    if (!at.valid) return r;
    ++counters.rays;
    if (scene_.occluded(shadow_ray(x2, at.l, at.distance))) return r;
    r.radiance = at.strength * float(along * hg_phase(there.g, glm::dot(at.l, w2)) *
                                     media_.transmittance(x2, at.l, at.to_emitter));
    return r;
}

BakeEstimator::ScatteredSurfaceLight BakeEstimator::surface_light_scattered(
    const vec3& p, const vec3& n, CounterRng& rng, BakeCounters& counters) const {
    const MediumPoint m = draw_medium_point(p, n, nullptr, rng, counters);
    const float u1 = rng.next_float(), u2 = rng.next_float();
    if (!m.valid) return {};
    const vec3 w2 = sample_hg_direction(float(m.here.g), m.w, u1, u2);
    ++counters.rays;
    const SurfaceHit hit = scene_.intersect(Ray{m.x, w2, 0.0f, INFINITY});
    if (!hit.valid) return {};
    // Surfaces the receiver sees reach it through its own indirect segment (the area tables
    // count their light scattered anywhere on the way); this is the light of the others.
    // From the spawned origin, to y's own distance from it: measured from p, the shortened ray
    // still reached y's surface whenever y lay closer than its cosine (|y - o| = |y - p| -
    // eps cos), so a visible y nearby read as hidden and its light was counted twice.
    const vec3 o = origin(p, n);
    const vec3 to_y = hit.position - o;
    const float d_y = glm::length(to_y);
    if (glm::dot(to_y, n) > 1e-3f * d_y) {
        ++counters.rays;
        if (!scene_.occluded(shadow_ray(o, to_y / d_y, d_y))) return {};
    }
    const Material& material = scene_.scene().materials[size_t(hit.material)];
    if (material.type == BrdfType::Mirror) return {};
    const vec3 albedo_y = material.albedo.eval(hit.uv);
    if (glm::all(glm::equal(albedo_y, vec3(0.0f)))) return {};
    // y's direct light and the media's response to it: the last vertex of a surface path.
    const IrradianceParts at_y =
        surface_path(hit.position, hit.shading_normal, albedo_y, settings_.bounces, rng, counters);
    const vec3 radiance = albedo_y * kInvPi * at_y.total();
    if (glm::all(glm::equal(radiance, vec3(0.0f)))) return {};
    if (!sees_receiver(m, counters)) return {};
    // The phase sampled at x cancels f; pi for the cosine-sampled w.
    const double to_receiver = kPiD * media_.transmittance(m.o, m.w, m.t) * m.here.sigma_s / m.pdf;
    const SegmentOptics optics = segment_optics(m.x, w2, hit.distance, rng);
    ScatteredSurfaceLight out;
    out.single = radiance * float(to_receiver * optics.transmittance());
    // Orders 2+: y as a differential-area emitter (area sampled at pdf_w2 cos_y / d^2) whose
    // in-medium response at x, scattered again at x by the phase, goes to the receiver.
    const double pdf_w2 = hg_phase(m.here.g, glm::dot(w2, m.w));
    const float cos_y = std::max(1e-3f, std::abs(glm::dot(hit.shading_normal, w2)));
    const double d = hit.distance;
    const vec3 intensity = radiance * float(d * d / (double(cos_y) * pdf_w2));
    // Scattered at x and again on the way from y: order 2 and up, none under media_bounces 1.
    if (settings_.media_bounces >= 2)
        out.multiple =
            float(to_receiver) * area_response_rescattered(intensity, w2, d, hit.shading_normal,
                                                           optics, m.here.g, m.w, counters);
    return out;
}

vec3 BakeEstimator::area_response_rescattered(const vec3& intensity, const vec3& l, double distance,
                                              const vec3& emitter_normal,
                                              const SegmentOptics& optics, double g_here,
                                              const vec3& w, BakeCounters& counters) const {
    if (!(optics.tau_s > 0.0) || !(optics.length > 0.0)) return vec3(0.0f);
    const double sigma_t = (optics.tau_s + optics.tau_a) / optics.length;
    const double optical = sigma_t * distance;
    if (optical > ZhDistanceTable::kMaxD) return vec3(0.0f);
    ImpulseQuery q;
    q.emitter = EmitterKind::Area;
    q.distance = std::max(optical, ZhDistanceTable::kMinD) / sigma_t;
    const float c = glm::dot(emitter_normal, l);
    q.shift = std::clamp(double(std::sqrt(std::max(0.0f, 1.0f - c * c))), 0.0, 1.0);
    q.medium = optics.effective();
    // One scattering event more at x: the response's orders up to media_bounces - 1.
    q.last_bounce = std::clamp(settings_.media_bounces - 1, 1, table_bounces_);
    q.collapsed = true;
    ++counters.impulse_queries;
    const ImpulseResponse r = query_impulse(*tables_, q);
    // The phase at x convolved with the response (Funk-Hecke: HG's Legendre coefficients are
    // g^l), towards the receiver: at cos = w . axis.
    const glm::dvec3 ld(l), wd(w);
    const glm::dvec3 axis = tilted_axis(ld, emitter_normal, r.axis_tilt);
    double single[kImpulseOrder], multiple[kImpulseOrder];
    double gl = 1.0;
    for (int k = 0; k < kImpulseOrder; ++k, gl *= g_here) {
        single[k] = r.single[size_t(k)] * gl;
        multiple[k] = r.multiple[size_t(k)] * gl;
    }
    // Orders 3+ (the response's multiple term) at kSurfaceEmitterMultipleWeight.
    const double radiance =
        zh_eval(kImpulseOrder, single, glm::dot(axis, wd)) +
        kSurfaceEmitterMultipleWeight * zh_eval(kImpulseOrder, multiple, glm::dot(ld, wd));
    return intensity * float(std::max(0.0, radiance));
}

vec3 BakeEstimator::single_correction(const EmitterSample& s, const vec3& p, const vec3& n,
                                      CounterRng& rng, BakeCounters& counters) const {
    // The tables' model: a half-space of the segment's effective medium whose boundary, normal
    // to l, lies D along l; along w its single-scattering integrand is
    // sigma_s f(l.w) E0 e^-st D e^-k t, k = st (1 - w.l), for t < D / (w.l) (w.l > 0).
    // Where the tables brought nothing (add_scattered: no medium on the segment, or past their
    // last distance) the model is empty and the correction is the real single scattering.
    const double depth = media_.exit_distance(p, s.dir);
    if (!std::isfinite(depth)) return vec3(0.0f);  // a medium filling space: the sun is dark
    const SegmentOptics optics =
        depth > 0.0 ? segment_optics(p, s.dir, depth, rng) : SegmentOptics{};
    HomogeneousMedium medium =
        optics.tau_s > 0.0 ? optics.effective() : HomogeneousMedium{0.0, 0.0, 0.0};
    if (medium.sigma_t() * depth > ZhDistanceTable::kMaxD)
        medium = HomogeneousMedium{0.0, 0.0, 0.0};
    const HalfSpaceSingleModel model{medium.sigma_s, medium.sigma_t(), medium.g, depth};
    // w in proportion to the model's radiance x cos: its part of the estimate is then nearly
    // the same for every w (single_scatter_lobe.h).
    const SingleScatterLobe lobe(model, s.dir, n);
    const MediumPoint m = draw_medium_point(p, n, nullptr, rng, counters, false, &lobe);
    if (glm::length(m.w) == 0.0f) return vec3(0.0f);  // a grazing direction: measure zero
    const double wl = glm::dot(m.w, s.dir);
    // Beyond the drawn part of the ray (the media's exit or the first surface) only the model
    // has medium.
    double difference = -model.integral(wl, m.t_end, kInfinity);
    if (m.pdf > 0.0) {
        const double model_here = model.at(wl, m.t) / m.pdf;
        double real_here = 0.0;
        const EmitterSeen at = m.valid ? emitter_seen(s, vec3(0.0f), m.x) : EmitterSeen{};
        if (at.valid && sees_receiver(m, counters)) {
            ++counters.rays;
            if (!scene_.occluded(shadow_ray(m.x, at.l, at.distance)))
                real_here = media_.transmittance(m.o, m.w, m.t) * m.here.sigma_s *
                            hg_phase(m.here.g, wl) *
                            media_.transmittance(m.x, at.l, at.to_emitter) / m.pdf;
        }
        difference += real_here - model_here;
    } else {
        // Nothing to draw from (no extinction along the ray): the real part is 0.
        difference -= model.integral(wl, 0.0, m.t_end);
    }
    return s.irradiance * float(m.direction_weight * difference);
}

vec3 BakeEstimator::local_single_correction(const EmitterSample& s, const vec3& p, const vec3& n,
                                            CounterRng& rng, BakeCounters& counters) const {
    // The tables' model: an infinite medium of the segment's effective optics around a point
    // (or differential-area, emission max(-n_e . l, 0)) emitter e; along w its integrand is
    // sigma_s f(l.w) I emission e^-st (t + r) / r^2, r = |e - x|, over all t >= 0: the point is
    // drawn equiangular about e on the whole ray, the real integrand is 0 past the media's exit
    // or the first surface.
    // An empty model where the tables brought nothing (as single_correction).
    const vec3 emitter = p + s.dir * float(s.distance);
    // w aims at the emitter as often as the cosine draws it (near_light_directions.h).
    const CosineAndPointDirections directions(origin(p, n), n, emitter);
    const MediumPoint m = draw_medium_point(p, n, &emitter, rng, counters, true, &directions);
    const SegmentOptics optics = segment_optics(p, s.dir, s.distance, rng);
    HomogeneousMedium model =
        optics.tau_s > 0.0 ? optics.effective() : HomogeneousMedium{0.0, 0.0, 0.0};
    if (model.sigma_t() * s.distance > ZhDistanceTable::kMaxD)
        model = HomogeneousMedium{0.0, 0.0, 0.0};
    const double st = model.sigma_t();
    const double g_model = model.g;
    if (!(m.pdf > 0.0) || !std::isfinite(m.t)) return vec3(0.0f);
    const glm::dvec3 to = glm::dvec3(emitter) - glm::dvec3(m.x);
    const double r = glm::length(to);
    if (!(r > 0.0)) return vec3(0.0f);
    const glm::dvec3 l = to / r;
    const double cos_lw = glm::dot(l, glm::dvec3(m.w));
    const double emission_model = s.kind == EmitterKind::Area
                                      ? std::max(0.0, -glm::dot(l, glm::dvec3(s.emitter_normal)))
                                      : 1.0;
    const double model_here = model.sigma_s * hg_phase(g_model, cos_lw) * emission_model *
                              std::exp(-st * (m.t + r)) / (r * r) / m.pdf;
    vec3 real_here(0.0f);
    if (m.valid) {
        const EmitterSeen at = emitter_seen(s, emitter, m.x);
        if (at.valid && sees_receiver(m, counters)) {
            ++counters.rays;
            if (!scene_.occluded(shadow_ray(m.x, at.l, at.distance)))
                real_here =
                    at.strength * float(media_.transmittance(m.o, m.w, m.t) * m.here.sigma_s *
                                        hg_phase(m.here.g, glm::dot(at.l, m.w)) *
                                        media_.transmittance(m.x, at.l, at.to_emitter) / m.pdf);
        }
    }
    return float(m.direction_weight) * (real_here - s.intensity * float(model_here));
}

IrradianceParts BakeEstimator::surface_path(const vec3& p, const vec3& n, const vec3& albedo,
                                            int depth, CounterRng& rng, BakeCounters& counters,
                                            FixedDirect* fixed, IrradianceParts* deferred,
                                            bool corrected, float mc_rate,
                                            UnoccludedSingle* unoccluded) const {
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
    const bool walk_here = lit_here && texel_walk();
    // Without the tables' multiple scattering where a walk supplies it (here or in the field).
    const bool no_multiple = walk_here || (corrected && texel_walk());
    // Other surfaces' light scattered on its way here comes from the texel's walk, not from
    // the indirect segment's vertex in the tables' infinite medium.
    const bool prepass = prepass_surface_depth_ >= 0;
    const bool surface_walk_here =
        lit_here && surface_light_walk() &&
        (prepass ? prepass_surface_depth_ <= settings_.bounces : depth < settings_.bounces);
    // A vertex whose field value holds its surface light's scattering (vertex_corrections.h).
    const bool field_surface_light =
        corrected && depth < settings_.bounces && corrections_->has_surface_light();
    // A deeper vertex reading the field keeps the tables' multiple scattering until it knows
    // whether the field holds for it (vertex_irradiance).
    const bool keep_multiple = no_multiple && unoccluded && !lit_here;
    for (size_t i = 0; i < local.size(); ++i) {
        const EmitterSample& s = local[i];
        OccludedConnection c;
        OccludedConnection* want = lit_here ? &c : nullptr;
        if (!fixed || !s.fixed) {
            const bool seen = direct_light(s, p, n, albedo_lum, rng, counters, parts, want,
                                           no_multiple && !keep_multiple);
            if (!seen && s.fixed && unoccluded)
                unoccluded->shadows |= uint64_t(1) << (unsigned(s.light) % 64u);
            if (!seen && lit_here) occluded[i] = c;
        } else if (learn) {
            if (!direct_light(s, p, n, albedo_lum, rng, counters, fixed_parts, want, no_multiple) &&
                lit_here)
                fixed->occluded.emplace_back(s.light, c);
        }
    }
    if (fixed) {
        if (learn) {
            fixed->known = true;
            fixed->parts = fixed_parts;
        }
        parts += fixed->parts;
        for (const auto& [light, c] : fixed->occluded)
            for (size_t i = 0; i < local.size(); ++i)
                if (local[i].light == light && local[i].fixed) occluded[i] = c;
    }
    // The Monte Carlo terms through the real media (corrections of the tables' single
    // scattering, the lit medium of connections below the horizon, hidden surfaces' light, the
    // multiple-scattering walk) run on a fraction of the paths (bake.texel_mc_rate), weighted
    // up: Russian roulette, decided once per vertex. At the texel they may be deferred: the
    // baker sums them apart and filters them over neighbouring texels (bake.texel_mc_radius).
    bool mc_here = lit_here;
    float mc_weight = 1.0f;
    const float rate = mc_rate > 0.0f ? mc_rate : settings_.texel_mc_rate;
    if (lit_here && rate < 1.0f) {
        mc_here = rng.next_float() < rate;
        mc_weight = 1.0f / rate;
    }
    // Here parts.single holds the tables' single scattering of the unoccluded connections.
    if (unoccluded) unoccluded->tables += parts.single;
    if (keep_multiple) {
        unoccluded->left_multiple = parts.multiple;
        parts.multiple = vec3(0.0f);
    }
    IrradianceParts mc;
    if (mc_here && !occluded.empty()) {
        // Each emitter's terms by roulette on its strength (bake.mc_emitter_budget).
        const std::vector<float> keep = mc_keep(local, occluded, n);
        for (size_t i = 0; i < occluded.size(); ++i) {
            if (!has_mc_term(local[i], occluded[i], n)) continue;
            const float w = emitter_roulette_weight(keep[i], rng);
            if (w == 0.0f) continue;
            IrradianceParts term;
            if (occluded[i].occluded) {
                add_lit_medium(local[i], p, n, occluded[i].multiple, rng, counters, term,
                               walk_here);
            } else {
                const vec3 correction = std::isfinite(local[i].distance)
                                            ? local_single_correction(local[i], p, n, rng, counters)
                                            : single_correction(local[i], p, n, rng, counters);
                // The prepass files corrections apart: the field carries them as a ratio.
                if (prepass && unoccluded)
                    unoccluded->correction += correction * (w * mc_weight);
                else
                    term.single += correction;
            }
            mc.single += term.single * w;
            mc.multiple += term.multiple * w;
        }
    }
    buffers[size_t(depth)] = std::move(local);
    if (mc_here && settings_.hidden_surface_light && !surface_walk_here && !prepass && depth == 0 &&
        settings_.bounces > 0) {
        const ScatteredSurfaceLight hidden = surface_light_scattered(p, n, rng, counters);
        mc.single += hidden.single;
        mc.multiple += hidden.multiple;
    }
    if ((walk_here || surface_walk_here) && mc_here) {
        // Through the real media: VPT's walk from the receiver, ending at the first surface;
        // emitters' orders 2+ by NEE from its second scattering event on (texel_multiple =
        // walk), the surface it ends on after scattering as the light of that surface
        // (texel_surface_light = walk).
        IrradianceParts surface_light;
        TexelWalk texel;
        texel.emitters_multiple = walk_here;
        texel.surface_light_depth = !surface_walk_here ? -1
                                    : prepass          ? prepass_surface_depth_
                                                       : depth + 1;
        texel.surface_light = &surface_light;
        const vec3 ld = sample_cosine_hemisphere(rng.next_float(), rng.next_float());
        if (ld.z > 1e-6f)
            mc.multiple +=
                walk(origin(p, n), Frame(n).to_world(ld), vec3(kPi), rng, counters, &texel)
                    .multiple;
        // The prepass files surface light under `surface`, where nothing else of the texel's
        // own Monte Carlo terms lands (no indirect segment runs there): the field keeps it apart.
        if (prepass)
            mc.surface += surface_light.total();
        else
            mc += surface_light;
    }
    if (depth < settings_.bounces && !(prepass && depth == 0))
        indirect_segment(p, n, albedo_lum, depth, rng, counters, parts,
                         mc_here && settings_.single_correction ? &mc.single : nullptr, deferred,
                         !surface_walk_here && !field_surface_light);
    if (mc_here) {
        mc.surface *= mc_weight;
        mc.single *= mc_weight;
        mc.multiple *= mc_weight;
        (deferred ? *deferred : parts) += mc;
    }
    return parts;
}

void BakeEstimator::indirect_segment(const vec3& p, const vec3& n, float albedo_lum, int depth,
                                     CounterRng& rng, BakeCounters& counters,
                                     IrradianceParts& parts, vec3* correction,
                                     IrradianceParts* deferred, bool scatter) const {
    // One indirect segment, cosine-sampled: irradiance = pi x radiance on average.
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const vec3 local_dir = sample_cosine_hemisphere(u1, u2);
    if (local_dir.z <= 1e-6f) return;
    const vec3 dir = Frame(n).to_world(local_dir);
    ++counters.rays;
    const SurfaceHit hit = scene_.intersect(Ray{origin(p, n), dir, 0.0f, INFINITY});
    if (!hit.valid) return;  // environment light arrives by NEE only
    const Material& material = scene_.scene().materials[size_t(hit.material)];
    if (material.type == BrdfType::Mirror) return;
    const vec3 albedo_y = material.albedo.eval(hit.uv);
    if (glm::all(glm::equal(albedo_y, vec3(0.0f)))) return;
    // y's deferred Monte Carlo terms travel to p apart from the rest (the response to y's
    // light is linear in it), so that the baker filters them too.
    IrradianceParts sub_deferred;
    const IrradianceParts sub = vertex_irradiance(hit, albedo_y, depth + 1, rng, counters,
                                                  deferred ? &sub_deferred : nullptr);
    const vec3 radiance = albedo_y * kInvPi * sub.total();  // L(y -> p), diffuse
    const vec3 radiance_deferred = albedo_y * kInvPi * sub_deferred.total();
    // A vertex that gathered nothing (its emitters hidden, its own path lost) sends nothing to
    // attenuate or scatter: no tracking, no table lookup.
    const bool any_deferred = !glm::all(glm::equal(radiance_deferred, vec3(0.0f)));
    if (glm::all(glm::equal(radiance, vec3(0.0f))) && !any_deferred) return;
    SegmentOptics optics;
    if (attenuates_) optics = segment_optics(p, dir, hit.distance, rng);
    parts.surface += kPi * radiance * optics.transmittance_float();
    if (any_deferred) deferred->surface += kPi * radiance_deferred * optics.transmittance_float();
    if (scatters_ && scatter) {
        // y as a differential-area emitter of intensity L dA cos_y max(n_y . u, 0) / cos_y: with
        // dA = d^2 domega / cos_y and domega = 1 / pdf, I0 = L d^2 / (cos_y pdf).
        const float cos_y = std::max(1e-3f, std::abs(glm::dot(hit.shading_normal, dir)));
        const float pdf = local_dir.z * kInvPi;
        const double d = hit.distance;
        const float to_intensity = float(d * d / (double(cos_y) * pdf));
        const vec3 intensity = radiance * to_intensity;
        const double shift = std::sqrt(std::max(0.0f, 1.0f - cos_y * cos_y));
        // The infinite medium's multiple response counts the medium behind y's surface, where
        // there is none: kSurfaceEmitterMultipleWeight of it (area_response_rescattered).
        IrradianceParts response;
        add_scattered(EmitterKind::Area, intensity, dir, d, shift, hit.shading_normal, optics, n,
                      albedo_lum, response, counters);
        response.multiple *= kSurfaceEmitterMultipleWeight;
        parts += response;
        if (any_deferred) {
            response = {};
            add_scattered(EmitterKind::Area, radiance_deferred * to_intensity, dir, d, shift,
                          hit.shading_normal, optics, n, albedo_lum, response, counters);
            response.multiple *= kSurfaceEmitterMultipleWeight;
            *deferred += response;
        }
        if (correction) {
            // y's light scattered once on the way is the area tables' infinite medium too.
            EmitterSample y;
            y.kind = EmitterKind::Area;
            y.dir = dir;
            y.distance = d;
            y.intensity = intensity + radiance_deferred * to_intensity;
            y.emitter_normal = hit.shading_normal;
            *correction += local_single_correction(y, p, n, rng, counters);
        }
    }
}

vec3 BakeEstimator::point_lights_along(const vec3& o, const vec3& d, double t_max, CounterRng& rng,
                                       BakeCounters& counters) const {
    vec3 sum(0.0f);
    const double t_end = std::min(t_max, media_.exit_distance(o, d));
    const std::vector<Light>& lights = scene_.scene().lights;
    // The roulette's strength of each point light: the integral of I / r^2 along the segment,
    // (I / h) x the angle it subtends (what equiangular sampling draws from).
    thread_local std::vector<float> keep;
    point_light_keep(
        [&](const Light& light) {
            if (!(t_end > 0.0) || !std::isfinite(t_end)) return 0.0f;
            const glm::dvec3 oc = glm::dvec3(light.position) - glm::dvec3(o);
            const double delta = glm::dot(oc, glm::dvec3(d));
            const double h = std::max(glm::length(oc - delta * glm::dvec3(d)), 1e-9);
            return float(double(luminance(light.intensity)) / h *
                         (std::atan((t_end - delta) / h) - std::atan(-delta / h)));
        },
        keep);
    size_t k = 0;
    for (const Light& light : lights) {
        if (light.type != LightType::Point) continue;
        const float keep_k = keep.empty() ? 1.0f : keep[k++];
        const float u = rng.next_float();  // drawn for every point light: streams stay aligned
        if (!(t_end > 0.0)) continue;
        // Equiangular sampling: the 1/r^2 of the light along the segment.
        const glm::dvec3 oc = glm::dvec3(light.position) - glm::dvec3(o);
        const double delta = glm::dot(oc, glm::dvec3(d));
        const double h = glm::length(oc - delta * glm::dvec3(d));
        if (h < 1e-9) continue;  // the light on the ray's line: a set of measure zero
        const float roulette = emitter_roulette_weight(keep_k, rng);
        if (roulette == 0.0f) continue;
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
        sum += light.intensity * float(w * roulette);
    }
    return sum;
}

bool BakeEstimator::aims_at_point_lights() const {
    return near_lights_.active() && !media_.empty();
}

bool BakeEstimator::sample_walk_direction(const vec3& x, const vec3& axis, const double* g,
                                          bool aim, CounterRng& rng, vec3* dir,
                                          float* weight) const {
    // A surface vertex (g null): the cosine about the normal `axis`, weight cos / pdf (pi with
    // the cosine alone). A medium vertex: HG about the direction of travel, weight phase / pdf.
    const float u_pick = aim ? rng.next_float() : 1.0f;
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const float fraction = near_lights_.fraction();
    if (u_pick < fraction) {
        if (!near_lights_.sample(x, u_pick / fraction, u1, u2, dir)) return false;
    } else if (g) {
        *dir = sample_hg_direction(float(*g), axis, u1, u2);
        if (!aim) {
            *weight = 1.0f;
            return true;
        }
    } else {
        const vec3 local = sample_cosine_hemisphere(u1, u2);
        if (local.z <= 1e-6f) return false;
        *dir = Frame(axis).to_world(local);
        if (!aim) {
            *weight = kPi;
            return true;
        }
    }
    const double base_value =
        g ? hg_phase(*g, glm::dot(axis, *dir)) : std::max(0.0f, glm::dot(axis, *dir)) * kInvPi;
    if (!(base_value > 0.0)) return false;
    const double pdf = near_lights_.mixture_pdf(x, *dir, base_value);
    // Cosine: the walk carries radiance x cos / pdf (= pi for the cosine alone).
    *weight = float((g ? base_value : base_value * kPiD) / pdf);
    return std::isfinite(*weight);
}

IrradianceParts BakeEstimator::volume_path(const vec3& p, const vec3& n, CounterRng& rng,
                                           BakeCounters& counters) const {
    IrradianceParts parts;
    std::vector<EmitterSample> emitters;
    // Direct light at the receiver, attenuated exactly.
    sample_emitters(p, rng, emitters);
    for (const EmitterSample& s : emitters) {
        const float cos_x = glm::dot(n, s.dir);
        if (s.behind || cos_x <= 0.0f || !visible(p, n, s.dir, s.distance, counters)) continue;
        parts.surface += s.irradiance * cos_x * float(media_.transmittance(p, s.dir, s.distance));
    }
    // The walk from a cosine-sampled direction (irradiance = pi x radiance), or one aimed past
    // a point light.
    vec3 dir;
    float weight = 0.0f;
    if (!sample_walk_direction(p, n, nullptr, aims_at_point_lights(), rng, &dir, &weight))
        return parts;
    parts += walk(origin(p, n), dir, vec3(weight), rng, counters);
    return parts;
}

IrradianceParts BakeEstimator::walk(vec3 pos, vec3 dir, vec3 throughput, CounterRng& rng,
                                    BakeCounters& counters, const TexelWalk* texel) const {
    IrradianceParts parts;
    const bool media_multiple_only = texel != nullptr;
    const bool gather_emitters = !texel || texel->emitters_multiple;
    std::vector<EmitterSample> emitters;
    std::vector<float> keep;  // the emitters' roulette at a scattering event
    int chain = 0;            // scattering events since the last surface vertex
    int category = -1;        // fixed at the first surface vertex: 0 surface, 1 single, 2 multiple
    int surface_vertices = 0, events = 0;
    WalkScatter last;  // the last scattering event (texel walks' surface light)
    const bool point_lit_mis =
        media_multiple_only && texel->surface_light_depth >= 0 && surface_light_mis();
    // point_lights_along() runs on the walk's segments: aim some of them past point lights.
    const bool aims = gather_emitters && aims_at_point_lights();
    auto add = [&](int cat, const vec3& v) {
        (cat == 0 ? parts.surface : cat == 1 ? parts.single : parts.multiple) += v;
    };
    while (events < 1024) {
        ++counters.rays;
        const SurfaceHit hit = scene_.intersect(Ray{pos, dir, 0.0f, INFINITY});
        const double t_max = hit.valid ? double(hit.distance) : kInfinity;
        if (!media_.empty() && chain < settings_.media_bounces && gather_emitters &&
            !(media_multiple_only && chain == 0))
            add(category >= 0 ? category : (chain == 0 ? 1 : 2),
                throughput * point_lights_along(pos, dir, t_max, rng, counters));
        MediumCollision c;
        if (media_multiple_only && events == 0) {
            // From the texel, light that reaches it unscattered is not the walk's: every walk
            // is made to scatter on its first segment (weighted by the chance it would).
            double forced = 0.0;
            if (!media_.empty())
                c = media_.sample_forced_collision(pos, dir, t_max, rng, kForcedCollisionTries,
                                                   &forced);
            if (!c.happened) break;
            throughput *= float(forced);
        } else if (!media_.empty()) {
            c = media_.sample_collision(pos, dir, t_max, rng);
        }
        if (c.happened) {
            if (chain >= settings_.media_bounces) break;  // the walk ends in the medium
            ++chain;
            ++events;
            const vec3 x = pos + dir * float(c.t);
            throughput *= float(c.sigma_s / c.sigma_t);
            const int cat = category >= 0 ? category : (chain == 1 ? 1 : 2);
            sample_emitters(x, rng, emitters);
            if (!gather_emitters || (media_multiple_only && chain == 1))
                emitters.clear();  // single: not asked
            // point_lights_along() has point lights; behind a quad nothing arrives.
            auto gathered = [](const EmitterSample& s) {
                return s.kind != EmitterKind::Point && !s.behind;
            };
            emitter_keep(
                emitters, [&](size_t i) { return gathered(emitters[i]); }, keep);
            for (size_t i = 0; i < emitters.size(); ++i) {
                const EmitterSample& s = emitters[i];
                if (!gathered(s)) continue;
                const float w = emitter_roulette_weight(keep[i], rng);
                if (w == 0.0f) continue;
                // Light travels along -s.dir, then along -dir after scattering at x.
                const float phase = float(hg_phase(c.g, glm::dot(s.dir, dir)));
                ++counters.rays;
                if (scene_.occluded(shadow_ray(x, s.dir, s.distance))) continue;
                add(cat, throughput * s.irradiance * (phase * w) *
                             float(media_.transmittance(x, s.dir, s.distance)));
            }
            const float survive =
                events >= 4
                    ? std::min(1.0f,
                               std::max(throughput.x, std::max(throughput.y, throughput.z)) / kPi)
                    : 1.0f;
            const bool aim = aims && chain < settings_.media_bounces;
            last = WalkScatter{x, dir, c.g, survive, aim};
            if (point_lit_mis)
                (chain == 1 ? texel->surface_light->single : texel->surface_light->multiple) +=
                    throughput * point_lit_surface_light(last, rng, counters);
            float weight = 0.0f;
            const vec3 travel = dir;  // sample_walk_direction writes dir
            if (!sample_walk_direction(x, travel, &c.g, aim, rng, &dir, &weight)) break;
            throughput *= weight;
            pos = x;
            if (events >= 4) {
                if (rng.next_float() >= survive) break;
                throughput /= survive;
            }
            continue;
        }
        if (media_multiple_only) {
            if (hit.valid && chain > 0 && texel->surface_light_depth >= 0)
                add_walk_surface_light(hit, chain, throughput, *texel, last, rng, counters);
            break;
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
            if (s.behind || cos_y <= 0.0f ||
                !visible(hit.position, ny, s.dir, s.distance, counters))
                continue;
            add(category, throughput * albedo_y * kInvPi * s.irradiance * cos_y *
                              float(media_.transmittance(hit.position, s.dir, s.distance)));
        }
        // Continue: cosine sampling at y makes the throughput factor the albedo.
        chain = 0;
        float weight = 0.0f;
        if (!sample_walk_direction(hit.position, ny, nullptr, aims, rng, &dir, &weight)) break;
        throughput *= albedo_y * (weight * kInvPi);  // weight: cos / pdf x pi
        pos = origin(hit.position, ny);
    }
    return parts;
}

IrradianceParts BakeEstimator::vertex_irradiance(const SurfaceHit& hit, const vec3& albedo,
                                                 int depth, CounterRng& rng, BakeCounters& counters,
                                                 IrradianceParts* deferred) const {
    VertexCorrectionField::Texel field;
    if (corrections_ && scatters_ && depth > settings_.lit_medium_depth)
        field = corrections_->locate(hit);
    UnoccludedSingle single;
    IrradianceParts parts =
        surface_path(hit.position, hit.shading_normal, albedo, depth, rng, counters, nullptr,
                     deferred, field.found(), -1.0f, field.found() ? &single : nullptr);
    // Read after the vertex's own path, which hides the read's cache miss. The corrections of
    // the unoccluded connections scale with the vertex's own tables' value of them. A vertex
    // shadowed otherwise than the texel (a pocket of a layered wall whose texel's centre sees
    // a lamp) keeps its tables' multiple scattering instead.
    if (field.found()) {
        if (field.holds_for(single.shadows))
            parts.single +=
                field.value(depth < settings_.bounces) + field.single_ratio() * single.tables;
        else
            parts.multiple += single.left_multiple;
    }
    return parts;
}

}  // namespace freqlab
