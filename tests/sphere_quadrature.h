// Quadrature over the unit sphere for tests: a pdf's normalisation and its mass per chi-square
// bin.
#pragma once

#include <boost/math/quadrature/gauss.hpp>

#include <algorithm>
#include <cmath>

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

}  // namespace freqlab::test
