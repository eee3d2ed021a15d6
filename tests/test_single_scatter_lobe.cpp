// The single-scattering lobe of single_correction (volume/single_scatter_lobe.h): the model's
// closed form against quadrature, the sampler against its own pdf (chi-square), the pdf's
// normalisation, and what the lobe is for: the model's part of the estimate nearly constant.
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss_kronrod.hpp>

#include "math/rng.h"
#include "math/sampling.h"
#include "sphere_quadrature.h"
#include "stats_helpers.h"
#include "volume/single_scatter_lobe.h"

using namespace freqlab;
using test::integrate_sphere;

namespace {

struct LobeCase {
    const char* name;
    HalfSpaceSingleModel model;
    float sun_from_normal_deg;
};

// Valley's haze under a high and a low sun, a thick medium, strong forward scattering, and a
// sun behind the receiver's plane (below its horizon: the lobe still covers the hemisphere).
std::vector<LobeCase> lobe_cases() {
    return {{"haze_high_sun", {0.006, 0.007, 0.4, 55.0}, 30.0f},
            {"haze_low_sun", {0.006, 0.007, 0.4, 130.0}, 80.0f},
            {"thick", {0.5, 0.6, 0.0, 4.0}, 45.0f},
            {"forward_g", {0.05, 0.06, 0.85, 20.0}, 60.0f},
            {"sun_below", {0.05, 0.06, 0.3, 10.0}, 110.0f}};
}

vec3 sun_direction(float deg) {
    const float t = glm::radians(deg);
    return vec3(std::sin(t), 0.0f, std::cos(t));
}

const vec3 kNormal(0.0f, 0.0f, 1.0f);

}  // namespace

TEST(SingleScatterLobe, ModelIntegralIsTheQuadratureOfItsIntegrand) {
    for (const LobeCase& c : lobe_cases()) {
        SCOPED_TRACE(c.name);
        for (double mu : {-0.9, -0.2, 0.05, 0.4, 0.97}) {
            const double t_end = mu > 0.0 ? c.model.depth / mu : 60.0 / c.model.sigma_t;
            const double quad = boost::math::quadrature::gauss_kronrod<double, 61>::integrate(
                [&](double t) { return c.model.at(mu, t); }, 0.0, t_end, 8, 1e-12);
            EXPECT_NEAR(c.model.integral(mu, 0.0, t_end), quad, 1e-9 * quad + 1e-15);
            // The tail past 60 mean free paths is below 1e-26 of the whole.
            EXPECT_NEAR(c.model.radiance(mu), quad, 1e-9 * quad + 1e-15);
        }
    }
}

TEST(SingleScatterLobe, PdfIntegratesToOne) {
    for (const LobeCase& c : lobe_cases()) {
        SCOPED_TRACE(c.name);
        const SingleScatterLobe lobe(c.model, sun_direction(c.sun_from_normal_deg), kNormal);
        ASSERT_TRUE(lobe.shaped());
        const double total = integrate_sphere([&](const vec3& w) { return lobe.pdf(w); }, 0.0, 1.0,
                                              0.0, 2.0 * M_PI, 32);
        EXPECT_NEAR(total, 1.0, 2e-3);
    }
}

TEST(SingleScatterLobe, SamplesFollowTheirPdf) {
    const test::DirectionBins bins{16, 32, 0.0, 1.0};
    const int n = 200000;
    for (const LobeCase& c : lobe_cases()) {
        SCOPED_TRACE(c.name);
        const SingleScatterLobe lobe(c.model, sun_direction(c.sun_from_normal_deg), kNormal);
        std::vector<double> observed(bins.size(), 0.0);
        CounterRng rng(41, 0, 0, 0);
        for (int i = 0; i < n; ++i) {
            vec3 w;
            double weight = 0.0;
            const float u1 = rng.next_float(), u2 = rng.next_float();
            if (!lobe.sample(u1, u2, &w, &weight)) continue;
            ASSERT_NEAR(weight, w.z / lobe.pdf(w), 1e-9 * weight);
            observed[bins.index(w)] += 1;
        }
        const std::vector<double> expected =
            bins.expected([&](const vec3& w) { return lobe.pdf(w); }, n);
        double chi2;
        const double p = test::chi_square_p_value(observed, expected, &chi2);
        EXPECT_GT(p, 1e-3) << "chi2 = " << chi2;
    }
}

// The correction's model part along w is L(mu) x cos / pdf: drawn by the lobe it stays within
// a few per cent of its mean (the hemisphere's integral of L cos), where the cosine's pi L(mu)
// spreads by a quarter to 3.5x its mean: the noise that reached valley's vertex correction
// field.
TEST(SingleScatterLobe, ModelPartIsNearlyConstant) {
    for (const LobeCase& c : lobe_cases()) {
        SCOPED_TRACE(c.name);
        const vec3 l = sun_direction(c.sun_from_normal_deg);
        const SingleScatterLobe lobe(c.model, l, kNormal);
        const double exact = integrate_sphere(
            [&](const vec3& w) { return c.model.radiance(glm::dot(w, l)) * double(w.z); }, 0.0, 1.0,
            0.0, 2.0 * M_PI, 32);
        CounterRng rng(43, 0, 0, 0);
        const int n = 40000;
        double sum = 0, sum2 = 0, cos_sum = 0, cos_sum2 = 0;
        for (int i = 0; i < n; ++i) {
            const float u1 = rng.next_float(), u2 = rng.next_float();
            vec3 w;
            double weight = 0.0, v = 0.0;
            if (lobe.sample(u1, u2, &w, &weight)) v = c.model.radiance(glm::dot(w, l)) * weight;
            sum += v;
            sum2 += v * v;
            const vec3 wc = sample_cosine_hemisphere(u1, u2);
            const double vc = kPiD * c.model.radiance(glm::dot(wc, l));
            cos_sum += vc;
            cos_sum2 += vc * vc;
        }
        const double mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
        const double cos_mean = cos_sum / n;
        const double cos_sd = std::sqrt(std::max(0.0, cos_sum2 / n - cos_mean * cos_mean));
        EXPECT_NEAR(mean, exact, 4.0 * sd / std::sqrt(double(n)) + 1e-9 * exact);
        // Measured 0.028 / 0.084 / 0.039 / 0.20 / 0.062 (cosine 0.24 / 0.72 / 0.32 / 3.5 /
        // 0.56). A sharp phase function leaves the cosine's tenth of the directions (its
        // backward ones) almost nothing: a spread of up to sqrt(0.1 / 0.9) = 0.33.
        EXPECT_LT(sd / mean, c.model.g > 0.5 ? 0.3 : 0.1) << "the cosine's: " << cos_sd / cos_mean;
        EXPECT_LT(sd / mean, 0.2 * cos_sd / cos_mean);
    }
}

TEST(SingleScatterLobe, AnEmptyModelIsTheCosine) {
    const SingleScatterLobe lobe(HalfSpaceSingleModel{}, sun_direction(30.0f), kNormal);
    EXPECT_FALSE(lobe.shaped());
    vec3 w;
    double weight = 0.0;
    ASSERT_TRUE(lobe.sample(0.3f, 0.7f, &w, &weight));
    const vec3 cosine = sample_cosine_hemisphere(0.3f, 0.7f);
    EXPECT_FLOAT_EQ(w.x, cosine.x);
    EXPECT_FLOAT_EQ(w.z, cosine.z);
    EXPECT_DOUBLE_EQ(weight, kPiD);
}
