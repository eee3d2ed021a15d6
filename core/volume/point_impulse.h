// Impulse responses of a point emitter in an infinite homogeneous medium (seed, Deuxième
// article §4.2 Eq. 4.1, §4.3): the ZH coefficients, about the axis from the receiver to the
// emitter, of the radiance arriving at the receiver directly (attenuated) and after exactly one
// scattering event. Emitter intensity I0 = 1 (W/sr); coefficients are radiance x solid angle.
//
// | quantity            | definition (receiver at 0, emitter at distance d on the axis) |
// |---------------------|--------------------------------------------------------------------------|
// | direct_l            | e^{-sigma_t d} / d^2 * y_l^0(axis)  (a delta towards the emitter) | |
// single_l            | int_S2 y_l^0(w) int_0^inf e^{-sigma_t t} sigma_s p(u . -w) e^{-sigma_t
// r}/r^2 | |                     | dt dw, r = |t w - d z|, u = (t w - d z)/r the light's direction
// there    | | sigma remap (tested)| with D = sigma_t d and the canonical medium sigma_s = sigma_t
// = 1:          | |                     | direct(d) = sigma_t^2 direct_1(D), single(d) = sigma_s
// sigma_t single_1(D) |
//
// Without absorption both factors are sigma_r^2 (sigma_r = sigma_s' / sigma_s) at the query
// distance sigma_r d, which is the seed's rule for point emitters; with absorption the seed's
// single factor sigma_r = sigma_t / sigma_s is not what the substitution gives: the tests
// (tests/test_point_impulse.cpp) compare against direct computation at the medium and decide.
#pragma once

#include <array>
#include <vector>

#include "volume/medium.h"

namespace freqlab {

constexpr int kImpulseOrder = 11;
using ZhVector = std::array<double, kImpulseOrder>;

ZhVector point_direct_zh(const HomogeneousMedium& medium, double distance);
// Deterministic quadrature: equi-angular substitution along each ray (the 1/r^2 peak becomes
// flat), 48-point Gauss-Legendre along the ray, 40 graded panels x 12 points over the angle.
ZhVector point_single_zh(const HomogeneousMedium& medium, double distance);

// Canonical single-scattering table (sigma_s = 1, sigma_a = 0) over optical distances
// D in [kMinD, kMaxD], 256 log-spaced bins, for one g; queried for any medium by the remap.
class PointImpulseTable {
  public:
    static constexpr double kMinD = 1e-3, kMaxD = 40.0;
    static constexpr int kBins = 256;

    explicit PointImpulseTable(double g);
    double g() const { return g_; }
    // Single-scattered ZH at `distance` in `medium` (its g is ignored: the table's is used).
    ZhVector single(const HomogeneousMedium& medium, double distance) const;
    ZhVector canonical_single(double optical_distance) const;  // sigma_s = sigma_t = 1

  private:
    double g_;
    // Stored as single_l(D) * D * e^D: removes the 1/D and e^{-D} trends so that linear
    // interpolation in log D is accurate.
    std::vector<ZhVector> scaled_;
};

}  // namespace freqlab
