// The texels a bake's key light does not reach directly (issue "Method B, part 3"): where the
// tables' unoccluded in-scattering does not apply and the lit-medium estimate
// (BakeEstimator::lit_medium_single) carries the light scattered into the shadow. Studies and
// tests measure the error there separately: averaged over a whole lightmap it vanishes.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/ray_scene.h"
#include "image/layers.h"
#include "volume/lightmap_atlas.h"

namespace freqlab {

// The point, directional or quad light that gives the most irradiance (luminance, unoccluded,
// at normal incidence, no media) at the centre of the scene's bounds; a quad counts from its
// centre (sample_light at u = (1/2, 1/2)). `found` is false when the scene has none of these
// lights (only an environment).
struct BakeKeyLight {
    bool found = false;
    int light = -1;  // index in the scene's lights
};
BakeKeyLight bake_key_light(const RayScene& scene);

// Per texel of `map`: 1 where the texel is Valid, faces the key light (its normal within 90
// degrees of the direction to it; on a quad's emitting side) and the segment to it is
// occluded: the cast shadow. Empty
// (all 0) without a key light.
std::vector<uint8_t> shadowed_texels(const RayScene& scene, const ObjectLightmap& map,
                                     const BakeKeyLight& key);

// A bake against a reference over the flagged texels (a shadow mask): lm_irradiance relMSE
// (compare_lightmaps' definition), the ratio of the mean lm_irradiance, and of the mean
// in-scattered irradiance (lm_inscatter_single + lm_inscatter_multiple), test over reference.
// Ratios are NaN when the reference's mean is 0 or no texel is flagged.
struct RegionComparison {
    long texels = 0;
    double irradiance_relmse = 0.0;
    double irradiance_ratio = 0.0, inscatter_ratio = 0.0;
    double test_irradiance = 0.0, ref_irradiance = 0.0;  // mean luminances over the region
    double test_inscatter = 0.0, ref_inscatter = 0.0;
};
RegionComparison compare_region(const LayerSet& test, const LayerSet& ref,
                                const std::vector<uint8_t>& only);
// Several lightmaps' regions as one: texel-weighted relMSE, ratios of the summed means.
RegionComparison combine_regions(const std::vector<RegionComparison>& parts);

}  // namespace freqlab
