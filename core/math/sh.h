// Real spherical harmonics and zonal harmonics (seed, Deuxième article §3.3, Eq. 3.12-3.13;
// Appendix 8). Method B's impulse responses are order-11 ZH vectors; everything here works
// in double precision on caller-provided arrays (no allocation per call).
//
// | quantity                    | definition used here                                        |
// |-----------------------------|-------------------------------------------------------------|
// | order N                     | bands l = 0 .. N-1, N^2 coefficients, index i = l(l+1)+m     |
// | y_l^m (Eq. 3.12)            | sqrt2 K_l^m sin(|m| phi) P_l^|m|(cos theta) for m < 0,       |
// |                             | K_l^0 P_l(cos theta) for m = 0, sqrt2 K_l^m cos(m phi) P_l^m  |
// |                             | for m > 0; K_l^m = sqrt((2l+1)/(4 pi) (l-|m|)!/(l+|m|)!);    |
// |                             | P_l^m without the Condon-Shortley phase (orthonormal either |
// |                             | way; tests/test_sh.cpp checks by quadrature)                 |
// | ZH vector z_l               | coefficients of y_l^0 for a function symmetric about +z      |
// | rotation (Eq. 3.13)         | h_l^m = sqrt(4 pi/(2l+1)) z_l y_l^m(axis)                      |
// | ZH double product (App. 8)  | integral of g(w.a) h(w.b) = sum_l g_l h_l P_l(a.b): O(N)      |
#pragma once

#include "math/types.h"

namespace freqlab {

constexpr int kMaxShOrder = 16;
constexpr int sh_index(int l, int m) {
    return l * (l + 1) + m;
}
constexpr int sh_count(int order) {
    return order * order;
}

// All y_l^m(direction) for l < order into out[sh_count(order)]; direction need not be unit.
void sh_eval(int order, const glm::dvec3& direction, double* out);
// Legendre polynomials P_0 .. P_{order-1} at x.
void legendre(int order, double x, double* out);
// sum_l z_l y_l^0 evaluated at cos(theta) from the ZH axis.
double zh_eval(int order, const double* zh, double cos_theta);
// SH coefficients (out[sh_count(order)]) of the ZH function turned to `axis` (Eq. 3.13).
void zh_rotate(int order, const double* zh, const glm::dvec3& axis, double* sh_out);
// Integral over the sphere of g(w . a) h(w . b) from the ZH vectors g, h (Appendix 8).
double zh_double_product(int order, const double* g, const glm::dvec3& a, const double* h,
                         const glm::dvec3& b);
// ZH coefficients of max(cos theta, 0) (the clamped cosine of diffuse reflection).
void zh_clamped_cosine(int order, double* out);

}  // namespace freqlab
