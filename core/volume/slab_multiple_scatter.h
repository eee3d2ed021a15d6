// Multiple scattering of a directional emitter in a homogeneous half-space medium by composing
// bounces (seed, Deuxième article §5.1), the counterpart of volume/multiple_scatter.h. The light
// (irradiance E0 = 1 across its beam) enters the medium through the boundary plane
// perpendicular to it; by symmetry every bounce's fluence depends only on the optical depth z
// below that plane. In the canonical medium (sigma_s = sigma_t = 1), with mu the cosine between
// a viewing direction and the direction to the light:
//   phi_0(z) = e^{-z},
//   L_{k+1}(s, mu) = int_0^{t_max} e^{-t} phi_k(s - t mu) / (4 pi) dt,  t_max = s / mu (mu > 0)
//                    or infinity (mu <= 0): above the boundary there is nothing to scatter,
//   phi_{k+1}(s) = 2 pi int_{-1}^{1} L_{k+1}(s, mu) d mu.
// A medium with albedo c = sigma_s / sigma_t scales bounce k by c^k at depth sigma_t s.
//
// | parameter | value                                                                           |
// |-----------|---------------------------------------------------------------------------------|
// | depths    | ZhDistanceTable's 256 log-spaced optical depths in [1e-3, 40]                    |
// | phi_k(z)  | Catmull-Rom of log phi_k in log z; z < 1e-3 keeps the first bin, z > 40 extends  |
// |           | log phi_k linearly in z from the last two bins                                  |
// | mu        | volume/polar_quadrature.h's directional_mu_nodes, 12 panels a half               |
// | ray       | u = 1 - e^{-(1 - mu) t}, 4 panels x 16 Gauss-Legendre points (see the .cpp)      |
#pragma once

#include <vector>

#include "volume/impulse_response.h"

namespace freqlab {

class SlabMultipleScatter {
  public:
    explicit SlabMultipleScatter(int bounces);  // bounces 1..bounces (0 is the direct term)
    // From saved values: zh[k][bin] canonical (k = 0 unused).
    explicit SlabMultipleScatter(std::vector<std::vector<ZhVector>> zh);
    const std::vector<std::vector<ZhVector>>& zh() const { return zh_; }
    int bounces() const { return int(zh_.size()) - 1; }
    ZhVector canonical(int k, double optical_depth) const;
    double fluence(int k, double optical_depth) const;  // 0 <= k <= bounces
    ZhVector bounces_in(const HomogeneousMedium& medium, double depth, int first, int last) const;

  private:
    std::vector<std::vector<ZhVector>> zh_;         // [k][bin]
    std::vector<std::vector<double>> log_fluence_;  // [k][bin]
    std::vector<double> packed_shape_;              // [bin][k][l] zh / zh_0: what is interpolated
    std::vector<double> packed_log_fluence_;        // [bin][k]
    void derive();
};

}  // namespace freqlab
