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
#include <cstdio>

#include "math/sampling.h"
#include "math/sh.h"
#include "volume/bake_estimators.h"
#include "volume/vertex_corrections.h"

namespace freqlab {

namespace {

constexpr int kProbeOrder = 3;

void add_sh(std::array<vec3, 9>& dst, const vec3& value, const vec3& dir) {
    double y[9];
    sh_eval(kProbeOrder, glm::dvec3(dir), y);
    for (int k = 0; k < 9; ++k) dst[size_t(k)] += value * float(y[k]);
}

// The first 3 bands of a ZH lobe (zh[0..2]) about `axis`, times `intensity`, into dst.
void add_lobe(std::array<vec3, 9>& dst, const vec3& intensity, const double* zh,
              const glm::dvec3& axis) {
    static_assert(ImpulseIrradiance::kProbeBands == kProbeOrder, "probe lobes are order 3");
    double sh[9];
    zh_rotate(kProbeOrder, zh, axis, sh);
    for (int k = 0; k < 9; ++k) dst[size_t(k)] += intensity * float(sh[k]);
}

}  // namespace

BakeEstimator::ProbeParts BakeEstimator::estimate_probe(const vec3& p, CounterRng& rng,
                                                        BakeCounters& counters) const {
    ProbeParts out;
    const vec3 no_offset(0.0f);
    // multiple_weight: kSurfaceEmitterMultipleWeight for a surface vertex as the emitter.
    auto scattered = [&](EmitterKind kind, const vec3& intensity, const vec3& dir, double distance,
                         double shift, const vec3& emitter_normal, const SegmentOptics& optics,
                         float multiple_weight = 1.0f) {
        const HomogeneousMedium m = optics.effective();
        if (!(m.sigma_s > 0.0) || !std::isfinite(distance) || !(distance > 0.0) ||
            m.sigma_t() * distance > ZhDistanceTable::kMaxD)
            return;
        const double g = m.g;  // within the tables' range (check_media)
        const int last_bounce = std::min(settings_.media_bounces, table_bounces_);
        const glm::dvec3 l(dir);
        if (const ImpulseIrradiance* table =
                irradiance_table(g, m.sigma_s / m.sigma_t(), last_bounce)) {
            // The tabulated lobes (impulse_irradiance.h): one lookup instead of a table query.
            ++counters.impulse_queries;
            const double sigma_t = m.sigma_t();
            const ImpulseIrradiance::At D = ImpulseIrradiance::at(sigma_t * distance);
            const ImpulseIrradiance::Lobes lobes = table->lobes(kind, D, shift);
            const float scale = kind == EmitterKind::Directional ? 1.0f : float(sigma_t * sigma_t);
            const glm::dvec3 axis = kind == EmitterKind::Area
                                        ? tilted_axis(l, emitter_normal, table->tilt(D, shift))
                                        : l;
            add_lobe(out.single, intensity * scale, lobes.single, axis);
            add_lobe(out.multiple, intensity * (scale * multiple_weight), lobes.multiple, l);
            return;
        }
        ImpulseQuery q;
        q.emitter = kind;
        q.distance = distance;
        q.shift = std::clamp(shift, 0.0, 1.0);
        q.medium = m;
        q.medium.g = g;
        q.last_bounce = last_bounce;
        q.collapsed = true;
        const ImpulseResponse r = query_impulse(*tables_, q);
        ++counters.impulse_queries;
        const glm::dvec3 axis =
            kind == EmitterKind::Area ? tilted_axis(l, emitter_normal, r.axis_tilt) : l;
        add_lobe(out.single, intensity, r.single.data(), axis);
        add_lobe(out.multiple, intensity * multiple_weight, r.multiple.data(), l);
    };

    std::vector<EmitterSample> emitters;
    sample_emitters(p, rng, emitters);
    for (const EmitterSample& s : emitters) {
        if (s.behind || !visible(p, no_offset, s.dir, s.distance, counters)) continue;
        SegmentOptics optics;
        if (attenuates_) {
            const double length =
                std::isfinite(s.distance) ? s.distance : media_.exit_distance(p, s.dir);
            optics = method_ == BakeMethod::Vpt ? media_.integrate(p, s.dir, length)
                                                : segment_optics(p, s.dir, length, rng);
        }
        add_sh(out.surface, s.irradiance * optics.transmittance_float(), s.dir);
        if (scatters_)
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
    if (glm::all(glm::equal(radiance, vec3(0.0f)))) return out;
    SegmentOptics optics;
    if (attenuates_) optics = segment_optics(p, dir, hit.distance, rng);
    add_sh(out.surface, kFourPi * radiance * optics.transmittance_float(), dir);
    if (scatters_) {
        const float cos_y = std::max(1e-3f, std::abs(glm::dot(hit.shading_normal, dir)));
        const double d = hit.distance;
        scattered(EmitterKind::Area, radiance * float(d * d * kFourPi / cos_y), dir, d,
                  std::sqrt(std::max(0.0f, 1.0f - cos_y * cos_y)), hit.shading_normal, optics,
                  kSurfaceEmitterMultipleWeight);
    }
    return out;
}

template <class Line>
void BakeEstimator::trace_occluded(const EmitterSample& s, const vec3& p, const vec3& n,
                                   const vec3& albedo, CounterRng& rng, Line& line) const {
    // The bake's own functions: the unoccluded response and the lit-medium estimate, the
    // latter averaged over draws of its own so that the visibility it implies is readable.
    BakeCounters counters;
    const IrradianceParts unoccluded =
        unoccluded_scatter(s, p, n, luminance(albedo), rng, counters);
    const vec3 higher = settings_.media_bounces > 2 && !texel_walk()
                            ? unoccluded_higher_orders(s, p, n, luminance(albedo), rng, counters)
                            : vec3(0.0f);
    constexpr int kDraws = 1024;
    double sum = 0.0, sum2 = 0.0, second = 0.0;
    int in_medium = 0, lit = 0;
    for (int i = 0; i < kDraws; ++i) {
        const LitMediumSample one = lit_medium_single(s, p, n, rng, counters);
        const double v = luminance(one.single);
        sum += v, sum2 += v * v;
        second += luminance(one.multiple);
        in_medium += one.in_medium, lit += one.lit;
    }
    const double mean = sum / kDraws;
    const double se = std::sqrt(std::max(0.0, sum2 / kDraws - mean * mean) / kDraws);
    const double table_single = luminance(unoccluded.single);
    line("  occluded: the lit medium around the receiver (%d draws: %d in the medium, %d lit)",
         kDraws, in_medium, lit);
    line("    unoccluded tables: single %.5g, multiple %.5g (orders 3+ %.5g)", table_single,
         double(luminance(unoccluded.multiple)), double(luminance(higher)));
    line("    lit-medium single %.5g +- %.2g -> visibility of the lit medium %.3f", mean, se,
         table_single > 0.0 ? mean / table_single : 0.0);
    if (texel_walk()) {
        line("    contributions: single %.5g; multiple from the texel's walk (below)", mean);
        return;
    }
    line(
        "    contributions: single %.5g, multiple %.5g (order 2 through the lit medium %.5g + "
        "the tables' orders 3+)",
        mean, second / kDraws + double(luminance(higher)), second / kDraws);
}

std::vector<std::string> BakeEstimator::trace_texel(const vec3& p, const vec3& n,
                                                    const vec3& albedo, CounterRng& rng) const {
    std::vector<std::string> lines;
    char buf[512];
    auto line = [&](const char* fmt, auto... args) {
        std::snprintf(buf, sizeof buf, fmt, args...);
        lines.emplace_back(buf);
    };
    line("method %s at (%.3f, %.3f, %.3f), n (%.2f, %.2f, %.2f), albedo %.3f", to_string(method_),
         p.x, p.y, p.z, n.x, n.y, n.z, luminance(albedo));
    const char* kinds[] = {"point", "directional", "area"};
    std::vector<EmitterSample> emitters;
    sample_emitters(p, rng, emitters);
    BakeCounters counters;
    // As the estimator: below the horizon the receiver's own surface occludes the segment.
    std::vector<OccludedConnection> connections(emitters.size());
    for (size_t i = 0; i < emitters.size(); ++i) {
        const EmitterSample& s = emitters[i];
        connections[i].occluded =
            s.behind || glm::dot(n, s.dir) <= 0.0f || !visible(p, n, s.dir, s.distance, counters);
    }
    // The roulette of the texel's Monte Carlo terms on the paths that run them.
    const std::vector<float> keep = mc_keep(emitters, connections, n);
    for (size_t i = 0; i < emitters.size(); ++i) {
        const EmitterSample& s = emitters[i];
        const float cos_x = glm::dot(n, s.dir);
        const bool vis = !connections[i].occluded;
        const double length =
            std::isfinite(s.distance) ? s.distance : media_.exit_distance(p, s.dir);
        const SegmentOptics o = media_.integrate(p, s.dir, length);
        const HomogeneousMedium m = o.effective();
        line("emitter %zu (%s): dir (%.2f, %.2f, %.2f), cos %.3f, %s", i, kinds[int(s.kind)],
             s.dir.x, s.dir.y, s.dir.z, cos_x,
             vis            ? "visible"
             : s.behind     ? "behind the light (its lit medium only)"
             : cos_x > 0.0f ? "occluded"
                            : "below the horizon");
        line(
            "  segment %.3f in media: tau_s %.4f tau_a %.4f T %.4f; effective sigma_s %.4f "
            "sigma_a %.4f g %.3f",
            std::isfinite(length) ? length : -1.0, o.tau_s, o.tau_a, o.transmittance(), m.sigma_s,
            m.sigma_a, m.g);
        line("  direct irradiance %.5g (x T for extinction, impulse and vpt)",
             double(luminance(s.irradiance)) * std::max(0.0f, cos_x));
        if (scatters_ && has_mc_term(s, connections[i], n))
            line(
                "  Monte Carlo terms: strength %.4g, kept with probability %.3f "
                "(bake.mc_emitter_budget %.3g)",
                double(emitter_strength(s)), double(keep[i]), double(settings_.mc_emitter_budget));
        if (!vis && scatters_) trace_occluded(s, p, n, albedo, rng, line);
        if (!tables_ || !(m.sigma_s > 0.0) || !vis) continue;
        ImpulseQuery q;
        q.emitter = s.kind;
        q.distance = std::isfinite(s.distance) ? s.distance : length;
        q.shift = s.shift;
        q.medium = m;
        q.last_bounce = std::min(settings_.media_bounces, table_bounces_);
        q.receiver = Receiver::OnSurface;
        if (!(q.distance > 0.0) || m.sigma_t() * q.distance > ZhDistanceTable::kMaxD) continue;
        const ImpulseResponse r = query_impulse(*tables_, q);
        for (const auto& [name, zh] :
             {std::pair{"single  ", &r.single}, std::pair{"multiple", &r.multiple}}) {
            std::string coeffs;
            for (double v : *zh) {
                std::snprintf(buf, sizeof buf, " %.3e", v);
                coeffs += buf;
            }
            line("  ZH %s x I%s", name, coeffs.c_str());
        }
        if (s.kind == EmitterKind::Area)
            line("  single lobe tilted %.2f deg", r.axis_tilt * 57.2958);
        IrradianceParts e;
        add_scattered(s.kind, s.intensity, s.dir, q.distance, s.shift, s.emitter_normal, o, n,
                      luminance(albedo), e, counters);
        line("  scattered irradiance: single %.5g, multiple %.5g", double(luminance(e.single)),
             double(luminance(e.multiple)));
    }
    if (scatters_ && settings_.hidden_surface_light && !surface_light_walk() &&
        settings_.lit_medium_depth >= 0 && settings_.bounces > 0) {
        // The bake's own estimate, averaged over draws of its own.
        constexpr int kDraws = 1024;
        vec3 single(0.0f), multiple(0.0f);
        for (int i = 0; i < kDraws; ++i) {
            const ScatteredSurfaceLight one = surface_light_scattered(p, n, rng, counters);
            single += one.single / float(kDraws);
            multiple += one.multiple / float(kDraws);
        }
        line(
            "hidden surfaces' light scattered in front of the texel (%d draws): single %.5g, "
            "multiple %.5g",
            kDraws, double(luminance(single)), double(luminance(multiple)));
    }
    if (texel_walk() && settings_.lit_medium_depth >= 0) {
        // The bake's own walk, averaged over draws of its own.
        constexpr int kDraws = 4096;
        double sum = 0.0, sum2 = 0.0;
        const TexelWalk emitters_only;
        for (int i = 0; i < kDraws; ++i) {
            const double v =
                luminance(texel_walk_from(p, n, rng, counters, emitters_only).multiple);
            sum += v, sum2 += v * v;
        }
        const double mean = sum / kDraws;
        line("multiple scattering of every emitter by the texel's walk (%d draws): %.5g +- %.2g",
             kDraws, mean, std::sqrt(std::max(0.0, sum2 / kDraws - mean * mean) / kDraws));
    }
    if (surface_light_walk() && settings_.lit_medium_depth >= 0 && settings_.bounces > 0) {
        // The bake's walk gathering other surfaces' light, averaged over draws of its own.
        constexpr int kDraws = 1024;
        TexelWalk surfaces;
        surfaces.emitters_multiple = false;
        surfaces.surface_light_depth = 1;
        IrradianceParts sum;
        surfaces.surface_light = &sum;
        for (int i = 0; i < kDraws; ++i) texel_walk_from(p, n, rng, counters, surfaces);
        line(
            "other surfaces' light scattered on its way here, by the texel's walk (%d draws): "
            "single %.5g, multiple %.5g (bake.texel_surface_light = walk)",
            kDraws, double(luminance(sum.single)) / kDraws,
            double(luminance(sum.multiple)) / kDraws);
    }
    if (scatters_ && settings_.lit_medium_depth >= 0)
        line(
            "in the bake these Monte Carlo terms (corrections, lit medium, hidden surfaces' "
            "light, walk) run on %.3g of the paths, weighted by %.3g, and are averaged over "
            "the texels within %d of this one on its surface, shadow side and light level "
            "(bake.texel_mc_rate, bake.texel_mc_radius)",
            double(settings_.texel_mc_rate), 1.0 / double(settings_.texel_mc_rate),
            settings_.texel_mc_radius);
    if (corrections_)
        line(
            "deeper path vertices add the vertex correction field where they land: the texels' "
            "own Monte Carlo terms from a prepass of %d paths a texel (bake.vertex_corrections)",
            corrections_->paths_per_texel());
    return lines;
}

}  // namespace freqlab
