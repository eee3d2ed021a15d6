// Scattered irradiance tables for one bake (seed, Deuxième article §5 Eq. 5.1 and Appendix 8,
// specialised): a lightmap texel needs the impulse response only through its O(N) double
// product with the clamped cosine, E(cos) = sum_l z_l c_l P_l(cos), so for the media of a bake
// (a handful of (g, albedo) pairs) the products z_l c_l are collapsed once per distance node
// and stored as the monomial coefficients of that degree-10 polynomial in cos: a path segment
// costs one blend of two coefficient rows and one Horner evaluation instead of a table query
// and two double products, exact in the cosine. Tabulated in the canonical medium
// (sigma_t = 1, sigma_s = albedo) and remapped like the tables themselves: x sigma_t^2 for
// point and area emitters, x 1 for directional ones (impulse_query.h). Nothing is
// re-tabulated from scratch: every node is a query of the impulse tables.
//
// | grid       | nodes                                      | interpolation                  |
// |------------|--------------------------------------------|--------------------------------|
// | distance D | 512, log-spaced in [kMinD, kMaxD]           | linear in log D, trend e^-D / D |
// |            |                                            | (point, area) or e^-D          |
// |            |                                            | (directional) divided out      |
// | cosine     | none: 11 coefficients of E's polynomial    | exact                          |
// | shift      | 8 (area: sin alpha = j / 7, as the tables) | linear                         |
// 512 x 11 floats per part (45 KB for point, 180 KB for the 8 area shifts) stay in L2; the
// first version, tabulated over 129 cosines, was 3.2 MB per medium and missed it.
// Measured against query + double product: tests/test_bake.cpp.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "volume/collapse_memo.h"
#include "volume/impulse_query.h"

namespace freqlab {

struct ScatteredIrradiance {
    double single = 0.0, multiple = 0.0;
};

class ImpulseIrradiance {
  public:
    static constexpr int kDistanceNodes = 512, kShiftNodes = 8, kTerms = kImpulseOrder;

    // g within the tables' range, albedo in [0, 1], last_bounce as in ImpulseQuery.
    ImpulseIrradiance(const ImpulseTables& tables, double g, double albedo, int last_bounce);

    // Where an optical distance falls on the grid (a table log2 and one exp, shared by the
    // lookups of a segment); invalid at D <= 0 or D >= kMaxD (nothing scattered arrives).
    struct At {
        bool valid = false;
        int i = 0;
        float fu = 0.0f;
        double trend_point = 0.0, trend_directional = 0.0;
    };
    static At at(double optical_distance);

    // Per unit emitter strength in the canonical medium (multiply by sigma_t^2 for point and
    // area emitters); `cos` is the cosine between the lobe axis and the receiver's normal.
    ScatteredIrradiance point(const At& d, double cos) const;
    ScatteredIrradiance directional(const At& d, double cos) const;
    // Area emitters: the single-scattered lobe's axis is tilted (area_tables.h), so its cosine
    // is the caller's to compute from tilt().
    double tilt(const At& d, double shift) const;
    ScatteredIrradiance area(const At& d, double shift, double cos_single, double cos_light) const;

    // Light probes (order-3 SH of incident radiance): the response's own first kProbeBands ZH
    // coefficients, single and multiple (area: multiple about the light axis), on the same
    // distance grid and with the same normalisation as the double products above.
    static constexpr int kProbeBands = 3;
    struct Lobes {
        double single[kProbeBands] = {}, multiple[kProbeBands] = {};
    };
    Lobes lobes(EmitterKind kind, const At& d, double shift) const;

  private:
    // Per distance node and channel (single, multiple scattering where they share an axis),
    // the kTerms monomial coefficients of E(cos) / trend, lowest power first.
    struct Grid {
        std::vector<float> values;  // [shift][distance][channel][term]
        int channels = 1;           // the shift bins (area) are the template argument of lookup()
        float* node(int shift, int i, int channel) {
            return &values[((size_t(shift) * kDistanceNodes + size_t(i)) * size_t(channels) +
                            size_t(channel)) *
                           kTerms];
        }
        // E / trend of channel 0 and, with two channels, 1 (Shifted: area, 8 shift bins);
        // Only >= 0: that channel alone (the other left 0).
        template <int Channels, bool Shifted, int Only = -1>
        void lookup(const At& d, double shift, double cos, double out[2]) const;
    };
    Grid point_, directional_;  // channels: single, multiple
    Grid area_single_;          // 8 shifts, 1 channel
    std::vector<float> tilt_;   // [shift][distance]
    // [distance][single 0..2, multiple 0..2] (point, directional); [shift][distance][0..2] (area)
    std::vector<float> lobe_point_, lobe_directional_, lobe_area_;
};

// A segment through several media: the tables at the corners of its (g, albedo) cell on a
// fixed grid, with their bilinear weights (ImpulseIrradianceCache::blend).
struct ImpulseIrradianceBlend {
    const ImpulseIrradiance* table[4] = {};
    double weight[4] = {};
    int count = 0;
};

// The tables a bake needs, built on first use per (g, albedo, last bounce) — quantised to
// 2^-16 so that one medium's segments (whose effective coefficients differ only by rounding)
// share one — and shared by all threads. get() returns null past kMaxEntries distinct keys,
// where callers query the tables directly.
//
// Segments through several media (valley's air and smoke) have effective coefficients that
// vary continuously: they took that direct query (2-5 us; 9 % of a valley bake at 1
// texel/unit), and which keys got a table depended on which thread came first. blend()
// answers them from tables at the nodes of a fixed grid instead, bilinear in u = -log2(1 - g)
// and v = -log2(1 - albedo), steps kBlendGStep and kBlendAlbedoStep: the multiple scattering
// grows like 1 / (1 - albedo) towards albedo 1 and the similar medium's sigma_s (1 - g) shrinks
// towards g 1, so equal steps there are equal relative steps (steps of 1/32 in g and 1/8 in v
// erred by up to 2.4 % at g 0.83; tests/test_bake.cpp). The last albedo node is albedo 1
// exactly. Deterministic (a node's table is a function of the node), ~300 KB a node, built
// when a segment first falls in one of its cells.
class ImpulseIrradianceCache {
  public:
    static constexpr size_t kMaxEntries = 64;
    static constexpr double kBlendGStep = 1.0 / 64.0;       // in u = -log2(1 - g)
    static constexpr double kBlendAlbedoStep = 1.0 / 32.0;  // in v = -log2(1 - albedo)
    static constexpr int kBlendAlbedoNodes = 641;           // v = 0 ... 20; the last: albedo 1
    explicit ImpulseIrradianceCache(const ImpulseTables& tables) : tables_(tables) {}
    const ImpulseIrradiance* get(double g, double albedo, int last_bounce) const;
    // g within the tables' range, albedo in [0, 1].
    ImpulseIrradianceBlend blend(double g, double albedo, int last_bounce) const;
    // The grid's albedo at node k (0 <= k < kBlendAlbedoNodes) and a albedo's coordinate there.
    static double blend_node_albedo(int k);
    static double blend_coordinate(double albedo);
    // The same for g (nodes clamped to the tables' |g| <= kGRange).
    static double blend_node_g(int k);
    static double blend_g_coordinate(double g);
    size_t blend_nodes() const;  // built so far

  private:
    const ImpulseIrradiance* node(int g_index, int albedo_index, int last_bounce) const;
    const ImpulseTables& tables_;
    uint64_t id_ = CollapseMemo::next_owner_id();  // the per-thread front cache's owner
    mutable std::mutex mutex_;
    // This cache's entries (kept alive while it lives); built ones are also kept process-wide
    // (the 16 most recent), so that a re-bake of the same media builds nothing.
    mutable std::map<uint64_t, std::shared_ptr<const ImpulseIrradiance>> entries_;
    mutable std::map<uint64_t, std::unique_ptr<const ImpulseIrradiance>> nodes_;
};

}  // namespace freqlab
