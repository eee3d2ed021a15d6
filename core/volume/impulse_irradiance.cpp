#include "volume/impulse_irradiance.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>

#include "math/sh.h"

namespace freqlab {

namespace {

constexpr int kD = ImpulseIrradiance::kDistanceNodes;
constexpr int kC = ImpulseIrradiance::kCosineNodes;
constexpr int kS = ImpulseIrradiance::kShiftNodes;

double node_distance(int i) {
    return ZhDistanceTable::kMinD *
           std::pow(ZhDistanceTable::kMaxD / ZhDistanceTable::kMinD, double(i) / (kD - 1));
}

double trend(double D, bool point_like) {
    return point_like ? std::exp(-D) / D : std::exp(-D);
}

double node_cosine(int j) {
    return -1.0 + 2.0 * j / (kC - 1);
}

// E(cos) = sum_l z_l c_l P_l(cos) at every cosine node, divided by the trend.
void fill_cosines(const ZhVector& z, const double* cosine_zh, double inv_trend, float* out) {
    double zc[kImpulseOrder];
    for (int l = 0; l < kImpulseOrder; ++l) zc[l] = z[size_t(l)] * cosine_zh[l];
    for (int j = 0; j < kC; ++j) {
        double p[kImpulseOrder];
        legendre(kImpulseOrder, node_cosine(j), p);
        double e = 0.0;
        for (int l = 0; l < kImpulseOrder; ++l) e += zc[l] * p[l];
        out[j] = float(e * inv_trend);
    }
}

}  // namespace

ImpulseIrradiance::At ImpulseIrradiance::at(double D) {
    At a;
    if (!(D > 0.0) || D >= ZhDistanceTable::kMaxD) return a;
    static const double inv_log_range =
        1.0 / std::log(ZhDistanceTable::kMaxD / ZhDistanceTable::kMinD);
    const double u = std::log(std::max(D, ZhDistanceTable::kMinD) / ZhDistanceTable::kMinD) *
                     inv_log_range * (kD - 1);
    a.valid = true;
    a.i = std::min(int(u), kD - 2);
    a.fu = u - a.i;
    a.trend_directional = std::exp(-D);
    a.trend_point = a.trend_directional / D;
    return a;
}

double ImpulseIrradiance::Grid::lookup(const At& d, double shift, double cos) const {
    if (!d.valid) return 0.0;
    const int i = d.i;
    const double fu = d.fu;
    const double v = (std::clamp(cos, -1.0, 1.0) + 1.0) * 0.5 * (kC - 1);
    const int j = std::min(int(v), kC - 2);
    const double fv = v - j;
    int s0 = 0;
    double fs = 0.0;
    if (shifts > 1) {
        const double w = std::clamp(shift, 0.0, 1.0) * (shifts - 1);
        s0 = std::min(int(w), shifts - 2);
        fs = w - s0;
    }
    double sum = 0.0;
    for (int ds = 0; ds < (shifts > 1 ? 2 : 1); ++ds) {
        const double ws = shifts > 1 ? (ds ? fs : 1.0 - fs) : 1.0;
        const float* row = &values[(size_t(s0 + ds) * kD + size_t(i)) * kC + size_t(j)];
        const double a = row[0] + fv * (row[1] - row[0]);
        const double b = row[kC] + fv * (row[kC + 1] - row[kC]);
        sum += ws * (a + fu * (b - a));
    }
    return sum;
}

ImpulseIrradiance::ImpulseIrradiance(const ImpulseTables& tables, double g, double albedo,
                                     int last_bounce) {
    double cosine_zh[kImpulseOrder];
    zh_clamped_cosine(kImpulseOrder, cosine_zh);
    ImpulseQuery q;
    q.medium = {albedo, 1.0 - albedo, g};
    q.last_bounce = last_bounce;
    q.collapsed = true;
    const bool multiple = last_bounce >= 2;
    for (Grid* grid :
         {&point_single_, &point_multiple_, &directional_single_, &directional_multiple_})
        grid->values.assign(size_t(kD) * kC, 0.0f);
    area_single_.shifts = kS;
    area_single_.values.assign(size_t(kS) * kD * kC, 0.0f);
    tilt_.assign(size_t(kS) * kD, 0.0f);
    // Sigma_s = 0 has no scattered light at all: the tables' queries need sigma_s > 0.
    if (!(albedo > 0.0)) return;
    // Isolated: the cache builds this while holding its lock, and a worker must not pick up an
    // outer task that would wait for that lock.
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(0, kD, [&](int i) {
            const double D = node_distance(i);
            ImpulseQuery local = q;
            local.distance = D;
            const double inv_point = 1.0 / trend(D, true), inv_dir = 1.0 / trend(D, false);
            local.emitter = EmitterKind::Point;
            ImpulseResponse r = query_impulse(tables, local);
            fill_cosines(r.single, cosine_zh, inv_point, &point_single_.values[size_t(i) * kC]);
            if (multiple)
                fill_cosines(r.multiple, cosine_zh, inv_point,
                             &point_multiple_.values[size_t(i) * kC]);
            local.emitter = EmitterKind::Directional;
            r = query_impulse(tables, local);
            fill_cosines(r.single, cosine_zh, inv_dir, &directional_single_.values[size_t(i) * kC]);
            if (multiple)
                fill_cosines(r.multiple, cosine_zh, inv_dir,
                             &directional_multiple_.values[size_t(i) * kC]);
            local.emitter = EmitterKind::Area;
            for (int s = 0; s < kS; ++s) {
                local.shift = double(s) / (kS - 1);
                r = query_impulse(tables, local);
                fill_cosines(r.single, cosine_zh, inv_point,
                             &area_single_.values[(size_t(s) * kD + size_t(i)) * kC]);
                tilt_[size_t(s) * kD + size_t(i)] = float(r.axis_tilt);
            }
        });
    });
}

ScatteredIrradiance ImpulseIrradiance::point(const At& d, double cos) const {
    return {point_single_.lookup(d, 0.0, cos) * d.trend_point,
            point_multiple_.lookup(d, 0.0, cos) * d.trend_point};
}

ScatteredIrradiance ImpulseIrradiance::directional(const At& d, double cos) const {
    return {directional_single_.lookup(d, 0.0, cos) * d.trend_directional,
            directional_multiple_.lookup(d, 0.0, cos) * d.trend_directional};
}

double ImpulseIrradiance::tilt(const At& d, double shift) const {
    if (!d.valid) return 0.0;
    const int i = d.i;
    const double fu = d.fu;
    const double w = std::clamp(shift, 0.0, 1.0) * (kS - 1);
    const int s0 = std::min(int(w), kS - 2);
    const double fs = w - s0;
    auto at = [&](int s, int k) { return double(tilt_[size_t(s) * kD + size_t(k)]); };
    const double a = at(s0, i) + fu * (at(s0, i + 1) - at(s0, i));
    const double b = at(s0 + 1, i) + fu * (at(s0 + 1, i + 1) - at(s0 + 1, i));
    return a + fs * (b - a);
}

ScatteredIrradiance ImpulseIrradiance::area(const At& d, double shift, double cos_single,
                                            double cos_light) const {
    // Multiple scattering of an area emitter is the point emitter's at a quarter (see
    // impulse_query.h), about the light axis.
    return {area_single_.lookup(d, shift, cos_single) * d.trend_point,
            0.25 * point_multiple_.lookup(d, 0.0, cos_light) * d.trend_point};
}

namespace {

// The process-wide store: the 16 most recently built tables, by (impulse tables, key).
std::shared_ptr<const ImpulseIrradiance> shared(const ImpulseTables& tables, uint64_t key, double g,
                                                double albedo, int last_bounce) {
    static std::mutex mutex;
    static std::vector<
        std::pair<std::pair<uint64_t, uint64_t>, std::shared_ptr<const ImpulseIrradiance>>>
        recent;
    const std::pair<uint64_t, uint64_t> id{tables.point_single().memo_id(), key};
    {
        std::lock_guard<std::mutex> lock(mutex);
        for (auto& [k, v] : recent)
            if (k == id) return v;
    }
    auto built = std::make_shared<const ImpulseIrradiance>(tables, g, albedo, last_bounce);
    std::lock_guard<std::mutex> lock(mutex);
    recent.emplace_back(id, built);
    if (recent.size() > 16) recent.erase(recent.begin());
    return built;
}

}  // namespace

const ImpulseIrradiance* ImpulseIrradianceCache::get(double g, double albedo,
                                                     int last_bounce) const {
    const double gq = std::round(g * 65536.0) / 65536.0;
    const double cq = std::round(albedo * 65536.0) / 65536.0;
    const uint64_t key = (uint64_t(int64_t(gq * 65536.0) + 65536) << 32) |
                         (uint64_t(cq * 65536.0) << 8) | uint64_t(last_bounce & 0xff);
    // Most segments of a bake meet the key they met last: no lock then.
    thread_local struct {
        uint64_t owner = 0, key = 0;
        const ImpulseIrradiance* value = nullptr;
    } last;
    if (last.owner == id_ && last.key == key && last.value) return last.value;
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = entries_.find(key);
    const ImpulseIrradiance* found = nullptr;
    if (it != entries_.end()) {
        found = it->second.get();
    } else if (entries_.size() < kMaxEntries) {
        std::shared_ptr<const ImpulseIrradiance> entry = shared(tables_, key, gq, cq, last_bounce);
        found = entries_.emplace(key, std::move(entry)).first->second.get();
    }
    if (found) last = {id_, key, found};
    return found;
}

}  // namespace freqlab
