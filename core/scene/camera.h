// A pinhole camera, keyframed over time or orbiting a centre at a constant rate.
#pragma once

#include <vector>

#include "math/types.h"

namespace freqlab {

struct CameraPose {
    vec3 position{0.0f, -5.0f, 1.0f};
    vec3 look_at{0.0f};
    vec3 up{0.0f, 0.0f, 1.0f};
    float fov_deg = 40.0f;  // vertical field of view
};

struct CameraKey {
    float time = 0.0f;
    CameraPose pose;
};

struct Camera {
    std::vector<CameraKey> keys;  // at least one; sorted by time
    // Orbit: when orbit_rad_per_s != 0 the position turns about the vertical axis through
    // look_at, starting from the keyed position.
    float orbit_rad_per_s = 0.0f;

    CameraPose at(float time) const;
    bool is_static() const { return keys.size() < 2 && orbit_rad_per_s == 0.0f; }
};

// Orthonormal camera frame and the ray through a film point (u, v in [0,1]^2, v down).
struct CameraRayGenerator {
    CameraRayGenerator(const CameraPose& pose, int width, int height);
    vec3 origin;
    vec3 direction(float u, float v) const;
    vec3 forward, right, up;
    float tan_half_fov, aspect;
};

}  // namespace freqlab
