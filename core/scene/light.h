// Lights of the scene model: a lat-long HDR environment map, a procedural sky (sun disk +
// zenith/horizon gradient, HDR), point, directional and quad area lights.
// Lat-long convention (z up): theta from +z (zenith), phi = atan2(y, x) turned by the map's
// rotation; u = phi / 2pi, v = theta / pi, row 0 at the zenith.
#pragma once

#include <memory>
#include <string>

#include "image/image_io.h"
#include "math/types.h"

namespace freqlab {

struct EnvironmentMap {
    std::string source;  // file path, or "generated:..." for test maps
    std::shared_ptr<const RgbImage> image;
    float rotation_deg = 0.0f;  // about +z
    float scale = 1.0f;

    vec3 eval(const vec3& direction) const;  // bilinear in the lat-long image
};

struct ProceduralSky {
    vec3 sun_direction = glm::normalize(vec3(0.4f, -0.3f, 0.6f));
    float sun_angular_radius_deg = 0.53f;
    vec3 sun_radiance{2.0e4f, 1.8e4f, 1.5e4f};
    vec3 zenith{0.25f, 0.45f, 1.0f};
    vec3 horizon{0.9f, 0.95f, 1.1f};
    vec3 ground{0.25f, 0.22f, 0.2f};

    vec3 eval(const vec3& direction) const;
};

enum class LightType { Environment, Sky, Point, Directional, Quad };
const char* to_string(LightType type);

struct Light {
    LightType type = LightType::Point;
    vec3 position{0.0f};       // Point
    vec3 intensity{1.0f};      // Point: W/sr; Directional: irradiance; Quad: radiance
    vec3 direction{0, 0, -1};  // Directional: direction the light travels
    vec3 corner{0.0f}, edge_u{1, 0, 0}, edge_v{0, 1, 0};  // Quad, emits on edge_u x edge_v side
    std::shared_ptr<const EnvironmentMap> environment;    // Environment
    ProceduralSky sky;                                    // Sky
};

}  // namespace freqlab
