#include "volume/impulse_irradiance.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "math/sh.h"

namespace freqlab {

namespace {

constexpr int kD = ImpulseIrradiance::kDistanceNodes;
constexpr int kS = ImpulseIrradiance::kShiftNodes;
constexpr int kL = ImpulseIrradiance::kTerms;

double node_distance(int i) {
    return ZhDistanceTable::kMinD *
           std::pow(ZhDistanceTable::kMaxD / ZhDistanceTable::kMinD, double(i) / (kD - 1));
}

double trend(double D, bool point_like) {
    return point_like ? std::exp(-D) / D : std::exp(-D);
}

// The monomial coefficients of sum_l z_l c_l P_l(x) / trend (Legendre's recurrence on the
// coefficient vectors, in double), into out[0..kL).
void polynomial_coefficients(const ZhVector& z, const double* cosine_zh, double inv_trend,
                             float* out) {
    double prev[kL] = {1.0}, cur[kL] = {0.0, 1.0}, sum[kL] = {};
    sum[0] = z[0] * cosine_zh[0];
    for (int k = 0; k < kL; ++k) sum[k] += z[1] * cosine_zh[1] * cur[k];
    for (int l = 1; l + 1 < kL; ++l) {
        // P_{l+1} = ((2l + 1) x P_l - l P_{l-1}) / (l + 1)
        double next[kL] = {};
        for (int k = 0; k < kL; ++k) {
            next[k] = -double(l) * prev[k];
            if (k > 0) next[k] += double(2 * l + 1) * cur[k - 1];
            next[k] /= double(l + 1);
        }
        for (int k = 0; k < kL; ++k) {
            prev[k] = cur[k];
            cur[k] = next[k];
            sum[k] += z[size_t(l + 1)] * cosine_zh[l + 1] * next[k];
        }
    }
    for (int k = 0; k < kL; ++k) out[k] = float(sum[k] * inv_trend);
}

}  // namespace

namespace {

// log2 of a normal float x >= 1 from its exponent bits and a 256-entry table of the mantissa's
// log2, linearly interpolated: <= 3e-6 off, i.e. 1e-4 of a distance bin, in a few dependent
// operations (the grid index heads every lookup's chain of latencies; logf was 30 % of at()).
float table_log2(float x) {
    static const std::array<float, 257> table = [] {
        std::array<float, 257> t{};
        for (int k = 0; k <= 256; ++k) t[size_t(k)] = float(std::log2(1.0 + k / 256.0));
        return t;
    }();
    uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const int exponent = int(bits >> 23) - 127;
    const uint32_t mantissa = bits & 0x7fffffu;
    const uint32_t k = mantissa >> 15;
    const float f = float(mantissa & 0x7fffu) * (1.0f / 32768.0f);
    return float(exponent) + table[k] + f * (table[k + 1] - table[k]);
}

}  // namespace

ImpulseIrradiance::At ImpulseIrradiance::at(double D) {
    At a;
    if (!(D > 0.0) || D >= ZhDistanceTable::kMaxD) return a;
    static const float scale =
        float((kD - 1) / std::log2(ZhDistanceTable::kMaxD / ZhDistanceTable::kMinD));
    const float u = table_log2(std::max(1.0f, float(D * (1.0 / ZhDistanceTable::kMinD)))) * scale;
    a.valid = true;
    a.i = std::min(int(u), kD - 2);
    a.fu = std::min(u - float(a.i), 1.0f);
    // Float exp (libm's, 1 ulp): the trend is off by ~1e-7, far below the distance
    // interpolation's own ~2e-3. Only the final product waits for it.
    a.trend_directional = double(std::exp(-float(D)));
    a.trend_point = a.trend_directional / D;
    return a;
}

namespace {

// sum_k c[k] x^k for the kL = 11 coefficients, by Estrin's scheme (a depth of 5 multiply-adds
// instead of Horner's 10: the lookup is latency-bound).
inline double polynomial11(const float* c, double x) {
    const double x2 = x * x, x4 = x2 * x2, x8 = x4 * x4;
    const double p01 = c[0] + x * c[1], p23 = c[2] + x * c[3], p45 = c[4] + x * c[5],
                 p67 = c[6] + x * c[7], p89 = c[8] + x * c[9];
    const double p0_3 = p01 + x2 * p23, p4_7 = p45 + x2 * p67, p8_10 = p89 + x2 * c[10];
    return (p0_3 + x4 * p4_7) + x8 * p8_10;
}
static_assert(kL == 11, "polynomial11 evaluates 11 terms");

}  // namespace

template <int Channels, bool Shifted, int Only>
void ImpulseIrradiance::Grid::lookup(const At& d, double shift, double cos, double out[2]) const {
    static_assert(Only < Channels, "a channel of the grid");
    out[0] = out[1] = 0.0;
    if (!d.valid) return;
    constexpr size_t row = size_t(Channels) * kL;
    // The channels evaluated: all, or Only's alone (an area emitter's multiple scattering, the
    // point emitter's: half the blend and one polynomial).
    constexpr int c_first = Only >= 0 ? Only : 0, c_last = Only >= 0 ? Only + 1 : Channels;
    constexpr size_t k_first = size_t(c_first) * kL, k_last = size_t(c_last) * kL;
    const float fu = d.fu;
    size_t first = size_t(d.i);
    float fs = 0.0f;
    if constexpr (Shifted) {
        const float ws = std::clamp(float(shift), 0.0f, 1.0f) * float(kS - 1);
        const int s0 = std::min(int(ws), kS - 2);
        fs = ws - float(s0);
        first += size_t(s0) * kD;
    }
    // Blend the coefficient rows (a straight loop over row floats: vectorized).
    const float* r0 = &values[first * row];
    float coef[row];
    for (size_t k = k_first; k < k_last; ++k) coef[k] = r0[k] + fu * (r0[row + k] - r0[k]);
    if constexpr (Shifted) {
        const float* r2 = r0 + size_t(kD) * row;  // the next shift bin
        for (size_t k = k_first; k < k_last; ++k) {
            const float next = r2[k] + fu * (r2[row + k] - r2[k]);
            coef[k] += fs * (next - coef[k]);
        }
    }
    const double x = std::clamp(cos, -1.0, 1.0);
    for (int c = c_first; c < c_last; ++c) out[c] = polynomial11(coef + size_t(c) * kL, x);
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
    for (Grid* grid : {&point_, &directional_}) {
        grid->channels = 2;
        grid->values.assign(size_t(kD) * 2 * kL, 0.0f);
    }
    area_single_.values.assign(size_t(kS) * kD * kL, 0.0f);
    tilt_.assign(size_t(kS) * kD, 0.0f);
    constexpr int kB = kProbeBands;
    lobe_point_.assign(size_t(kD) * 2 * kB, 0.0f);
    lobe_directional_.assign(size_t(kD) * 2 * kB, 0.0f);
    lobe_area_.assign(size_t(kS) * kD * kB, 0.0f);
    auto store_lobe = [](const ZhVector& z, double inv_trend, float* out) {
        for (int b = 0; b < kB; ++b) out[b] = float(z[size_t(b)] * inv_trend);
    };
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
            polynomial_coefficients(r.single, cosine_zh, inv_point, point_.node(0, i, 0));
            store_lobe(r.single, inv_point, &lobe_point_[size_t(i) * 2 * kB]);
            if (multiple) {
                polynomial_coefficients(r.multiple, cosine_zh, inv_point, point_.node(0, i, 1));
                store_lobe(r.multiple, inv_point, &lobe_point_[size_t(i) * 2 * kB + kB]);
            }
            local.emitter = EmitterKind::Directional;
            r = query_impulse(tables, local);
            polynomial_coefficients(r.single, cosine_zh, inv_dir, directional_.node(0, i, 0));
            store_lobe(r.single, inv_dir, &lobe_directional_[size_t(i) * 2 * kB]);
            if (multiple) {
                // Probes are mid-air (the half-space); lightmap texels lie on the medium's
                // boundary (the slab-bottom table).
                store_lobe(r.multiple, inv_dir, &lobe_directional_[size_t(i) * 2 * kB + kB]);
                local.receiver = Receiver::OnSurface;
                const ImpulseResponse texel = query_impulse(tables, local);
                local.receiver = Receiver::InMedium;
                polynomial_coefficients(texel.multiple, cosine_zh, inv_dir,
                                        directional_.node(0, i, 1));
            }
            local.emitter = EmitterKind::Area;
            for (int s = 0; s < kS; ++s) {
                local.shift = double(s) / (kS - 1);
                r = query_impulse(tables, local);
                polynomial_coefficients(r.single, cosine_zh, inv_point, area_single_.node(s, i, 0));
                tilt_[size_t(s) * kD + size_t(i)] = float(r.axis_tilt);
                store_lobe(r.single, inv_point, &lobe_area_[(size_t(s) * kD + size_t(i)) * kB]);
            }
        });
    });
}

ScatteredIrradiance ImpulseIrradiance::point(const At& d, double cos) const {
    double v[2];
    point_.lookup<2, false>(d, 0.0, cos, v);
    return {v[0] * d.trend_point, v[1] * d.trend_point};
}

ScatteredIrradiance ImpulseIrradiance::directional(const At& d, double cos) const {
    double v[2];
    directional_.lookup<2, false>(d, 0.0, cos, v);
    return {v[0] * d.trend_directional, v[1] * d.trend_directional};
}

double ImpulseIrradiance::tilt(const At& d, double shift) const {
    if (!d.valid) return 0.0;
    const int i = d.i;
    const float fu = d.fu;
    const float w = std::clamp(float(shift), 0.0f, 1.0f) * (kS - 1);
    const int s0 = std::min(int(w), kS - 2);
    const float fs = w - float(s0);
    const float* a = &tilt_[size_t(s0) * kD + size_t(i)];
    const float* b = a + kD;
    const float lo = a[0] + fu * (a[1] - a[0]), hi = b[0] + fu * (b[1] - b[0]);
    return double(lo + fs * (hi - lo));
}

ScatteredIrradiance ImpulseIrradiance::area(const At& d, double shift, double cos_single,
                                            double cos_light) const {
    // Multiple scattering of an area emitter is the point emitter's at a quarter (see
    // impulse_query.h), about the light axis.
    double single[2], point[2];
    area_single_.lookup<1, true>(d, shift, cos_single, single);
    point_.lookup<2, false, 1>(d, 0.0, cos_light, point);
    return {single[0] * d.trend_point, 0.25 * point[1] * d.trend_point};
}

ImpulseIrradiance::Lobes ImpulseIrradiance::lobes(EmitterKind kind, const At& d,
                                                  double shift) const {
    Lobes out;
    if (!d.valid) return out;
    constexpr int kB = kProbeBands;
    const float fu = d.fu;
    auto lerp = [&](const float* a, size_t stride, int k) {
        return double(a[k] + fu * (a[stride + size_t(k)] - a[k]));
    };
    const bool directional = kind == EmitterKind::Directional;
    const std::vector<float>& pd = directional ? lobe_directional_ : lobe_point_;
    const float* row = &pd[size_t(d.i) * 2 * kB];
    const double trend = directional ? d.trend_directional : d.trend_point;
    for (int b = 0; b < kB; ++b) {
        out.single[b] = lerp(row, 2 * kB, b) * trend;
        out.multiple[b] = lerp(row, 2 * kB, kB + b) * trend;
    }
    if (kind != EmitterKind::Area) return out;
    // Area: single from the shifted tables, multiple the point emitter's at a quarter (area()).
    const float w = std::clamp(float(shift), 0.0f, 1.0f) * (kS - 1);
    const int s0 = std::min(int(w), kS - 2);
    const double fs = w - float(s0);
    const float* a0 = &lobe_area_[(size_t(s0) * kD + size_t(d.i)) * kB];
    const float* a1 = a0 + size_t(kD) * kB;
    for (int b = 0; b < kB; ++b) {
        out.single[b] = ((1.0 - fs) * lerp(a0, kB, b) + fs * lerp(a1, kB, b)) * d.trend_point;
        out.multiple[b] *= 0.25;
    }
    return out;
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
    // Most segments of a bake meet the medium they met last: no lock and no rounding then.
    thread_local struct {
        uint64_t owner = 0;
        double g = NAN, albedo = NAN;
        int last_bounce = -1;
        uint64_t key = 0;
        const ImpulseIrradiance* value = nullptr;
    } last;
    if (last.owner == id_ && last.g == g && last.albedo == albedo &&
        last.last_bounce == last_bounce && last.value)
        return last.value;
    const double gq = std::round(g * 65536.0) / 65536.0;
    const double cq = std::round(albedo * 65536.0) / 65536.0;
    const uint64_t key = (uint64_t(int64_t(gq * 65536.0) + 65536) << 32) |
                         (uint64_t(cq * 65536.0) << 8) | uint64_t(last_bounce & 0xff);
    if (last.owner == id_ && last.key == key && last.value) {
        last.g = g;
        last.albedo = albedo;
        return last.value;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = entries_.find(key);
    const ImpulseIrradiance* found = nullptr;
    if (it != entries_.end()) {
        found = it->second.get();
    } else if (entries_.size() < kMaxEntries) {
        std::shared_ptr<const ImpulseIrradiance> entry = shared(tables_, key, gq, cq, last_bounce);
        found = entries_.emplace(key, std::move(entry)).first->second.get();
    }
    if (found) last = {id_, g, albedo, last_bounce, key, found};
    return found;
}

double ImpulseIrradianceCache::blend_node_albedo(int k) {
    if (k >= kBlendAlbedoNodes - 1) return 1.0;
    return 1.0 - std::exp2(-double(k) * kBlendAlbedoStep);
}

double ImpulseIrradianceCache::blend_coordinate(double albedo) {
    const double v_max = double(kBlendAlbedoNodes - 1);
    // Between the second-last node and albedo 1 the coordinate is linear in the albedo.
    const double a_last = blend_node_albedo(kBlendAlbedoNodes - 2);
    if (albedo >= a_last) return v_max - 1.0 + (albedo - a_last) / (1.0 - a_last);
    return -std::log2(1.0 - std::max(albedo, 0.0)) / kBlendAlbedoStep;
}

double ImpulseIrradianceCache::blend_node_g(int k) {
    return std::clamp(1.0 - std::exp2(-double(k) * kBlendGStep), -kGRange, kGRange);
}

double ImpulseIrradianceCache::blend_g_coordinate(double g) {
    return -std::log2(1.0 - g) / kBlendGStep;
}

const ImpulseIrradiance* ImpulseIrradianceCache::node(int g_index, int albedo_index,
                                                      int last_bounce) const {
    const uint64_t key = (uint64_t(uint32_t(g_index + 1024)) << 24) |
                         (uint64_t(uint32_t(albedo_index)) << 8) | uint64_t(last_bounce & 0xff);
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = nodes_.find(key);
    if (it != nodes_.end()) return it->second.get();
    auto built = std::make_unique<const ImpulseIrradiance>(
        tables_, blend_node_g(g_index), blend_node_albedo(albedo_index), last_bounce);
    return nodes_.emplace(key, std::move(built)).first->second.get();
}

size_t ImpulseIrradianceCache::blend_nodes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return nodes_.size();
}

ImpulseIrradianceBlend ImpulseIrradianceCache::blend(double g, double albedo,
                                                     int last_bounce) const {
    // The cell: g nodes g0 < g1 (their positions clamped to the tables' range, where the end
    // cell is narrower: linear in the coordinate between the clamped nodes), albedo nodes k,
    // k + 1.
    const double u = blend_g_coordinate(std::clamp(g, -kGRange, kGRange));
    const int gi = int(std::floor(u));
    const double u0 = blend_g_coordinate(blend_node_g(gi));
    const double u1 = blend_g_coordinate(blend_node_g(gi + 1));
    const double fg = u1 > u0 ? std::clamp((u - u0) / (u1 - u0), 0.0, 1.0) : 0.0;
    const double v = blend_coordinate(std::clamp(albedo, 0.0, 1.0));
    const int ai = std::min(int(std::floor(v)), kBlendAlbedoNodes - 2);
    const double fa = std::clamp(v - ai, 0.0, 1.0);
    // The last cell's four tables per thread: consecutive mixture segments mostly share it.
    thread_local struct {
        uint64_t owner = 0;
        int gi = 0, ai = 0, last_bounce = -1;
        const ImpulseIrradiance* t[4] = {};
    } last;
    if (!(last.owner == id_ && last.gi == gi && last.ai == ai && last.last_bounce == last_bounce)) {
        for (int c = 0; c < 4; ++c) last.t[c] = node(gi + (c & 1), ai + (c >> 1), last_bounce);
        last.owner = id_;
        last.gi = gi;
        last.ai = ai;
        last.last_bounce = last_bounce;
    }
    ImpulseIrradianceBlend b;
    for (int c = 0; c < 4; ++c) {
        const double w = ((c & 1) ? fg : 1.0 - fg) * ((c >> 1) ? fa : 1.0 - fa);
        if (w == 0.0) continue;
        b.table[b.count] = last.t[c];
        b.weight[b.count] = w;
        ++b.count;
    }
    return b;
}

}  // namespace freqlab
