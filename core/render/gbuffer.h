// The G-buffer pass: primary rays in 8-wide packets over 16x16 tiles (oneTBB), giving each
// pixel its first surface. It is method `gbuffer` on the command line and the first stage of
// every later method.
//
// | parameter            | meaning                                                          |
// |----------------------|------------------------------------------------------------------|
// | frame.width/height   | image size                                                       |
// | frame.seed           | with (frame, pixel, sample) keys the jitter of AA samples        |
// | gbuffer.aa_samples   | jittered rays averaged into `albedo` and `color` (when           |
// |                      | `antialiased`: the shading methods use the centre hits only, so  |
// |                      | they skip these rays and take both from the centre hit)          |
#pragma once

#include <atomic>
#include <vector>

#include "accel/ray_scene.h"
#include "base/job.h"
#include "image/layers.h"
#include "settings/render_settings.h"

namespace freqlab {

// Per-pixel first hits of the pixel-centre rays; what later stages consume.
struct GBuffer {
    int width = 0, height = 0;
    std::vector<SurfaceHit> hits;
    std::vector<vec3> view_dirs;  // unit, from the camera through the pixel centre
    const SurfaceHit& at(int x, int y) const { return hits[size_t(y) * width + x]; }
};

struct GBufferOutput {
    GBuffer gbuffer;
    LayerSet layers;  // color (preview), albedo, normal, position, depth, object
    long rays = 0;
};

// `scene` must already be update()d to the frame's time.
GBufferOutput render_gbuffer(const RayScene& scene, int frame, const FrameSettings& frame_settings,
                             const GBufferSettings& settings, Progress& progress,
                             bool antialiased = true);

}  // namespace freqlab
