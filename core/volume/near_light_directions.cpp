#include "volume/near_light_directions.h"

#include <cmath>

#include "math/sampling.h"

namespace freqlab {

namespace {
// The disk's radius over the distance to the light: directions within atan(k) = 27 degrees of
// the light. Any k > 0 bounds the variance near the light; a wide cone wastes directions on
// light that the phase function finds as well.
constexpr double kDiskRadiusOverDistance = 0.5;
}  // namespace

NearLightDirections::NearLightDirections(const std::vector<Light>& lights, float fraction)
    : fraction_(fraction) {
    if (!(fraction > 0.0f)) return;
    for (const Light& light : lights)
        if (light.type == LightType::Point) lights_.push_back(light.position);
}

// With R = k |L - x|, the disk point at radius rho = R u1 is seen at tan(theta) = k u1 from
// the axis towards the light: a cone whose tangent is uniform, density 1 / (2 pi k cos^2
// sin) in solid angle (1 / (2 pi rho R) in the disk times r^2 / cos, with r = |L - x| / cos).
bool sample_towards_point(const vec3& x, const vec3& light, float u1, float u2, vec3* dir) {
    const vec3 to_light = light - x;
    const float d = glm::length(to_light);
    if (!(d > 0.0f)) return false;
    const float tan_t = float(kDiskRadiusOverDistance) * u1, phi = kTwoPi * u2;
    *dir = Frame(to_light / d).to_world(vec3(tan_t * std::cos(phi), tan_t * std::sin(phi), 1.0f));
    *dir = glm::normalize(*dir);
    return true;
}

double towards_point_pdf(const vec3& x, const vec3& light, const vec3& dir) {
    const glm::dvec3 to_light = glm::dvec3(light) - glm::dvec3(x);
    const double d = glm::length(to_light);
    if (!(d > 0.0)) return 0.0;
    const glm::dvec3 axis = to_light / d, w(dir);
    const double cos_t = glm::dot(w, axis), sin_t = glm::length(glm::cross(w, axis));
    if (!(cos_t > 0.0) || !(sin_t < kDiskRadiusOverDistance * cos_t) || !(sin_t > 0.0)) return 0.0;
    return 1.0 / (2.0 * kPiD * kDiskRadiusOverDistance * cos_t * cos_t * sin_t);
}

bool NearLightDirections::sample(const vec3& x, float u_pick, float u1, float u2, vec3* dir) const {
    const size_t i = std::min(lights_.size() - 1, size_t(double(u_pick) * double(lights_.size())));
    return sample_towards_point(x, lights_[i], u1, u2, dir);
}

double NearLightDirections::pdf(const vec3& x, const vec3& dir) const {
    double sum = 0.0;
    for (const vec3& light : lights_) sum += towards_point_pdf(x, light, dir);
    return sum / double(lights_.size());
}

bool CosineAndPointDirections::sample(float u1, float u2, vec3* w, double* weight) const {
    if (u1 < kPointFraction) {
        if (!sample_towards_point(x_, point_, u1 / kPointFraction, u2, w)) return false;
    } else {
        const vec3 local = sample_cosine_hemisphere(
            std::min((u1 - kPointFraction) / (1.0f - kPointFraction), 0.99999994f), u2);
        *w = Frame(n_).to_world(local);
    }
    const double cos_n = glm::dot(*w, n_);
    if (!(cos_n > 1e-6)) return false;
    const double pdf = (1.0 - kPointFraction) * cos_n * kInvPi +
                       kPointFraction * towards_point_pdf(x_, point_, *w);
    *weight = cos_n / pdf;
    return std::isfinite(*weight);
}

}  // namespace freqlab
