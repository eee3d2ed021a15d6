// The BRDF's footprint on the sphere of incident directions (seed, Premier article §4, Eq. 4.2):
// a radially symmetric lobe about mu_rho (the mirror direction for glossy BRDFs, the normal for
// Lambert) of standard deviation sigma_rho, which windows the environment's bandwidth query.
//
// | model              | footprint                                                          |
// |--------------------|--------------------------------------------------------------------|
// | Phong, e > 3       | Var[e] = int t^2 / (1 + t^2)^{e/2} dt = sqrt(pi) G((e-3)/2) / (2 G(e/2)) |
// |                    | (t: tangent-plane coordinate); sigma_rho = sqrt(Var[e]); computed with |
// |                    | std::lgamma, not the seed's three-term Stirling series              |
// | Beckmann / GGX     | the Phong-equivalent exponent e = 2 / alpha^2 - 2 (the inverse of the  |
// |                    | seed's alpha = sqrt(2 / (2 + e)), which it prints with the roles swapped)
// | | Lambert, e <= 3    | the whole hemisphere about the normal (Var[e] diverges for e <= 3)  |
#pragma once

#include "math/types.h"
#include "scene/material.h"

namespace freqlab {

// Var[e] for e > 3; +infinity for e <= 3 (the integral diverges) — callers use the footprint.
double phong_variance(double exponent);
double phong_exponent_of_roughness(double alpha);

struct BrdfFootprint {
    bool whole_hemisphere = true;
    double sigma = 0.0;  // tangent-plane standard deviation when !whole_hemisphere
    // Angular radius used for queries: atan(3 sigma), or pi/2 for the whole hemisphere.
    double query_radius() const;
};

BrdfFootprint brdf_footprint(const Material& material);

}  // namespace freqlab
