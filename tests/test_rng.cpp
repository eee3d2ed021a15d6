// The counter-based generator: reproducible by key, independent of call order, uniform (chi^2).
#include <gtest/gtest.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <vector>

#include "math/rng.h"

using namespace freqlab;

TEST(Rng, SameKeySameStream) {
    CounterRng a(1, 2, 3, 4), b(1, 2, 3, 4), c(1, 2, 3, 5);
    for (int i = 0; i < 100; ++i) {
        const uint32_t va = a.next_u32();
        EXPECT_EQ(va, b.next_u32());
        EXPECT_NE(va, c.next_u32());  // 2^-32 chance per draw of a false failure
    }
}

TEST(Rng, UniformByChiSquare) {
    // 64 bins over 2^20 draws taken across many keys, as the renderer uses them.
    const int bins = 64;
    std::vector<double> count(bins, 0.0);
    long n = 0;
    for (uint64_t pixel = 0; pixel < 4096; ++pixel)
        for (uint64_t sample = 0; sample < 16; ++sample) {
            CounterRng r(0, 7, pixel, sample);
            for (int k = 0; k < 16; ++k, ++n) count[size_t(r.next_float() * bins)] += 1;
        }
    double chi2 = 0;
    const double expected = double(n) / bins;
    for (double c : count) chi2 += (c - expected) * (c - expected) / expected;
    const boost::math::chi_squared dist(bins - 1);
    const double p = boost::math::cdf(boost::math::complement(dist, chi2));
    EXPECT_GT(p, 1e-4) << "chi2 = " << chi2;
}

TEST(Rng, FloatsStayBelowOne) {
    CounterRng r(9, 9, 9, 9);
    for (int i = 0; i < 100000; ++i) {
        const float f = r.next_float();
        ASSERT_GE(f, 0.0f);
        ASSERT_LT(f, 1.0f);
    }
}

TEST(Rng, FillFloatsIsTheSameStreamAsNextFloat) {
    CounterRng a(3, 1, 4, 1), b(3, 1, 4, 1);
    for (int n : {1, 7, 32, 3}) {
        std::vector<float> block(size_t(n), -1.0f);
        a.fill_floats(block.data(), n);
        for (int i = 0; i < n; ++i) ASSERT_EQ(block[size_t(i)], b.next_float()) << n << " " << i;
        ASSERT_EQ(a.counter(), b.counter());
    }
    EXPECT_EQ(a.next_float(), b.next_float());
}
