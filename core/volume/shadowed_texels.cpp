#include "volume/shadowed_texels.h"

#include <limits>

#include "scene/scene.h"
#include "volume/lightmap_baker.h"

namespace freqlab {

BakeKeyLight bake_key_light(const RayScene& scene) {
    BakeKeyLight best;
    const vec3 centre = 0.5f * (scene.bounds_min() + scene.bounds_max());
    float best_irradiance = 0.0f;
    const std::vector<Light>& lights = scene.scene().lights;
    for (size_t i = 0; i < lights.size(); ++i) {
        const Light& light = lights[i];
        if (light.type != LightType::Directional && light.type != LightType::Point &&
            light.type != LightType::Quad)
            continue;
        // At normal incidence and whatever side of a quad the centre is on.
        float e = luminance(light.intensity);
        if (light.type != LightType::Directional) {
            const vec3 position = light.type == LightType::Quad
                                      ? light.corner + 0.5f * (light.edge_u + light.edge_v)
                                      : light.position;
            const vec3 to = position - centre;
            const float area = light.type == LightType::Quad
                                   ? glm::length(glm::cross(light.edge_u, light.edge_v))
                                   : 1.0f;
            e *= area / std::max(glm::dot(to, to), 1e-6f);
        }
        if (e > best_irradiance) {
            best_irradiance = e;
            best.found = true;
            best.light = int(i);
        }
    }
    return best;
}

std::vector<uint8_t> shadowed_texels(const RayScene& scene, const ObjectLightmap& map,
                                     const BakeKeyLight& key) {
    std::vector<uint8_t> out(map.texels.size(), 0);
    if (!key.found) return out;
    const Light& light = scene.scene().lights[size_t(key.light)];
    for (size_t i = 0; i < map.texels.size(); ++i) {
        const LightmapTexel& t = map.texels[i];
        if (t.state != TexelState::Valid) continue;
        const LightSample s = sample_light(light, t.position, vec2(0.5f));
        if (!s.valid || glm::dot(s.direction, t.normal) <= 0.0f) continue;
        out[i] =
            scene.occluded(shadow_ray(spawn_point(t.position, t.normal), s.direction, s.distance))
                ? 1
                : 0;
    }
    return out;
}

RegionComparison compare_region(const LayerSet& test, const LayerSet& ref,
                                const std::vector<uint8_t>& only) {
    RegionComparison r;
    const LightmapError e = compare_lightmaps(test, ref, "lm_irradiance", &only);
    r.texels = e.texels;
    r.irradiance_relmse = e.relmse;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (r.texels == 0) {
        r.irradiance_ratio = r.inscatter_ratio = nan;
        return r;
    }
    const double test_e = valid_texel_luminance_sum(test, "lm_irradiance", &only);
    const double ref_e = valid_texel_luminance_sum(ref, "lm_irradiance", &only);
    auto inscatter = [&](const LayerSet& l) {
        return valid_texel_luminance_sum(l, "lm_inscatter_single", &only) +
               valid_texel_luminance_sum(l, "lm_inscatter_multiple", &only);
    };
    const double test_s = inscatter(test), ref_s = inscatter(ref);
    r.test_irradiance = test_e / double(r.texels);
    r.ref_irradiance = ref_e / double(r.texels);
    r.test_inscatter = test_s / double(r.texels);
    r.ref_inscatter = ref_s / double(r.texels);
    r.irradiance_ratio = ref_e > 0.0 ? test_e / ref_e : nan;
    r.inscatter_ratio = ref_s > 0.0 ? test_s / ref_s : nan;
    return r;
}

RegionComparison combine_regions(const std::vector<RegionComparison>& parts) {
    RegionComparison all;
    double rel = 0.0, te = 0.0, re = 0.0, ts = 0.0, rs = 0.0;
    for (const RegionComparison& p : parts) {
        const double n = double(p.texels);
        all.texels += p.texels;
        rel += p.irradiance_relmse * n;
        te += p.test_irradiance * n, re += p.ref_irradiance * n;
        ts += p.test_inscatter * n, rs += p.ref_inscatter * n;
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (all.texels == 0) {
        all.irradiance_ratio = all.inscatter_ratio = nan;
        return all;
    }
    const double n = double(all.texels);
    all.irradiance_relmse = rel / n;
    all.test_irradiance = te / n, all.ref_irradiance = re / n;
    all.test_inscatter = ts / n, all.ref_inscatter = rs / n;
    all.irradiance_ratio = re > 0.0 ? te / re : nan;
    all.inscatter_ratio = rs > 0.0 ? ts / rs : nan;
    return all;
}

}  // namespace freqlab
