// Impulse's Monte Carlo terms at a texel through the real media and geometry (issue "Method B,
// part 3"; BakeEstimator, bake_estimators.h): the light scattered by the lit medium around a
// receiver whose connection to an emitter is occluded (single scattering at a point drawn
// towards the receiver, order 2 through the lit medium, orders 3+ from the unoccluded tables),
// the emitters' choice by roulette on their strength (emitter_roulette.h), and the control
// variates that correct the tables' single scattering of unoccluded connections by the real
// media (single_correction: distant emitters, directions from the tables' half-space model,
// single_scatter_lobe.h; local_single_correction: point and area emitters, the cosine mixed
// with the cone towards the emitter, near_light_directions.h), and the light of surfaces the
// receiver cannot see scattered in the medium in front of it (surface_light_scattered).
//
// | parameter             | meaning                                                       |
// |-----------------------|---------------------------------------------------------------|
// | kBelowHorizonKeep     | 0.25: environment samples below the horizon kept by roulette  |
// | mc_emitter_budget     | bake.mc_emitter_budget: emitters kept per vertex on average   |
#include <cmath>
#include <cstring>
#include <limits>

#include "math/sampling.h"
#include "math/sh.h"
#include "volume/bake_estimators.h"

namespace freqlab {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr float kBelowHorizonKeep = 0.25f;

}  // namespace

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
    if (!emitter && std::isfinite(t_end)) {
        // A collision of the real media, forced before t_end: t's density is sigma_t(t) T(t) /
        // P, so sigma_s / pdf stays near P wherever the point lands. A free flight at the
        // segment's mean extinction put a point inside one of valley's smoke grids (sigma_s
        // 0.18, 30x the air's) at the air's pdf: statue01:97,282 read 17.3 of single
        // scattering from one draw where VPT reads 0.045. Its own stream, drawn from u3: the
        // draw takes one or two numbers.
        uint64_t bits;
        std::memcpy(&bits, &u3, sizeof bits);
        CounterRng own(bits, 0, 0, 0);
        double p_collide = 0.0;
        const MediumCollision c = media_.sample_forced_collision(m.o, m.w, t_end, own, &p_collide);
        if (!c.happened) return m;
        m.t = c.t;
        m.pdf = c.pdf;
    } else if (!emitter) {
        // A medium filling all space and no surface along w: a free flight at the extinction
        // at p (the exact optics of the estimates make any positive pdf unbiased).
        const double sigma = media_.at(m.o).sigma_t();
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

SingleCorrection BakeEstimator::single_correction(const EmitterSample& s, const vec3& p,
                                                  const vec3& n, CounterRng& rng,
                                                  BakeCounters& counters) const {
    // The tables' model: a half-space of the segment's effective medium whose boundary, normal
    // to l, lies D along l; along w its single-scattering integrand is
    // sigma_s f(l.w) E0 e^-st D e^-k t, k = st (1 - w.l), for t < D / (w.l) (w.l > 0).
    // Where the tables brought nothing (add_scattered: no medium on the segment, or past their
    // last distance) the model is empty and the correction is the real single scattering.
    const double depth = media_.exit_distance(p, s.dir);
    if (!std::isfinite(depth)) return {};  // a medium filling space: the sun is dark
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
    if (glm::length(m.w) == 0.0f) return {};  // a grazing direction: measure zero
    const double wl = glm::dot(m.w, s.dir);
    // Beyond the drawn part of the ray (the media's exit or the first surface) only the model
    // has medium.
    double model_part = model.integral(wl, m.t_end, kInfinity), real_here = 0.0;
    if (m.pdf > 0.0) {
        model_part += model.at(wl, m.t) / m.pdf;
        const EmitterSeen at = m.valid ? emitter_seen(s, vec3(0.0f), m.x) : EmitterSeen{};
        if (at.valid && sees_receiver(m, counters)) {
            ++counters.rays;
            if (!scene_.occluded(shadow_ray(m.x, at.l, at.distance)))
                real_here = media_.transmittance(m.o, m.w, m.t) * m.here.sigma_s *
                            hg_phase(m.here.g, wl) *
                            media_.transmittance(m.x, at.l, at.to_emitter) / m.pdf;
        }
    } else {
        // Nothing to draw from (no extinction along the ray): the real part is 0.
        model_part += model.integral(wl, 0.0, m.t_end);
    }
    const vec3 scale = s.irradiance * float(m.direction_weight);
    return {scale * float(real_here), scale * float(model_part)};
}

SingleCorrection BakeEstimator::local_single_correction(const EmitterSample& s, const vec3& p,
                                                        const vec3& n, CounterRng& rng,
                                                        BakeCounters& counters) const {
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
    if (!(m.pdf > 0.0) || !std::isfinite(m.t)) return {};
    const glm::dvec3 to = glm::dvec3(emitter) - glm::dvec3(m.x);
    const double r = glm::length(to);
    if (!(r > 0.0)) return {};
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
    const float weight = float(m.direction_weight);
    return {weight * real_here, weight * s.intensity * float(model_here)};
}

}  // namespace freqlab
