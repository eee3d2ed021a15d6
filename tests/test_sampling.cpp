// Sampling routines against their own pdfs (Mitsuba-style chi-square tests), pdf
// normalisation by quadrature, and MIS weights that sum to one.
#include <gtest/gtest.h>

#include <boost/math/quadrature/gauss.hpp>

#include "math/fast_atan2.h"
#include "math/rng.h"
#include "math/sampling.h"
#include "scene/brdf.h"
#include "scene/light.h"
#include "sphere_quadrature.h"
#include "stats_helpers.h"
#include "volume/near_light_directions.h"

using namespace freqlab;
using boost::math::quadrature::gauss;
using test::integrate_sphere;
using test::spherical;

namespace {

Material material(BrdfType type, float exponent = 1, float roughness = 0.5f) {
    Material m;
    m.type = type;
    m.phong_exponent = exponent;
    m.roughness = roughness;
    return m;
}

struct BrdfCase {
    const char* name;
    Material m;
    float view_theta_deg;
};

std::vector<BrdfCase> brdf_cases() {
    return {{"lambert", material(BrdfType::Lambert), 30},
            {"phong_e8", material(BrdfType::Phong, 8), 0},
            {"phong_e40", material(BrdfType::Phong, 40), 50},
            {"beckmann_0.2", material(BrdfType::Beckmann, 1, 0.2f), 30},
            {"beckmann_0.7", material(BrdfType::Beckmann, 1, 0.7f), 70},
            {"ggx_0.1", material(BrdfType::Ggx, 1, 0.1f), 10},
            {"ggx_0.6", material(BrdfType::Ggx, 1, 0.6f), 60}};
}

vec3 view_direction(float theta_deg) {
    const float t = glm::radians(theta_deg);
    return vec3(std::sin(t), 0.0f, std::cos(t));
}

}  // namespace

TEST(Sampling, BrdfSamplesFollowTheirPdf) {
    const test::DirectionBins bins{20, 40};
    const int n = 400000;
    for (const BrdfCase& c : brdf_cases()) {
        SCOPED_TRACE(c.name);
        const Brdf brdf(c.m, vec3(1.0f), vec3(0, 0, 1));
        const vec3 wo = view_direction(c.view_theta_deg);
        std::vector<double> observed(bins.size(), 0.0);
        CounterRng rng(11, 0, 0, 0);
        for (int i = 0; i < n; ++i) {
            const BrdfSample s = brdf.sample(wo, rng.next_float(), rng.next_float());
            if (s.pdf <= 0) continue;
            EXPECT_NEAR(s.pdf, brdf.pdf(wo, s.wi), 1e-3f * s.pdf);
            observed[bins.index(s.wi)] += 1;
        }
        const std::vector<double> expected =
            bins.expected([&](const vec3& wi) { return double(brdf.pdf(wo, wi)); }, n);
        double chi2;
        const double p = test::chi_square_p_value(observed, expected, &chi2);
        EXPECT_GT(p, 1e-3) << "chi2 = " << chi2;
    }
}

TEST(Sampling, BrdfPdfsIntegrateToOne) {
    // Microfacet sampling draws h ~ D(h) cos(theta_h) and reflects wo about it; when
    // wo.h <= 0 the sample fails (pdf 0). So the pdf over directions integrates to 1 minus that
    // failure mass, itself an integral over h; Lambert and Phong never fail.
    for (const BrdfCase& c : brdf_cases()) {
        SCOPED_TRACE(c.name);
        const Brdf brdf(c.m, vec3(1.0f), vec3(0, 0, 1));
        const vec3 wo = view_direction(c.view_theta_deg);
        const double total = integrate_sphere(
            [&](const vec3& wi) { return double(brdf.pdf(wo, wi)); }, -1, 1, 0, 2 * M_PI, 64);
        double failure = 0;
        if (c.m.type == BrdfType::Beckmann || c.m.type == BrdfType::Ggx) {
            auto d = [&](float cos_h) {
                return c.m.type == BrdfType::Ggx ? Brdf::ggx_d(cos_h, c.m.roughness)
                                                 : Brdf::beckmann_d(cos_h, c.m.roughness);
            };
            const double d_norm = integrate_sphere(
                [&](const vec3& h) { return double(d(h.z) * h.z); }, 0, 1, 0, 2 * M_PI, 64);
            EXPECT_NEAR(d_norm, 1.0, 2e-3) << "projected microfacet area";
            failure = integrate_sphere(
                [&](const vec3& h) { return glm::dot(wo, h) <= 0 ? double(d(h.z) * h.z) : 0.0; }, 0,
                1, 0, 2 * M_PI, 64);
        }
        EXPECT_NEAR(total + failure, 1.0, 2e-3) << "failure mass " << failure;
    }
}

TEST(Sampling, MisWeightsSumToOne) {
    CounterRng rng(5, 0, 0, 0);
    for (int i = 0; i < 10000; ++i) {
        const float pa = rng.next_float() * 10.0f, pb = rng.next_float() * 10.0f;
        const float na = float(1 + i % 7), nb = float(1 + i % 5);
        if (pa <= 0 || pb <= 0) continue;
        EXPECT_NEAR(power_heuristic(na, pa, nb, pb) + power_heuristic(nb, pb, na, pa), 1.0f, 1e-6f);
    }
    EXPECT_EQ(power_heuristic(1, 0.0f, 1, 1.0f), 0.0f);  // a strategy that cannot sample it
    EXPECT_EQ(power_heuristic(1, 1.0f, 1, 0.0f), 1.0f);
}

namespace {

// A small non-uniform lat-long map: gradient, a bright spot, and a black region.
std::shared_ptr<const RgbImage> test_map() {
    auto img = std::make_shared<RgbImage>();
    img->width = 32;
    img->height = 16;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            float v = 0.2f + 0.05f * x;
            if (x >= 20 && x < 23 && y >= 4 && y < 6) v = 40.0f;
            if (y >= 12 && x < 8) v = 0.0f;
            img->pixels.push_back(vec3(v, 0.5f * v, 0.25f * v));
        }
    return img;
}

}  // namespace

// Counts of `env`'s samples in bins of `bin` x `bin` texels against the bins' probabilities.
// `max_mismatches`: the samples whose direction maps back to a neighbouring texel, by float
// rounding at its edges (more edges, more of them: see the sky test below).
static void check_environment_samples(const EnvironmentMap& env, bool inverted, int bin = 1,
                                      int max_mismatches = 10) {
    const int n = 1000000;
    const int w = env.distribution().width() / bin, h = env.distribution().height() / bin;
    std::vector<double> observed(size_t(w) * h, 0.0), expected(observed.size(), 0.0);
    CounterRng rng(3, 0, 0, 0);
    // The density jumps at texel edges, so a sample within float rounding of an edge may
    // round-trip into the neighbour texel: allow a handful of such mismatches, no more.
    int mismatches = 0;
    for (int i = 0; i < n; ++i) {
        vec3 d;
        float pdf;
        const vec4 u(rng.next_float(), rng.next_float(), rng.next_float(), rng.next_float());
        vec3 radiance;
        if (inverted) {
            vec2 within;
            const int texel = env.sample_texel_inverted(vec2(u), &within);
            radiance = env.sample_at(texel, vec4(0.0f, 0.0f, within), &d, &pdf);
        } else {
            radiance = env.sample(u, &d, &pdf);
        }
        ASSERT_GT(pdf, 0.0f);
        // The staged lookup (texel_of, eval_with_pdf_at) of the sampled direction gives back
        // the sample's density and radiance.
        vec2 uv_back;
        float pdf_back;
        const vec3 radiance_back =
            env.eval_with_pdf_at(env.texel_of(d, &uv_back), uv_back, &pdf_back);
        mismatches += std::fabs(pdf - pdf_back) > 2e-3f * pdf || radiance != radiance_back;
        const vec2 uv = env.direction_to_uv(d);
        const int x = std::clamp(int(uv.x * w), 0, w - 1), y = std::clamp(int(uv.y * h), 0, h - 1);
        observed[size_t(y) * w + x] += 1;
    }
    EXPECT_LE(mismatches, max_mismatches) << "sampled pdf disagrees with pdf(direction)";
    for (int y = 0; y < h * bin; ++y)
        for (int x = 0; x < w * bin; ++x)
            expected[size_t(y / bin) * w + size_t(x / bin)] +=
                n * env.distribution().texel_probability(x, y);
    double chi2;
    EXPECT_GT(test::chi_square_p_value(observed, expected, &chi2), 1e-3) << "chi2 = " << chi2;
}

// Both ways of drawing a texel: the alias table (independent samples) and the CDF inversion
// (stratified samples; here fed independent uniforms, so chi-square applies).
TEST(Sampling, EnvironmentSamplesFollowTexelProbabilities) {
    const EnvironmentMap env("test", test_map(), 37.0f, 1.0f);
    ASSERT_EQ(env.distribution().tile(), 1);  // 512 texels: below kMinTiledTexels
    for (bool inverted : {false, true}) {
        SCOPED_TRACE(inverted ? "CDF inversion" : "alias table");
        check_environment_samples(env, inverted);
    }
}

// A sky without a sun disc is smooth: its density is constant over tiles (a table that stays
// in cache) at a second-moment cost under 1 %; the samples still follow it, by alias table and
// by inversion, in bins of 2 x 2 texels (each a quarter of a tile or less, so a sample placed
// in the wrong texel of its tile fails the test). A sun disc keeps the per-texel density.
TEST(Sampling, SmoothSkiesAreSampledByTilesThatCostUnderOnePercent) {
    ProceduralSky sky;
    sky.sun_radiance = vec3(0.0f);
    const auto image = sky.bake(512, 256);
    const EnvironmentMap env("sky", image, 37.0f, 1.0f);
    const Distribution2D& d = env.distribution();
    ASSERT_GT(d.tile(), 2);
    EXPECT_LE(d.inflation(), Distribution2D::kMaxTileInflation);
    EXPECT_GE(d.inflation(), 1.0);
    // Each texel's density is its tile's mean.
    std::vector<float> weights(size_t(512) * 256);
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 512; ++x)
            weights[size_t(y) * 512 + x] =
                luminance(image->at(x, y)) * std::sin(float(M_PI) * (y + 0.5f) / 256.0f);
    double sum = 0.0;
    for (float w : weights) sum += w;
    const int f = d.tile();
    for (int ty : {0, 3, 7}) {
        double tile_sum = 0.0;
        for (int y = ty * f; y < (ty + 1) * f; ++y)
            for (int x = 5 * f; x < 6 * f; ++x) tile_sum += weights[size_t(y) * 512 + x];
        EXPECT_NEAR(d.texel_probability(5 * f + 1, ty * f + f - 1), tile_sum / sum / double(f * f),
                    1e-6 * tile_sum / sum);
    }
    // The sampled directions fall in their texels as that density says. 512 x 256 texels
    // have 16x the 32 x 16 map's edges per unit of (u, v): of 1 M samples ~30 map back to a
    // neighbouring texel whether sampled per texel or by tiles (measured: 31 and 32), up to 11
    // of them across a row (this sky's radiance changes only from row to row).
    for (bool inverted : {false, true}) {
        SCOPED_TRACE(inverted ? "CDF inversion" : "alias table");
        check_environment_samples(env, inverted, 2, 30);
    }
    // Weights constant over tiles cost nothing; a one-texel sun in a tile costs ~ the tile.
    std::vector<float> flat(size_t(64) * 32, 1.0f);
    EXPECT_DOUBLE_EQ(Distribution2D::tile_inflation(flat, 64, 32, 8), 1.0);
    flat[size_t(9) * 64 + 9] = 1e6f;
    EXPECT_GT(Distribution2D::tile_inflation(flat, 64, 32, 8), 50.0);
    ProceduralSky sunny;  // the default sun
    ASSERT_GT(luminance(sunny.sun_radiance), 0.0f);
    EXPECT_EQ(EnvironmentMap("sun", sunny.bake(512, 256), 0.0f, 1.0f).distribution().tile(), 1);
}

TEST(Sampling, EnvironmentPdfIntegratesToOneAndCoversTheRadiance) {
    const EnvironmentMap env("test", test_map(), 37.0f, 1.0f);
    // Piecewise constant in (u, v): integrate texel by texel over (theta, phi) with the
    // solid-angle element sin(theta) dtheta dphi.
    const int w = env.distribution().width(), h = env.distribution().height();
    double total = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double t0 = M_PI * y / h, t1 = M_PI * (y + 1) / h;
            const double p0 = 2 * M_PI * x / w + glm::radians(37.0),
                         p1 = 2 * M_PI * (x + 1) / w + glm::radians(37.0);
            total += gauss<double, 7>::integrate(
                [&](double t) {
                    return std::sin(t) *
                           gauss<double, 7>::integrate(
                               [&](double phi) {
                                   return double(env.pdf(spherical(std::cos(t), phi)));
                               },
                               p0, p1);
                },
                t0, t1);
        }
    EXPECT_NEAR(total, 1.0, 1e-4);
    // Wherever the lighting function is positive the pdf is too.
    CounterRng rng(8, 0, 0, 0);
    for (int i = 0; i < 200000; ++i) {
        const vec3 d = sample_uniform_sphere(rng.next_float(), rng.next_float());
        if (luminance(env.eval(d)) > 0.0f) {
            ASSERT_GT(env.pdf(d), 0.0f);
        }
    }
}

TEST(Sampling, FastAtan2IsAsAccurateAsTheFloatLibrary) {
    CounterRng rng(11, 0, 0, 0);
    double worst = 0.0, worst_library = 0.0;
    for (int i = 0; i < 1000000; ++i) {
        // Magnitudes over 6 decades, every sign and octant.
        const float y = (rng.next_float() - 0.5f) * std::pow(10.0f, 6.0f * rng.next_float() - 3.0f);
        const float x = (rng.next_float() - 0.5f) * std::pow(10.0f, 6.0f * rng.next_float() - 3.0f);
        const double exact = std::atan2(double(y), double(x));
        worst = std::max(worst, std::fabs(double(fast_atan2(y, x)) - exact));
        worst_library = std::max(worst_library, std::fabs(double(std::atan2(y, x)) - exact));
    }
    // Float atan2 itself is off by up to about an ulp of pi (2.4e-7 measured); ours adds the
    // polynomial's 3.7e-8 and the rounding of a few float operations (2.9e-7 measured).
    EXPECT_LT(worst, 2.0 * 2.384e-7) << "library: " << worst_library;
    EXPECT_LT(worst, 1.5 * worst_library) << "library: " << worst_library;
    // The axes and the origin.
    EXPECT_EQ(fast_atan2(0.0f, 0.0f), 0.0f);
    EXPECT_NEAR(fast_atan2(0.0f, -1.0f), M_PI, 1e-7);
    EXPECT_NEAR(fast_atan2(1.0f, 0.0f), M_PI / 2, 1e-7);
    EXPECT_NEAR(fast_atan2(-1.0f, 0.0f), -M_PI / 2, 1e-7);
    EXPECT_NEAR(fast_atan2(-1.0f, -1.0f), -3 * M_PI / 4, 1e-7);
}

// The media samplers shared by method B's bakers and VPT (math/sampling.h): histograms of many
// samples against the bin integrals of their own pdfs (pbrt-v4's media_test.cpp style).
namespace {

template <class Sample, class Pdf>
double samples_against_pdf(Sample sample, Pdf pdf, double lo, double hi, int bins) {
    std::vector<double> observed(size_t(bins), 0.0), expected(size_t(bins), 0.0);
    const int n = 200000;
    CounterRng rng(9, 1, 2, 3);
    for (int i = 0; i < n; ++i) {
        const double x = sample(rng.next_double());
        const int b = int((x - lo) / (hi - lo) * bins);
        if (b >= 0 && b < bins) observed[size_t(b)] += 1.0;
    }
    for (int b = 0; b < bins; ++b) {
        const double a = lo + (hi - lo) * b / bins, c = lo + (hi - lo) * (b + 1) / bins;
        expected[size_t(b)] = n * gauss<double, 20>::integrate(pdf, a, c);
    }
    double chi2;
    const double p = test::chi_square_p_value(observed, expected, &chi2);
    EXPECT_GT(p, 1e-3) << "chi2 = " << chi2;
    return p;
}

}  // namespace

TEST(Sampling, HenyeyGreensteinCosinesFollowThePhaseFunction) {
    for (float g : {-0.7f, -0.2f, 0.0f, 0.3f, 0.5f, 0.9f}) {
        SCOPED_TRACE(g);
        samples_against_pdf([&](double u) { return double(sample_hg_cos(g, float(u))); },
                            [&](double c) { return 2 * M_PI * hg_phase(g, c); }, -1.0, 1.0, 64);
        // The phase function integrates to one over the sphere.
        double total = 0.0;
        for (int k = 0; k < 64; ++k)
            total += gauss<double, 20>::integrate([&](double c) { return hg_phase(g, c); },
                                                  -1.0 + k / 32.0, -1.0 + (k + 1) / 32.0);
        EXPECT_NEAR(total * 2 * M_PI, 1.0, 1e-6);
    }
}

TEST(Sampling, EquiangularDistancesFollowTheirPdf) {
    struct Case {
        double delta, h, t0, t1;
    };
    for (const Case& c : {Case{0.5, 0.2, 0.0, 3.0}, Case{-1.0, 0.7, 0.0, 2.0},
                          Case{4.0, 0.05, 0.0, 5.0}, Case{1.0, 1.0, 0.5, 1.5}}) {
        SCOPED_TRACE(c.delta);
        samples_against_pdf(
            [&](double u) {
                EquiangularSample s;
                EXPECT_TRUE(sample_equiangular(c.delta, c.h, c.t0, c.t1, u, &s));
                EXPECT_NEAR(s.pdf, equiangular_pdf(c.delta, c.h, c.t0, c.t1, s.t), 1e-9 * s.pdf);
                return s.t;
            },
            [&](double t) { return equiangular_pdf(c.delta, c.h, c.t0, c.t1, t); }, c.t0, c.t1, 48);
    }
}

TEST(Sampling, TruncatedExponentialDistancesFollowTheirPdf) {
    for (double sigma : {0.1, 1.0, 7.0}) {
        SCOPED_TRACE(sigma);
        const double t_end = 2.0;
        const double mass = -std::expm1(-sigma * t_end);
        samples_against_pdf(
            [&](double u) {
                const TruncatedExponentialSample s = sample_truncated_exponential(sigma, t_end, u);
                EXPECT_NEAR(s.pdf, sigma * std::exp(-sigma * s.t) / mass, 1e-9 * s.pdf);
                return s.t;
            },
            [&](double t) { return sigma * std::exp(-sigma * t) / mass; }, 0.0, t_end, 40);
    }
}

TEST(Sampling, HenyeyGreensteinDirectionsAreThePhaseFunctionAboutTheirAxis) {
    // sample_hg_direction's cosine with the axis follows HG (chi-square in cos), its azimuth
    // about the axis is uniform (chi-square in phi), and it is a unit vector.
    const vec3 axis = glm::normalize(vec3(0.3f, -0.5f, 0.8f));
    const Frame frame(axis);
    for (float g : {-0.6f, 0.0f, 0.8f}) {
        SCOPED_TRACE(g);
        CounterRng rng(17, 3, 0, 0);
        const int n = 200000, bins = 32;
        std::vector<double> cos_obs(bins, 0.0), cos_exp(bins, 0.0), phi_obs(bins, 0.0),
            phi_exp(bins, n / double(bins));
        for (int i = 0; i < n; ++i) {
            const vec3 d = sample_hg_direction(g, axis, rng.next_float(), rng.next_float());
            ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
            const vec3 l = frame.to_local(d);
            const int cb = std::clamp(int((l.z + 1.0f) * 0.5f * bins), 0, bins - 1);
            const double phi = std::atan2(double(l.y), double(l.x)) + M_PI;
            const int pb = std::clamp(int(phi / (2 * M_PI) * bins), 0, bins - 1);
            cos_obs[size_t(cb)] += 1;
            phi_obs[size_t(pb)] += 1;
        }
        for (int b = 0; b < bins; ++b)
            cos_exp[size_t(b)] = n * gauss<double, 20>::integrate(
                                         [&](double c) { return 2 * M_PI * hg_phase(g, c); },
                                         -1.0 + 2.0 * b / bins, -1.0 + 2.0 * (b + 1) / bins);
        double chi2;
        EXPECT_GT(test::chi_square_p_value(cos_obs, cos_exp, &chi2), 1e-3) << "cos chi2 " << chi2;
        EXPECT_GT(test::chi_square_p_value(phi_obs, phi_exp, &chi2), 1e-3) << "phi chi2 " << chi2;
    }
}

TEST(Sampling, NearLightDirectionsFollowTheirPdf) {
    // Directions aimed past a point light (volume/near_light_directions.h): the angle to the
    // light's direction against the pdf() integrated over rings of it (chi-square), none
    // outside the cone, and two lights' pdf the mean of each one's.
    const vec3 x(0.2f, -0.4f, 0.1f), light(1.0f, 2.0f, 3.0f);
    Light point;
    point.position = light;
    const NearLightDirections one({point}, 1.0f);
    const vec3 axis = glm::normalize(light - x);
    const Frame frame(axis);
    const double max_angle = std::atan(0.5);  // the cone the strategy covers (any point's)
    auto direction_at = [&](double theta) {
        return frame.to_world(vec3(float(std::sin(theta)), 0.0f, float(std::cos(theta))));
    };
    const int n = 200000, bins = 32;
    std::vector<double> observed(bins + 1, 0.0), expected(bins + 1, 0.0);
    CounterRng rng(23, 1, 0, 0);
    for (int i = 0; i < n; ++i) {
        vec3 d;
        ASSERT_TRUE(one.sample(x, rng.next_float(), rng.next_float(), rng.next_float(), &d));
        ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
        const double theta = std::acos(std::clamp(double(glm::dot(d, axis)), -1.0, 1.0));
        observed[size_t(std::min(bins, int(theta / max_angle * bins)))] += 1;
    }
    for (int b = 0; b < bins; ++b)
        expected[size_t(b)] =
            n * gauss<double, 20>::integrate(
                    [&](double t) { return 2 * M_PI * std::sin(t) * one.pdf(x, direction_at(t)); },
                    max_angle * b / bins, max_angle * (b + 1) / bins);
    EXPECT_EQ(observed[size_t(bins)], 0.0) << "outside the cone";
    EXPECT_EQ(one.pdf(x, direction_at(max_angle * 1.01)), 0.0);
    EXPECT_EQ(one.pdf(x, -axis), 0.0);
    observed.pop_back(), expected.pop_back();
    double chi2;
    EXPECT_GT(test::chi_square_p_value(observed, expected, &chi2), 1e-3) << "chi2 " << chi2;
    Light other = point;
    other.position = vec3(-2.0f, 0.5f, 1.0f);
    const NearLightDirections two({point, other}, 0.3f);
    const NearLightDirections alone({other}, 0.3f);
    const vec3 d = direction_at(0.2);
    EXPECT_NEAR(two.pdf(x, d), 0.5 * (one.pdf(x, d) + alone.pdf(x, d)), 1e-9 * one.pdf(x, d));
    const double f = two.fraction();
    EXPECT_NEAR(two.mixture_pdf(x, d, 0.25), (1 - f) * 0.25 + f * two.pdf(x, d), 1e-9);
}

TEST(Sampling, LightSamplesGiveTheClosedFormIrradiance) {
    // A point light: I / d^2 exactly, towards it.
    Light point;
    point.type = LightType::Point;
    point.position = vec3(1, 2, 3);
    point.intensity = vec3(5.0f);
    const LightSample ps = sample_light(point, vec3(1, 2, 1), vec2(0.3f));
    ASSERT_TRUE(ps.valid);
    EXPECT_FLOAT_EQ(ps.distance, 2.0f);
    EXPECT_FLOAT_EQ(ps.irradiance.x, 5.0f / 4.0f);
    EXPECT_FLOAT_EQ(ps.direction.z, 1.0f);
    EXPECT_FALSE(sample_light(point, point.position, vec2(0.0f)).valid);
    // A directional light: its irradiance, against its direction of travel, unbounded.
    Light sun;
    sun.type = LightType::Directional;
    sun.direction = vec3(0, 0, -1);
    sun.intensity = vec3(3.0f);
    const LightSample ds = sample_light(sun, vec3(0.0f), vec2(0.0f));
    EXPECT_TRUE(ds.valid && std::isinf(ds.distance) && ds.direction.z == 1.0f);
    EXPECT_FLOAT_EQ(ds.irradiance.y, 3.0f);
    // A square quad of radiance L at height h, facing down, over a receiver facing up below a
    // corner: the mean of irradiance x cos over uniform samples is pi L times the
    // differential-area-to-parallel-rectangle form factor (closed form), within 4 standard errors.
    const double a = 1.5, b = 0.8, h = 0.7, L = 2.0;
    Light quad;
    quad.type = LightType::Quad;
    quad.corner = vec3(0, 0, float(h));
    quad.edge_u = vec3(0, float(b), 0);  // edge_u x edge_v = -z: emits downwards
    quad.edge_v = vec3(float(a), 0, 0);
    quad.intensity = vec3(float(L));
    const double A = a / h, B = b / h;
    const double form = (A / std::sqrt(1 + A * A) * std::atan(B / std::sqrt(1 + A * A)) +
                         B / std::sqrt(1 + B * B) * std::atan(A / std::sqrt(1 + B * B))) /
                        (2 * M_PI);
    const double expected = M_PI * L * form;
    CounterRng rng(5, 9, 0, 0);
    const int n = 400000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const LightSample s =
            sample_light(quad, vec3(0.0f), vec2(rng.next_float(), rng.next_float()));
        ASSERT_TRUE(s.valid);
        const double e = double(s.irradiance.x) * s.direction.z;
        sum += e;
        sum2 += e * e;
    }
    const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, expected, 4 * se) << "se " << se;
    EXPECT_LT(se, 0.01 * expected);
    // The back of the quad receives nothing.
    EXPECT_FALSE(sample_light(quad, vec3(0.5f, 0.5f, float(h) + 1.0f), vec2(0.5f)).valid);
}
