// What a game would show of a bake: the scene seen from a camera with every lightmapped
// surface displaying its lightmap (bilinear between texel centres, as a GPU sampler would),
// traced with Embree primary rays so that it needs no GL and runs headless. Objects without
// a lightmap (spheres, mirrors, moving objects) show an unlit albedo preview; misses show the
// environment.
//
// Layers: color (lm_total, or the unlit preview), lm_irradiance, lm_inscatter (single +
// multiple irradiance), texel_valid (categorical, nearest texel), lightmap_texel (the texel's
// x, y and lightmap index; -1 off lightmaps: what the inspector's texel trace needs); with an
// impulse bake's layers also texel_mc_window (the nearest texel's filter window).
#pragma once

#include "image/layers.h"
#include "scene/camera.h"
#include "volume/lightmap_baker.h"

namespace freqlab {

// `baked[i]` are the layers of `maps[i]` (LightmapBaker::layers).
LayerSet render_lightmap_preview(const RayScene& scene, const CameraPose& pose, int width,
                                 int height, const std::vector<ObjectLightmap>& maps,
                                 const std::vector<LayerSet>& baked);

// A camera orbiting `pose.look_at`: yaw about the vertical, pitch above the horizon.
CameraPose orbit_pose(const CameraPose& pose, float yaw_deg, float pitch_deg, float zoom);

}  // namespace freqlab
