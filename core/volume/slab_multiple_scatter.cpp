#include "volume/slab_multiple_scatter.h"

#include <tbb/parallel_for.h>
#include <boost/math/quadrature/gauss.hpp>

#include <cmath>

#include "math/sh.h"
#include "volume/polar_quadrature.h"

namespace freqlab {

namespace {

// ZhDistanceTable's Catmull-Rom stencil in log depth (its trend is not used here).
ZhDistanceTable::Stencil depth_stencil(double z) {
    return ZhDistanceTable::stencil(ZhDistanceTable::Trend::DirectionalLike,
                                    std::max(z, ZhDistanceTable::kMinD));
}

}  // namespace

double SlabMultipleScatter::fluence(int k, double z) const {
    if (k == 0) return std::exp(-std::max(z, 0.0));
    const std::vector<double>& lf = log_fluence_[size_t(k)];
    const int n = ZhDistanceTable::kBins;
    if (z >= ZhDistanceTable::kMaxD) {
        const double z1 = ZhDistanceTable::distance_of_bin(n - 2), z2 = ZhDistanceTable::kMaxD;
        const double slope = (lf[size_t(n) - 1] - lf[size_t(n) - 2]) / (z2 - z1);
        return std::exp(lf[size_t(n) - 1] + slope * (z - z2));
    }
    return std::exp(
        ZhDistanceTable::interpolate(depth_stencil(z), [&](int i) { return lf[size_t(i)]; }));
}

SlabMultipleScatter::SlabMultipleScatter(int bounces)
    : zh_(size_t(bounces) + 1, std::vector<ZhVector>(ZhDistanceTable::kBins)),
      log_fluence_(size_t(bounces) + 1, std::vector<double>(ZhDistanceTable::kBins)) {
    using boost::math::quadrature::gauss;
    const auto& xt = gauss<double, 16>::abscissa();
    const auto& wt = gauss<double, 16>::weights();
    for (int i = 0; i < ZhDistanceTable::kBins; ++i)
        log_fluence_[0][size_t(i)] = -ZhDistanceTable::distance_of_bin(i);
    for (int k = 0; k < bounces; ++k) {
        tbb::parallel_for(0, ZhDistanceTable::kBins, [&](int bin) {
            const double s = ZhDistanceTable::distance_of_bin(bin);
            ZhVector z{};
            double p[kImpulseOrder];
            for (const auto& [mu, wmu] : directional_mu_nodes(s, 12)) {
                // u = 1 - e^{-(1 - mu) t}: e^{-t} dt = e^{-mu t} du / (1 - mu), and since
                // phi_k(z) ~ e^{-z} x (slowly varying), e^{-mu t} phi_k(s - t mu) stays bounded
                // and smooth in u whichever way the ray goes.
                const double a_rate = 1.0 - mu;
                const double u_max = mu > 0 ? -std::expm1(-a_rate * s / mu) : 1.0;
                double radiance = 0.0;
                const double edges[5] = {0.0, 0.5 * u_max, 0.8 * u_max, 0.95 * u_max, u_max};
                for (int pnl = 0; pnl < 4; ++pnl) {
                    const double a = edges[pnl], b = edges[pnl + 1];
                    for (size_t e = 0; e < xt.size(); ++e)
                        for (double sign : {-1.0, 1.0}) {
                            const double u = 0.5 * (a + b) + sign * 0.5 * (b - a) * xt[e];
                            const double t = -std::log1p(-u) / a_rate;
                            radiance +=
                                wt[e] * 0.5 * (b - a) * std::exp(-mu * t) * fluence(k, s - t * mu);
                        }
                }
                radiance /= 4.0 * kPiD * a_rate;
                legendre(kImpulseOrder, mu, p);
                for (int l = 0; l < kImpulseOrder; ++l)
                    z[size_t(l)] += 2.0 * kPiD * wmu * radiance *
                                    std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)) * p[l];
            }
            zh_[size_t(k) + 1][size_t(bin)] = z;
            log_fluence_[size_t(k) + 1][size_t(bin)] = std::log(std::sqrt(4.0 * kPiD) * z[0]);
        });
    }
    derive();
}

SlabMultipleScatter::SlabMultipleScatter(std::vector<std::vector<ZhVector>> zh)
    : zh_(std::move(zh)) {
    log_fluence_.assign(zh_.size(), std::vector<double>(ZhDistanceTable::kBins));
    for (int i = 0; i < ZhDistanceTable::kBins; ++i)
        log_fluence_[0][size_t(i)] = -ZhDistanceTable::distance_of_bin(i);
    // A bounce below the float range where it was stored (a thin slab's k-th bounce grows as
    // Z^k: 1e-90 at Z = 1e-3, k = 30) reads 0: its log fluence is held at e^-745 (0 in
    // double), finite so that interpolation next to it stays defined, and its shape at 0.
    for (size_t k = 1; k < zh_.size(); ++k)
        for (int i = 0; i < ZhDistanceTable::kBins; ++i) {
            const double dc = zh_[k][size_t(i)][0];
            log_fluence_[k][size_t(i)] = dc > 0.0 ? std::log(std::sqrt(4.0 * kPiD) * dc) : -745.0;
        }
    derive();
}

void SlabMultipleScatter::derive() {
    // The ZH shape zh / zh_0 and the log fluence, packed [bin][k] for queries.
    const size_t nk = zh_.size(), nb = ZhDistanceTable::kBins;
    packed_shape_.assign(nb * nk * kImpulseOrder, 0.0);
    packed_log_fluence_.assign(nb * nk, 0.0);
    for (size_t k = 1; k < nk; ++k)
        for (size_t i = 0; i < nb; ++i) {
            packed_log_fluence_[i * nk + k] = log_fluence_[k][i];
            for (size_t l = 0; l < size_t(kImpulseOrder); ++l)
                packed_shape_[(i * nk + k) * kImpulseOrder + l] =
                    zh_[k][i][0] > 0.0 ? zh_[k][i][l] / zh_[k][i][0] : 0.0;
        }
}

ZhVector SlabMultipleScatter::canonical(int k, double z) const {
    ZhVector out{};
    if (k < 1 || k > bounces() || !(z >= 0) || z >= ZhDistanceTable::kMaxD) return out;
    const ZhDistanceTable::Stencil st = depth_stencil(z);
    const double dc = fluence(k, z) / std::sqrt(4.0 * kPiD);
    const size_t nk = zh_.size();
    for (int l = 0; l < kImpulseOrder; ++l)
        out[size_t(l)] =
            dc * ZhDistanceTable::interpolate(st, [&](int i) {
                return packed_shape_[(size_t(i) * nk + size_t(k)) * kImpulseOrder + size_t(l)];
            });
    return out;
}

ZhVector SlabMultipleScatter::bounces_in(const HomogeneousMedium& m, double depth, int first,
                                         int last) const {
    ZhVector z{};
    const double c = m.sigma_s / m.sigma_t(), D = m.sigma_t() * depth;
    first = std::max(first, 1);
    last = std::min(last, bounces());
    if (!(D >= 0) || D >= ZhDistanceTable::kMaxD || first > last) return z;
    // The same stencil as canonical(), computed once for every bounce.
    const ZhDistanceTable::Stencil st = depth_stencil(D);
    const int* bins = st.bin;
    const double* w = st.weight;
    const size_t nk = zh_.size();
    double ck = std::pow(c, first);
    for (int k = first; k <= last; ++k, ck *= c) {
        double log_phi = 0.0, shape[kImpulseOrder] = {};
        for (int j = 0; j < 4; ++j) {
            const size_t at = size_t(bins[j]) * nk + size_t(k);
            log_phi += w[j] * packed_log_fluence_[at];
            const double* row = &packed_shape_[at * kImpulseOrder];
            for (int l = 0; l < kImpulseOrder; ++l) shape[l] += w[j] * row[l];
        }
        const double dc = ck * std::exp(log_phi) / std::sqrt(4.0 * kPiD);
        for (int l = 0; l < kImpulseOrder; ++l) z[size_t(l)] += dc * shape[l];
    }
    return z;
}

}  // namespace freqlab
