#include "volume/impulse_response.h"

#include "volume/collapse_memo.h"

#include "math/sh.h"
#include "volume/polar_quadrature.h"

#include <tbb/parallel_for.h>
#include <boost/math/quadrature/gauss.hpp>

#include <algorithm>
#include <cmath>

namespace freqlab {

namespace {

// y_l^0 for every l at once (math/sh.h's Legendre recurrence).
void zh_basis_all(double cos_theta, double* y) {
    legendre(kImpulseOrder, cos_theta, y);
    for (int l = 0; l < kImpulseOrder; ++l) y[l] *= std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD));
}

// Phase functions as a small set of terms whose responses are accumulated together: HG
// alone (one term) or the Legendre basis b_k(c) = (2k+1)/(4 pi) P_k(c) (kPhaseTerms terms).
struct HgPhase {
    double g;
    static constexpr int count = 1;
    void eval(double c, double* out) const { out[0] = hg_phase(g, c); }
};
struct LegendrePhaseBasis {
    static constexpr int count = kPhaseTerms;
    void eval(double c, double* out) const {
        double p0 = 1.0, p1 = c;
        out[0] = 1.0 / (4.0 * kPiD);
        if (count > 1) out[1] = 3.0 * c / (4.0 * kPiD);
        for (int k = 2; k < count; ++k) {
            const double p2 = ((2.0 * k - 1.0) * c * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
            out[k] = (2.0 * k + 1.0) / (4.0 * kPiD) * p2;
        }
    }
};
// A single-scattering table's columns: the Legendre basis, then HG at every g node.
struct SingleTableColumns {
    static constexpr int count = kSingleColumns;
    HgAtGNodes hg;
    void eval(double c, double* out) const {
        LegendrePhaseBasis{}.eval(c, out);
        hg.eval(c, out + kPhaseTerms);
    }
};

// Point emitter: single-scattered radiance from direction theta (from the axis to the
// emitter), per phase term, times sin(theta) so that it stays finite where the ray passes
// through the emitter. Equi-angular substitution t = t0 + h tan(phi): dt / r^2 = dphi / h.
template <class Phase>
void point_radiance_times_sin(double sigma_s, double sigma_t, double d, double theta,
                              const Phase& phase, double* out) {
    using boost::math::quadrature::gauss;
    for (int j = 0; j < Phase::count; ++j) out[j] = 0.0;
    const double ct = std::cos(theta), st = std::sin(theta);
    const double t0 = d * ct, h = d * st;  // closest approach along the ray, and its distance
    if (h < 1e-300) return;
    const double phi_a = std::atan2(-t0, h);
    const auto& x = gauss<double, 48>::abscissa();
    const auto& w = gauss<double, 48>::weights();
    const double mid = 0.5 * (phi_a + 0.5 * kPiD), half = 0.5 * (0.5 * kPiD - phi_a);
    double terms[Phase::count];
    for (size_t k = 0; k < x.size(); ++k)
        for (double sign : {-1.0, 1.0}) {
            const double phi = mid + sign * half * x[k];
            const double t = t0 + h * std::tan(phi), r = h / std::cos(phi);
            // Light travels from the emitter (at d z) to x_t = t w, then towards the receiver
            // (-w): cos = u . (-w) with u = (t w - d z) / r, so u . w = (t - d cos theta) / r.
            const double cos_scatter = -(t - t0) / r;
            const double common = std::exp(-sigma_t * (t + r)) * sigma_s * w[k] * half / d;
            phase.eval(cos_scatter, terms);
            for (int j = 0; j < Phase::count; ++j) out[j] += common * terms[j];
        }
}

template <class Phase>
void point_single(double sigma_s, double sigma_t, double d, const Phase& phase, ZhVector* out,
                  PolarRule rule = PolarRule::Fine) {
    for (int j = 0; j < Phase::count; ++j) out[j] = ZhVector{};
    // Graded towards theta = 0, where the response to a forward-peaked phase function and to
    // short distances concentrates (volume/polar_quadrature.h).
    double radiance[Phase::count], basis[kImpulseOrder];
    for (const PolarNode& node : graded_polar_nodes(rule)) {
        point_radiance_times_sin(sigma_s, sigma_t, d, node.theta, phase, radiance);
        zh_basis_all(std::cos(node.theta), basis);
        const double weight = 2.0 * kPiD * node.weight;
        for (int j = 0; j < Phase::count; ++j)
            for (int l = 0; l < kImpulseOrder; ++l)
                out[j][size_t(l)] += weight * radiance[j] * basis[l];
    }
}

// Directional emitter: the ray integral in closed form (see the header), per phase term.
template <class Phase>
void directional_single(double sigma_s, double sigma_t, double s, const Phase& phase, ZhVector* out,
                        bool coarse = false) {
    for (int j = 0; j < Phase::count; ++j) out[j] = ZhVector{};
    double terms[Phase::count];
    for (const MuNode& node : directional_mu_nodes(sigma_t * s, coarse ? 12 : 24)) {
        const double mu = node.mu;
        const double kk = sigma_t * (1.0 - mu);
        double path;  // int_0^t_max e^{-sigma_t t (1 - mu)} dt
        if (mu > 0) {
            const double t_max = s / mu;
            path = kk * t_max < 1e-8 ? t_max : -std::expm1(-kk * t_max) / kk;
        } else {
            path = 1.0 / kk;
        }
        const double common = 2.0 * kPiD * sigma_s * std::exp(-sigma_t * s) * path * node.weight;
        phase.eval(mu, terms);
        double y[kImpulseOrder];
        zh_basis_all(mu, y);
        for (int l = 0; l < kImpulseOrder; ++l)
            for (int j = 0; j < Phase::count; ++j) out[j][size_t(l)] += common * terms[j] * y[l];
    }
}

}  // namespace

// ZH of `weight` times a delta on the axis: weight y_l^0(axis).
ZhVector axis_delta_zh(double weight) {
    ZhVector z{};
    for (int l = 0; l < kImpulseOrder; ++l)
        z[size_t(l)] = weight * std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD));
    return z;
}

ZhVector point_direct_zh(const HomogeneousMedium& m, double d) {
    return axis_delta_zh(std::exp(-m.sigma_t() * d) / (d * d));
}

ZhVector point_single_zh(const HomogeneousMedium& m, double d) {
    ZhVector z;
    point_single(m.sigma_s, m.sigma_t(), d, HgPhase{m.g}, &z);
    return z;
}

double g_node(int j) {
    const int panel = j / kGNodes, k = j % kGNodes;
    const double a = kGPanelEdges[size_t(panel)], b = kGPanelEdges[size_t(panel) + 1];
    return 0.5 * (a + b) + 0.5 * (b - a) * std::cos((2.0 * k + 1.0) * kPiD / (2.0 * kGNodes));
}

HgAtGNodes::HgAtGNodes() {
    for (int j = 0; j < kGNodeCount; ++j) {
        const double g = g_node(j);
        scale[j] = (1.0 - g * g) / (4.0 * kPiD);
        a[j] = 1.0 + g * g;
        b[j] = 2.0 * g;
    }
}

int g_panel(double g) {
    int panel = 0;
    while (panel + 1 < kGPanels && g > kGPanelEdges[size_t(panel) + 1]) ++panel;
    return panel;
}

namespace {

// Barycentric weights of Chebyshev nodes (first kind): (-1)^k sin(theta_k), the same on every
// panel (an affine map of the nodes scales them all alike).
struct GNodeConstants {
    double weight[kGNodes];
    GNodeConstants() {
        for (int k = 0; k < kGNodes; ++k)
            weight[k] = (k % 2 ? -1.0 : 1.0) * std::sin((2.0 * k + 1.0) * kPiD / (2.0 * kGNodes));
    }
};

}  // namespace

void g_node_weights(double g, double* weights) {
    static const GNodeConstants c;
    const int first = g_panel(g) * kGNodes;
    double sum = 0.0;
    for (int k = 0; k < kGNodes; ++k) {
        const double diff = g - g_node(first + k);
        if (diff == 0.0) {
            for (int i = 0; i < kGNodes; ++i) weights[i] = i == k ? 1.0 : 0.0;
            return;
        }
        weights[k] = c.weight[k] / diff;
        sum += weights[k];
    }
    for (int k = 0; k < kGNodes; ++k) weights[k] /= sum;
}

PhaseResponses point_single_basis(double optical_distance, PolarRule rule) {
    PhaseResponses r;
    point_single(1.0, 1.0, optical_distance, LegendrePhaseBasis{}, r.data(), rule);
    return r;
}

SingleColumns point_single_columns(double optical_distance, PolarRule rule) {
    SingleColumns r;
    point_single(1.0, 1.0, optical_distance, SingleTableColumns{}, r.data(), rule);
    return r;
}

ZhVector directional_direct_zh(const HomogeneousMedium& m, double depth) {
    return axis_delta_zh(std::exp(-m.sigma_t() * depth));
}

ZhVector directional_single_zh(const HomogeneousMedium& m, double s) {
    ZhVector z;
    directional_single(m.sigma_s, m.sigma_t(), s, HgPhase{m.g}, &z);
    return z;
}

PhaseResponses directional_single_basis(double optical_distance, bool coarse) {
    PhaseResponses r;
    directional_single(1.0, 1.0, optical_distance, LegendrePhaseBasis{}, r.data(), coarse);
    return r;
}

SingleColumns directional_single_columns(double optical_distance, bool coarse) {
    SingleColumns r;
    directional_single(1.0, 1.0, optical_distance, SingleTableColumns{}, r.data(), coarse);
    return r;
}

double ZhDistanceTable::distance_of_bin(int i) {
    return kMinD * std::pow(kMaxD / kMinD, double(i) / (kBins - 1));
}

ZhDistanceTable::ZhDistanceTable(Trend trend, const std::vector<ZhVector>& canonical)
    : trend_(trend), scaled_(kBins) {
    for (int i = 0; i < kBins; ++i) {
        const double D = distance_of_bin(i);
        for (int l = 0; l < kImpulseOrder; ++l)
            scaled_[size_t(i)][size_t(l)] = canonical[size_t(i)][size_t(l)] / this->trend(D);
    }
}

std::vector<ZhVector> ZhDistanceTable::canonical() const {
    std::vector<ZhVector> out(kBins);
    for (int i = 0; i < kBins; ++i)
        for (int l = 0; l < kImpulseOrder; ++l)
            out[size_t(i)][size_t(l)] = scaled_[size_t(i)][size_t(l)] * trend(distance_of_bin(i));
    return out;
}

double ZhDistanceTable::trend(double D) const {
    return trend_ == Trend::PointLike ? std::exp(-D) / D : std::exp(-D);
}

ZhDistanceTable::Stencil ZhDistanceTable::stencil(Trend trend, double D) {
    Stencil st{};
    st.valid = D > 0 && D < kMaxD;  // beyond kMaxD the response is below e^-40
    if (!st.valid) return st;
    const double u = std::log(std::max(D, kMinD) / kMinD) / std::log(kMaxD / kMinD) * (kBins - 1);
    const int i = std::min(int(u), kBins - 2);
    const double f = u - i, f2 = f * f, f3 = f2 * f;
    // Catmull-Rom in log D: linear interpolation left 0.8 % errors on high-order coefficients
    // near their zero crossings (tests/test_impulse_response.cpp).
    st.bin[0] = std::max(i - 1, 0);
    st.bin[1] = i;
    st.bin[2] = i + 1;
    st.bin[3] = std::min(i + 2, kBins - 1);
    st.weight[0] = -0.5 * f3 + f2 - 0.5 * f;
    st.weight[1] = 1.5 * f3 - 2.5 * f2 + 1.0;
    st.weight[2] = -1.5 * f3 + 2.0 * f2 + 0.5 * f;
    st.weight[3] = 0.5 * f3 - 0.5 * f2;
    st.trend = trend == Trend::PointLike ? std::exp(-D) / D : std::exp(-D);
    return st;
}

ZhVector ZhDistanceTable::at(double D) const {
    ZhVector z{};
    const Stencil st = stencil(trend_, D);
    if (!st.valid) return z;
    for (int l = 0; l < kImpulseOrder; ++l) {
        double v = 0;
        for (int k = 0; k < 4; ++k) v += st.weight[k] * scaled_[size_t(st.bin[k])][size_t(l)];
        z[size_t(l)] = v * st.trend;
    }
    return z;
}

SingleScatterTable::SingleScatterTable(Emitter emitter) : emitter_(emitter) {
    const ZhDistanceTable::Trend trend = emitter == Emitter::Point
                                             ? ZhDistanceTable::Trend::PointLike
                                             : ZhDistanceTable::Trend::DirectionalLike;
    // One quadrature pass per distance gives every phase term's response; a coarse pass beside
    // it gives the entry's error estimate.
    std::vector<SingleColumns> responses(ZhDistanceTable::kBins);
    error_.assign(ZhDistanceTable::kBins, 0.0);
    tbb::parallel_for(0, ZhDistanceTable::kBins, [&](int i) {
        const double D = ZhDistanceTable::distance_of_bin(i);
        const bool point = emitter == Emitter::Point;
        responses[size_t(i)] = point ? point_single_columns(D) : directional_single_columns(D);
        const SingleColumns coarse = point ? point_single_columns(D, PolarRule::Coarse)
                                           : directional_single_columns(D, true);
        for (int j = 0; j < kSingleColumns; ++j)
            for (int l = 0; l < kImpulseOrder; ++l)
                error_[size_t(i)] = std::max(error_[size_t(i)],
                                             std::fabs(responses[size_t(i)][size_t(j)][size_t(l)] -
                                                       coarse[size_t(j)][size_t(l)]));
    });
    terms_.reserve(kSingleColumns);
    for (int j = 0; j < kSingleColumns; ++j) {
        std::vector<ZhVector> column(ZhDistanceTable::kBins);
        for (int i = 0; i < ZhDistanceTable::kBins; ++i)
            column[size_t(i)] = responses[size_t(i)][size_t(j)];
        terms_.emplace_back(trend, column);
    }
    pack();
}

SingleScatterTable::SingleScatterTable(Emitter emitter,
                                       const std::vector<std::vector<ZhVector>>& terms,
                                       std::vector<double> error)
    : emitter_(emitter), error_(std::move(error)) {
    const ZhDistanceTable::Trend trend = emitter == Emitter::Point
                                             ? ZhDistanceTable::Trend::PointLike
                                             : ZhDistanceTable::Trend::DirectionalLike;
    for (const std::vector<ZhVector>& column : terms) terms_.emplace_back(trend, column);
    pack();
}

void SingleScatterTable::pack() {
    const size_t nb = ZhDistanceTable::kBins, nt = terms_.size(), no = kImpulseOrder;
    packed_.assign(nb * nt * no, 0.0);
    for (size_t j = 0; j < nt; ++j)
        for (size_t i = 0; i < nb; ++i)
            for (size_t l = 0; l < no; ++l)
                packed_[(i * nt + j) * no + l] = terms_[j].scaled()[i][l];
}

double SingleScatterTable::worst_relative_error() const {
    const std::vector<ZhVector> iso = terms_[0].canonical();  // b_0: the isotropic phase
    double worst = 0.0;
    for (size_t i = 0; i < error_.size(); ++i)
        worst = std::max(worst, error_[i] / std::fabs(iso[i][0]));
    return worst;
}

std::vector<std::vector<ZhVector>> SingleScatterTable::canonical_terms() const {
    std::vector<std::vector<ZhVector>> out;
    for (const ZhDistanceTable& t : terms_) out.push_back(t.canonical());
    return out;
}

ZhVector SingleScatterTable::single(const HomogeneousMedium& m, double distance,
                                    bool collapse) const {
    ZhVector z{};
    const ZhDistanceTable::Trend trend = emitter_ == Emitter::Point
                                             ? ZhDistanceTable::Trend::PointLike
                                             : ZhDistanceTable::Trend::DirectionalLike;
    const ZhDistanceTable::Stencil st = ZhDistanceTable::stencil(trend, m.sigma_t() * distance);
    if (!st.valid) return z;
    // |g| <= kGInner: HG = sum_k g^k b_k, so the response is the same sum of the basis
    // responses; terms below |g|^k = 1e-10 are skipped (12 terms at |g| = 0.15, 32 at 0.5).
    // Beyond: barycentric interpolation between HG's responses at the g nodes of g's panel.
    // The sum over columns is collapsed once per g (quantised to 2^-20) and memoised per thread
    // (collapse_memo.h).
    const size_t nt = terms_.size();
    auto column_weights = [&](double g, double* w) {
        std::fill(w, w + nt, 0.0);
        if (std::fabs(g) <= kGInner) {
            double gk = 1.0;
            for (size_t j = 0; j < size_t(kPhaseTerms) && std::fabs(gk) > 1e-10; ++j, gk *= g)
                w[j] = gk;
        } else {
            g_node_weights(g, w + kPhaseTerms + g_panel(g) * kGNodes);
        }
    };
    double w[kSingleColumns];
    const double gq = std::round(m.g * 1048576.0) / 1048576.0;
    const std::vector<double>* collapsed =
        !collapse
            ? nullptr
            : CollapseMemo::get(memo_id_, uint64_t(int64_t(gq * 1048576.0) + (1ll << 40)), [&] {
                  double wq[kSingleColumns];
                  column_weights(gq, wq);
                  std::vector<double> c(size_t(ZhDistanceTable::kBins) * kImpulseOrder, 0.0);
                  for (size_t b = 0; b < size_t(ZhDistanceTable::kBins); ++b)
                      for (size_t j = 0; j < nt; ++j)
                          if (wq[j] != 0.0)
                              for (int l = 0; l < kImpulseOrder; ++l)
                                  c[b * kImpulseOrder + size_t(l)] +=
                                      wq[j] * packed_[(b * nt + j) * kImpulseOrder + size_t(l)];
                  return c;
              });
    if (collapsed) {
        ZhDistanceTable::interpolate_rows(st, collapsed->data(), z.data());
    } else {
        column_weights(m.g, w);
        for (size_t j = 0; j < nt; ++j)
            if (w[j] != 0.0)
                for (int k = 0; k < 4; ++k) {
                    const double wk = w[j] * st.weight[k];
                    const double* row = &packed_[(size_t(st.bin[k]) * nt + j) * kImpulseOrder];
                    for (int l = 0; l < kImpulseOrder; ++l) z[size_t(l)] += wk * row[l];
                }
    }
    // Optical-distance substitution (see the header): the factors were derived, then tested.
    const double factor =
        (emitter_ == Emitter::Point ? m.sigma_s * m.sigma_t() : m.sigma_s / m.sigma_t()) * st.trend;
    for (double& v : z) v *= factor;
    return z;
}

}  // namespace freqlab
