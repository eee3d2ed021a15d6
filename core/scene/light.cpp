#include "scene/light.h"

#include <algorithm>
#include <cmath>

namespace freqlab {

const char* to_string(LightType type) {
    switch (type) {
        case LightType::Environment:
            return "envmap";
        case LightType::Sky:
            return "sky";
        case LightType::Point:
            return "point";
        case LightType::Directional:
            return "directional";
        case LightType::Quad:
            return "quad";
    }
    return "?";
}

vec3 EnvironmentMap::eval(const vec3& d) const {
    const float theta = std::acos(std::clamp(d.z, -1.0f, 1.0f));
    float phi = std::atan2(d.y, d.x) - glm::radians(rotation_deg);
    phi -= kTwoPi * std::floor(phi / kTwoPi);
    const int w = image->width, h = image->height;
    const float x = phi / kTwoPi * w - 0.5f, y = theta / kPi * h - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const float fx = x - x0, fy = y - y0;
    auto texel = [&](int xi, int yi) {
        xi = ((xi % w) + w) % w;
        yi = std::clamp(yi, 0, h - 1);
        return image->at(xi, yi);
    };
    return scale * glm::mix(glm::mix(texel(x0, y0), texel(x0 + 1, y0), fx),
                            glm::mix(texel(x0, y0 + 1), texel(x0 + 1, y0 + 1), fx), fy);
}

vec3 ProceduralSky::eval(const vec3& d) const {
    const float cos_sun = glm::dot(d, sun_direction);
    if (cos_sun >= std::cos(glm::radians(sun_angular_radius_deg))) return sun_radiance;
    if (d.z < 0.0f) return ground;
    // Gradient from the horizon to the zenith, brighter around the sun (a soft aureole).
    const float t = std::pow(1.0f - d.z, 3.0f);
    const float aureole = 0.5f * std::pow(std::max(cos_sun, 0.0f), 32.0f);
    return glm::mix(zenith, horizon, t) * (1.0f + aureole);
}

}  // namespace freqlab
