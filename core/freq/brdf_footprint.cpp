#include "freq/brdf_footprint.h"

#include <cmath>
#include <limits>

namespace freqlab {

double phong_variance(double e) {
    if (!(e > 3.0)) return std::numeric_limits<double>::infinity();
    // lgamma keeps the ratio finite for exponents up to ~1e300 (G itself overflows near 171).
    return 0.5 * std::sqrt(3.14159265358979323846) *
           std::exp(std::lgamma(0.5 * (e - 3.0)) - std::lgamma(0.5 * e));
}

double phong_exponent_of_roughness(double alpha) {
    alpha = std::clamp(alpha, 1e-4, 1.0);
    return 2.0 / (alpha * alpha) - 2.0;
}

double BrdfFootprint::query_radius() const {
    return whole_hemisphere ? 0.5 * 3.14159265358979323846 : std::atan(3.0 * sigma);
}

BrdfFootprint brdf_footprint(const Material& m) {
    double e = 0.0;
    switch (m.type) {
        case BrdfType::Lambert:
            return BrdfFootprint{};
        case BrdfType::Mirror:
            return BrdfFootprint{false, 0.0};
        case BrdfType::Phong:
            e = m.phong_exponent;
            break;
        case BrdfType::Beckmann:
        case BrdfType::Ggx:
            e = phong_exponent_of_roughness(m.roughness);
            break;
    }
    const double v = phong_variance(e);
    if (!std::isfinite(v)) return BrdfFootprint{};
    return BrdfFootprint{false, std::sqrt(v)};
}

}  // namespace freqlab
