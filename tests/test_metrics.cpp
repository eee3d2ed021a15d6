// Metrics on images with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "base/error.h"
#include "image/metrics.h"
#include "math/rng.h"
#include "volume/lightmap_baker.h"

using namespace freqlab;

namespace {

LayerSet constant_image(int w, int h, float v) {
    LayerSet s(w, h);
    Layer& c = s.add("color", LayerKind::Color, 3);
    for (float& x : c.data) x = v;
    return s;
}

LayerSet smooth_image(int w, int h) {
    LayerSet s(w, h);
    Layer& c = s.add("color", LayerKind::Color, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < 3; ++k)
                c.at(w, x, y, k) = 0.5f + 0.4f * std::sin(0.1f * x + 0.07f * y + k);
    return s;
}

}  // namespace

TEST(Metrics, RmseOfConstantOffset) {
    const LayerSet ref = smooth_image(64, 48);
    LayerSet test = ref;
    for (float& v : test.layers()[0].data) v += 0.25f;
    const ImageMetrics m = compare_layers(test, ref);
    EXPECT_NEAR(m.rmse, 0.25, 1e-6);
    EXPECT_NEAR(m.max_abs, 0.25, 1e-6);
    EXPECT_EQ(m.nonfinite, 0);
}

TEST(Metrics, RelMseHasTheStatedForm) {
    const LayerSet ref = constant_image(16, 16, 0.49f);
    const LayerSet test = constant_image(16, 16, 0.99f);
    // (0.5)^2 / (0.49 + 0.01)^2 = 1
    EXPECT_NEAR(compare_layers(test, ref).relmse, 1.0, 1e-5);
}

TEST(Metrics, SsimIsOneOnIdenticalImages) {
    const LayerSet a = smooth_image(64, 48);
    const ImageMetrics m = compare_layers(a, a);
    EXPECT_NEAR(m.ssim, 1.0, 1e-9);
    EXPECT_EQ(m.rmse, 0.0);
}

TEST(Metrics, SsimDropsWithNoise) {
    const LayerSet ref = smooth_image(64, 48);
    LayerSet weak = ref, strong = ref;
    CounterRng rng(3, 0, 0, 0);
    for (size_t i = 0; i < weak.layers()[0].data.size(); ++i) {
        const float n = rng.next_float() - 0.5f;
        weak.layers()[0].data[i] += 0.05f * n;
        strong.layers()[0].data[i] += 0.5f * n;
    }
    const double s_weak = compare_layers(weak, ref).ssim,
                 s_strong = compare_layers(strong, ref).ssim;
    EXPECT_LT(s_weak, 0.999);
    EXPECT_LT(s_strong, s_weak);
    EXPECT_GT(s_strong, -1.0);
}

TEST(Metrics, SsimMatchesClosedFormForConstantImages) {
    // Constant images: variances and covariance vanish, SSIM = (2ab + C1) / (a^2 + b^2 + C1).
    const double a = 0.3, b = 0.6, c1 = 1e-4;
    const double expected = (2 * a * b + c1) / (a * a + b * b + c1);
    EXPECT_NEAR(
        compare_layers(constant_image(32, 32, float(a)), constant_image(32, 32, float(b))).ssim,
        expected, 1e-5);
}

TEST(Metrics, CountsNonFiniteInTestAndExcludesThem) {
    const LayerSet ref = constant_image(8, 8, 0.5f);
    LayerSet test = ref;
    test.layers()[0].data[0] = NAN;
    test.layers()[0].data[5] = INFINITY;
    const ImageMetrics m = compare_layers(test, ref);
    EXPECT_EQ(m.nonfinite, 2);
    EXPECT_EQ(m.rmse, 0.0);
}

TEST(Metrics, MismatchedSizesAreAnError) {
    try {
        compare_layers(constant_image(8, 8, 0), constant_image(8, 9, 0));
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("8x8"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("8x9"), std::string::npos);
    }
}

#include "image/colormap.h"

TEST(Colormap, TicksAreNiceAndInsideTheRange) {
    EXPECT_EQ(colorbar_ticks(0.0, 1.0), (std::vector<double>{0.0, 0.2, 0.4, 0.6, 0.8, 1.0}));
    const std::vector<double> t = colorbar_ticks(-3.7, 12.2);
    ASSERT_GE(t.size(), 3u);
    EXPECT_DOUBLE_EQ(t.front(), 0.0);
    for (size_t i = 0; i < t.size(); ++i) {
        EXPECT_GE(t[i], -3.7);
        EXPECT_LE(t[i], 12.2);
        if (i) {
            EXPECT_NEAR(t[i] - t[i - 1], 5.0, 1e-12);  // 1-2-5 steps: 5 here
        }
    }
    EXPECT_EQ(colorbar_ticks(2.0, 2.0), (std::vector<double>{2.0, 2.0}));  // degenerate range
}

TEST(Colormap, KnownValues) {
    // Endpoints of matplotlib's viridis, the middle of the diverging map is white-ish grey.
    EXPECT_NEAR(viridis(0.0f).r, 0x44 / 255.0f, 1e-6f);
    EXPECT_NEAR(viridis(1.0f).g, 0xe7 / 255.0f, 1e-6f);
    EXPECT_NEAR(diverging(0.0f).r, 0xf7 / 255.0f, 1e-6f);
    EXPECT_NEAR(categorical(11).r, categorical(1).r, 0.0f);  // the palette cycles
}

// Lightmap measures count valid texels only: not empty, inside-geometry or dilated ones.
TEST(LightmapMeasures, OnlyValidTexelsCount) {
    LayerSet lm(4, 1), ref(4, 1);
    for (LayerSet* set : {&lm, &ref}) {
        Layer& valid = set->add("texel_valid", LayerKind::Categorical, 1);
        valid.data = {float(TexelState::Empty), float(TexelState::Valid),
                      float(TexelState::InsideGeometry), float(TexelState::Dilated)};
    }
    Layer& a = lm.add("lm_irradiance", LayerKind::Color, 3);
    Layer& b = ref.add("lm_irradiance", LayerKind::Color, 3);
    for (int i = 0; i < 4; ++i)
        for (int c = 0; c < 3; ++c) {
            a.data[size_t(3 * i + c)] = float(i + 1);
            b.data[size_t(3 * i + c)] = i == 1 ? 1.0f : 100.0f;
        }
    EXPECT_FLOAT_EQ(float(valid_texel_luminance_sum(lm, "lm_irradiance")), 2.0f);
    const LightmapError e = compare_lightmaps(lm, ref, "lm_irradiance");
    EXPECT_EQ(e.texels, 1);
    EXPECT_NEAR(e.relmse, 1.0, 1e-5);  // (2 - 1)^2 / 1^2 at the one valid texel
}

// The worst texels are those whose terms weigh most in relMSE, largest first, with their
// positions and shares: a near-black reference texel weighs ~1 / e^2 and rules the measure.
TEST(LightmapMeasures, WorstTexelsAreTheLargestRelMseTerms) {
    const int w = 8, h = 4;
    LayerSet lm(w, h), ref(w, h);
    for (LayerSet* set : {&lm, &ref}) {
        Layer& valid = set->add("texel_valid", LayerKind::Categorical, 1);
        std::fill(valid.data.begin(), valid.data.end(), float(TexelState::Valid));
    }
    Layer& a = lm.add("lm_irradiance", LayerKind::Color, 3);
    Layer& b = ref.add("lm_irradiance", LayerKind::Color, 3);
    std::fill(a.data.begin(), a.data.end(), 1.0f);
    std::fill(b.data.begin(), b.data.end(), 1.0f);
    const size_t dark = 3 * w + 5, brighter = 1 * w + 2;  // (5, 3) and (2, 1)
    for (int c = 0; c < 3; ++c) {
        b.data[3 * dark + size_t(c)] = 0.0f;      // the reference sees no light here
        a.data[3 * dark + size_t(c)] = 0.01f;     // a little: (0.01 / e)^2 per channel
        a.data[3 * brighter + size_t(c)] = 1.5f;  // 50 % too bright: 0.25 per channel
    }
    const LightmapError e = compare_lightmaps(lm, ref, "lm_irradiance", nullptr, 3);
    ASSERT_EQ(e.worst.size(), 3u);
    EXPECT_EQ(e.worst[0].x, 5);
    EXPECT_EQ(e.worst[0].y, 3);
    EXPECT_FLOAT_EQ(float(e.worst[0].ref), 0.0f);
    EXPECT_NEAR(e.worst[0].test, 0.01, 1e-6);
    EXPECT_EQ(e.worst[1].x, 2);
    EXPECT_EQ(e.worst[1].y, 1);
    EXPECT_DOUBLE_EQ(e.worst[2].relmse_share, 0.0);
    // e = 1e-3 x the reference's mean (31 / 32): the dark texel's term over all of them.
    const double eps = 1e-3 * 31.0 / 32.0;
    const double dark_term = 3 * 1e-4 / (eps * eps), bright_term = 3 * 0.25;
    EXPECT_NEAR(e.worst[0].relmse_share, dark_term / (dark_term + bright_term), 1e-5);
    EXPECT_NEAR(e.relmse, (dark_term + bright_term) / (3.0 * w * h), 1e-3);
    // Over the lit texels (reference >= 2 % of its mean) the dark one does not count.
    EXPECT_EQ(e.texels_lit, w * h - 1);
    EXPECT_NEAR(e.relmse_lit, 3 * 0.25 / (1.0 + eps * eps) / (3.0 * (w * h - 1)), 1e-12);
}

// A bake's error from its lightmaps' (combine_lightmap_errors): texel-weighted relmse, lit
// texels' by their count, squares for rmse; the reference's noise only where every measured
// part knows it; a part without texels left out.
TEST(LightmapMeasures, ABakesErrorWeighsItsLightmapsByTheirTexels) {
    LightmapError a, b, empty;
    a.relmse = 0.5, a.relmse_lit = 0.1, a.rmse = 2.0, a.texels = 100, a.texels_lit = 10;
    a.reference_noise = 0.01, a.reference_noise_lit = 0.02;
    b.relmse = 2.0, b.relmse_lit = 0.4, b.rmse = 1.0, b.texels = 300, b.texels_lit = 30;
    b.reference_noise = 0.03, b.reference_noise_lit = 0.04;
    const LightmapError e = combine_lightmap_errors({a, empty, b});
    EXPECT_EQ(e.texels, 400);
    EXPECT_EQ(e.texels_lit, 40);
    EXPECT_DOUBLE_EQ(e.relmse, (0.5 * 100 + 2.0 * 300) / 400.0);
    EXPECT_DOUBLE_EQ(e.relmse_lit, (0.1 * 10 + 0.4 * 30) / 40.0);
    EXPECT_DOUBLE_EQ(e.rmse, std::sqrt((4.0 * 100 + 1.0 * 300) / 400.0));
    EXPECT_DOUBLE_EQ(e.reference_noise, (0.01 * 100 + 0.03 * 300) / 400.0);
    EXPECT_DOUBLE_EQ(e.reference_noise_lit, (0.02 * 10 + 0.04 * 30) / 40.0);
    EXPECT_TRUE(std::isnan(e.rel_l2));
    b.reference_noise = b.reference_noise_lit = -1.0;  // one reference for b
    EXPECT_EQ(combine_lightmap_errors({a, b}).reference_noise, -1.0);
    EXPECT_EQ(combine_lightmap_errors({}).texels, 0);
}

// A reference given as two independent halves (compare_lightmaps' ref_half): the reference is
// their mean and reference_noise estimates the relMSE its own noise adds, texel by texel from
// the halves' difference ((a - b)^2 / 4, the variance of the mean of two). Synthetic lightmaps
// with known noise: truth 1-3, each half +- N(0, 0.06), the test +- N(0, 0.03); with noise this
// small against the truth the weights 1 / r^2 are nearly fixed, so reference_noise =
// mean(0.06^2 / 2 / truth^2) and relmse - reference_noise = mean(0.03^2 / truth^2), each to
// ~0.5 % over 3 x 40000 channels (2 % allowed; a factor 2 in the estimate misses by 50 %).
TEST(LightmapMeasures, ReferenceHalvesMeasureTheReferencesOwnNoise) {
    const int w = 200, h = 200;
    LayerSet test(w, h), half_a(w, h), half_b(w, h);
    for (LayerSet* set : {&test, &half_a, &half_b}) {
        Layer& valid = set->add("texel_valid", LayerKind::Categorical, 1);
        std::fill(valid.data.begin(), valid.data.end(), float(TexelState::Valid));
        set->add("lm_irradiance", LayerKind::Color, 3);
    }
    std::mt19937 gen(7);
    std::normal_distribution<double> normal(0.0, 1.0);
    const double sigma_ref = 0.06, sigma_test = 0.03;
    double want_noise = 0.0, want_own = 0.0;
    const size_t n = size_t(w) * h * 3;
    for (size_t k = 0; k < n; ++k) {
        const double truth = 1.0 + 2.0 * double(k % 997) / 996.0;
        half_a.find("lm_irradiance")->data[k] = float(truth + sigma_ref * normal(gen));
        half_b.find("lm_irradiance")->data[k] = float(truth + sigma_ref * normal(gen));
        test.find("lm_irradiance")->data[k] = float(truth + sigma_test * normal(gen));
        want_noise += sigma_ref * sigma_ref / 2.0 / (truth * truth) / double(n);
        want_own += sigma_test * sigma_test / (truth * truth) / double(n);
    }
    const LightmapError e = compare_lightmaps(test, half_a, "lm_irradiance", nullptr, 0, &half_b);
    std::printf("reference noise %.6f (want %.6f), own %.6f (want %.6f)\n", e.reference_noise,
                want_noise, e.relmse - e.reference_noise, want_own);
    EXPECT_NEAR(e.reference_noise, want_noise, 0.02 * want_noise);
    EXPECT_NEAR(e.relmse - e.reference_noise, want_own, 0.02 * want_own);
    EXPECT_NEAR(e.reference_noise_lit, e.reference_noise, 1e-12) << "every texel is lit";
    // One reference: its noise is not known.
    EXPECT_EQ(compare_lightmaps(test, half_a, "lm_irradiance").reference_noise, -1.0);
}
