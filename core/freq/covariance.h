// The 2x2 light-field covariance operators of method A (seed, Premier article Eq. 5.2 and
// Appendix 9.1, Eq. 9.1-9.11): spatial / angular variances of the light field from the
// environment to the surface and to the eye, which set the image-space sampling density and
// the cache's validity bandwidths.
//
// | operator      | matrix                         | meaning                                  |
// |---------------|--------------------------------|------------------------------------------|
// | T_d           | [[1, -d], [0, 1]]              | travel over a distance d (Eq. 9.2/9.6/9.9) |
// | C_L           | [[c_i, 0], [k, 1]]             | into the surface frame: foreshortening c_i =
// cos(theta_i), curvature k (Eq. 9.3) | | B_rho         | [[0, 0], [0, b]], b = 4 pi^2 / s | Phong
// BRDF of shininess s (Eq. 9.4)      | | C_v           | [[c_v, 0], [c_v k, -1]]        | out to
// the eye, c_v = 1 / cos(theta_v) (Eq. 9.5) | Chain (Eq. 9.7-9.8): S_c = C_L^T S C_L; S_rho = S_c -
// S_c B S_c / (1 + tr(S_c B)); S_o = C_v^T S_rho C_v; S_image = T_d^T S_o T_d. Occluded
// (Eq. 9.10-9.11): the emitted covariance diag(a, sigma_L^2) is sheared by T_{t_min} first, in the
// limit a -> infinity, taken here in closed form (derivation in covariance.cpp) rather than with a
// large a.
#pragma once

#include <glm/glm.hpp>

namespace freqlab {

using Mat2 = glm::dmat2;  // column-major: m[col][row]

Mat2 travel_operator(double distance);
Mat2 surface_in_operator(double cos_in, double curvature);
Mat2 brdf_operator(double b);
Mat2 surface_out_operator(double inv_cos_view, double curvature);
double phong_bandwidth_b(double shininess);  // b = 1 / cov = 4 pi^2 / s

struct CovarianceInputs {
    double sigma_l2 = 1.0;      // angular variance of the environment in the BRDF cone
    double cos_in = 1.0;        // c_i
    double curvature = 0.0;     // k
    double b = 1.0;             // BRDF operator
    double inv_cos_view = 1.0;  // c_v
    double eye_distance = 1.0;  // d
    double t_min = 1.0;         // occluded: minimum occluder distance (> 0)
};

struct CovarianceResult {
    Mat2 object;  // Sigma^o_{S,theta}
    Mat2 image;   // Sigma_{S,theta}
};

CovarianceResult unoccluded_covariance(const CovarianceInputs& in);
// With emitted spatial content a (Eq. 9.10); the occluded case is its a -> infinity limit.
CovarianceResult occluded_covariance(const CovarianceInputs& in, double a);
CovarianceResult occluded_covariance_limit(const CovarianceInputs& in);

}  // namespace freqlab
