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
            Light sun;  // the sun as a directional light (only its direction is read)
            sun.type = LightType::Directional;
            sun.direction = -glm::normalize(
                env->uv_to_direction(vec2((bx + 0.5f) / img.width, (by + 0.5f) / img.height)));
            keys.push_back(sun);
        }
    }
    for (const Light& l : rs.scene().lights) {
        if (keys.size() >= 3) break;
        if (l.type == LightType::Point || l.type == LightType::Directional) keys.push_back(l);
    }
    return keys;
}

uint8_t key_light_mask(const RayScene& rs, const std::vector<KeyLight>& keys, const vec3& p,
                       const vec3& n) {
    uint8_t mask = 0;
    const vec3 o = spawn_point(p, n);
    for (size_t k = 0; k < keys.size() && k < 3; ++k) {
        const LightSample s = sample_light(keys[k], o, vec2(0.0f));
        if (s.valid && !rs.occluded(shadow_ray(o, s.direction, s.distance)))
            mask |= uint8_t(1u << k);
    }
    return mask;
}

}  // namespace freqlab
