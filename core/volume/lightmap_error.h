// Error of a baked lightmap against a reference bake (issue "Method B, part 2"): per lightmap
// and layer, relMSE over the valid texels, over the lit ones, and the reference's own noise when
// it comes in two halves; a whole bake's from its lightmaps'. What `freqlab bake --reference`,
// `bench --study bake` and the tests measure.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "image/layers.h"

namespace freqlab {

// Error of a lightmap layer against a reference bake of the same scene and atlas, over the
// reference's valid texels only (gutters and flagged texels would dilute it):
// relmse = mean over texels and channels of (I - R)^2 / (R^2 + e^2), e = 1e-3 x mean(R), so
// the measure does not depend on the light's units; rmse likewise; rel_l2 = |I - R| / |R|.
// `worst` lists the texels whose terms weigh most in relmse, largest first: where a relMSE
// ruled by a few texels lives (near-black reference texels weigh up to 1 / e^2).
struct TexelError {
    int x = 0, y = 0;
    double test = 0.0, ref = 0.0;  // luminance
    double relmse_share = 0.0;     // the texel's part of relmse (all shares sum to 1)
};
// relmse_lit: the same over the texels whose reference (mean of channels) reaches
// kLightmapLitTexelFractionOfMean of its mean, texels_lit of them.
struct LightmapError {
    double relmse = 0.0, rmse = 0.0, rel_l2 = 0.0, relmse_lit = 0.0;
    long texels = 0, texels_lit = 0;
    // With two reference halves: the relMSE that the reference (their mean) has against the
    // truth by its own noise, over all and over the lit texels; every measured relMSE holds it
    // on average (E (t - r)^2 = (t - truth)^2 + var r). -1: one reference, not known.
    double reference_noise = -1.0, reference_noise_lit = -1.0;
    std::vector<TexelError> worst;
};
// Throws Error when sizes differ or a layer is missing. `only` (one flag per texel), when
// given, restricts the measure to the flagged valid texels (shadowed_texels.h). `ref_half`,
// when given, is a second reference independent of `ref` (another seed, the same samples): the
// reference is then their mean, and its own noise is estimated texel by texel from their
// difference, (a - b)^2 / 4 (the variance of the mean of two), weighted as the relMSE weighs.
LightmapError compare_lightmaps(const LayerSet& test, const LayerSet& ref, const std::string& layer,
                                const std::vector<uint8_t>* only = nullptr, size_t worst = 0,
                                const LayerSet* ref_half = nullptr);
// The luminance of an RGB layer summed over the lightmap's valid texels (the texels
// compare_lightmaps measures; `only` as there); throws Error when a layer is missing.
double valid_texel_luminance_sum(const LayerSet& lightmap, const std::string& layer,
                                 const std::vector<uint8_t>* only = nullptr);
// A whole bake's error from its lightmaps': relmse texel-weighted, relmse_lit by their lit
// texels, the reference's noise alike where every part knows it (else -1); rmse from the
// texel-weighted squares; rel_l2 and worst are not combined (NaN, empty). Parts without
// texels are left out.
LightmapError combine_lightmap_errors(const std::vector<LightmapError>& parts);

}  // namespace freqlab
