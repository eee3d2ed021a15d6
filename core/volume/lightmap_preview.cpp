#include "volume/lightmap_preview.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace freqlab {

namespace {

// Bilinear between texel centres of an RGB (or scalar) layer; uv in texels.
vec3 sample_bilinear(const Layer& layer, int width, int height, vec2 uv) {
    const float fx = uv.x - 0.5f, fy = uv.y - 0.5f;
    const int x0 = std::clamp(int(std::floor(fx)), 0, width - 1);
    const int y0 = std::clamp(int(std::floor(fy)), 0, height - 1);
    const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
    const float wx = std::clamp(fx - float(x0), 0.0f, 1.0f),
                wy = std::clamp(fy - float(y0), 0.0f, 1.0f);
    auto at = [&](int x, int y) {
        vec3 v(0.0f);
        for (int c = 0; c < std::min(3, layer.channels); ++c) v[c] = layer.at(width, x, y, c);
        return v;
    };
    return (1 - wy) * ((1 - wx) * at(x0, y0) + wx * at(x1, y0)) +
           wy * ((1 - wx) * at(x0, y1) + wx * at(x1, y1));
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
    std::vector<int> map_of(scene.objects.size(), -1);
    for (size_t i = 0; i < maps.size(); ++i) map_of[size_t(maps[i].object)] = int(i);
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
            const int m = map_of[size_t(hit.object)];
            if (m < 0 || hit.primitive < 0 ||
                size_t(hit.primitive) * 3 + 2 >= maps[size_t(m)].triangle_uv.size()) {
                const Material& mat = scene.materials[size_t(hit.material)];
                const vec3 a = mat.albedo.eval(hit.uv) *
                               (0.2f + 0.8f * std::abs(glm::dot(hit.shading_normal, d)));
                for (int c = 0; c < 3; ++c) color.data[i * 3 + c] = a[c];
                continue;
            }
            const ObjectLightmap& map = maps[size_t(m)];
            const LayerSet& layers = baked[size_t(m)];
            // Barycentrics of the hit in the triangle (world space, the instance at time 0).
            const SceneObject& obj = scene.objects[size_t(hit.object)];
            const uvec3 tri = obj.mesh->triangles[size_t(hit.primitive)];
            const mat4& to_world = rs.object_to_world(hit.object);
            const vec3 a = vec3(to_world * vec4(obj.mesh->positions[tri.x], 1.0f));
            const vec3 b = vec3(to_world * vec4(obj.mesh->positions[tri.y], 1.0f));
            const vec3 c3 = vec3(to_world * vec4(obj.mesh->positions[tri.z], 1.0f));
            const vec3 n = glm::cross(b - a, c3 - a);
            const float area2 = glm::dot(n, n);
            if (area2 <= 0.0f) continue;
            const float wb = glm::dot(glm::cross(hit.position - a, c3 - a), n) / area2;
            const float wc = glm::dot(glm::cross(b - a, hit.position - a), n) / area2;
            const float wa = 1.0f - wb - wc;
            const vec2* t = &map.triangle_uv[size_t(hit.primitive) * 3];
            const vec2 uv = wa * t[0] + wb * t[1] + wc * t[2];
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
            texel.data[i * 3 + 0] = float(tx);
            texel.data[i * 3 + 1] = float(ty);
            texel.data[i * 3 + 2] = float(m);
        }
    });
    return out;
}

}  // namespace freqlab
