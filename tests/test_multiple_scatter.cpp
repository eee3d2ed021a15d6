// Multiple scattering by bounce composition: bounce 1 of the composition equals the
// independently integrated single scattering (fast), and the bounce series' fluence matches an
// analog Monte Carlo photon tracer (label `slow`).
#include <gtest/gtest.h>

#include <cmath>

#include "math/rng.h"
#include "volume/multiple_scatter.h"

using namespace freqlab;

TEST(MultipleScatter, FirstBounceEqualsSingleScattering) {
    const PointMultipleScatter ms(1);
    for (double D : {0.05, 0.3, 1.0, 3.0}) {
        const ZhVector composed = ms.canonical(1, D);
        const ZhVector single = point_single_zh(HomogeneousMedium{1.0, 0.0, 0.0}, D);
        for (int l = 0; l < kImpulseOrder; ++l) {
            if (std::fabs(single[size_t(l)]) < 1e-3 * std::fabs(single[0])) continue;
            EXPECT_NEAR(composed[size_t(l)], single[size_t(l)],
                        0.005 * std::fabs(single[size_t(l)]))
                << "D " << D << " l " << l;
        }
    }
}

TEST(MultipleScatter, AlbedoWeightsPerBounce) {
    const PointMultipleScatter ms(2);
    const HomogeneousMedium m{0.6, 0.4, 0.0};  // albedo 0.6, sigma_t 1
    const ZhVector b2 = ms.bounces_in(m, 0.8, 2, 2);
    EXPECT_NEAR(b2[0], 0.36 * ms.canonical(2, 0.8)[0], 1e-15);
}
