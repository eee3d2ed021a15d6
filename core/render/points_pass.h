// `--method points`: a radiance point (render/radiance_point.h) at every pixel, or every k-th
// (points.stride; the k x k block shows it), writing its estimate and every quantity of its
// frequency analysis as layers.
#pragma once

#include <array>

#include "freq/env_bandwidth.h"
#include "render/gbuffer.h"
#include "render/radiance_point.h"

namespace freqlab {

struct PointsPassOutput {
    long rays = 0;
    long nonfinite = 0;
    long pixels_shaded = 0;  // pixels a radiance point was computed at (one per stride block)
};

// The layers written, in order (after `color` and `variance`).
const std::vector<std::string>& radiance_point_layer_names();

// The point's values in the order of radiance_point_layer_names().
std::array<double, 10> radiance_point_fields(const RadiancePoint& point);

PointContext point_context(const GBuffer& gbuffer, int x, int y, float time);

PointsPassOutput render_points(const RayScene& scene, const GBuffer& gbuffer, int frame,
                               const FrameSettings& frame_settings, const ShadingSettings& shading,
                               const PointsSettings& settings,
                               const EnvBandwidthHierarchy* bandwidth, LayerSet& layers,
                               Progress& progress);

// Seed purpose tag of radiance points (distinct from the shading pass's stream).
constexpr uint64_t kPointsStream = 0x504f494e54ULL;  // "POINT"

}  // namespace freqlab
