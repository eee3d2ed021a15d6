// The slab-bottom multiple-scattering table (volume/slab_bottom_multiple_scatter.h) against
// independent quadrature: the first bounce's fluence inside the slab and its ZH at the
// receiver in closed form along the ray, the second bounce's receiver radiance by nested
// adaptive quadrature, and the half-space as the thick-slab limit of the interior.
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>

#include "math/sh.h"
#include "volume/slab_bottom_multiple_scatter.h"

using namespace freqlab;
using boost::math::quadrature::gauss_kronrod;

namespace {

// Bounce-1 radiance at depth z of a slab of thickness Z, looking at cosine mu from the light
// axis (canonical, isotropic): the ray reaches the lit face (mu > 0) or the bottom (mu < 0).
double first_radiance(double z, double mu, double Z) {
    const double k = 1.0 - mu;
    const double t_max = mu > 0 ? z / mu : (Z - z) / -mu;
    return std::exp(-z) * -std::expm1(-k * t_max) / k / (4 * M_PI);
}

double first_fluence(double z, double Z, double tolerance = 1e-12) {
    auto f = [&](double mu) { return 2 * M_PI * first_radiance(z, mu, Z); };
    return gauss_kronrod<double, 31>::integrate(f, -1.0, 0.0, 10, tolerance) +
           gauss_kronrod<double, 31>::integrate(f, 0.0, 1.0, 10, tolerance);
}

// ZH coefficient l of a radiance L(mu) that vanishes for mu <= 0.
template <class F>
double zh_of(F&& radiance, int l) {
    auto f = [&](double mu) {
        double p[kImpulseOrder];
        legendre(kImpulseOrder, mu, p);
        return 2 * M_PI * radiance(mu) * std::sqrt((2.0 * l + 1) / (4 * M_PI)) * p[l];
    };
    return gauss_kronrod<double, 31>::integrate(f, 0.0, 1.0, 12, 1e-11);
}

}  // namespace

TEST(SlabBottom, FirstBounceMatchesClosedForms) {
    for (double Z : {0.01, 0.3, 1.0, 3.0, 12.0}) {
        const SlabBottomSolution s = solve_slab_bottom(Z, 2);
        // The interior fluence of bounce 1.
        for (size_t i = 0; i < s.z.size(); i += s.z.size() / 5) {
            const double want = first_fluence(s.z[i], Z);
            EXPECT_NEAR(s.phi[1][i], want, 2e-3 * want) << "Z " << Z << " z " << s.z[i];
        }
        // The receiver's ZH of bounce 1, every order that carries 0.1 % of the DC.
        auto radiance = [&](double mu) { return first_radiance(Z, mu, Z); };
        const double dc = zh_of(radiance, 0);
        for (int l = 0; l < kImpulseOrder; ++l) {
            const double want = zh_of(radiance, l);
            if (std::abs(want) < 1e-3 * dc) continue;
            EXPECT_NEAR(s.zh[1][size_t(l)], want, 2e-3 * std::abs(want) + 1e-5 * dc)
                << "Z " << Z << " l " << l;
        }
    }
}

TEST(SlabBottom, SecondBounceAtTheReceiverMatchesNestedQuadrature) {
    for (double Z : {0.2, 1.5}) {
        const SlabBottomSolution s = solve_slab_bottom(Z, 2);
        // L_2(mu) = 1 / (4 pi mu) int_0^Z e^{-(Z - z') / mu} phi_1(z') dz'.
        auto radiance = [&](double mu) {
            auto along = [&](double zp) {
                return std::exp(-(Z - zp) / mu) * first_fluence(zp, Z, 1e-9);
            };
            return gauss_kronrod<double, 15>::integrate(along, 0.0, Z, 5, 1e-7) / (4 * M_PI * mu);
        };
        // L_2 once per node of a fixed rule (panels graded towards mu = 0), projected on
        // every order there.
        using boost::math::quadrature::gauss;
        const auto& x = gauss<double, 20>::abscissa();
        const auto& w = gauss<double, 20>::weights();
        double want[3] = {};
        for (int p = 0; p < 8; ++p) {
            const double a = std::pow(p / 8.0, 2.0), b = std::pow((p + 1) / 8.0, 2.0);
            for (size_t i = 0; i < x.size(); ++i)
                for (double sign : {-1.0, 1.0}) {
                    const double mu = 0.5 * (a + b) + sign * 0.5 * (b - a) * x[i];
                    double leg[kImpulseOrder];
                    legendre(kImpulseOrder, mu, leg);
                    const double r = radiance(mu) * 2 * M_PI * w[i] * 0.5 * (b - a);
                    for (int l = 0; l < 3; ++l)
                        want[l] += r * std::sqrt((2.0 * l + 1) / (4 * M_PI)) * leg[l];
                }
        }
        for (int l = 0; l < 3; ++l)
            EXPECT_NEAR(s.zh[2][size_t(l)], want[l], 3e-3 * std::abs(s.zh[2][0]))
                << "Z " << Z << " l " << l;
    }
}

// The table serves bounces_in() like the half-space one, and sits below it: the slab has no
// medium under the receiver to send light back up.
TEST(SlabBottom, TableIsBelowTheHalfSpaceAndVanishesForThinSlabs) {
    const SlabMultipleScatter bottom = build_slab_bottom_multiple_scatter(4);
    const SlabMultipleScatter half(4);
    const HomogeneousMedium m{0.9, 0.1, 0.0};
    for (double d : {0.05, 0.5, 2.0, 8.0}) {
        const ZhVector a = bottom.bounces_in(m, d, 2, 4), b = half.bounces_in(m, d, 2, 4);
        EXPECT_GT(a[0], 0.0) << d;
        EXPECT_LT(a[0], b[0]) << d;
    }
    // Bounce 2 of a thin slab grows as Z^2 (two scattering events in a layer of thickness Z).
    const double r = bottom.canonical(2, 0.02)[0] / bottom.canonical(2, 0.01)[0];
    EXPECT_GT(r, 3.0);
    EXPECT_LT(r, 4.6);
}
