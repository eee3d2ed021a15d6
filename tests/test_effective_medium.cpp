// Effective coefficients of a heterogeneous segment (seed §4.4).
#include <gtest/gtest.h>

#include <cmath>

#include "volume/effective_medium.h"
#include "volume/impulse_response.h"

using namespace freqlab;

TEST(EffectiveMedium, TransmittanceIsExactAndGIsScatteringWeighted) {
    const std::vector<MediumPiece> pieces = {
        {0.5, {2.0, 0.1, 0.6}}, {1.0, {0.0, 0.3, 0.0}}, {0.25, {4.0, 0.0, -0.2}}};
    const HomogeneousMedium m = effective_medium(pieces);
    double product = 1.0, length = 0.0;
    for (const MediumPiece& p : pieces) {
        product *= std::exp(-p.medium.sigma_t() * p.length);
        length += p.length;
    }
    // The directly attenuated term of the effective medium is the exact product.
    EXPECT_NEAR(std::exp(-m.sigma_t() * length), product, 1e-15);
    EXPECT_NEAR(point_direct_zh(m, length)[0],
                product / (length * length) * std::sqrt(1 / (4 * M_PI)), 1e-15);
    // g weighted by scattering optical thickness: (0.6 * 1.0 + (-0.2) * 1.0) / 2.0.
    EXPECT_NEAR(m.g, 0.2, 1e-15);
    EXPECT_NEAR(m.sigma_s, 2.0 / 1.75, 1e-15);
    // A homogeneous segment is itself; an empty one is a vacuum.
    const HomogeneousMedium same =
        effective_medium({{0.3, {1.5, 0.2, 0.4}}, {0.7, {1.5, 0.2, 0.4}}});
    EXPECT_NEAR(same.sigma_s, 1.5, 1e-15);
    EXPECT_NEAR(same.g, 0.4, 1e-15);
    EXPECT_EQ(effective_medium({}).sigma_t(), 0.0);
}
