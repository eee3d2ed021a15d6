// The branch-free math of the vectorized integrator (math/fast_math.h) against libm in double,
// over each function's whole domain, and the batched BRDF / environment routines
// (scene/brdf_batch.h, EnvironmentMap's batch overloads) against the one-direction reference
// implementations that the chi-square and quadrature tests check.
#include <gtest/gtest.h>

#include <cmath>

#include "math/fast_math.h"
#include "math/rng.h"
#include "scene/brdf.h"
#include "scene/brdf_batch.h"
#include "scene/light.h"

using namespace freqlab;

TEST(FastMath, SinCosWithinTwoUlpOfOneOverTheDomain) {
    double worst = 0;
    for (int i = -4000000; i <= 4000000; ++i) {
        const float x = float(i) * 1e-4f;  // [-400, 400]
        float s, c;
        fast_sincos(x, &s, &c);
        worst = std::max(worst, std::fabs(s - std::sin(double(x))));
        worst = std::max(worst, std::fabs(c - std::cos(double(x))));
    }
    EXPECT_LT(worst, 2.0 * 0x1p-24) << worst;
}

TEST(FastMath, Log2Exp2AndPowAgainstLibm) {
    double worst_log = 0, worst_exp = 0, worst_pow = 0;
    for (int i = 0; i <= 200000; ++i) {
        const float x = float(std::exp2(-120.0 + 240.0 * i / 200000.0));
        // Beyond the function's own ~2e-7, a float result rounds by half an ulp of log2 x.
        const double log2_x = std::log2(double(x));
        worst_log =
            std::max(worst_log, std::fabs(fast_log2(x) - log2_x) - std::fabs(log2_x) * 0x1p-24);
        const float y = float(-125.0 + 252.0 * i / 200000.0);
        const double e2 = std::exp2(double(y));
        worst_exp = std::max(worst_exp, std::fabs(fast_exp2(y) - e2) / e2);
    }
    // pow over the ranges the lobes use: cosines in (0, 1], exponents up to 10^4.
    for (int i = 1; i <= 1000; ++i)
        for (float e : {0.01f, 0.5f, 1.0f, 40.0f, 1000.0f, 10000.0f}) {
            const float x = float(i) / 1000.0f;
            const double ref = std::pow(double(x), double(e));
            if (ref < 1e-30) continue;
            // log2 x is exact to ~2e-7 absolute: pow's relative error is e x that x ln 2.
            const double rel = std::fabs(fast_pow(x, e) - ref) / ref;
            worst_pow = std::max(worst_pow, rel / (1.0 + e * std::fabs(std::log2(double(x)))));
        }
    EXPECT_LT(worst_log, 2.5e-7) << worst_log;
    EXPECT_LT(worst_exp, 3.0 * 0x1p-24) << worst_exp;
    EXPECT_LT(worst_pow, 4e-7) << worst_pow;
    EXPECT_EQ(fast_exp2(-200.0f), 0.0f);
    EXPECT_EQ(fast_pow(0.0f, 3.0f), 0.0f);
    EXPECT_EQ(fast_pow(0.0f, 0.0f), 1.0f);
}

namespace {

Material material(BrdfType type) {
    Material m;
    m.type = type;
    m.phong_exponent = 40.0f;
    m.roughness = type == BrdfType::Ggx ? 0.35f : 0.3f;
    return m;
}

vec3 random_direction(CounterRng& rng) {
    const float z = 1.0f - 2.0f * rng.next_float(), phi = kTwoPi * rng.next_float();
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return vec3(r * std::cos(phi), r * std::sin(phi), z);
}

// |a - b| relative to the larger, with an absolute floor for values near zero.
double relative(double a, double b) {
    return std::fabs(a - b) / std::max({std::fabs(a), std::fabs(b), 1e-3});
}

}  // namespace

TEST(BrdfBatch, EvalPdfAndSamplesMatchTheReferenceBrdf) {
    const vec3 albedo(0.7f, 0.5f, 0.3f);
    for (BrdfType type : {BrdfType::Lambert, BrdfType::Phong, BrdfType::Beckmann, BrdfType::Ggx}) {
        const Material m = material(type);
        CounterRng rng(7, 0, uint64_t(type), 0);
        for (int point = 0; point < 40; ++point) {
            const vec3 normal = random_direction(rng), wo = random_direction(rng);
            const Brdf brdf(m, albedo, normal);
            const BrdfBatch batch(brdf, wo);
            constexpr int n = 64;
            float x[n], y[n], z[n], value[n], pdf[n], u1[n], u2[n];
            for (int i = 0; i < n; ++i) {
                const vec3 d = random_direction(rng);
                x[i] = d.x, y[i] = d.y, z[i] = d.z;
                u1[i] = rng.next_float(), u2[i] = rng.next_float();
            }
            batch.eval(n, x, y, z, value, pdf);
            for (int i = 0; i < n; ++i) {
                const vec3 d(x[i], y[i], z[i]);
                ASSERT_LT(relative(value[i] * albedo.x, brdf.eval(wo, d).x), 1e-4)
                    << to_string(type) << " point " << point << " direction " << i;
                ASSERT_LT(relative(pdf[i], brdf.pdf(wo, d)), 1e-4) << to_string(type);
            }
            batch.sample(n, u1, u2, x, y, z, value, pdf);
            for (int i = 0; i < n; ++i) {
                const BrdfSample ref = brdf.sample(wo, u1[i], u2[i]);
                if (ref.pdf <= 0.0f) {
                    ASSERT_EQ(pdf[i], 0.0f) << to_string(type);
                    continue;
                }
                ASSERT_LT(glm::length(vec3(x[i], y[i], z[i]) - ref.wi), 2e-5f) << to_string(type);
                // Microfacet pdfs divide by |wo + wi| = 2 wo.h: near 0 (grazing samples) both
                // routines lose every digit to cancellation, so only conditioned samples compare.
                if (glm::length(wo + ref.wi) < 0.05f) continue;
                ASSERT_LT(relative(pdf[i], ref.pdf), 2e-3)
                    << to_string(type) << " " << pdf[i] << " vs " << ref.pdf << " u " << u1[i]
                    << " " << u2[i] << " wo.n " << glm::dot(wo, normal);
                ASSERT_LT(relative(value[i] * albedo.x, ref.f.x), 2e-3) << to_string(type);
            }
        }
    }
}

TEST(EnvironmentBatch, SamplesAndLookupsMatchTheOneDirectionRoutines) {
    // A map with structure in both directions and a rotation, so texels and pdfs all differ.
    auto image = std::make_shared<RgbImage>();
    image->width = 64, image->height = 32;
    image->pixels.resize(size_t(image->width * image->height));
    for (int yy = 0; yy < image->height; ++yy)
        for (int xx = 0; xx < image->width; ++xx)
            image->pixels[size_t(yy * image->width + xx)] =
                vec3(1.0f + float((xx * 7 + yy * 3) % 11), 0.5f + float(yy), 2.0f);
    const EnvironmentMap env("test", image, 37.0f, 1.0f);
    CounterRng rng(3, 0, 0, 0);
    constexpr int n = 4096;
    std::vector<int> texel(n), scratch_texel(n);
    std::vector<vec4> u(n);
    std::vector<float> x(n), y(n), z(n), pdf(n), sin_theta(n);
    std::vector<vec3> radiance(n);
    for (int i = 0; i < n; ++i) {
        u[size_t(i)] = vec4(rng.next_float(), rng.next_float(), rng.next_float(), rng.next_float());
        texel[size_t(i)] = env.sample_texel(u[size_t(i)]);
    }
    env.sample_directions(n, texel.data(), u.data(), x.data(), y.data(), z.data(),
                          sin_theta.data());
    env.texel_values(n, texel.data(), sin_theta.data(), pdf.data(), radiance.data());
    for (int i = 0; i < n; ++i) {
        vec3 d;
        float p;
        const vec3 le = env.sample_at(texel[size_t(i)], u[size_t(i)], &d, &p);
        ASSERT_LT(glm::length(vec3(x[size_t(i)], y[size_t(i)], z[size_t(i)]) - d), 1e-6f);
        ASSERT_LT(relative(pdf[size_t(i)], p), 1e-5);
        ASSERT_EQ(radiance[size_t(i)], le);
    }
    // Lookups of random directions: the same texel and density (texel edges aside).
    for (int i = 0; i < n; ++i) {
        const vec3 d = random_direction(rng);
        x[size_t(i)] = d.x, y[size_t(i)] = d.y, z[size_t(i)] = d.z;
    }
    env.lookup_texels(n, x.data(), y.data(), z.data(), scratch_texel.data(), sin_theta.data());
    env.texel_values(n, scratch_texel.data(), sin_theta.data(), pdf.data(), radiance.data());
    int same = 0;
    for (int i = 0; i < n; ++i) {
        float p;
        const vec3 le = env.eval_with_pdf(vec3(x[size_t(i)], y[size_t(i)], z[size_t(i)]), &p);
        if (le != radiance[size_t(i)]) continue;
        ++same;
        ASSERT_LT(relative(pdf[size_t(i)], p), 1e-4);
    }
    EXPECT_GE(same, n - 2);
}
