// The Owen-scrambled Sobol points of math/sobol.h: prefixes of 2^m points are (0,m,2)-nets
// (exact counts), and each point is uniform over seeds (chi-square), which is what keeps the
// estimates that use them unbiased.
#include <gtest/gtest.h>

#include <vector>

#include "math/rng.h"
#include "math/sobol.h"
#include "stats_helpers.h"

using namespace freqlab;

TEST(Sobol, UnscrambledStartIsTheKnownSequence) {
    // In index order (no Gray code): (0, 0), (1/2, 1/2), (1/4, 3/4), (3/4, 1/4), (1/8, 5/8).
    const uint32_t x[] = {0u, 1u << 31, 1u << 30, 3u << 30, 1u << 29};
    const uint32_t y[] = {0u, 1u << 31, 3u << 30, 1u << 30, 5u << 29};
    for (uint32_t i = 0; i < 5; ++i) {
        EXPECT_EQ(sobol_dimension0(i), x[i]) << i;
        EXPECT_EQ(sobol_dimension1(i), y[i]) << i;
    }
}

TEST(Sobol, ScrambledPrefixesAreNets) {
    // Every prefix of 2^m points has exactly one point in each elementary box 2^-a x 2^-(m-a).
    CounterRng rng(5, 0, 0, 0);
    for (int trial = 0; trial < 8; ++trial) {
        const uint32_t sx = rng.next_u32(), sy = rng.next_u32();
        for (int m = 0; m <= 10; ++m)
            for (int a = 0; a <= m; ++a) {
                std::vector<int> count(size_t(1) << m, 0);
                for (uint32_t i = 0; i < (1u << m); ++i) {
                    const uint32_t x = owen_scramble(sobol_dimension0(i), sx);
                    const uint32_t y = owen_scramble(sobol_dimension1(i), sy);
                    const uint64_t bx = a ? x >> (32 - a) : 0, by = m - a ? y >> (32 - (m - a)) : 0;
                    ++count[size_t((bx << (m - a)) | by)];
                }
                for (int c : count) ASSERT_EQ(c, 1) << "m " << m << " a " << a;
            }
    }
}

TEST(Sobol, EachPointIsUniformOverSeeds) {
    const int bins = 16, seeds = 1 << 16;
    CounterRng rng(6, 0, 0, 0);
    for (uint32_t index : {0u, 1u, 6u, 37u, 1000u}) {
        std::vector<double> observed(size_t(bins) * bins, 0.0);
        for (int s = 0; s < seeds; ++s) {
            const ScrambledSobol2D seq(rng.next_u32(), rng.next_u32());
            const vec2 p = seq.at(index);
            ASSERT_GE(p.x, 0.0f);
            ASSERT_LT(p.y, 1.0f);
            observed[size_t(int(p.y * bins)) * bins + size_t(p.x * bins)] += 1;
        }
        const std::vector<double> expected(observed.size(), double(seeds) / (bins * bins));
        double chi2;
        EXPECT_GT(test::chi_square_p_value(observed, expected, &chi2), 1e-4)
            << "index " << index << " chi2 " << chi2;
    }
}
