// Multiple scattering of a directional emitter (volume/slab_multiple_scatter.h): the first
// composed bounce is the single-scattering table at g = 0; the second bounce's fluence against
// an independent nested adaptive quadrature from the closed-form first bounce; albedo weights.
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>

#include "shared_tables.h"
#include "volume/slab_multiple_scatter.h"

using namespace freqlab;

namespace {

// Bounce-1 radiance at depth s towards mu (canonical, isotropic), in closed form.
double first_bounce_radiance(double s, double mu) {
    const double k = 1.0 - mu;
    if (mu > 0) return std::exp(-s) * -std::expm1(-s * k / mu) / k / (4 * M_PI);
    return std::exp(-s) / k / (4 * M_PI);
}

double first_bounce_fluence(double z) {
    using boost::math::quadrature::gauss_kronrod;
    auto f = [&](double mu) { return 2 * M_PI * first_bounce_radiance(z, mu); };
    return gauss_kronrod<double, 31>::integrate(f, -1.0, 0.0, 10, 1e-11) +
           gauss_kronrod<double, 31>::integrate(f, 0.0, 1.0, 10, 1e-11);
}

// Second-bounce fluence at depth s: 2 pi int dmu int dt e^-t phi_1(s - t mu) / (4 pi).
double second_bounce_fluence(double s) {
    using boost::math::quadrature::gauss_kronrod;
    auto radiance = [&](double mu) {
        auto along = [&](double t) { return std::exp(-t) * first_bounce_fluence(s - t * mu); };
        const double t_max = mu > 0 ? s / mu : 60.0;
        return gauss_kronrod<double, 15>::integrate(along, 0.0, std::min(t_max, 60.0), 6, 1e-8) /
               (4 * M_PI);
    };
    auto f = [&](double mu) { return 2 * M_PI * radiance(mu); };
    return gauss_kronrod<double, 15>::integrate(f, -1.0, 0.0, 6, 1e-8) +
           gauss_kronrod<double, 15>::integrate(f, 0.0, 1.0, 6, 1e-8);
}

}  // namespace

TEST(SlabMultipleScatter, FirstBounceEqualsSingleScatteringTable) {
    const ImpulseTables& t = test_support::shared_impulse_tables();
    const HomogeneousMedium m{1.0, 0.0, 0.0};
    for (double s : {0.01, 0.3, 1.0, 4.0, 12.0}) {
        const ZhVector a = t.directional_multiple().canonical(1, s);
        const ZhVector b = t.directional_single().single(m, s);
        for (int l = 0; l < kImpulseOrder; ++l) {
            if (std::fabs(b[size_t(l)]) < 1e-3 * std::fabs(b[0])) continue;
            EXPECT_NEAR(a[size_t(l)], b[size_t(l)], 0.005 * std::fabs(b[size_t(l)]))
                << "s " << s << " l " << l;
        }
    }
}

TEST(SlabMultipleScatter, SecondBounceFluenceMatchesNestedQuadrature) {
    const SlabMultipleScatter& slab = test_support::shared_impulse_tables().directional_multiple();
    for (double s : {0.2, 1.0, 3.0}) {
        const double expected = second_bounce_fluence(s);
        EXPECT_NEAR(slab.fluence(2, s), expected, 0.005 * expected) << "s " << s;
    }
}

TEST(SlabMultipleScatter, AlbedoWeightsPerBounce) {
    const SlabMultipleScatter& slab = test_support::shared_impulse_tables().directional_multiple();
    const HomogeneousMedium m{0.6, 0.4, 0.0};  // c = 0.6, sigma_t = 1
    const ZhVector z = slab.bounces_in(m, 1.5, 2, 3);
    const ZhVector b2 = slab.canonical(2, 1.5), b3 = slab.canonical(3, 1.5);
    for (int l = 0; l < kImpulseOrder; ++l)
        EXPECT_NEAR(z[size_t(l)], 0.36 * b2[size_t(l)] + 0.216 * b3[size_t(l)], 1e-14);
    // Doubling sigma_t halves the depth at which the same canonical value is read.
    const HomogeneousMedium m2{1.2, 0.8, 0.0};
    const ZhVector z2 = slab.bounces_in(m2, 0.75, 2, 3);
    for (int l = 0; l < kImpulseOrder; ++l) EXPECT_NEAR(z2[size_t(l)], z[size_t(l)], 1e-14);
}
