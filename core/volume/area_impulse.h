// Differential-area emitters (seed, Deuxième article §4.2, Eq. 4.3, Fig. 23): the incident
// radiance at a receiver from light that left a small cosine-weighted emitter is not
// circularly symmetric once the emitter's normal turns away from the receiver, so its full SH
// projection is computed and then approximated by a ZH lobe about a best-fit axis, searched
// with Brent's method (Boost.Math) on the arc between the direction to the light l and the
// optimal linear direction l_opt.
//
// | quantity    | definition (receiver at 0, emitter at d z, I0 = 1)                            |
// |-------------|-------------------------------------------------------------------------------|
// | emitter     | radiant intensity max(n . u, 0) along unit direction u from the emitter      |
// | alpha       | angle between n and the direction from the emitter to the receiver (-z)      |
// | single      | int_0^inf e^{-sigma_t t} sigma_s p(u . -w) max(n . u, 0) e^{-sigma_t r}/r^2 dt  |
// | l_opt       | (L_1^1, L_1^-1, L_1^0): our y_1^m carry no Condon-Shortley phase, so the       |
// |             | seed's minus signs (which come with that phase) are not needed               |
// | fit error   | || f - ZH_a(f) ||^2 = ||f||^2 - sum_l c_l^2, c_l = sqrt(4pi/(2l+1)) sum_m f_l^m |
// |             | y_l^m(a): the L2-optimal ZH about axis a (orthonormality of y_l^0(. a))       |
#pragma once

#include <array>

#include "math/types.h"
#include "volume/impulse_response.h"

namespace freqlab {

constexpr int kAreaShCount = kImpulseOrder * kImpulseOrder;
using ShVector = std::array<double, kAreaShCount>;

ShVector area_single_sh(const HomogeneousMedium& medium, double distance, double alpha);

struct ZhAxisFit {
    glm::dvec3 light_axis, optimal_linear_axis, fitted_axis;
    double error_light, error_optimal_linear, error_fitted;  // squared L2 errors
    double fit_angle;  // between fitted_axis and light_axis (radians)
    ZhVector zh;       // the lobe about fitted_axis
};

// ZH coefficients of the L2-best lobe about `axis`, and its squared error.
ZhVector zh_about_axis(const ShVector& sh, const glm::dvec3& axis, double* squared_error);
ZhAxisFit fit_zh_axis(const ShVector& sh);

}  // namespace freqlab
