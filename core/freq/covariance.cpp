#include "freq/covariance.h"

#include <cmath>

namespace freqlab {

namespace {

// Row-major construction: rows (a b) and (c d).
Mat2 rows(double a, double b, double c, double d) {
    return Mat2(a, c, b, d);
}

Mat2 apply(const Mat2& op, const Mat2& s) {
    return glm::transpose(op) * s * op;
}

// S_rho = S_c - b u u^T / (1 + b tau), u = S_c e2, tau = u_2 (S_c symmetric), written with 1/b
// so that the broadest lobe (b = inf: a Phong exponent of 0, GGX / Beckmann roughness 1) takes
// its limit S_c - u u^T / tau instead of inf / inf.
Mat2 brdf_step(const Mat2& sc, double b) {
    const glm::dvec2 u = sc[1];  // column 1 = S_c e2
    const double denominator = 1.0 / b + u.y;
    if (!(denominator > 0.0)) return sc;  // tau = 0 (then u = 0): nothing for the BRDF to filter
    return sc - glm::outerProduct(u, u) / denominator;
}

CovarianceResult finish(const CovarianceInputs& in, const Mat2& s_rho) {
    CovarianceResult r;
    r.object = apply(surface_out_operator(in.inv_cos_view, in.curvature), s_rho);
    r.image = apply(travel_operator(in.eye_distance), r.object);
    return r;
}

}  // namespace

Mat2 travel_operator(double d) {
    return rows(1, -d, 0, 1);
}
Mat2 surface_in_operator(double ci, double k) {
    return rows(ci, 0, k, 1);
}
Mat2 brdf_operator(double b) {
    return rows(0, 0, 0, b);
}
Mat2 surface_out_operator(double cv, double k) {
    return rows(cv, 0, cv * k, -1);
}
double phong_bandwidth_b(double s) {
    return 4.0 * 3.14159265358979323846 * 3.14159265358979323846 / s;
}

CovarianceResult unoccluded_covariance(const CovarianceInputs& in) {
    const Mat2 emitted = rows(0, 0, 0, in.sigma_l2);
    const Mat2 sc = apply(surface_in_operator(in.cos_in, in.curvature), emitted);
    return finish(in, brdf_step(sc, in.b));
}

CovarianceResult occluded_covariance(const CovarianceInputs& in, double a) {
    const Mat2 emitted = rows(a, 0, 0, in.sigma_l2);
    const Mat2 st = apply(travel_operator(in.t_min), emitted);
    const Mat2 sc = apply(surface_in_operator(in.cos_in, in.curvature), st);
    return finish(in, brdf_step(sc, in.b));
}

CovarianceResult occluded_covariance_limit(const CovarianceInputs& in) {
    // Write S_c = a p p^T + s q q^T with p = C_L^T T^T e1 = (c_i - k t, -t) and
    // q = C_L^T e2 = (k, 1) (s = sigma_L^2, t = t_min). With B = b e2 e2^T the BRDF step is
    //   S_rho = S_c - b (S_c e2)(S_c e2)^T / (1 + b (a p2^2 + s q2^2)),
    // and letting a -> infinity (p2 = -t != 0) the a-terms cancel, leaving
    //   S_rho = (1 + b s q2^2) / (b p2^2) p p^T - (s q2 / p2)(p q^T + q p^T) + s q q^T.
    const double s = in.sigma_l2, t = in.t_min, b = in.b;
    const glm::dvec2 p(in.cos_in - in.curvature * t, -t), q(in.curvature, 1.0);
    const Mat2 pp = glm::outerProduct(p, p), pq = glm::outerProduct(q, p) + glm::outerProduct(p, q),
               qq = glm::outerProduct(q, q);
    // (1 + b s q2^2) / b written as 1/b + s q2^2: finite for b = inf (the broadest lobe).
    const Mat2 s_rho = (1.0 / b + s * q.y * q.y) / (p.y * p.y) * pp - (s * q.y / p.y) * pq + s * qq;
    return finish(in, s_rho);
}

}  // namespace freqlab
