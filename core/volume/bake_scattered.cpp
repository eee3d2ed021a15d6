// The tables' side of method B's impulse estimator (BakeEstimator, bake_estimators.h): the
// scattered light a segment x -> emitter or surface vertex adds at x, from the ZH impulse
// response tables (seed, Deuxième article §4.4 effective medium of a segment, §5 emitter kinds:
// point, directional and the differential-area table for quad lights and surface vertices;
// App. 8 the ZH -> irradiance double product, tabulated per optical distance in
// impulse_irradiance.h). Only on unoccluded segments (§5.2); of an occluded connection the
// tables give orders 3 and up as if it were unoccluded (order 2 is second_scatter's).
//
// | parameter     | meaning                                                               |
// |---------------|-----------------------------------------------------------------------|
// | back_scatter  | bake.back_scatter: the surface variant's shift (off / on / albedo)     |
// | media_bounces | bake.media_bounces: the tables' last scattering order read            |
#include <algorithm>
#include <cmath>

#include "math/sh.h"
#include "volume/bake_estimators.h"

namespace freqlab {

namespace {

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

}  // namespace

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

}  // namespace freqlab
