// Quadrature over the unit sphere for tests: a pdf's normalisation and its mass per chi-square
// bin.
#pragma once

#include <boost/math/quadrature/gauss.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "math/types.h"

namespace freqlab::test {

inline vec3 spherical(double cos_theta, double phi) {
    const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    return vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(cos_theta));
}

// Integral of f(direction) over a (cos theta, phi) rectangle: 20-point Gauss-Legendre in
// each variable on each of sub x sub cells (the lobes tested are smooth at that scale).
template <class F>
double integrate_sphere(F f, double c0 = -1, double c1 = 1, double p0 = 0, double p1 = 2 * M_PI,
                        int sub = 1) {
    double total = 0;
    for (int i = 0; i < sub; ++i)
        for (int j = 0; j < sub; ++j) {
            const double a0 = c0 + (c1 - c0) * i / sub, a1 = c0 + (c1 - c0) * (i + 1) / sub;
            const double b0 = p0 + (p1 - p0) * j / sub, b1 = p0 + (p1 - p0) * (j + 1) / sub;
            total += boost::math::quadrature::gauss<double, 20>::integrate(
                [&](double c) {
                    return boost::math::quadrature::gauss<double, 20>::integrate(
                        [&](double phi) { return f(spherical(c, phi)); }, b0, b1);
                },
                a0, a1);
        }
    return total;
}

// A (cos theta, phi) grid over [c0, c1] x [0, 2 pi): the bins of a chi-square test of sampled
// directions against their pdf.
struct DirectionBins {
    int cos_bins = 16, phi_bins = 32;
    double c0 = -1.0, c1 = 1.0;
    size_t size() const { return size_t(cos_bins * phi_bins); }
    size_t index(const vec3& w) const {
        const int ci = std::clamp(int((double(w.z) - c0) / (c1 - c0) * cos_bins), 0, cos_bins - 1);
        double phi = std::atan2(double(w.y), double(w.x));
        if (phi < 0) phi += 2 * M_PI;
        const int pi = std::clamp(int(phi / (2 * M_PI) * phi_bins), 0, phi_bins - 1);
        return size_t(ci * phi_bins + pi);
    }
    // n samples' expected count in each bin.
    template <class Pdf>
    std::vector<double> expected(Pdf pdf, int n) const {
        std::vector<double> out(size());
        for (int ci = 0; ci < cos_bins; ++ci)
            for (int pi = 0; pi < phi_bins; ++pi)
                out[size_t(ci * phi_bins + pi)] =
                    n * integrate_sphere(pdf, c0 + (c1 - c0) * ci / cos_bins,
                                         c0 + (c1 - c0) * (ci + 1) / cos_bins,
                                         2 * M_PI * pi / phi_bins, 2 * M_PI * (pi + 1) / phi_bins);
        return out;
    }
};

}  // namespace freqlab::test
