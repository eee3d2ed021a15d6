// Sampling warps and the orthonormal frame used by every integrator (seed §1.3.4: importance
// sampling and MIS). Directions in a local Frame have z along the frame's normal.
#pragma once

#include <algorithm>
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

// Henyey-Greenstein phase function of the cosine between the propagation directions before
// and after a scattering event; integrates to 1 over the sphere (seed, Deuxieme article §4.5).
inline double hg_phase(double g, double cos_theta) {
    const double denom = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * 3.14159265358979323846 * denom * std::sqrt(denom));
}

// A cosine distributed as hg_phase(g, cos) x 2 pi (the inverse of its CDF).
inline float sample_hg_cos(float g, float u) {
    if (std::abs(g) < 1e-3f) return 1.0f - 2.0f * u;
    const float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u);
    return std::clamp((1.0f + g * g - s * s) / (2.0f * g), -1.0f, 1.0f);
}
// A direction whose cosine with `axis` follows HG(g): where light came from before it was
// scattered into `axis`'s direction of travel reversed.
inline vec3 sample_hg_direction(float g, const vec3& axis, float u1, float u2) {
    const float cos_t = sample_hg_cos(g, u1);
    const float sin_t = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
    const float phi = kTwoPi * u2;
    return Frame(axis).to_world(vec3(sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t));
}

// Equiangular sampling of a distance t in [t0, t1] along a ray for a point at signed distance
// `delta` along it (closest approach) and `h` > 0 from it: pdf(t) = h / ((b - a) r(t)^2),
// proportional to 1 / r^2 (Kulla & Fajardo 2012). t1 may be infinite. False when the range
// is empty.
struct EquiangularSample {
    double t = 0.0, pdf = 0.0;
};
inline bool sample_equiangular(double delta, double h, double t0, double t1, double u,
                               EquiangularSample* out) {
    const double a = std::atan2(t0 - delta, h);
    const double b = std::isfinite(t1) ? std::atan2(t1 - delta, h) : 1.57079632679489661923;
    if (!(b > a) || !(h > 0.0)) return false;
    const double theta = a + u * (b - a);
    out->t = delta + h * std::tan(theta);
    const double r2 = h * h + (out->t - delta) * (out->t - delta);
    out->pdf = h / ((b - a) * r2);
    return true;
}
inline double equiangular_pdf(double delta, double h, double t0, double t1, double t) {
    const double a = std::atan2(t0 - delta, h);
    const double b = std::isfinite(t1) ? std::atan2(t1 - delta, h) : 1.57079632679489661923;
    if (!(b > a) || t < t0 || t > t1) return 0.0;
    return h / ((b - a) * (h * h + (t - delta) * (t - delta)));
}

// A distance in [0, t_end] with pdf sigma e^{-sigma t} / (1 - e^{-sigma t_end}) (free flight
// conditioned on a collision inside the segment; t_end may be infinite). sigma > 0.
struct TruncatedExponentialSample {
    double t = 0.0, pdf = 0.0;
};
inline TruncatedExponentialSample sample_truncated_exponential(double sigma, double t_end,
                                                               double u) {
    const double mass = std::isfinite(t_end) ? -std::expm1(-sigma * t_end) : 1.0;
    const double tau = -std::log1p(-u * mass);
    return {tau / sigma, sigma * std::exp(-tau) / mass};
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
