// The bounce series against an analog Monte Carlo photon tracer (label `slow`): photons leave a
// point source isotropically (I0 = 1 W/sr, 4 pi W in all) in an infinite medium with sigma_t = 1
// and albedo c; track lengths in spherical shells estimate the fluence there. The composed
// series sum_k c^k phi_k, averaged over the same shells, must agree within 3 standard errors.
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss.hpp>

#include <cmath>
#include <cstdio>

#include "math/rng.h"
#include "math/sampling.h"
#include "volume/multiple_scatter.h"

using namespace freqlab;

TEST(MultipleScatterSlow, SeriesMatchesAnalogPhotonTracer) {
    const double c = 0.7;
    const int bounces = 30;  // c^31 ~ 2e-5 of the total: far below the MC error
    const PointMultipleScatter ms(bounces);
    const double shells[][2] = {{0.4, 0.5}, {0.9, 1.1}, {1.8, 2.2}, {2.8, 3.2}};
    const int n_shells = 4;
    // Tally only scattered light (bounce >= 1): the direct term is exact anyway.
    std::vector<double> sum(n_shells, 0.0), sum2(n_shells, 0.0);
    const long photons = 400000;
    for (long p = 0; p < photons; ++p) {
        CounterRng rng(77, 0, uint64_t(p), 0);
        glm::dvec3 x(0.0);
        glm::dvec3 dir(sample_uniform_sphere(rng.next_float(), rng.next_float()));
        std::vector<double> tally(n_shells, 0.0);
        bool scattered = false;
        for (int event = 0; event < 400; ++event) {
            const double s = -std::log(1.0 - rng.next_double());
            if (scattered) {
                // Track length of the segment x -> x + s dir inside each shell.
                for (int k = 0; k < n_shells; ++k) {
                    // Solve |x + t dir| = R for the two radii; sum the lengths inside.
                    auto inside_ball = [&](double R) {
                        const double b = glm::dot(x, dir), cc = glm::dot(x, x) - R * R;
                        const double disc = b * b - cc;
                        if (disc <= 0) return 0.0;
                        const double t0 = std::max(0.0, -b - std::sqrt(disc)),
                                     t1 = std::min(s, -b + std::sqrt(disc));
                        return std::max(0.0, t1 - t0);
                    };
                    tally[size_t(k)] += inside_ball(shells[k][1]) - inside_ball(shells[k][0]);
                }
            }
            x += s * dir;
            if (glm::length(x) > 12.0) break;   // contributes below 1e-5 to the shells
            if (rng.next_double() >= c) break;  // absorbed
            dir = glm::dvec3(sample_uniform_sphere(rng.next_float(), rng.next_float()));
            scattered = true;
        }
        for (int k = 0; k < n_shells; ++k) {
            sum[size_t(k)] += tally[size_t(k)];
            sum2[size_t(k)] += tally[size_t(k)] * tally[size_t(k)];
        }
    }
    using boost::math::quadrature::gauss;
    for (int k = 0; k < n_shells; ++k) {
        const double r0 = shells[k][0], r1 = shells[k][1];
        const double volume = 4.0 / 3.0 * M_PI * (r1 * r1 * r1 - r0 * r0 * r0);
        // Fluence = power x track length / volume; power 4 pi W.
        const double mean = sum[size_t(k)] / photons, var = sum2[size_t(k)] / photons - mean * mean;
        const double mc = 4 * M_PI * mean / volume,
                     se = 4 * M_PI * std::sqrt(var / photons) / volume;
        const double series = gauss<double, 20>::integrate(
                                  [&](double r) {
                                      double f = 0, ck = c;
                                      for (int b = 1; b <= bounces; ++b, ck *= c)
                                          f += ck * ms.fluence(b, r);
                                      return 4 * M_PI * r * r * f;
                                  },
                                  r0, r1) /
                              volume;
        std::printf("shell %.1f-%.1f: series %.5f, MC %.5f +- %.5f (%.2f %%)\n", r0, r1, series, mc,
                    se, 100 * se / mc);
        EXPECT_NEAR(series, mc, 3 * se) << "shell " << r0 << "-" << r1 << ": series " << series
                                        << ", MC " << mc << " +- " << se;
    }
}
