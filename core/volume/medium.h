// Homogeneous participating media and the Henyey-Greenstein phase function (seed, Deuxième
// article §3.1, §4.5).
#pragma once

#include <cmath>

namespace freqlab {

struct HomogeneousMedium {
    double sigma_s = 1.0;  // scattering coefficient (1 / scene unit)
    double sigma_a = 0.0;  // absorption coefficient
    double g = 0.0;        // Henyey-Greenstein anisotropy in (-1, 1)
    double sigma_t() const { return sigma_s + sigma_a; }
};

// HG phase function of the cosine between the propagation directions before and after the
// scattering event; integrates to 1 over the sphere.
inline double hg_phase(double g, double cos_theta) {
    const double denom = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * 3.14159265358979323846 * denom * std::sqrt(denom));
}

}  // namespace freqlab
