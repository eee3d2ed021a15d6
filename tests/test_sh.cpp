// SH / ZH against quadrature (issue "Method B, part 1", acceptance 1): orthonormality, ZH
// rotation vs the numerical projection of the rotated function, the O(N) double product vs
// the full SH dot product, and the clamped cosine.
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss.hpp>

#include <cmath>
#include <functional>
#include <vector>

#include "math/rng.h"
#include "math/sh.h"

using namespace freqlab;
using glm::dvec3;

namespace {

constexpr int kOrder = 11;  // method B's tables
constexpr int kN = kOrder * kOrder;

// Integral over the sphere of f(w) with Gauss-Legendre in cos(theta) (exact for polynomials of
// degree < 2 * 32) and the trapezoid rule in phi (exact for trigonometric degree < 64).
double integrate_sphere(const std::function<double(const dvec3&)>& f) {
    using boost::math::quadrature::gauss;
    const int n_phi = 64;
    return gauss<double, 32>::integrate(
        [&](double z) {
            const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
            double sum = 0;
            for (int k = 0; k < n_phi; ++k) {
                const double phi = 2 * M_PI * (k + 0.5) / n_phi;
                sum += f(dvec3(s * std::cos(phi), s * std::sin(phi), z));
            }
            return sum * 2 * M_PI / n_phi;
        },
        -1.0, 1.0);
}

std::vector<double> project(const std::function<double(const dvec3&)>& f) {
    std::vector<double> coeffs(kN);
    for (int i = 0; i < kN; ++i)
        coeffs[size_t(i)] = integrate_sphere([&](const dvec3& w) {
            double y[kN];
            sh_eval(kOrder, w, y);
            return f(w) * y[i];
        });
    return coeffs;
}

std::vector<double> random_zh(uint64_t key) {
    CounterRng rng(key, 0, 0, 0);
    std::vector<double> z(kOrder);
    for (double& v : z) v = rng.next_double() * 2 - 1;
    return z;
}

dvec3 random_axis(uint64_t key) {
    CounterRng rng(key, 1, 0, 0);
    const double z = 1 - 2 * rng.next_double(), phi = 2 * M_PI * rng.next_double();
    const double s = std::sqrt(1 - z * z);
    return dvec3(s * std::cos(phi), s * std::sin(phi), z);
}

}  // namespace

TEST(SphericalHarmonics, OrthonormalByQuadrature) {
    // Gram matrix in one sweep over the quadrature points.
    std::vector<double> gram(size_t(kN) * kN, 0.0);
    using boost::math::quadrature::gauss;
    const int n_phi = 64;
    const auto& nodes = gauss<double, 32>::abscissa();
    const auto& weights = gauss<double, 32>::weights();
    for (size_t a = 0; a < nodes.size(); ++a)
        for (double z : {nodes[a], -nodes[a]}) {
            if (a == 0 && z < 0 && nodes[0] == 0.0) continue;  // the centre node once
            const double s = std::sqrt(1 - z * z);
            for (int k = 0; k < n_phi; ++k) {
                const double phi = 2 * M_PI * (k + 0.5) / n_phi;
                double y[kN];
                sh_eval(kOrder, dvec3(s * std::cos(phi), s * std::sin(phi), z), y);
                const double w = weights[a] * 2 * M_PI / n_phi;
                for (int i = 0; i < kN; ++i)
                    for (int j = 0; j < kN; ++j) gram[size_t(i) * kN + j] += w * y[i] * y[j];
            }
        }
    for (int i = 0; i < kN; ++i)
        for (int j = 0; j < kN; ++j)
            EXPECT_NEAR(gram[size_t(i) * kN + j], i == j ? 1.0 : 0.0, 1e-10) << i << "," << j;
}

TEST(SphericalHarmonics, ZonalIsTheM0Band) {
    // y_l^0 about +z is what zh_eval reconstructs.
    double y[kN];
    for (double z : {-0.9, -0.2, 0.0, 0.5, 0.99}) {
        sh_eval(kOrder, dvec3(std::sqrt(1 - z * z), 0, z), y);
        for (int l = 0; l < kOrder; ++l) {
            double e[kOrder] = {};
            e[l] = 1.0;
            EXPECT_NEAR(zh_eval(kOrder, e, z), y[sh_index(l, 0)], 1e-12);
        }
    }
}

TEST(SphericalHarmonics, ZhRotationMatchesNumericalProjection) {
    for (uint64_t key : {1u, 2u, 3u}) {
        const std::vector<double> zh = random_zh(key);
        const dvec3 axis = random_axis(key);
        double rotated[kN];
        zh_rotate(kOrder, zh.data(), axis, rotated);
        const std::vector<double> numeric =
            project([&](const dvec3& w) { return zh_eval(kOrder, zh.data(), glm::dot(w, axis)); });
        for (int i = 0; i < kN; ++i)
            EXPECT_NEAR(rotated[i], numeric[size_t(i)], 1e-8) << "coefficient " << i;
    }
}

TEST(SphericalHarmonics, ZhDoubleProductMatchesFullShDotProduct) {
    for (uint64_t key : {4u, 5u, 6u, 7u}) {
        const std::vector<double> g = random_zh(key), h = random_zh(key + 100);
        const dvec3 a = random_axis(key), b = random_axis(key + 100);
        double ga[kN], hb[kN];
        zh_rotate(kOrder, g.data(), a, ga);
        zh_rotate(kOrder, h.data(), b, hb);
        double full = 0;
        for (int i = 0; i < kN; ++i) full += ga[i] * hb[i];
        EXPECT_NEAR(zh_double_product(kOrder, g.data(), a, h.data(), b), full, 1e-10);
    }
    // And against the integral itself.
    const std::vector<double> g = random_zh(9), h = random_zh(10);
    const dvec3 a = random_axis(9), b = random_axis(10);
    const double integral = integrate_sphere([&](const dvec3& w) {
        return zh_eval(kOrder, g.data(), glm::dot(w, a)) *
               zh_eval(kOrder, h.data(), glm::dot(w, b));
    });
    EXPECT_NEAR(zh_double_product(kOrder, g.data(), a, h.data(), b), integral, 1e-10);
}

TEST(SphericalHarmonics, ClampedCosineByQuadrature) {
    double c[kOrder];
    zh_clamped_cosine(kOrder, c);
    using boost::math::quadrature::gauss;
    for (int l = 0; l < kOrder; ++l) {
        double e[kOrder] = {};
        e[l] = 1.0;
        // The kink at z = 0 is integrated exactly on [0, 1] alone.
        const double q = 2 * M_PI *
                         gauss<double, 32>::integrate(
                             [&](double z) { return z * zh_eval(kOrder, e, z); }, 0.0, 1.0);
        EXPECT_NEAR(c[l], q, 1e-12) << "l = " << l;
    }
    EXPECT_NEAR(c[0], std::sqrt(M_PI) / 2, 1e-14);
    EXPECT_NEAR(c[1], std::sqrt(M_PI / 3), 1e-14);
}
