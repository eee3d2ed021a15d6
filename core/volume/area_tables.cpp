#include "volume/area_tables.h"

#include <tbb/parallel_for.h>
#include <boost/math/quadrature/gauss.hpp>

#include <cmath>

#include "math/sh.h"
#include "volume/area_impulse.h"

namespace freqlab {

namespace {

constexpr int kHalfAzimuths = 32;

using RadianceBlock = std::array<std::array<double, kGNodeCount>, kShiftBins>;

// Single-scattered radiance x sin(theta) arriving from direction w (canonical medium, I0 = 1),
// for every shift bin and g node: one ray integral shared by all of them. `iso_only`: the
// g = 0 node alone (the axis fit's pass; the 45 nodes' phase and sums were a third of the
// tabulation).
void radiance_times_sin(double D, const glm::dvec3& w, double theta, const HgAtGNodes& hg,
                        const glm::dvec3* normals, RadianceBlock& out, bool iso_only) {
    using boost::math::quadrature::gauss;
    for (auto& row : out) row.fill(0.0);
    const double ct = std::cos(theta), st = std::sin(theta);
    const double t0 = D * ct, h = D * st;
    if (h < 1e-300) return;
    const double phi_a = std::atan2(-t0, h);
    const double mid = 0.5 * (phi_a + 0.5 * kPiD), half = 0.5 * (0.5 * kPiD - phi_a);
    const auto& xr = gauss<double, 48>::abscissa();
    const auto& wr = gauss<double, 48>::weights();
    for (size_t e = 0; e < xr.size(); ++e)
        for (double sign : {-1.0, 1.0}) {
            const double phi = mid + sign * half * xr[e];
            const double t = t0 + h * std::tan(phi), r = h / std::cos(phi);
            const glm::dvec3 u = (t * w - glm::dvec3(0, 0, D)) / r;  // emitter -> x_t
            const double c = -glm::dot(u, w);                        // scattering cosine
            // Equi-angular along the ray: dt / r^2 = dphi / h; times sin(theta) = 1 / D.
            const double common = wr[e] * half / D * std::exp(-(t + r));
            double phase[kGNodeCount];
            const int j0 = iso_only ? kGIsotropicNode : 0;
            const int j1 = iso_only ? kGIsotropicNode + 1 : kGNodeCount;
            if (iso_only) {
                const double x = hg.a[j0] - hg.b[j0] * c;
                phase[j0] = hg.scale[j0] / (x * std::sqrt(x));
            } else {
                hg.eval(c, phase);
            }
            for (int s = 0; s < kShiftBins; ++s) {
                const double emission = glm::dot(normals[s], u);
                if (emission <= 0) continue;
                for (int j = j0; j < j1; ++j)
                    out[size_t(s)][size_t(j)] += common * emission * phase[j];
            }
        }
}

// Projects the radiance over one polar rule onto the ZH about `axes` (or, with `sh_iso`, the
// full SH of the g = 0 node for the axis fit).
void integrate(double D, PolarRule rule, const glm::dvec3* normals, const glm::dvec3* axes,
               std::array<GNodeResponses, kShiftBins>* zh,
               std::array<ShVector, kShiftBins>* sh_iso) {
    const HgAtGNodes hg;
    RadianceBlock radiance;
    double y[kAreaShCount], p[kImpulseOrder], norm[kImpulseOrder];
    for (int l = 0; l < kImpulseOrder; ++l) norm[l] = std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD));
    const int iso = kGIsotropicNode;
    for (const PolarNode& node : graded_polar_nodes(rule)) {
        const double st = std::sin(node.theta), ct = std::cos(node.theta);
        for (int k = 0; k < kHalfAzimuths; ++k) {
            const double azimuth = kPiD * (k + 0.5) / kHalfAzimuths;
            const glm::dvec3 w(st * std::cos(azimuth), st * std::sin(azimuth), ct);
            radiance_times_sin(D, w, node.theta, hg, normals, radiance, !zh);
            // Both mirror halves of the azimuth circle.
            const double weight = node.weight * 2.0 * kPiD / kHalfAzimuths;
            if (sh_iso) {
                sh_eval(kImpulseOrder, w, y);
                for (int s = 0; s < kShiftBins; ++s)
                    for (int i = 0; i < kAreaShCount; ++i)
                        (*sh_iso)[size_t(s)][size_t(i)] += weight * radiance[size_t(s)][iso] * y[i];
            }
            if (zh)
                for (int s = 0; s < kShiftBins; ++s) {
                    legendre(kImpulseOrder, glm::dot(w, axes[s]), p);
                    for (int j = 0; j < kGNodeCount; ++j) {
                        const double v = weight * radiance[size_t(s)][size_t(j)];
                        ZhVector& out = (*zh)[size_t(s)][size_t(j)];
                        for (int l = 0; l < kImpulseOrder; ++l)
                            out[size_t(l)] += v * norm[l] * p[l];
                    }
                }
        }
    }
    if (sh_iso)  // sin(m phi) terms vanish by the mirror symmetry; half-circle sums leave noise
        for (auto& sh : *sh_iso)
            for (int l = 1; l < kImpulseOrder; ++l)
                for (int m = -l; m < 0; ++m) sh[size_t(sh_index(l, m))] = 0.0;
}

}  // namespace

AreaTableRow area_single_row(double D) {
    glm::dvec3 normals[kShiftBins], axes[kShiftBins];
    for (int s = 0; s < kShiftBins; ++s) {
        const double sa = shift_of_bin(s), ca = std::sqrt(std::max(1.0 - sa * sa, 0.0));
        normals[s] = glm::dvec3(sa, 0.0, -ca);
    }
    AreaTableRow row{};
    std::array<ShVector, kShiftBins> sh{};
    integrate(D, PolarRule::Fine, normals, nullptr, nullptr, &sh);
    for (int s = 0; s < kShiftBins; ++s) {
        const ZhAxisFit fit = fit_zh_axis(sh[size_t(s)]);
        row.tilt[size_t(s)] = std::atan2(fit.fitted_axis.x, fit.fitted_axis.z);
        axes[s] = glm::dvec3(std::sin(row.tilt[size_t(s)]), 0.0, std::cos(row.tilt[size_t(s)]));
    }
    std::array<GNodeResponses, kShiftBins> coarse{};
    integrate(D, PolarRule::Fine, normals, axes, &row.zh, nullptr);
    integrate(D, PolarRule::Coarse, normals, axes, &coarse, nullptr);
    for (int s = 0; s < kShiftBins; ++s)
        for (int j = 0; j < kGNodeCount; ++j)
            for (int l = 0; l < kImpulseOrder; ++l)
                row.error[size_t(s)] = std::max(row.error[size_t(s)],
                                                std::fabs(row.zh[size_t(s)][size_t(j)][size_t(l)] -
                                                          coarse[size_t(s)][size_t(j)][size_t(l)]));
    return row;
}

AreaSingleScatterTable::AreaSingleScatterTable() : rows_(ZhDistanceTable::kBins) {
    tbb::parallel_for(0, ZhDistanceTable::kBins, [&](int i) {
        rows_[size_t(i)] = area_single_row(ZhDistanceTable::distance_of_bin(i));
    });
    pack();
}

AreaSingleScatterTable::AreaSingleScatterTable(std::vector<AreaTableRow> rows)
    : rows_(std::move(rows)) {
    pack();
}

void AreaSingleScatterTable::pack() {
    const size_t block = size_t(kShiftBins) * kGNodeCount * kImpulseOrder;
    packed_.assign(rows_.size() * block, 0.0f);
    tilt_.assign(rows_.size() * kShiftBins, 0.0);
    for (size_t i = 0; i < rows_.size(); ++i) {
        for (int s = 0; s < kShiftBins; ++s)
            tilt_[i * kShiftBins + size_t(s)] = rows_[i].tilt[size_t(s)];
        const double D = ZhDistanceTable::distance_of_bin(int(i));
        const double inv_trend = D * std::exp(D);
        float* out = &packed_[i * block];
        for (int s = 0; s < kShiftBins; ++s)
            for (int j = 0; j < kGNodeCount; ++j)
                for (int l = 0; l < kImpulseOrder; ++l)
                    *out++ = float(rows_[i].zh[size_t(s)][size_t(j)][size_t(l)] * inv_trend);
    }
}

TiltedZh AreaSingleScatterTable::single(const HomogeneousMedium& m, double distance,
                                        double shift) const {
    TiltedZh r;
    const ZhDistanceTable::Stencil st =
        ZhDistanceTable::stencil(ZhDistanceTable::Trend::PointLike, m.sigma_t() * distance);
    if (!st.valid) return r;
    const double u = std::clamp(shift, 0.0, 1.0) * (kShiftBins - 1);
    const int s0 = std::min(int(u), kShiftBins - 2);
    const double fs = u - s0;
    double gw[kGNodes];
    g_node_weights(m.g, gw);
    // Distance and shift weights first, over the contiguous block of g's panel (vectorises),
    // then g.
    constexpr int kNodeBlock = kGNodes * kImpulseOrder;
    const size_t shift_block = size_t(kGNodeCount) * kImpulseOrder;
    const size_t block = size_t(kShiftBins) * shift_block;
    const size_t panel = size_t(g_panel(m.g)) * kNodeBlock;
    float acc[kNodeBlock] = {};  // 8 terms of float data: float sums lose nothing that matters
    for (int k = 0; k < 4; ++k)
        for (int ds = 0; ds < 2; ++ds) {
            const double ws = st.weight[k] * (ds ? fs : 1.0 - fs);
            if (ws == 0.0) continue;
            const float* base =
                &packed_[size_t(st.bin[k]) * block + size_t(s0 + ds) * shift_block + panel];
            const float wsf = float(ws);
            for (int x = 0; x < kNodeBlock; ++x) acc[x] += wsf * base[x];
            r.tilt += ws * tilt_[size_t(st.bin[k]) * kShiftBins + size_t(s0 + ds)];
        }
    for (int j = 0; j < kGNodes; ++j)
        for (int l = 0; l < kImpulseOrder; ++l)
            r.zh[size_t(l)] += gw[j] * double(acc[j * kImpulseOrder + l]);
    const double factor = m.sigma_s * m.sigma_t() * st.trend;
    for (double& v : r.zh) v *= factor;
    return r;
}

double AreaSingleScatterTable::worst_relative_error() const {
    double worst = 0.0;
    for (const AreaTableRow& row : rows_)
        for (int s = 0; s < kShiftBins; ++s) {
            const double dc = std::fabs(row.zh[size_t(s)][kGIsotropicNode][0]);
            if (dc > 0) worst = std::max(worst, row.error[size_t(s)] / dc);
        }
    return worst;
}

ZhVector area_direct_zh(const HomogeneousMedium& m, double d, double shift) {
    const double s = std::clamp(shift, 0.0, 1.0), cos_alpha = std::sqrt(1.0 - s * s);
    ZhVector z = point_direct_zh(m, d);
    for (double& v : z) v *= cos_alpha;
    return z;
}

}  // namespace freqlab
