#include "volume/slab_bottom_multiple_scatter.h"

#include <tbb/parallel_for.h>
#include <boost/math/special_functions/expint.hpp>

#include <algorithm>
#include <cmath>

namespace freqlab {

namespace {

constexpr double kMaxSpacing = 0.1;  // optical units between interior nodes
constexpr int kMinNodes = 24;
constexpr int kMaxE = kImpulseOrder + 3;  // E_n up to n = 13 (receiver, l = 10: E_{m+3})

// E_n(x) for x >= 0 (E_n(0) = 1 / (n - 1), n >= 2).
double expint_n(int n, double x) {
    if (x <= 0.0) return 1.0 / double(n - 1);
    if (x > 700.0) return 0.0;  // below the smallest double
    return boost::math::expint(n, x);
}

// Monomial coefficients a[l][m] of the Legendre polynomials P_l, l < kImpulseOrder.
std::vector<std::vector<double>> legendre_monomials() {
    std::vector<std::vector<double>> a(kImpulseOrder, std::vector<double>(kImpulseOrder, 0.0));
    a[0][0] = 1.0;
    if (kImpulseOrder > 1) a[1][1] = 1.0;
    for (int l = 1; l + 1 < kImpulseOrder; ++l)
        for (int m = 0; m < kImpulseOrder; ++m) {
            const double up = m > 0 ? (2.0 * l + 1.0) * a[size_t(l)][size_t(m) - 1] : 0.0;
            a[size_t(l) + 1][size_t(m)] = (up - l * a[size_t(l) - 1][size_t(m)]) / (l + 1.0);
        }
    return a;
}

// Weights w[j] with int_0^Z E_n(|z - z'|) phi(z') dz' = sum_j w[j] phi(z_j) for phi linear
// between nodes: per element, with x_lo / x_hi its distances from z to the near / far node
// and h its length, the near node gets E_{n+1}(x_lo) - D and the far one D - E_{n+1}(x_hi),
// D = (E_{n+2}(x_lo) - E_{n+2}(x_hi)) / h. e1[j], e2[j]: E_{n+1}, E_{n+2} at |z - z_j|.
void product_weights(const std::vector<double>& nodes, size_t at, const std::vector<double>& e1,
                     const std::vector<double>& e2, double* w) {
    const size_t n = nodes.size();
    std::fill(w, w + n, 0.0);
    for (size_t j = 0; j + 1 < n; ++j) {
        const double h = nodes[j + 1] - nodes[j];
        if (!(h > 0.0)) continue;
        // The node nearer to z (z is a node, so never inside an element).
        const size_t near = j + 1 <= at ? j + 1 : j, far = near == j ? j + 1 : j;
        const double d = (e2[near] - e2[far]) / h;
        w[near] += e1[near] - d;
        w[far] += d - e1[far];
    }
}

}  // namespace

SlabBottomSolution solve_slab_bottom(double Z, int bounces) {
    SlabBottomSolution out;
    const int n = std::max(kMinNodes, int(std::ceil(kPiD * Z / (2.0 * kMaxSpacing))) + 1);
    out.z.resize(size_t(n));
    for (int i = 0; i < n; ++i)
        out.z[size_t(i)] = 0.5 * Z * (1.0 - std::cos(kPiD * double(i) / double(n - 1)));
    out.z.back() = Z;
    const size_t N = size_t(n);
    // The interior composition as a matrix: K[i][j] = 1/2 x the E_1 product weight.
    std::vector<double> K(N * N), e2(N), e3(N);
    for (size_t i = 0; i < N; ++i) {
        for (size_t j = 0; j < N; ++j) {
            const double x = std::abs(out.z[i] - out.z[j]);
            e2[j] = expint_n(2, x);
            e3[j] = expint_n(3, x);
        }
        product_weights(out.z, i, e2, e3, &K[i * N]);
        for (size_t j = 0; j < N; ++j) K[i * N + j] *= 0.5;
    }
    out.phi.assign(size_t(bounces) + 1, std::vector<double>(N, 0.0));
    for (size_t j = 0; j < N; ++j) out.phi[0][j] = std::exp(-out.z[j]);
    for (int k = 0; k < bounces; ++k)
        for (size_t i = 0; i < N; ++i) {
            double s = 0.0;
            for (size_t j = 0; j < N; ++j) s += K[i * N + j] * out.phi[size_t(k)][j];
            out.phi[size_t(k) + 1][i] = s;
        }
    // The receiver's rows: for each l, 1/2 c_l sum_m a_lm x the E_{m+1} product weights at Z.
    static const std::vector<std::vector<double>> a = legendre_monomials();
    std::vector<std::vector<double>> e(kMaxE + 1, std::vector<double>(N));
    for (int m = 2; m <= kMaxE; ++m)
        for (size_t j = 0; j < N; ++j) e[size_t(m)][j] = expint_n(m, Z - out.z[j]);
    std::vector<std::vector<double>> row(kImpulseOrder, std::vector<double>(N, 0.0));
    std::vector<double> w(N);
    for (int m = 0; m < kImpulseOrder; ++m) {
        product_weights(out.z, N - 1, e[size_t(m) + 2], e[size_t(m) + 3], w.data());
        for (int l = m; l < kImpulseOrder; ++l) {
            const double c =
                0.5 * std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)) * a[size_t(l)][size_t(m)];
            if (c == 0.0) continue;
            for (size_t j = 0; j < N; ++j) row[size_t(l)][j] += c * w[j];
        }
    }
    out.zh.assign(size_t(bounces) + 1, ZhVector{});
    for (int k = 1; k <= bounces; ++k)
        for (int l = 0; l < kImpulseOrder; ++l) {
            double s = 0.0;
            for (size_t j = 0; j < N; ++j) s += row[size_t(l)][j] * out.phi[size_t(k) - 1][j];
            out.zh[size_t(k)][size_t(l)] = s;
        }
    return out;
}

SlabMultipleScatter build_slab_bottom_multiple_scatter(int bounces) {
    std::vector<std::vector<ZhVector>> zh(size_t(bounces) + 1,
                                          std::vector<ZhVector>(ZhDistanceTable::kBins));
    tbb::parallel_for(0, ZhDistanceTable::kBins, [&](int bin) {
        const SlabBottomSolution s =
            solve_slab_bottom(ZhDistanceTable::distance_of_bin(bin), bounces);
        for (int k = 1; k <= bounces; ++k) zh[size_t(k)][size_t(bin)] = s.zh[size_t(k)];
    });
    return SlabMultipleScatter(std::move(zh));
}

}  // namespace freqlab
