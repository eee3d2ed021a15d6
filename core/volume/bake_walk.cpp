// The walks through the real media (BakeEstimator, bake_estimators.h): VPT's path from a
// receiver (method vpt, and impulse's texel walk for its multiple scattering and other
// surfaces' light, issue "Method B, part 3"): exact free flights, NEE at every scattering
// event, point lights in media by equiangular sampling along every segment
// (point_lights_along), directions by the phase function mixed with the cone past a point
// light (sample_walk_direction, near_light_directions.h), Russian roulette after 4 events.
//
// | parameter            | meaning                                                        |
// |----------------------|----------------------------------------------------------------|
// | near_light_fraction  | bake.near_light_fraction: directions aimed past a point light  |
#include <cmath>
#include <limits>

#include "math/sampling.h"
#include "math/sh.h"
#include "volume/bake_estimators.h"

namespace freqlab {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace

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
        std::isfinite(t_end) && t_end > 0.0 ? distant_strength_ * float(t_end) : 0.0f, keep);
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

IrradianceParts BakeEstimator::texel_walk_from(const vec3& p, const vec3& n, CounterRng& rng,
                                               BakeCounters& counters,
                                               const TexelWalk& texel) const {
    // Cosine-sampled: irradiance = pi x radiance.
    const vec3 local = sample_cosine_hemisphere(rng.next_float(), rng.next_float());
    if (local.z <= 1e-6f) return IrradianceParts{};
    return walk(origin(p, n), Frame(n).to_world(local), vec3(kPi), rng, counters, &texel);
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
            if (!media_.empty()) c = media_.sample_forced_collision(pos, dir, t_max, rng, &forced);
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

}  // namespace freqlab
