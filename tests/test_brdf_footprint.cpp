// Eq. 4.2 (issue "Method A, part 1", acceptance 3): Var[e] against direct quadrature for e in
// (3, 1e5] to 1e-6 relative, and no NaN/Inf for any exponent or roughness.
#include <gtest/gtest.h>

#include <boost/math/quadrature/tanh_sinh.hpp>

#include <cmath>

#include "freq/brdf_footprint.h"

using namespace freqlab;

TEST(BrdfFootprint, VarianceMatchesQuadrature) {
    boost::math::quadrature::tanh_sinh<double> integrator;
    for (double e : {3.05, 3.5, 4.0, 7.3, 12.0, 50.0, 333.0, 2000.0, 1e4, 1e5}) {
        // t = cot(psi) maps the heavy tail (t^(2-e) for e near 3) to an integrable singularity
        // at psi = 0, where sin(psi) is exact, which tanh-sinh handles:
        // Var = 2 int_0^{pi/2} cos^2(psi) sin^(e-4)(psi) dpsi (exp/log: no overflow).
        const double q =
            2.0 * integrator.integrate(
                      [&](double psi) {
                          const double sn = std::sin(psi), c = std::cos(psi);
                          return sn > 0 ? c * c * std::exp((e - 4.0) * std::log(sn)) : 0.0;
                      },
                      0.0, M_PI / 2, 1e-14);
        EXPECT_NEAR(phong_variance(e), q, 1e-6 * q) << "e = " << e;
    }
}

TEST(BrdfFootprint, FiniteForEveryExponentAndRoughness) {
    for (double e : {1e-9, 0.5, 2.999, 3.0, 3.0001, 1e6, 1e12}) {
        Material m;
        m.type = BrdfType::Phong;
        m.phong_exponent = float(e);
        const BrdfFootprint f = brdf_footprint(m);
        EXPECT_TRUE(std::isfinite(f.sigma)) << e;
        EXPECT_TRUE(std::isfinite(f.query_radius())) << e;
        EXPECT_EQ(f.whole_hemisphere, e <= 3.0) << e;
    }
    for (double alpha : {1e-6, 0.01, 0.3, 0.7, 0.99, 1.0})
        for (BrdfType t : {BrdfType::Beckmann, BrdfType::Ggx}) {
            Material m;
            m.type = t;
            m.roughness = float(alpha);
            const BrdfFootprint f = brdf_footprint(m);
            EXPECT_TRUE(std::isfinite(f.sigma) && std::isfinite(f.query_radius())) << alpha;
        }
    // Narrower lobes for larger exponents, and the Phong-equivalent mapping round trip.
    EXPECT_GT(phong_variance(10.0), phong_variance(100.0));
    EXPECT_NEAR(phong_exponent_of_roughness(std::sqrt(2.0 / (2.0 + 48.0))), 48.0, 1e-9);
    Material lambert;
    EXPECT_TRUE(brdf_footprint(lambert).whole_hemisphere);
}
