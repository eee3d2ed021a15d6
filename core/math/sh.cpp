#include "math/sh.h"

#include <cmath>

namespace freqlab {

namespace {

// K_l^m with the factorial ratio built as a product, stable for the orders used here.
double sh_norm(int l, int m) {
    double ratio = 1.0;  // (l-m)! / (l+m)!
    for (int k = l - m + 1; k <= l + m; ++k) ratio /= double(k);
    return std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD) * ratio);
}

}  // namespace

void legendre(int order, double x, double* out) {
    if (order <= 0) return;
    out[0] = 1.0;
    if (order > 1) out[1] = x;
    for (int l = 2; l < order; ++l)
        out[l] = ((2.0 * l - 1.0) * x * out[l - 1] - (l - 1.0) * out[l - 2]) / l;
}

void sh_eval(int order, const glm::dvec3& direction, double* out) {
    const glm::dvec3 d = glm::normalize(direction);
    const double x = d.z, s = std::sqrt(std::max(0.0, 1.0 - x * x));
    const double phi = std::atan2(d.y, d.x);
    // Associated Legendre P_l^m(x) without the Condon-Shortley phase, by the standard
    // recurrences: P_m^m = (2m-1)!! s^m, P_{m+1}^m = x (2m+1) P_m^m, then upward in l.
    double pmm = 1.0;
    for (int m = 0; m < order; ++m) {
        if (m > 0) pmm *= (2.0 * m - 1.0) * s;
        double p_prev = 0.0, p = pmm;
        const double c = std::cos(m * phi), sn = std::sin(m * phi);
        for (int l = m; l < order; ++l) {
            if (l == m + 1) {
                p_prev = p;
                p = x * (2.0 * m + 1.0) * pmm;
            } else if (l > m + 1) {
                const double next = ((2.0 * l - 1.0) * x * p - (l + m - 1.0) * p_prev) / (l - m);
                p_prev = p;
                p = next;
            }
            const double k = sh_norm(l, m);
            if (m == 0) {
                out[sh_index(l, 0)] = k * p;
            } else {
                out[sh_index(l, m)] = std::sqrt(2.0) * k * c * p;
                out[sh_index(l, -m)] = std::sqrt(2.0) * k * sn * p;
            }
        }
    }
}

double zh_eval(int order, const double* zh, double cos_theta) {
    double p[kMaxShOrder];
    legendre(order, cos_theta, p);
    double v = 0.0;
    for (int l = 0; l < order; ++l) v += zh[l] * std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)) * p[l];
    return v;
}

void zh_rotate(int order, const double* zh, const glm::dvec3& axis, double* sh_out) {
    double y[kMaxShOrder * kMaxShOrder];
    sh_eval(order, axis, y);
    for (int l = 0; l < order; ++l) {
        const double n = std::sqrt(4.0 * kPiD / (2.0 * l + 1.0));
        for (int m = -l; m <= l; ++m) sh_out[sh_index(l, m)] = n * zh[l] * y[sh_index(l, m)];
    }
}

double zh_double_product(int order, const double* g, const glm::dvec3& a, const double* h,
                         const glm::dvec3& b) {
    // Funk-Hecke + the addition theorem: sum_m y_l^m(a) y_l^m(b) = (2l+1)/(4 pi) P_l(a.b),
    // so the O(N^2) SH dot product of the two rotated functions collapses to O(N).
    double p[kMaxShOrder];
    legendre(order, glm::dot(glm::normalize(a), glm::normalize(b)), p);
    double sum = 0.0;
    for (int l = 0; l < order; ++l) sum += g[l] * h[l] * p[l];
    return sum;
}

void zh_clamped_cosine(int order, double* out) {
    // c_l = K_l^0 A_l with A_l = 2 pi int_0^1 x P_l(x) dx (Ramamoorthi & Hanrahan 2001):
    // A_0 = pi, A_1 = 2 pi / 3, A_l = 0 for odd l > 1, and for even l
    // A_l = 2 pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) * l! / (2^l ((l/2)!)^2).
    for (int l = 0; l < order; ++l) {
        double a;
        if (l == 0)
            a = kPiD;
        else if (l == 1)
            a = 2.0 * kPiD / 3.0;
        else if (l % 2)
            a = 0.0;
        else {
            const int h = l / 2;
            const double binomial_term =
                std::exp(std::lgamma(l + 1.0) - l * std::log(2.0) - 2.0 * std::lgamma(h + 1.0));
            a = 2.0 * kPiD * ((h % 2) ? 1.0 : -1.0) / ((l + 2.0) * (l - 1.0)) * binomial_term;
        }
        out[l] = std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)) * a;
    }
}

}  // namespace freqlab
