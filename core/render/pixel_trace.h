// The built-in methods' parts of a pixel trace (--debug-pixel, the inspector): each re-runs
// the pixel's estimate as the render ran it (same seed keys, same estimator) and prints it.
#pragma once

#include "render/method.h"
#include "render/reconstruction.h"

namespace freqlab {

// mis, reference: every direct-lighting sample (strategy, direction, pdfs, MIS weight,
// contribution, visibility).
void trace_direct_lighting(const PixelTraceContext& c, TraceLines& out);
// points: the radiance point's whole chain (bandwidths, N_Omega, visibility).
void trace_radiance_point(const PixelTraceContext& c, TraceLines& out);
// sparse: the radiance points the reconstruction used here, with their weights (Eq. 6.2).
void trace_reconstruction(const PixelTraceContext& c, TraceLines& out);
// The contributions reconstruct() summed at pixel (x, y) of `r`, rebuilt from its layers, the
// scene at the frame's time (rs updated to it) and the reused samples' positions: the weights
// trace_reconstruction prints, equal to the render's (tested against its ReconstructionRecord).
ReconstructionRecord rebuild_reconstruction(const RayScene& rs, const RenderConfig& config,
                                            const FrameResult& r, const CameraRayGenerator& camera,
                                            int x, int y);
// cache: the cache entries at the pixel with their decisions, then the reconstruction.
void trace_cache(const PixelTraceContext& c, TraceLines& out);

}  // namespace freqlab
