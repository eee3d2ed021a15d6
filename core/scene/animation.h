// Rigid animation of objects: keyframed translate / rotate / scale (linear, slerp) plus an
// optional constant-rate spin about a local axis (rotors, turntables). Time is in seconds;
// a frame's time is frame / fps, never the wall clock.
#pragma once

#include <vector>

#include "math/types.h"

namespace freqlab {

struct Trs {
    vec3 translate{0.0f};
    quat rotate{1.0f, 0.0f, 0.0f, 0.0f};
    vec3 scale{1.0f};
    mat4 matrix() const;
};

struct TrsKey {
    float time = 0.0f;
    Trs value;
};

struct Animation {
    Trs base;                  // used when there are no keyframes
    std::vector<TrsKey> keys;  // sorted by time; clamped outside their span
    vec3 spin_axis{0.0f, 0.0f, 1.0f};
    float spin_rad_per_s = 0.0f;  // local-space spin applied inside the keyed transform

    bool is_static() const { return keys.size() < 2 && spin_rad_per_s == 0.0f; }
    // Object-to-world at time t: T * R * Spin(t) * S.
    mat4 at(float time) const;
    // World-space velocity (units per second) at time t of the material point that is at
    // `world_point` then: a central difference of the transform over +-1 ms.
    vec3 velocity_of(const vec3& world_point, float time) const;
};

}  // namespace freqlab
