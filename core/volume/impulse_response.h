// Impulse responses of point and directional emitters in homogeneous media (seed, Deuxième
// article §4.2 Eq. 4.1, §4.3): the ZH coefficients, about the axis from the receiver to the
// emitter, of the radiance arriving at the receiver directly (attenuated) and after exactly one
// scattering event. Emitter intensity I0 = 1 (W/sr); coefficients are radiance x solid angle.
//
// | quantity            | definition (receiver at 0, emitter at distance d on the axis) |
// |---------------------|--------------------------------------------------------------------------|
// | direct_l            | e^{-sigma_t d} / d^2 * y_l^0(axis)  (a delta towards the emitter) | |
// single_l            | int_S2 y_l^0(w) int_0^inf e^{-sigma_t t} sigma_s p(u . -w) e^{-sigma_t
// r}/r^2 | |                     | dt dw, r = |t w - d z|, u = (t w - d z)/r the light's direction
// there    | | sigma remap (tested)| with D = sigma_t d and the canonical medium sigma_s = sigma_t
// = 1:          | |                     | direct(d) = sigma_t^2 direct_1(D), single(d) = sigma_s
// sigma_t single_1(D) |
//
// Without absorption both factors are sigma_r^2 (sigma_r = sigma_s' / sigma_s) at the query
// distance sigma_r d, which is the seed's rule for point emitters; with absorption the seed's
// single factor sigma_r = sigma_t / sigma_s is not what the substitution gives: the tests
// (tests/test_impulse_response.cpp) compare against direct computation at the medium and decide.
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include "volume/collapse_memo.h"
#include "volume/medium.h"
#include "volume/polar_quadrature.h"

namespace freqlab {

constexpr int kImpulseOrder = 11;
using ZhVector = std::array<double, kImpulseOrder>;

ZhVector point_direct_zh(const HomogeneousMedium& medium, double distance);
// Deterministic quadrature: equi-angular substitution along each ray (the 1/r^2 peak becomes
// flat), 48-point Gauss-Legendre along the ray, 40 graded panels x 12 points over the angle.
ZhVector point_single_zh(const HomogeneousMedium& medium, double distance);

// Directional emitter (Eq. 4.2) with irradiance E0 = 1 above a medium whose boundary plane,
// perpendicular to the light, lies `depth` above the receiver (towards the light); the ZH axis
// points at the light. The ray integral has a closed form per direction:
//   single(mu) = sigma_s p(mu) e^{-sigma_t s} (1 - e^{-sigma_t t_max (1 - mu)}) / (sigma_t (1 -
//   mu)), t_max = s / mu above the horizon of the boundary (mu > 0), infinite below it.
// Remap (tested): single(s) = sigma_s / sigma_t * single_1(sigma_t s); direct(s) = e^{-sigma_t s}.
ZhVector directional_direct_zh(const HomogeneousMedium& medium, double depth);
ZhVector directional_single_zh(const HomogeneousMedium& medium, double depth);

// Responses to the Legendre phase basis b_k(c) = (2k+1)/(4 pi) P_k(c), k < kPhaseTerms, in the
// canonical medium (sigma_s = sigma_t = 1). HG's expansion is p_g = sum_k g^k b_k, and single
// scattering is linear in the phase function, so single(g) = sum_k g^k response_k, exact up to
// the truncation g^kPhaseTerms (|g| <= 0.6: below 1e-7). This replaces the seed's linear
// interpolation between tables at g = -0.5, 0, 0.5, which measured 4-16 % off per coefficient
// at g = -0.3, 0.2, 0.45 (closing note of the session that wrote this).
constexpr int kPhaseTerms = 32;
using PhaseResponses = std::array<ZhVector, kPhaseTerms>;
PhaseResponses point_single_basis(double optical_distance, PolarRule rule = PolarRule::Fine);
PhaseResponses directional_single_basis(double optical_distance, bool coarse = false);

// Chebyshev nodes in g, panel by panel, for what 32 basis terms cannot carry: the area tables
// everywhere, and every table beyond |g| = kGInner (HG's Legendre series converges like g^k:
// 0.9^32 = 0.03). As a function of g the response is analytic inside |g| < 1 (HG's
// singularity, 1 + g^2 - 2 g c = 0, has |g| = 1), so polynomial interpolation at kGNodes
// Chebyshev nodes of a panel [a, b] converges like rho^-kGNodes, rho = s + sqrt(s^2 - 1),
// s = (1 - c) / h the singularity's distance from the panel's centre c in half-widths h. The
// panels are cut so that every one has rho >= 3 (the central [-0.6, 0.6]: s = 5/3, rho = 3;
// [0.6, 0.9]: s = 5/3; [0.9, 0.95]: s = 3, rho = 5.8). Measured on the central panel: 0.5 %
// for point-like responses at g = -0.3, 0.2, 0.5, 1 % at l = 9, 10 for the directional one.
// |g| > kGRange is refused where a method-B bake starts (impulse_query.h: check_table_g).
constexpr int kGNodes = 9;  // per panel
constexpr int kGPanels = 5;
constexpr double kGInner = 0.6;   // the Legendre basis's range (point, directional)
constexpr double kGRange = 0.95;  // the tables' range
constexpr std::array<double, kGPanels + 1> kGPanelEdges = {-0.95, -0.9, -0.6, 0.6, 0.9, 0.95};
constexpr int kGNodeCount = kGPanels * kGNodes;
constexpr int kGIsotropicNode = (kGPanels / 2) * kGNodes + kGNodes / 2;  // g = 0 exactly
double g_node(int j);  // node j of all panels: panel j / kGNodes, Chebyshev node j % kGNodes
// The panel whose nodes interpolate at g (outside [-kGRange, kGRange]: the end panel).
int g_panel(double g);
// Barycentric interpolation weights at g for the kGNodes nodes of g_panel(g) (they sum to 1).
void g_node_weights(double g, double* weights);
using GNodeResponses = std::array<ZhVector, kGNodeCount>;

// HG at every g node, its per-node constants computed once: what the single-scattering and
// area tables evaluate at each quadrature point.
struct HgAtGNodes {
    double scale[kGNodeCount], a[kGNodeCount], b[kGNodeCount];
    HgAtGNodes();
    void eval(double c, double* out) const {
        for (int j = 0; j < kGNodeCount; ++j) {
            const double x = a[j] - b[j] * c;
            out[j] = scale[j] / (x * std::sqrt(x));
        }
    }
};

// A single-scattering table's columns at one distance: the kPhaseTerms Legendre responses,
// then HG's response at each of the kGNodeCount g nodes (one quadrature pass gives all).
constexpr int kSingleColumns = kPhaseTerms + kGNodeCount;
using SingleColumns = std::array<ZhVector, kSingleColumns>;
SingleColumns point_single_columns(double optical_distance, PolarRule rule = PolarRule::Fine);
SingleColumns directional_single_columns(double optical_distance, bool coarse = false);

// ZH vectors over optical distances D in [kMinD, kMaxD], 256 log-spaced bins, Catmull-Rom
// interpolated in log D after removing the e^{-D} (and, for point emitters, 1/D) trends.
class ZhDistanceTable {
  public:
    static constexpr double kMinD = 1e-3, kMaxD = 40.0;
    static constexpr int kBins = 256;
    enum class Trend { PointLike, DirectionalLike };  // divide out e^-D / D, or e^-D only
    static double distance_of_bin(int i);

    ZhDistanceTable(Trend trend, const std::vector<ZhVector>& canonical);  // kBins entries
    ZhVector at(double optical_distance) const;
    std::vector<ZhVector> canonical() const;  // the kBins tabulated vectors (for saving)
    const std::vector<ZhVector>& scaled() const { return scaled_; }

    // The four bins and Catmull-Rom weights around D, and the trend to multiply back; `valid`
    // is false outside (0, kMaxD). Shared so that many tables on one grid interpolate once.
    struct Stencil {
        int bin[4];
        double weight[4];
        double trend;
        bool valid;
    };
    static Stencil stencil(Trend trend, double optical_distance);
    // sum_k weight[k] value(bin[k]): any per-bin quantity on the same grid.
    // z[l] += sum_k weight[k] rows[bin[k]][l], l < kImpulseOrder: a table of ZH rows (one per
    // bin, row-major) interpolated into z.
    static void interpolate_rows(const Stencil& st, const double* rows, double* z) {
        for (int k = 0; k < 4; ++k) {
            const double* row = rows + size_t(st.bin[k]) * kImpulseOrder;
            for (int l = 0; l < kImpulseOrder; ++l) z[size_t(l)] += st.weight[k] * row[l];
        }
    }
    template <class Value>
    static double interpolate(const Stencil& st, Value value) {
        double v = 0.0;
        for (int k = 0; k < 4; ++k) v += st.weight[k] * value(st.bin[k]);
        return v;
    }

  private:
    double trend(double D) const;
    Trend trend_;
    std::vector<ZhVector> scaled_;
};

// Single scattering of one emitter type for any medium and any |g| <= kGRange: the Legendre
// basis's kPhaseTerms responses for |g| <= kGInner, HG's own responses at the g nodes beyond.
class SingleScatterTable {
  public:
    enum class Emitter { Point, Directional };
    explicit SingleScatterTable(Emitter emitter);  // tabulates (~0.3 s on 2 cores)
    // From saved values: terms[k][bin] is the canonical response of column k (SingleColumns);
    // error[bin] the entry's estimated quadrature error (max over columns and orders, canonical
    // units).
    SingleScatterTable(Emitter emitter, const std::vector<std::vector<ZhVector>>& terms,
                       std::vector<double> error);
    std::vector<std::vector<ZhVector>> canonical_terms() const;
    const std::vector<double>& error() const { return error_; }
    // The largest estimated error relative to the entry's isotropic DC.
    double worst_relative_error() const;
    // Single-scattered ZH at `distance` (point: to the emitter; directional: to the medium's
    // boundary) in `medium`.
    // `collapsed` (bakers): g quantised to 2^-20 and the phase-term sum memoised per g
    // (collapse_memo.h); otherwise the exact sum at g.
    ZhVector single(const HomogeneousMedium& medium, double distance, bool collapsed = false) const;
    // Identity of the contents (copies share it): what memoised derivations are keyed by.
    uint64_t memo_id() const { return memo_id_; }

  private:
    void pack();
    Emitter emitter_;
    std::vector<ZhDistanceTable> terms_;  // one per column (SingleColumns)
    std::vector<double> packed_;          // [bin][column][l] scaled values: a query reads 4 blocks
    uint64_t memo_id_ = CollapseMemo::next_owner_id();  // collapsed-over-g memo (single())
    std::vector<double> error_;                         // [bin]
};

}  // namespace freqlab
