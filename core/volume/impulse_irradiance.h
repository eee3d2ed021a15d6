// Scattered irradiance tables for one bake (seed, Deuxième article §5 Eq. 5.1 and Appendix 8,
// specialised): a lightmap texel needs the impulse response only through its O(N) double
// product with the clamped cosine, E = sum_l z_l c_l P_l(cos), so for the media of a bake
// (a handful of (g, albedo) pairs) that product is tabulated once over optical distance and
// cosine, and a path segment costs one bilinear lookup instead of a table query and two
// double products. Tabulated in the canonical medium (sigma_t = 1, sigma_s = albedo) and
// remapped like the tables themselves: x sigma_t^2 for point and area emitters, x 1 for
// directional ones (impulse_query.h). Nothing is re-tabulated from scratch: every node is a
// query of the impulse tables.
//
// | grid       | nodes                                    | interpolation            |
// |------------|------------------------------------------|--------------------------|
// | distance D | 512, log-spaced in [kMinD, kMaxD]         | linear in log D, trend   |
// |            |                                          | e^-D / D (point, area) or |
// |            |                                          | e^-D (directional) divided out |
// | cosine     | 129, uniform in [-1, 1] (lobe axis . n)   | linear                   |
// | shift      | 8 (area: sin alpha = j / 7, as the tables) | linear                  |
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
    static constexpr int kDistanceNodes = 512, kCosineNodes = 129, kShiftNodes = 8;

    // g within the tables' range, albedo in [0, 1], last_bounce as in ImpulseQuery.
    ImpulseIrradiance(const ImpulseTables& tables, double g, double albedo, int last_bounce);

    // Where an optical distance falls on the grid (one log and one exp, shared by the lookups
    // of a segment); invalid at D <= 0 or D >= kMaxD (nothing scattered arrives).
    struct At {
        bool valid = false;
        int i = 0;
        double fu = 0.0, trend_point = 0.0, trend_directional = 0.0;
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

  private:
    struct Grid {
        // [shift][distance][cosine] values with the trend divided out.
        std::vector<float> values;
        int shifts = 1;
        double lookup(const At& d, double shift, double cos) const;  // without the trend
    };
    Grid point_single_, point_multiple_, directional_single_, directional_multiple_, area_single_;
    std::vector<float> tilt_;  // [shift][distance]
};

// The tables a bake needs, built on first use per (g, albedo, last bounce) — quantised to
// 2^-16 so that one medium's segments (whose effective coefficients differ only by rounding)
// share one — and shared by all threads. Returns null past kMaxEntries distinct keys (media
// mixtures with continuously varying coefficients), where callers query the tables directly.
class ImpulseIrradianceCache {
  public:
    static constexpr size_t kMaxEntries = 64;
    explicit ImpulseIrradianceCache(const ImpulseTables& tables) : tables_(tables) {}
    const ImpulseIrradiance* get(double g, double albedo, int last_bounce) const;

  private:
    const ImpulseTables& tables_;
    uint64_t id_ = CollapseMemo::next_owner_id();  // the per-thread front cache's owner
    mutable std::mutex mutex_;
    // This cache's entries (kept alive while it lives); built ones are also kept process-wide
    // (the 16 most recent), so that a re-bake of the same media builds nothing.
    mutable std::map<uint64_t, std::shared_ptr<const ImpulseIrradiance>> entries_;
};

}  // namespace freqlab
