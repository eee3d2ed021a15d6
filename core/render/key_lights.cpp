#include "render/key_lights.h"

#include <algorithm>

namespace freqlab {

std::vector<KeyLight> key_lights(const RayScene& rs) {
    std::vector<KeyLight> keys;
    if (const EnvironmentMap* env = rs.environment()) {
        const RgbImage& img = env->image();
        double mean = 0.0;
        float best = -1.0f;
        int bx = 0, by = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const float l = luminance(img.at(x, y));
                mean += l;
                if (l > best) best = l, bx = x, by = y;
            }
        mean /= double(img.width) * img.height;
        if (best > 20.0 * mean && best > 0.0f) {
            KeyLight k;
            k.direction = glm::normalize(
                env->uv_to_direction(vec2((bx + 0.5f) / img.width, (by + 0.5f) / img.height)));
            keys.push_back(k);
        }
    }
    for (const Light& l : rs.scene().lights) {
        if (keys.size() >= 3) break;
        if (l.type == LightType::Point) {
            KeyLight k;
            k.distant = false;
            k.position = l.position;
            keys.push_back(k);
        } else if (l.type == LightType::Directional) {
            KeyLight k;
            k.direction = -l.direction;
            keys.push_back(k);
        }
    }
    return keys;
}

uint8_t key_light_mask(const RayScene& rs, const std::vector<KeyLight>& keys, const vec3& p,
                       const vec3& n) {
    uint8_t mask = 0;
    const float scale =
        std::max(1.0f, std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))));
    const vec3 o = p + n * (1e-3f * scale);
    for (size_t k = 0; k < keys.size() && k < 3; ++k) {
        Ray ray;
        ray.origin = o;
        if (keys[k].distant) {
            ray.direction = keys[k].direction;
            ray.tfar = INFINITY;
        } else {
            const vec3 to = keys[k].position - o;
            const float d = glm::length(to);
            if (d <= 0.0f) continue;
            ray.direction = to / d;
            ray.tfar = d * (1.0f - 1e-4f);
        }
        if (!rs.occluded(ray)) mask |= uint8_t(1u << k);
    }
    return mask;
}

}  // namespace freqlab
