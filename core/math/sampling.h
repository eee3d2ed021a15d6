// Sampling warps and the orthonormal frame used by every integrator (seed §1.3.4: importance
// sampling and MIS). Directions in a local Frame have z along the frame's normal.
#pragma once

#include <cmath>

#include "math/types.h"

namespace freqlab {

// Orthonormal basis around a unit vector (Duff et al. 2017's branchless construction).
struct Frame {
    vec3 t, b, n;
    Frame() : t(1, 0, 0), b(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const vec3& normal) : n(normal) {
        const float sign = std::copysign(1.0f, n.z);
        const float a = -1.0f / (sign + n.z);
        const float c = n.x * n.y * a;
        t = vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
        b = vec3(c, sign + n.y * n.y * a, -n.y);
    }
    vec3 to_local(const vec3& v) const {
        return vec3(glm::dot(v, t), glm::dot(v, b), glm::dot(v, n));
    }
    vec3 to_world(const vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

inline vec3 reflect_about(const vec3& v, const vec3& n) {
    return 2.0f * glm::dot(v, n) * n - v;
}

// Cosine-weighted hemisphere about +z: pdf = cos(theta) / pi.
inline vec3 sample_cosine_hemisphere(float u1, float u2) {
    const float r = std::sqrt(u1), phi = kTwoPi * u2;
    return vec3(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1)));
}
inline float cosine_hemisphere_pdf(float cos_theta) {
    return cos_theta > 0 ? cos_theta * kInvPi : 0.0f;
}

inline vec3 sample_uniform_sphere(float u1, float u2) {
    const float z = 1.0f - 2.0f * u1, r = std::sqrt(std::max(0.0f, 1.0f - z * z)),
                phi = kTwoPi * u2;
    return vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// Direction at angle alpha from +z with cos(alpha) distributed as cos^e (Phong lobe):
// pdf = (e + 1) / (2 pi) cos^e(alpha) over the hemisphere about +z.
inline vec3 sample_power_cosine(float e, float u1, float u2) {
    const float cos_a = std::pow(u1, 1.0f / (e + 1.0f));
    const float sin_a = std::sqrt(std::max(0.0f, 1.0f - cos_a * cos_a)), phi = kTwoPi * u2;
    return vec3(sin_a * std::cos(phi), sin_a * std::sin(phi), cos_a);
}
inline float power_cosine_pdf(float e, float cos_a) {
    return cos_a > 0 ? (e + 1.0f) / kTwoPi * std::pow(cos_a, e) : 0.0f;
}

// Veach's power heuristic (beta = 2) for strategy f with nf samples against g with ng.
// Straight-line code so that the integrator's sample loops vectorize; 0 when f <= 0 (or NaN),
// 1 when f^2 overflows.
inline float power_heuristic(float nf, float pdf_f, float ng, float pdf_g) {
    const float f = nf * pdf_f, g = ng * pdf_g, f2 = f * f;
    const float w = f2 / (f2 + g * g);
    return f > 0.0f ? (f2 <= 3.40282347e38f ? w : 1.0f) : 0.0f;
}

}  // namespace freqlab
