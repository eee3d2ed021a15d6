// Point-emitter impulse responses (issue "Method B, part 1", acceptance 2 and part of 3):
// the tabulator's single scattering against an independent brute-force 2D integration of
// Eq. 4.1 written here with Boost's adaptive quadrature (tanh-sinh / exp-sinh along the ray,
// Gauss-Kronrod over the angle), and the sigma remap against direct computation.
#include <gtest/gtest.h>

#include <boost/math/quadrature/exp_sinh.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/math/quadrature/tanh_sinh.hpp>

#include <cmath>

#include "volume/impulse_response.h"

using namespace freqlab;

namespace {

double legendre_p(int l, double x) {
    double p0 = 1, p1 = x;
    if (l == 0) return p0;
    for (int k = 2; k <= l; ++k) {
        const double p2 = ((2.0 * k - 1) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

// Eq. 4.1's single-scattered part, straight from its definition.
double brute_force_single(const HomogeneousMedium& m, double d, int l) {
    using namespace boost::math::quadrature;
    tanh_sinh<double> ts;
    exp_sinh<double> es;
    auto radiance = [&](double theta) {
        const double ct = std::cos(theta), st = std::sin(theta);
        auto integrand = [&](double t) {
            // Point on the ray: t (st, 0, ct); emitter at (0, 0, d).
            const double x = t * st, z = t * ct - d;
            const double r = std::sqrt(x * x + z * z);
            // Light propagates from the emitter to the point (u = (x, 0, z) / r), then to the
            // receiver (direction -w): cos = -(u . w).
            const double cos_scatter = -(x * st + z * ct) / r;
            return std::exp(-m.sigma_t() * (t + r)) * m.sigma_s * hg_phase(m.g, cos_scatter) /
                   (r * r);
        };
        const double t0 = d * ct;
        double inner = 0;
        if (t0 > 0) inner += ts.integrate(integrand, 0.0, t0);
        inner += es.integrate([&](double s) { return integrand(std::max(t0, 0.0) + s); });
        return inner;
    };
    auto f = [&](double theta) {
        return 2 * M_PI * std::sin(theta) * radiance(theta) *
               std::sqrt((2.0 * l + 1) / (4 * M_PI)) * legendre_p(l, std::cos(theta));
    };
    double error;
    const double a = gauss_kronrod<double, 61>::integrate(f, 0.0, 0.2, 12, 1e-10, &error);
    const double b = gauss_kronrod<double, 61>::integrate(f, 0.2, M_PI, 12, 1e-10, &error);
    return a + b;
}

}  // namespace

TEST(PointImpulse, SingleScatteringMatchesBruteForce) {
    struct Config {
        double sigma_s, sigma_a, g, d;
    };
    // Up to the tables' |g| = 0.95: haze and fog scatter strongly forward.
    const Config configs[] = {{1.0, 0.0, 0.0, 0.3},  {1.0, 0.0, 0.0, 2.0},  {0.5, 0.2, 0.0, 1.5},
                              {1.0, 0.0, 0.5, 1.0},  {2.0, 0.5, -0.5, 0.7}, {0.3, 0.0, 0.5, 4.0},
                              {0.5, 0.05, 0.9, 1.0}, {1.0, 0.0, 0.95, 0.4}, {0.3, 0.0, -0.8, 2.0},
                              {0.2, 0.02, 0.95, 6.0}};
    for (const Config& c : configs) {
        const HomogeneousMedium m{c.sigma_s, c.sigma_a, c.g};
        const ZhVector z = point_single_zh(m, c.d);
        const double dc = brute_force_single(m, c.d, 0);
        for (int l = 0; l < kImpulseOrder; ++l) {
            const double ref = l == 0 ? dc : brute_force_single(m, c.d, l);
            if (std::fabs(ref) < 1e-3 * std::fabs(dc))
                continue;  // tiny coefficients: absolute check
            EXPECT_NEAR(z[size_t(l)], ref, 0.005 * std::fabs(ref))
                << "sigma_s " << c.sigma_s << " sigma_a " << c.sigma_a << " g " << c.g << " d "
                << c.d << " l " << l;
        }
    }
}

TEST(PointImpulse, DirectTermIsTheAttenuatedDelta) {
    const HomogeneousMedium m{0.7, 0.3, 0.0};
    const ZhVector z = point_direct_zh(m, 2.0);
    EXPECT_NEAR(z[0], std::exp(-2.0) / 4.0 * std::sqrt(1 / (4 * M_PI)), 1e-15);
    EXPECT_NEAR(z[3], std::exp(-2.0) / 4.0 * std::sqrt(7 / (4 * M_PI)), 1e-15);
}

TEST(PointImpulse, SigmaRemapMatchesDirectComputation) {
    const SingleScatterTable table(SingleScatterTable::Emitter::Point);
    for (double sigma_s : {0.1, 0.3, 3.0, 10.0})
        for (double sigma_a : {0.0, 0.1, 1.0})
            for (double g : {-0.93, -0.7, -0.3, 0.2, 0.5, 0.75, 0.9, 0.95})
                for (double d : {0.05, 0.4, 1.3}) {
                    const HomogeneousMedium m{sigma_s, sigma_a, g};
                    if (m.sigma_t() * d >= ZhDistanceTable::kMaxD) continue;
                    const ZhVector q = table.single(m, d), direct = point_single_zh(m, d);
                    for (int l = 0; l < kImpulseOrder; ++l) {
                        if (std::fabs(direct[size_t(l)]) < 1e-3 * std::fabs(direct[0])) continue;
                        EXPECT_NEAR(q[size_t(l)], direct[size_t(l)],
                                    0.005 * std::fabs(direct[size_t(l)]))
                            << "sigma_s " << sigma_s << " sigma_a " << sigma_a << " d " << d
                            << " l " << l;
                    }
                }
}

namespace {

// Eq. 4.2 straight from its definition: the ray integral numerically, not in closed form.
double brute_force_directional(const HomogeneousMedium& m, double s, int l) {
    using namespace boost::math::quadrature;
    tanh_sinh<double> ts;
    exp_sinh<double> es;
    auto radiance = [&](double theta) {
        const double mu = std::cos(theta);
        // Depth below the boundary of the point t along the ray: s - t mu; light from above.
        auto integrand = [&](double t) {
            return std::exp(-m.sigma_t() * t) * m.sigma_s * hg_phase(m.g, mu) *
                   std::exp(-m.sigma_t() * (s - t * mu));
        };
        return mu > 0 ? ts.integrate(integrand, 0.0, s / mu) : es.integrate(integrand);
    };
    auto f = [&](double theta) {
        return 2 * M_PI * std::sin(theta) * radiance(theta) *
               std::sqrt((2.0 * l + 1) / (4 * M_PI)) * legendre_p(l, std::cos(theta));
    };
    double error;
    return gauss_kronrod<double, 61>::integrate(f, 0.0, M_PI / 2, 12, 1e-10, &error) +
           gauss_kronrod<double, 61>::integrate(f, M_PI / 2, M_PI, 12, 1e-10, &error);
}

}  // namespace

TEST(DirectionalImpulse, SingleScatteringMatchesBruteForce) {
    struct Config {
        double sigma_s, sigma_a, g, s;
    };
    const Config configs[] = {{1.0, 0.0, 0.0, 0.2},  {1.0, 0.0, 0.0, 3.0},  {0.5, 0.5, 0.0, 1.0},
                              {1.0, 0.0, 0.5, 0.7},  {2.0, 0.1, -0.5, 0.4}, {0.2, 0.0, 0.5, 5.0},
                              {0.5, 0.05, 0.9, 1.0}, {1.0, 0.0, 0.95, 0.3}, {0.3, 0.0, -0.8, 2.0},
                              {1.0, 0.0, -0.95, 0.5}};
    for (const Config& c : configs) {
        const HomogeneousMedium m{c.sigma_s, c.sigma_a, c.g};
        const ZhVector z = directional_single_zh(m, c.s);
        const double dc = brute_force_directional(m, c.s, 0);
        for (int l = 0; l < kImpulseOrder; ++l) {
            const double ref = l == 0 ? dc : brute_force_directional(m, c.s, l);
            if (std::fabs(ref) < 1e-3 * std::fabs(dc)) continue;
            EXPECT_NEAR(z[size_t(l)], ref, 0.005 * std::fabs(ref))
                << "sigma_s " << c.sigma_s << " sigma_a " << c.sigma_a << " g " << c.g << " s "
                << c.s << " l " << l;
        }
    }
}

TEST(DirectionalImpulse, SigmaRemapMatchesDirectComputation) {
    const SingleScatterTable table(SingleScatterTable::Emitter::Directional);
    for (double sigma_s : {0.1, 0.3, 3.0, 10.0})
        for (double sigma_a : {0.0, 0.1, 1.0})
            for (double g : {-0.93, -0.7, -0.3, 0.2, 0.5, 0.75, 0.9, 0.95})
                for (double s : {0.05, 0.4, 1.3}) {
                    const HomogeneousMedium m{sigma_s, sigma_a, g};
                    if (m.sigma_t() * s >= ZhDistanceTable::kMaxD) continue;
                    const ZhVector q = table.single(m, s), direct = directional_single_zh(m, s);
                    for (int l = 0; l < kImpulseOrder; ++l) {
                        if (std::fabs(direct[size_t(l)]) < 1e-3 * std::fabs(direct[0])) continue;
                        EXPECT_NEAR(q[size_t(l)], direct[size_t(l)],
                                    0.005 * std::fabs(direct[size_t(l)]))
                            << "sigma_s " << sigma_s << " sigma_a " << sigma_a << " s " << s
                            << " l " << l;
                    }
                }
}
