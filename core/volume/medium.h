// Homogeneous participating media (seed, Deuxième article §3.1, §4.5); the Henyey-Greenstein
// phase function is math/sampling.h's hg_phase.
#pragma once

#include <cmath>

#include "math/sampling.h"

namespace freqlab {

struct HomogeneousMedium {
    double sigma_s = 1.0;  // scattering coefficient (1 / scene unit)
    double sigma_a = 0.0;  // absorption coefficient
    double g = 0.0;        // Henyey-Greenstein anisotropy in (-1, 1)
    double sigma_t() const { return sigma_s + sigma_a; }
};

}  // namespace freqlab
