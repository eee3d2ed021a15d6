// Multiple scattering of a directional emitter at a receiver on the bottom face of a slab of
// medium (issue "Method B, part 3"): the geometry of a lightmap texel under a layer of haze,
// whose medium ends at its surface. volume/slab_multiple_scatter.h's half-space continues
// below the receiver, so every bounce also brings back light from an infinitely deep medium
// there (3.9x VPT's multiple scattering on sun_haze). Probes (mid-air receivers) keep the
// half-space.
//
// Canonical medium (sigma_s = sigma_t = 1), the slab perpendicular to the light, optical
// thickness Z, depth z in [0, Z] from the lit face; isotropic scattering (anisotropy enters
// through similarity, impulse_query.h). The bounce-k fluence obeys the plane-parallel
// composition (a layer at z' seen from z is a plane of sources: 2 pi E_1(|z - z'|)):
//   phi_0(z) = e^{-z},   phi_{k+1}(z) = 1/2 int_0^Z E_1(|z - z'|) phi_k(z') dz',
// and the receiver at z = Z sees, looking into the slab at cosine mu > 0 from the light axis,
//   L_{k+1}(mu) = 1 / (4 pi mu) int_0^Z e^{-(Z - z') / mu} phi_k(z') dz'   (0 for mu <= 0),
// whose ZH coefficients are 1/2 int_0^Z phi_k(z') c_l sum_m a_lm E_{m+1}(Z - z') dz' (P_l(mu) =
// sum_m a_lm mu^m, int_0^1 e^{-x/mu} mu^{m-1} dmu = E_{m+1}(x)).
//
// | parameter | value                                                                       |
// |-----------|-----------------------------------------------------------------------------|
// | Z         | ZhDistanceTable's 256 log-spaced optical thicknesses in [1e-3, 40]           |
// | z nodes   | Chebyshev-Lobatto on [0, Z], max(24, pi Z / 0.2 + 1): spacing <= 0.1 inside |
// | phi_k     | piecewise linear between nodes, integrated against E_n exactly (E_{n+1},    |
// |           | E_{n+2} at the node distances: Nystrom product integration)                   |
#pragma once

#include <vector>

#include "volume/slab_multiple_scatter.h"

namespace freqlab {

// The table, in SlabMultipleScatter's form (zh[k][bin] at depth bin = the slab's thickness, k =
// 1..bounces, so bounces_in() serves it unchanged).
SlabMultipleScatter build_slab_bottom_multiple_scatter(int bounces);

// The composition itself at one thickness (tests): nodes z and phi[k][node] for k = 0..bounces,
// and the receiver's ZH zh[k] for k = 1..bounces (zh[0] zero).
struct SlabBottomSolution {
    std::vector<double> z;
    std::vector<std::vector<double>> phi;
    std::vector<ZhVector> zh;
};
SlabBottomSolution solve_slab_bottom(double thickness, int bounces);

}  // namespace freqlab
