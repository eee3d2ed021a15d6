// Multiple scattering of a point emitter in an infinite homogeneous medium by composing bounces
// (seed, Deuxième article §5.1): bounce k+1 re-integrates Eq. 4.1 with the emitter replaced by
// the bounce-k radiance, here for isotropic scattering (the seed treats multiple scattering as
// isotropic, anisotropy entering through the similarity rule sigma_s (1 - g)).
//
// With isotropic scattering the source of bounce k+1 at a point is sigma_s / (4 pi) times the
// bounce-k fluence there, and by symmetry that fluence depends only on the distance r to the
// emitter: phi_k(r). So, in the canonical medium (sigma_s = sigma_t = 1, optical units),
//   L_{k+1}(D, mu) = int_0^inf e^{-t} phi_k(r(t)) / (4 pi) dt,  r(t)^2 = D^2 + t^2 - 2 D t mu,
//   phi_{k+1}(D) = 2 pi int_{-1}^{1} L_{k+1}(D, mu) d mu,  phi_0(D) = e^{-D} / D^2 (I0 = 1),
// mu the cosine from the direction towards the emitter. A medium with albedo c = sigma_s /
// sigma_t scales bounce k by sigma_t^2 c^k at D = sigma_t d (tests/test_multiple_scatter.cpp).
//
// | parameter  | value                                                                      |
// |------------|----------------------------------------------------------------------------|
// | distances  | ZhDistanceTable's 256 log-spaced optical distances in [1e-3, 40]           |
// | phi_k(r)   | Catmull-Rom in log r of phi_k(r) r^2 e^{r}; r < 1e-3 keeps the last value  |
// | ray        | equi-angular substitution about the closest approach to the emitter        |
#pragma once

#include <vector>

#include "volume/collapse_memo.h"

#include "volume/impulse_response.h"

namespace freqlab {

class PointMultipleScatter {
  public:
    // Bounces 1..bounces (bounce 0 is the direct term).
    explicit PointMultipleScatter(int bounces);
    // From saved values: fluence_scaled[k][bin] = phi_k(D) D^2 e^D, zh[k][bin] (k = 0 unused).
    PointMultipleScatter(std::vector<std::vector<double>> fluence_scaled,
                         std::vector<std::vector<ZhVector>> zh)
        : fluence_scaled_(std::move(fluence_scaled)), zh_(std::move(zh)) {
        scale();
    }
    const std::vector<std::vector<double>>& fluence_scaled() const { return fluence_scaled_; }
    const std::vector<std::vector<ZhVector>>& zh() const { return zh_; }
    int bounces() const { return int(zh_.size()) - 1; }
    // Canonical ZH of bounce k (1 <= k <= bounces) at optical distance D.
    ZhVector canonical(int k, double optical_distance) const;
    // Fluence of bounce k (0 <= k <= bounces) at optical distance D (canonical medium).
    double fluence(int k, double optical_distance) const;
    // Sum of bounces first..last in `medium` at `distance` (albedo weights c^k). `collapsed`
    // (bakers): the albedo quantised to 2^-24 and the sum over bounces memoised per albedo
    // (collapse_memo.h); otherwise the exact sum.
    ZhVector bounces_in(const HomogeneousMedium& medium, double distance, int first, int last,
                        bool collapsed = false) const;

  private:
    std::vector<std::vector<double>> fluence_scaled_;   // [k][bin]: phi_k(D) D^2 e^D
    std::vector<std::vector<ZhVector>> zh_;             // [k][bin] (k = 0 unused)
    std::vector<double> packed_;                        // [bin][k][l] zh_ x D^2 e^D
    uint64_t memo_id_ = CollapseMemo::next_owner_id();  // collapsed-over-bounces memo
    void scale();
};

}  // namespace freqlab
