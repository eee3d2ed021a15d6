// Method A's image reconstruction (seed, Premier article §6, Eq. 6.1-6.2): each pixel's shading
// is the normalised cross-bilateral sum of the radiance points around it on the same object,
// with features {p, n, mu_v, sigma_v}; textures multiply afterwards (the caller demodulates the
// samples by their texture value and remodulates the result).
//
// | parameter | meaning                                                                      |
// |-----------|------------------------------------------------------------------------------|
// | radius    | per pixel, 2 / sqrt(density) clamped to [1, f_max]: about two sample spacings |
// | weights   | exp(-sum_f |f_i - f_p|^2 / (2 sigma_f^2)); distance in pixel footprints       |
// | fallback  | no weight above 1e-6: the radius doubles (up to 4 f_max); still none: the     |
// |           | pixel is reported and the caller shades it (never black, never NaN)          |
#pragma once

#include <vector>

#include "render/sparse_sampling.h"

namespace freqlab {

struct ReconstructionInput {
    int width = 0, height = 0;
    std::vector<PixelFeature> features;
    std::vector<float> mu_v, sigma_v;  // per pixel (measured where sampled, upsampled elsewhere)
    std::vector<float> radius;         // per pixel, px
    std::vector<char> sampled;         // per pixel
    std::vector<vec3> value;           // per pixel, read where sampled (demodulated)
    // Where a sample's position differs from its pixel's (cached points reprojected off the
    // pixel centre): per pixel, read where sampled; empty: the pixel's own features.
    std::vector<PixelFeature> sample_features;
};

struct ReconstructionOutput {
    std::vector<vec3> value;
    std::vector<float> weight, radius_used;
    std::vector<char> fallback;  // no usable neighbour even at 4 f_max
    long fallback_pixels = 0;
};

// What the reconstruction summed at one pixel, recorded while it ran (--debug-pixel, the
// inspector, tests): every sample it weighed at the radius it settled on, in scan order.
struct ReconstructionRecord {
    int x = -1, y = -1;  // the pixel to record (set by the caller)
    struct Contribution {
        int x, y;
        double weight;
    };
    std::vector<Contribution> used;
    float radius = 0.0f;
    double sum = 0.0;
    bool recorded = false;
};

// `record`, when given, receives pixel (record->x, record->y)'s contributions.
ReconstructionOutput reconstruct(const ReconstructionInput& in, const SparseSettings& settings,
                                 ReconstructionRecord* record = nullptr);

// Pixel (x, y)'s contributions at exactly radius r (the radius the render settled on): the
// same sums reconstruct() runs, for a trace that rebuilds the inputs around one pixel.
void reconstruct_pixel_at(const ReconstructionInput& in, int x, int y, float r,
                          const SparseSettings& settings, ReconstructionRecord& record);

// Eq. 6.2's weight of the sample at pixel j for pixel i (what reconstruct() sums; the inspector
// lists it). Distance in units of pixel i's footprint.
double reconstruction_weight(const PixelFeature& fi, const PixelFeature& fj, float mu_i, float mu_j,
                             float sigma_i, float sigma_j, const SparseSettings& settings);

}  // namespace freqlab
