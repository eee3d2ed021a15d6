// The vector types of freqlab: GLM, single precision for geometry and radiance.
// World convention: right-handed, +z is up (the zenith of environment maps).
#pragma once

#include <cmath>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace freqlab {

using glm::ivec2;
using glm::ivec3;
using glm::mat3;
using glm::mat4;
using glm::quat;
using glm::uvec3;
using glm::vec2;
using glm::vec3;
using glm::vec4;

constexpr float kPi = 3.14159265358979323846f;
constexpr double kPiD = 3.14159265358979323846;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kTwoPi = 6.28318530717958647692f;

inline bool all_finite(const vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline float luminance(const vec3& c) {
    return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

}  // namespace freqlab
