#include "scene/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace freqlab {

CameraPose Camera::at(float time) const {
    CameraPose pose = keys.front().pose;
    if (keys.size() > 1 && time > keys.front().time) {
        if (time >= keys.back().time) {
            pose = keys.back().pose;
        } else {
            auto hi = std::upper_bound(keys.begin(), keys.end(), time,
                                       [](float t, const CameraKey& k) { return t < k.time; });
            auto lo = hi - 1;
            const float u = (time - lo->time) / (hi->time - lo->time);
            pose.position = glm::mix(lo->pose.position, hi->pose.position, u);
            pose.look_at = glm::mix(lo->pose.look_at, hi->pose.look_at, u);
            pose.up = glm::normalize(glm::mix(lo->pose.up, hi->pose.up, u));
            pose.fov_deg = glm::mix(lo->pose.fov_deg, hi->pose.fov_deg, u);
        }
    }
    if (orbit_rad_per_s != 0.0f) {
        const mat4 r = glm::rotate(mat4(1.0f), orbit_rad_per_s * time, vec3(0, 0, 1));
        pose.position = pose.look_at + vec3(r * vec4(pose.position - pose.look_at, 0.0f));
    }
    return pose;
}

CameraRayGenerator::CameraRayGenerator(const CameraPose& pose, int width, int height) {
    origin = pose.position;
    forward = glm::normalize(pose.look_at - pose.position);
    right = glm::normalize(glm::cross(forward, pose.up));
    up = glm::cross(right, forward);
    tan_half_fov = std::tan(0.5f * glm::radians(pose.fov_deg));
    aspect = float(width) / float(height);
}

vec3 CameraRayGenerator::direction(float u, float v) const {
    const float x = (2.0f * u - 1.0f) * tan_half_fov * aspect;
    const float y = (1.0f - 2.0f * v) * tan_half_fov;
    return glm::normalize(forward + x * right + y * up);
}

}  // namespace freqlab
