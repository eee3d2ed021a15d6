// The texel walk's light of other surfaces (issue "Method B, part 3"; BakeSettings::
// texel_surface_light = walk): where the walk from a texel reaches a surface y after
// scattering at x, y's radiance albedo / pi x E(y) arrives at the texel through x.
//
// A surface right next to a point light is lit as 1 / r^2 (cornell_fog's ceiling above its
// light: irradiance 5-48): the walk lands there rarely and brings a large value, weighted by
// 1 / texel_mc_rate (one walk in 200000 from a short-box texel at 2x density brought 1500x the
// mean). Light tracing finds those points in proportion to their light: from each point light
// a direction drawn uniformly reaches y with density cos_L / (4 pi r_L^2) (area measure),
// and E_L(y) / pdf = 4 pi I T(L, y) cos_s / cos_g carries no 1 / r^2. At every scattering
// event x of the walk, one such y per point light is connected to x (a shadow ray, the
// transmittance, the phase function, cos_y / |x - y|^2); where the walk itself lands on y,
// each point light's part of E(y) is split with it. Both strategies' densities of y are known
// in area measure (the walk's: the phase function's, times the chance of no collision before
// y and of surviving the roulette, times cos_y / |x - y|^2), and the power heuristic weighs
// them (Veach's multiple importance sampling): unbiased, and the hot spot comes by light
// tracing. The rest of E(y) (other emitters, in-scattering at y, bounces) stays the walk's.
//
// | parameter          | meaning                                                          |
// |--------------------|------------------------------------------------------------------|
// | surface_light_mis  | bake.surface_light_mis: 1 adds light tracing from point lights    |
// | rays per event     | 2 per point light (from the light; x to y), 1 per landing and     |
// |                    | point light (y to the light)                                       |
#include <cmath>

#include "volume/bake_estimators.h"

namespace freqlab {

bool BakeEstimator::surface_light_mis() const {
    return surface_light_walk() && settings_.surface_light_mis;
}

bool BakeEstimator::point_lit_point(const Light& light, const SurfaceHit& y,
                                    const WalkScatter& from, bool check_visibility,
                                    BakeCounters& counters, PointLitPoint* out) const {
    const vec3 to_light = light.position - y.position;
    const float r_light = glm::length(to_light);
    if (!(r_light > 0.0f)) return false;
    const vec3 l = to_light / r_light;
    const vec3 to_x = from.x - y.position;
    const float r_x = glm::length(to_x);
    if (!(r_x > 0.0f)) return false;
    const vec3 v = to_x / r_x;
    // The light and x on the same side of y, as direct_light() reads E(y) (shading normal).
    const float cos_light_s = glm::dot(y.shading_normal, l);
    const float cos_light_g = glm::dot(y.geometric_normal, l);
    const float cos_x_g = glm::dot(y.geometric_normal, v);
    if (cos_light_s <= 0.0f || cos_light_g * cos_x_g <= 0.0f) return false;
    if (check_visibility && !visible(y.position, y.shading_normal, l, r_light, counters))
        return false;
    const double t_light = media_.transmittance(y.position, l, r_light);
    out->irradiance =
        light.intensity * float(double(cos_light_s) / (double(r_light) * r_light) * t_light);
    out->light_pdf = std::abs(cos_light_g) / (4.0 * kPiD * double(r_light) * r_light);
    const double t_x = media_.transmittance(from.x, -v, r_x);
    const double phase = hg_phase(from.g, glm::dot(from.dir_in, -v));
    const double dir_pdf = from.aimed ? near_lights_.mixture_pdf(from.x, -v, phase) : phase;
    const double geometry = t_x * std::abs(cos_x_g) / (double(r_x) * r_x);
    out->walk_f = phase * geometry;
    out->walk_pdf = dir_pdf * from.survive * geometry;
    out->to_y = -v;
    out->distance = r_x;
    return true;
}

vec3 BakeEstimator::point_lit_surface_light(const WalkScatter& at, CounterRng& rng,
                                            BakeCounters& counters) const {
    vec3 sum(0.0f);
    const std::vector<Light>& lights = scene_.scene().lights;
    // The roulette (emitter_roulette.h) on each light's strength at x, I / |x - light|^2.
    thread_local std::vector<float> keep;
    point_light_keep(
        [&](const Light& light) {
            const vec3 to = light.position - at.x;
            return luminance(light.intensity) / std::max(glm::dot(to, to), 1e-12f);
        },
        distant_strength_, keep);
    size_t k = 0;
    for (const Light& light : lights) {
        if (light.type != LightType::Point) continue;
        const float keep_k = keep.empty() ? 1.0f : keep[k++];
        // Drawn for every point light: streams stay aligned.
        const float u1 = rng.next_float(), u2 = rng.next_float();
        const float roulette = emitter_roulette_weight(keep_k, rng);
        if (roulette == 0.0f) continue;
        const vec3 w = sample_uniform_sphere(u1, u2);
        ++counters.rays;
        const SurfaceHit y = scene_.intersect(Ray{light.position, w, 0.0f, INFINITY});
        if (!y.valid) continue;
        const Material& material = scene_.scene().materials[size_t(y.material)];
        if (material.type == BrdfType::Mirror) continue;
        const vec3 albedo = material.albedo.eval(y.uv);
        if (glm::all(glm::equal(albedo, vec3(0.0f)))) continue;
        PointLitPoint p;
        // y is the light's first hit: visible from it.
        if (!point_lit_point(light, y, at, false, counters, &p)) continue;
        ++counters.rays;
        if (scene_.occluded(shadow_ray(at.x, p.to_y, p.distance))) continue;
        // f / pdf with f = albedo / pi E_L(y) x the path's factor from x to y (phase x
        // transmittance x cos_y / r^2; the roulette is not part of the light's path).
        const double weight =
            p.light_pdf * p.light_pdf / (p.light_pdf * p.light_pdf + p.walk_pdf * p.walk_pdf);
        sum += albedo * kInvPi * p.irradiance * float(p.walk_f / p.light_pdf * weight * roulette);
    }
    return sum;
}

void BakeEstimator::add_walk_surface_light(const SurfaceHit& hit, int chain, const vec3& throughput,
                                           const TexelWalk& texel, const WalkScatter& from,
                                           CounterRng& rng, BakeCounters& counters) const {
    // The walk scattered `chain` times since the texel and reached y: y's radiance towards it,
    // a diffuse vertex of the surface path (the same estimate an indirect segment takes).
    const Material& material = scene_.scene().materials[size_t(hit.material)];
    if (material.type == BrdfType::Mirror) return;
    const vec3 albedo_y = material.albedo.eval(hit.uv);
    if (glm::all(glm::equal(albedo_y, vec3(0.0f)))) return;
    const IrradianceParts at_y =
        vertex_irradiance(hit, albedo_y, texel.surface_light_depth, rng, counters);
    vec3 irradiance = at_y.total();
    if (surface_light_mis()) {
        // Each point light's part of E(y) is shared with point_lit_surface_light.
        for (const Light& light : scene_.scene().lights) {
            if (light.type != LightType::Point) continue;
            PointLitPoint p;
            if (!point_lit_point(light, hit, from, true, counters, &p)) continue;
            const double traced =
                p.light_pdf * p.light_pdf / (p.light_pdf * p.light_pdf + p.walk_pdf * p.walk_pdf);
            irradiance -= p.irradiance * float(traced);
        }
    }
    const vec3 arriving = throughput * albedo_y * kInvPi * irradiance;
    (chain == 1 ? texel.surface_light->single : texel.surface_light->multiple) += arriving;
}

}  // namespace freqlab
