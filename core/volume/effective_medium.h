// Heterogeneous media seen as homogeneous per ray (seed, Deuxième article §4.4, Fig. 25): the
// effective coefficients of a segment are its optical thicknesses divided by its length, so
// the directly attenuated light is exact (exp of a sum = product of exps) and single scattering
// is approximated. The effective g is the scattering-weighted mean, so a segment with no
// scattering contributes no anisotropy.
#pragma once

#include <vector>

#include "volume/medium.h"

namespace freqlab {

struct MediumPiece {
    double length;  // of the segment inside this piece
    HomogeneousMedium medium;
};

// Throws nothing; an empty or zero-length segment gives a vacuum (all coefficients 0).
HomogeneousMedium effective_medium(const std::vector<MediumPiece>& pieces);

}  // namespace freqlab
