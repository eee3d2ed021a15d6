#include "volume/multiple_scatter.h"

#include "volume/collapse_memo.h"

#include "math/sh.h"
#include "volume/polar_quadrature.h"

#include <tbb/parallel_for.h>
#include <boost/math/quadrature/gauss.hpp>

#include <cmath>

namespace freqlab {

namespace {}  // namespace

double PointMultipleScatter::fluence(int k, double D) const {
    if (!(D > 0) || D >= ZhDistanceTable::kMaxD) return 0.0;
    const std::vector<double>& row = fluence_scaled_[size_t(k)];
    const double scaled =
        ZhDistanceTable::interpolate(ZhDistanceTable::stencil(ZhDistanceTable::Trend::PointLike,
                                                              std::max(D, ZhDistanceTable::kMinD)),
                                     [&](int i) { return row[size_t(i)]; });
    return scaled * std::exp(-D) / (D * D);
}

PointMultipleScatter::PointMultipleScatter(int bounces)
    : fluence_scaled_(size_t(bounces) + 1, std::vector<double>(ZhDistanceTable::kBins)),
      zh_(size_t(bounces) + 1, std::vector<ZhVector>(ZhDistanceTable::kBins)) {
    using boost::math::quadrature::gauss;
    for (int i = 0; i < ZhDistanceTable::kBins; ++i)
        fluence_scaled_[0][size_t(i)] = 1.0;  // e^-D / D^2
    const auto& xr = gauss<double, 32>::abscissa();
    const auto& wr = gauss<double, 32>::weights();
    for (int k = 0; k < bounces; ++k) {
        tbb::parallel_for(0, ZhDistanceTable::kBins, [&](int bin) {
            const double D = ZhDistanceTable::distance_of_bin(bin);
            ZhVector z{};
            // Over theta (from the direction towards the emitter), graded towards 0: the
            // radiance behaves like 1 / sin(theta) there, which the sin(theta) of the solid
            // angle cancels (in mu it would be an endpoint singularity).
            for (const PolarNode& node : graded_polar_nodes()) {
                const double mu = std::cos(node.theta);
                const double t0 = D * mu, h = D * std::sin(node.theta);
                // Along the ray: t = t0 + h tan(phi), dt = h / cos^2(phi) dphi.
                const double phi_a = std::atan2(-t0, std::max(h, 1e-300));
                const double mid = 0.5 * (phi_a + 0.5 * kPiD), half = 0.5 * (0.5 * kPiD - phi_a);
                double radiance = 0.0;
                for (size_t e = 0; e < xr.size(); ++e)
                    for (double s2 : {-1.0, 1.0}) {
                        const double phi = mid + s2 * half * xr[e];
                        const double c = std::cos(phi);
                        const double t = t0 + h * std::tan(phi), r = h / c;
                        radiance += wr[e] * half * h / (c * c) * std::exp(-t) * fluence(k, r) /
                                    (4.0 * kPiD);
                    }
                const double weight = 2.0 * kPiD * std::sin(node.theta) * node.weight;
                double p[kImpulseOrder];
                legendre(kImpulseOrder, mu, p);
                for (int l = 0; l < kImpulseOrder; ++l)
                    z[size_t(l)] +=
                        weight * radiance * std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)) * p[l];
            }
            zh_[size_t(k) + 1][size_t(bin)] = z;
            // Fluence = integral of the radiance over the sphere = sqrt(4 pi) x the DC.
            fluence_scaled_[size_t(k) + 1][size_t(bin)] =
                std::sqrt(4.0 * kPiD) * z[0] * D * D * std::exp(D);
        });
    }
    scale();
}

void PointMultipleScatter::scale() {
    // [bin][k][l] of zh x D^2 e^D: one query reads 4 contiguous blocks for all its bounces.
    const size_t nk = zh_.size(), nb = ZhDistanceTable::kBins, no = kImpulseOrder;
    packed_.assign(nb * nk * no, 0.0);
    for (size_t k = 1; k < nk; ++k)
        for (size_t i = 0; i < nb; ++i) {
            const double D = ZhDistanceTable::distance_of_bin(int(i)), scale = D * D * std::exp(D);
            for (size_t l = 0; l < no; ++l) packed_[(i * nk + k) * no + l] = zh_[k][i][l] * scale;
        }
}

ZhVector PointMultipleScatter::canonical(int k, double D) const {
    ZhVector z{};
    if (k < 1 || k > bounces()) return z;
    // Same grid and stencil as the single-scattering tables; the trend here is e^-D / D^2.
    const ZhDistanceTable::Stencil st =
        ZhDistanceTable::stencil(ZhDistanceTable::Trend::PointLike, D);
    if (!st.valid) return z;
    const double trend = std::exp(-D) / (D * D);
    const size_t nk = zh_.size();
    for (int j = 0; j < 4; ++j) {
        const double* row = &packed_[(size_t(st.bin[j]) * nk + size_t(k)) * kImpulseOrder];
        for (int l = 0; l < kImpulseOrder; ++l) z[size_t(l)] += st.weight[j] * row[l];
    }
    for (double& v : z) v *= trend;
    return z;
}

ZhVector PointMultipleScatter::bounces_in(const HomogeneousMedium& m, double distance, int first,
                                          int last, bool collapse) const {
    ZhVector z{};
    const double c = m.sigma_s / m.sigma_t(), D = m.sigma_t() * distance;
    const ZhDistanceTable::Stencil st =
        ZhDistanceTable::stencil(ZhDistanceTable::Trend::PointLike, D);
    first = std::max(first, 1);
    last = std::min(last, bounces());
    if (!st.valid || first > last) return z;
    // One stencil for every bounce; the albedo weights c^k fold into the bin weights. The sum
    // over bounces is collapsed once per (albedo quantised to 2^-24, first, last) and memoised
    // per thread (collapse_memo.h).
    const size_t nk = zh_.size();
    const double cq = std::round(c * 16777216.0) / 16777216.0;
    const uint64_t key =
        (uint64_t(cq * 16777216.0) << 16) | (uint64_t(first) << 8) | uint64_t(last);
    const std::vector<double>* collapsed =
        !collapse ? nullptr : CollapseMemo::get(memo_id_, key, [&] {
            std::vector<double> out(size_t(ZhDistanceTable::kBins) * kImpulseOrder, 0.0);
            for (size_t b = 0; b < size_t(ZhDistanceTable::kBins); ++b) {
                double ck = std::pow(cq, first);
                const double* row = &packed_[(b * nk + size_t(first)) * kImpulseOrder];
                for (int k = first; k <= last; ++k, ck *= cq, row += kImpulseOrder)
                    for (int l = 0; l < kImpulseOrder; ++l)
                        out[b * kImpulseOrder + size_t(l)] += ck * row[l];
            }
            return out;
        });
    if (collapsed) {
        ZhDistanceTable::interpolate_rows(st, collapsed->data(), z.data());
    } else {
        const double first_weight = std::pow(c, first);
        for (int j = 0; j < 4; ++j) {
            double ck = first_weight * st.weight[j];
            const double* row = &packed_[(size_t(st.bin[j]) * nk + size_t(first)) * kImpulseOrder];
            for (int k = first; k <= last; ++k, ck *= c, row += kImpulseOrder)
                for (int l = 0; l < kImpulseOrder; ++l) z[size_t(l)] += ck * row[l];
        }
    }
    // Trend e^-D / D^2 (the stencil's is e^-D / D) and the sigma_t^2 of the remap.
    const double factor = m.sigma_t() * m.sigma_t() * std::exp(-D) / (D * D);
    for (double& v : z) v *= factor;
    return z;
}

}  // namespace freqlab
