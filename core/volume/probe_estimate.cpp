// Light probes of method B's bakers (issue "Method B, part 2"; seed, Deuxième article §5: "for
// lightprobes, we typically directly store the incident radiance l_in"): the incident radiance
// at a point in space as order-3 SH, by the same four methods as the lightmaps.
//
// | part      | how it enters the SH                                                         |
// |-----------|------------------------------------------------------------------------------|
// | emitters  | radiance x solid angle along the emitter's direction: L dw y(w) (delta lights  |
// |           | exactly, quads and the environment by one sample each)                        |
// | indirect  | one uniform direction w per path: 4 pi L(w) y(w), L from the surface it hits  |
// | impulse   | each segment's scattered ZH response, its first 3 bands turned to the segment's |
// |           | axis (Eq. 3.13); probes float in space, so the infinite-medium tables        |
// | vpt       | direct light attenuated exactly, then VPT's walk from a uniform direction      |
#include <cmath>

#include "math/sampling.h"
#include "math/sh.h"
#include "volume/bake_estimators.h"

namespace freqlab {

namespace {

constexpr int kProbeOrder = 3;

void add_sh(std::array<vec3, 9>& dst, const vec3& value, const vec3& dir) {
    double y[9];
    sh_eval(kProbeOrder, glm::dvec3(dir), y);
    for (int k = 0; k < 9; ++k) dst[size_t(k)] += value * float(y[k]);
}

// The first 3 bands of a ZH lobe about `axis`, times `intensity`, into dst.
void add_lobe(std::array<vec3, 9>& dst, const vec3& intensity, const ZhVector& zh,
              const glm::dvec3& axis) {
    double sh[9];
    zh_rotate(kProbeOrder, zh.data(), axis, sh);
    for (int k = 0; k < 9; ++k) dst[size_t(k)] += intensity * float(sh[k]);
}

}  // namespace

BakeEstimator::ProbeParts BakeEstimator::estimate_probe(const vec3& p, CounterRng& rng,
                                                        BakeCounters& counters) const {
    ProbeParts out;
    const bool attenuate = method_ != BakeMethod::Surface && !media_.empty();
    const bool scatter = method_ == BakeMethod::Impulse && !media_.empty() && tables_;
    const vec3 no_offset(0.0f);
    auto scattered = [&](EmitterKind kind, const vec3& intensity, const vec3& dir, double distance,
                         double shift, const vec3& emitter_normal, const SegmentOptics& optics) {
        const HomogeneousMedium m = optics.effective();
        if (!(m.sigma_s > 0.0) || !std::isfinite(distance) || !(distance > 0.0) ||
            m.sigma_t() * distance > ZhDistanceTable::kMaxD)
            return;
        ImpulseQuery q;
        q.emitter = kind;
        q.distance = distance;
        q.shift = std::clamp(shift, 0.0, 1.0);
        q.medium = m;
        q.medium.g = std::clamp(m.g, -kGRange, kGRange);
        q.last_bounce = std::min(settings_.media_bounces, table_bounces_);
        q.collapsed = true;
        const ImpulseResponse r = query_impulse(*tables_, q);
        ++counters.impulse_queries;
        const glm::dvec3 l(dir);
        glm::dvec3 axis = l;
        if (kind == EmitterKind::Area) {
            glm::dvec3 t = glm::dvec3(emitter_normal) - glm::dot(glm::dvec3(emitter_normal), l) * l;
            const double len = glm::length(t);
            if (len > 1e-9) axis = std::cos(r.axis_tilt) * l + std::sin(r.axis_tilt) * (t / len);
        }
        add_lobe(out.single, intensity, r.single, axis);
        add_lobe(out.multiple, intensity, r.multiple, l);
    };

    std::vector<EmitterSample> emitters;
    sample_emitters(p, rng, emitters);
    for (const EmitterSample& s : emitters) {
        if (!visible(p, no_offset, s.dir, s.distance, counters)) continue;
        SegmentOptics optics;
        if (attenuate || method_ == BakeMethod::Vpt) {
            const double length =
                std::isfinite(s.distance) ? s.distance : media_.exit_distance(p, s.dir);
            optics = media_.integrate(p, s.dir, length);
        }
        add_sh(out.surface, s.irradiance * float(optics.transmittance()), s.dir);
        if (scatter)
            scattered(s.kind, s.intensity, s.dir,
                      std::isfinite(s.distance) ? s.distance : optics.length, s.shift,
                      s.emitter_normal, optics);
    }
    const vec3 dir = sample_uniform_sphere(rng.next_float(), rng.next_float());
    constexpr float kFourPi = 4.0f * kPi;  // 1 / pdf of a uniform direction
    if (method_ == BakeMethod::Vpt) {
        const IrradianceParts w = walk(p, dir, vec3(kFourPi), rng, counters);
        add_sh(out.surface, w.surface, dir);
        add_sh(out.single, w.single, dir);
        add_sh(out.multiple, w.multiple, dir);
        return out;
    }
    if (settings_.bounces < 1) return out;
    ++counters.rays;
    const SurfaceHit hit = scene_.intersect(Ray{p, dir, 0.0f, INFINITY});
    if (!hit.valid) return out;
    const Material& material = scene_.scene().materials[size_t(hit.material)];
    if (material.type == BrdfType::Mirror) return out;
    const vec3 albedo_y = material.albedo.eval(hit.uv);
    const IrradianceParts sub =
        surface_path(hit.position, hit.shading_normal, albedo_y, 1, rng, counters);
    const vec3 radiance = albedo_y * kInvPi * sub.total();
    SegmentOptics optics;
    if (attenuate) optics = media_.integrate(p, dir, hit.distance);
    add_sh(out.surface, kFourPi * radiance * float(optics.transmittance()), dir);
    if (scatter) {
        const float cos_y = std::max(1e-3f, std::abs(glm::dot(hit.shading_normal, dir)));
        const double d = hit.distance;
        scattered(EmitterKind::Area, radiance * float(d * d * kFourPi / cos_y), dir, d,
                  std::sqrt(std::max(0.0f, 1.0f - cos_y * cos_y)), hit.shading_normal, optics);
    }
    return out;
}

}  // namespace freqlab
