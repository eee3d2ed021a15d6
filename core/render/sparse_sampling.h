// Method A's image-space sampling (seed, Premier article §5.1 "Sampling Density and Radiance
// Point Placement", §7): the density from the screen-space bandwidth, rejection sampling, and
// the depth- and normal-aware bilateral upsampling of the initial points' visibility statistics.
//
// | step        | rule                                                                       |
// |-------------|----------------------------------------------------------------------------|
// | density     | B_S (cycles/rad) x max(f_x / W, f_y / H) (rad/px) x density_scale, clamped  |
// |             | to [B_min, 1], B_min = 1 / (2 f_max)                                        |
// | rejection   | a pixel gets one radiance point when u < density, u uniform in [0, 1): 1    |
// |             | always samples, 0 never                                                    |
// | upsampling  | Gaussian in pixels (sigma = stride, radius 2 stride) x exp(-|n - n'|^2 / 2  |
// |             | 0.25^2) x exp(-(world distance / (stride footprints))^2 / 2), same object  |
#pragma once

#include <array>
#include <vector>

#include "accel/ray_scene.h"
#include "math/rng.h"
#include "math/types.h"
#include "scene/camera.h"
#include "settings/sparse_settings.h"

namespace freqlab {

double sampling_density(double B_S, double radians_per_pixel, const SparseSettings& settings);
bool rejection_sample(double density, CounterRng& rng);

// What the filters compare between pixels (from the G-buffer).
struct PixelFeature {
    bool valid = false;
    int object = -1;
    vec3 position{0.0f}, normal{0.0f};
    float footprint = 0.0f;  // world size of the pixel on the surface
};

// The pixel's features from its centre hit: its extent on the surface is the pixel's angular
// width at the hit, stretched by the grazing angle (without it, rows of a far plane never find
// each other).
PixelFeature pixel_feature(const SurfaceHit& hit, const vec3& view_dir, double radians_per_pixel);
// max(f_x / W, f_y / H): the angle one pixel subtends (seed §7).
double radians_per_pixel(const CameraRayGenerator& camera, int width, int height);

// {occluded, log t_min, occlusion ratio, sigma_V, log luminance of the demodulated shading, B_t}:
// the log luminance only feeds the cache's observed-change test; B_t (and t_min) the planned
// points' own values (render/radiance_point.h, VisibilityPlan).
constexpr int kUpsampledStats = 6;
using VisibilityStats = std::array<float, kUpsampledStats>;

// Fills `out` at every pixel from the values at `sources` (pixel indices); `found[i]` is false
// where no source on the same object was in reach (its statistics are then unknown).
void upsample_statistics(int width, int height, const std::vector<PixelFeature>& features,
                         const std::vector<int>& sources,
                         const std::vector<VisibilityStats>& values, int stride,
                         std::vector<VisibilityStats>& out, std::vector<char>& found);

}  // namespace freqlab
