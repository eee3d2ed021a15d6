// Shades every pixel's G-buffer hit with the direct-lighting estimator at a fixed sample
// count: the `mis` method (the seed's equal-time MIS baseline) and, at a high count, the
// `reference`. Pixel centres only, as method A's radiance points are: the comparison is of
// shading, not of antialiasing.
#pragma once

#include "render/direct_lighting.h"
#include "render/gbuffer.h"

namespace freqlab {

struct ShadingPassOutput {
    long rays = 0;
    long nonfinite = 0;  // estimates that were NaN/Inf (set to 0 in `color`, counted here)
};

// Writes `color` (radiance) and `variance` (of each pixel's luminance estimate) into `layers`.
ShadingPassOutput shade_pixels(const RayScene& scene, const GBuffer& gbuffer, int frame,
                               const FrameSettings& frame_settings, int spp,
                               const ShadingSettings& shading, SampleSequence sequence,
                               LayerSet& layers, Progress& progress);

// Purpose tags folded into the seed so that streams of different passes never coincide.
constexpr uint64_t kShadingStream = 0x5348414445ULL;  // "SHADE"

}  // namespace freqlab
