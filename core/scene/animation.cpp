#include "scene/animation.h"

#include <algorithm>

#include <glm/gtc/matrix_transform.hpp>

namespace freqlab {

mat4 Trs::matrix() const {
    return glm::translate(mat4(1.0f), translate) * glm::mat4_cast(rotate) *
           glm::scale(mat4(1.0f), scale);
}

mat4 Animation::at(float time) const {
    Trs trs = base;
    if (!keys.empty()) {
        if (time <= keys.front().time) {
            trs = keys.front().value;
        } else if (time >= keys.back().time) {
            trs = keys.back().value;
        } else {
            auto hi = std::upper_bound(keys.begin(), keys.end(), time,
                                       [](float t, const TrsKey& k) { return t < k.time; });
            auto lo = hi - 1;
            const float u = (time - lo->time) / (hi->time - lo->time);
            trs.translate = glm::mix(lo->value.translate, hi->value.translate, u);
            trs.rotate = glm::slerp(lo->value.rotate, hi->value.rotate, u);
            trs.scale = glm::mix(lo->value.scale, hi->value.scale, u);
        }
    }
    const mat4 spin = glm::rotate(mat4(1.0f), spin_rad_per_s * time, spin_axis);
    return glm::translate(mat4(1.0f), trs.translate) * glm::mat4_cast(trs.rotate) * spin *
           glm::scale(mat4(1.0f), trs.scale);
}

vec3 Animation::velocity_of(const vec3& p, float t) const {
    if (is_static()) return vec3(0.0f);
    const float h = 1e-3f;
    const vec4 local = glm::inverse(at(t)) * vec4(p, 1.0f);
    return (vec3(at(t + h) * local) - vec3(at(t - h) * local)) / (2.0f * h);
}

}  // namespace freqlab
