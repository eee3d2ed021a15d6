#include "volume/lightmap_preview.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace freqlab {

namespace {

// Bilinear between texel centres of an RGB (or scalar) layer; uv in texels.
vec3 sample_bilinear(const Layer& layer, int width, int height, vec2 uv) {
    return freqlab::sample_bilinear(layer.data.data(), layer.channels, width, height, uv);
}

}  // namespace

CameraPose orbit_pose(const CameraPose& pose, float yaw_deg, float pitch_deg, float zoom) {
    CameraPose p = pose;
    const vec3 offset = pose.position - pose.look_at;
    const float radius = glm::length(offset) / std::max(zoom, 1e-3f);
    const float yaw0 = std::atan2(offset.y, offset.x);
    const float pitch0 = std::asin(std::clamp(offset.z / glm::length(offset), -1.0f, 1.0f));
    const float yaw = yaw0 + glm::radians(yaw_deg);
    const float pitch = std::clamp(pitch0 + glm::radians(pitch_deg), -1.5f, 1.5f);
    p.position = pose.look_at + radius * vec3(std::cos(pitch) * std::cos(yaw),
                                              std::cos(pitch) * std::sin(yaw), std::sin(pitch));
    return p;
}

LayerSet render_lightmap_preview(const RayScene& rs, const CameraPose& pose, int width, int height,
                                 const std::vector<ObjectLightmap>& maps,
                                 const std::vector<LayerSet>& baked) {
    const Scene& scene = rs.scene();
    const LightmapLookup lookup(maps, scene.objects.size());
    LayerSet out(width, height);
    Layer& color = out.add("color", LayerKind::Color, 3,
                           "the lightmapped scene: lm_total on baked surfaces, an unlit albedo "
                           "preview elsewhere, the environment behind");
    Layer& irradiance = out.add("lm_irradiance", LayerKind::Color, 3, "the baked irradiance seen");
    Layer& inscatter = out.add("lm_inscatter", LayerKind::Color, 3,
                               "in-scattered irradiance (single + multiple) seen");
    Layer& valid = out.add("texel_valid", LayerKind::Categorical, 1,
                           "the nearest texel's state (empty where no lightmap is seen)");
    valid.legend = texel_state_legend();
    Layer& texel = out.add("lightmap_texel", LayerKind::Continuous, 3,
                           "x, y of the nearest texel and the lightmap's index (-1: none)");
    // Impulse's bakes: how many texels the nearest texel's Monte Carlo terms were averaged over
    // (few: they rest on few samples, weighted by 1 / rate).
    const bool windowed = std::any_of(baked.begin(), baked.end(), [](const LayerSet& l) {
        return l.find("texel_mc_window") != nullptr;
    });
    Layer* window = windowed ? &out.add("texel_mc_window", LayerKind::Continuous, 1,
                                        "texels the nearest texel's Monte Carlo terms were "
                                        "averaged over (bake.texel_mc_radius)")
                             : nullptr;
    const CameraRayGenerator gen(pose, width, height);
    tbb::parallel_for(0, height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            const vec3 d = gen.direction((x + 0.5f) / width, (y + 0.5f) / height);
            const SurfaceHit hit = rs.intersect(Ray{gen.origin, d, 0.0f, INFINITY});
            const size_t i = size_t(y) * width + x;
            for (int c = 0; c < 3; ++c) texel.data[i * 3 + c] = -1.0f;
            if (!hit.valid) {
                const vec3 bg = rs.background(d);
                for (int c = 0; c < 3; ++c) color.data[i * 3 + c] = bg[c];
                continue;
            }
            const int m = lookup.find(hit.object, hit.primitive);
            if (m < 0) {
                const Material& mat = scene.materials[size_t(hit.material)];
                const vec3 a = mat.albedo.eval(hit.uv) *
                               (0.2f + 0.8f * std::abs(glm::dot(hit.shading_normal, d)));
                for (int c = 0; c < 3; ++c) color.data[i * 3 + c] = a[c];
                continue;
            }
            const ObjectLightmap& map = maps[size_t(m)];
            const LayerSet& layers = baked[size_t(m)];
            vec2 uv;
            if (!lightmap_uv(rs, map, hit, &uv)) continue;
            const vec3 total = sample_bilinear(layers.get("lm_total"), map.width, map.height, uv);
            const vec3 e = sample_bilinear(layers.get("lm_irradiance"), map.width, map.height, uv);
            const vec3 s1 =
                sample_bilinear(layers.get("lm_inscatter_single"), map.width, map.height, uv);
            const vec3 s2 =
                sample_bilinear(layers.get("lm_inscatter_multiple"), map.width, map.height, uv);
            for (int c = 0; c < 3; ++c) {
                color.data[i * 3 + c] = total[c];
                irradiance.data[i * 3 + c] = e[c];
                inscatter.data[i * 3 + c] = s1[c] + s2[c];
            }
            const int tx = std::clamp(int(uv.x), 0, map.width - 1);
            const int ty = std::clamp(int(uv.y), 0, map.height - 1);
            valid.data[i] = layers.get("texel_valid").data[size_t(ty) * map.width + tx];
            if (const Layer* w = window ? layers.find("texel_mc_window") : nullptr)
                window->data[i] = w->data[size_t(ty) * map.width + tx];
            texel.data[i * 3 + 0] = float(tx);
            texel.data[i * 3 + 1] = float(ty);
            texel.data[i * 3 + 2] = float(m);
        }
    });
    return out;
}

}  // namespace freqlab
