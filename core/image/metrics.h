// Image error metrics used by `freqlab compare`, the bench and the tests.
//
// | metric   | definition                                                                  |
// |----------|-----------------------------------------------------------------------------|
// | rmse     | sqrt(mean over pixels and RGB channels of (I - R)^2)                         |
// | relmse   | mean over pixels and RGB channels of (I - R)^2 / (R + eps)^2, eps = 0.01     |
// | ssim     | mean SSIM of luminance, 11x11 Gaussian window sigma = 1.5, K1 = 0.01,        |
// |          | K2 = 0.03, dynamic range L = 1 (radiance is not clamped), valid region only |
// | max_abs  | max |I - R| over pixels and channels                                         |
// | nonfinite| number of NaN/Inf values in TEST (they are excluded from the sums above)     |
#pragma once

#include <string>

#include "image/layers.h"

namespace freqlab {

// The two relMSE floors, named once. Images (radiance of display-referred scenes, ~1): an
// absolute eps, so dark pixels do not dominate. Lightmaps (irradiance in each scene's own
// units, 1e-2 to 1e2): eps relative to the reference's mean (lightmap_baker.h).
constexpr double kImageRelMseEpsilon = 0.01;
constexpr double kLightmapRelMseEpsilonOfMean = 1e-3;
// relMSE's companion over the lit texels only: those whose reference reaches this fraction of
// its mean (near-black reference texels weigh up to 1 / e^2 = 1e6 / mean^2 in relMSE, so a
// handful of them, lit by one rare path of a test run, rule it for every method).
constexpr double kLightmapLitTexelFractionOfMean = 0.02;

struct ImageMetrics {
    double rmse = 0, relmse = 0, ssim = 1, max_abs = 0;
    long nonfinite = 0;
};

// Compares one layer of the same name in both sets (default `color`). Sizes must match; a
// non-finite REF value is an error (a reference must be clean).
ImageMetrics compare_layers(const LayerSet& test, const LayerSet& ref,
                            const std::string& layer = "color",
                            double relmse_eps = kImageRelMseEpsilon);

// SSIM of two single-channel images of equal size (row-major).
double ssim(const std::vector<float>& a, const std::vector<float>& b, int width, int height);

}  // namespace freqlab
