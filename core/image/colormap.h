// Display of layers: exposure + sRGB for colour, viridis for continuous, a blue-white-red
// diverging map for signed (symmetric about 0) and the Tableau-10 palette for categorical.
// The same functions serve PNG export and, later, the GL overlays' reference tests.
#pragma once

#include <vector>

#include "image/layers.h"
#include "math/types.h"

namespace freqlab {

vec3 viridis(float t);        // t in [0, 1]
vec3 diverging(float t);      // t in [-1, 1]; 0 is white
vec3 categorical(int index);  // cycles through 10 colours
// A categorical layer's colours: its own palette, else the 10 Tableau colours.
std::vector<vec3> layer_palette(const Layer& layer);
vec3 category_colour(const Layer& layer, int index);
float linear_to_srgb(float c);

struct DisplayRange {
    float lo = 0.0f, hi = 1.0f;
};
// Continuous scalars: [min, 99.5th percentile] of the finite values (robust to fireflies);
// vectors: [min, max]; Signed: [-m, m] with m = max |v|.
DisplayRange auto_range(const Layer& layer);

struct DisplayParams {
    float exposure_ev = 0.0f;  // colour layers: multiply by 2^ev before sRGB
    bool auto_range = true;
    DisplayRange range;  // used when !auto_range
};

// "Nice" tick values (1, 2, 5 x 10^k steps) inside [lo, hi], at most about `max_ticks`.
std::vector<double> colorbar_ticks(double lo, double hi, int max_ticks = 6);

// Tonemapped/colormapped 8-bit RGB of one layer. Non-finite values show as magenta so they
// never pass unnoticed.
std::vector<unsigned char> layer_to_rgb8(const LayerSet& set, const Layer& layer,
                                         const DisplayParams& params = {});

}  // namespace freqlab
