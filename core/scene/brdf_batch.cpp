#include "scene/brdf_batch.h"

#include <algorithm>
#include <cmath>

#include "math/fast_math.h"

namespace freqlab {

namespace {

// Every term is computed for every lane and the invalid ones are selected away afterwards:
// no branch, no early return, so the loops below vectorize. Divisions by zero in lanes that
// are discarded are harmless (no FP traps are enabled).

struct LocalValue {
    float value, pdf;
};

inline LocalValue lambert(const BrdfBatch::Lobe&, float, float, float z) {
    const bool up = z > 0.0f;
    return {up ? kInvPi : 0.0f, up ? z * kInvPi : 0.0f};
}

inline LocalValue phong(const BrdfBatch::Lobe& l, float x, float y, float z) {
    const float c = -l.wo.x * x - l.wo.y * y + l.wo.z * z;
    const float lobe = fast_pow(std::max(c, 0.0f), l.exponent);
    const bool facing = c > 0.0f;
    return {facing && z > 0.0f ? (l.exponent + 2.0f) * (1.0f / kTwoPi) * lobe : 0.0f,
            facing ? (l.exponent + 1.0f) * (1.0f / kTwoPi) * lobe : 0.0f};
}

inline float beckmann_d(float cos_h, float a2) {
    const float c2 = cos_h * cos_h, tan2 = (1.0f - c2) / c2;
    const float d = fast_exp(-tan2 / a2) / (kPi * a2 * c2 * c2);
    return cos_h > 0.0f ? d : 0.0f;
}
inline float ggx_d(float cos_h, float a2) {
    const float c2 = cos_h * cos_h, tan2 = (1.0f - c2) / c2, k = a2 + tan2;
    const float d = a2 / (kPi * c2 * c2 * k * k);
    return cos_h > 0.0f ? d : 0.0f;
}
inline float beckmann_g1(float cos_v, float alpha) {
    const float tan_v = std::sqrt(std::max(0.0f, 1.0f - cos_v * cos_v)) / cos_v;
    const float a = tan_v > 0.0f ? 1.0f / (alpha * tan_v) : 2.0f;
    const float g =
        a >= 1.6f ? 1.0f : (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
    return cos_v > 0.0f ? g : 0.0f;
}
inline float ggx_g1(float cos_v, float alpha2) {
    const float tan2 = (1.0f - cos_v * cos_v) / (cos_v * cos_v);
    const float g = 2.0f / (1.0f + std::sqrt(1.0f + alpha2 * tan2));
    return cos_v > 0.0f ? g : 0.0f;
}

template <bool Ggx>
inline LocalValue microfacet(const BrdfBatch::Lobe& l, float x, float y, float z) {
    const float hx = l.wo.x + x, hy = l.wo.y + y, hz = l.wo.z + z;
    const float len = std::sqrt(hx * hx + hy * hy + hz * hz);
    const float inv = 1.0f / len;
    const float cos_h = hz * inv, wo_h = (l.wo.x * hx + l.wo.y * hy + l.wo.z * hz) * inv;
    const float d = Ggx ? ggx_d(cos_h, l.alpha2) : beckmann_d(cos_h, l.alpha2);
    const float g1 = Ggx ? ggx_g1(z, l.alpha2) : beckmann_g1(z, l.alpha);
    const float value = d * l.g1_wo * g1 / (4.0f * l.wo.z * z);
    const float pdf = d * cos_h / (4.0f * wo_h);
    return {z > 0.0f ? value : 0.0f, len >= 1e-7f && wo_h > 0.0f ? pdf : 0.0f};
}

template <LocalValue (*Model)(const BrdfBatch::Lobe&, float, float, float)>
void eval_loop(const BrdfBatch::Lobe& l, const Frame& f, int n, const float* __restrict x,
               const float* __restrict y, const float* __restrict z, float* __restrict value,
               float* __restrict pdf) {
    for (int i = 0; i < n; ++i) {
        const float lx = x[i] * f.t.x + y[i] * f.t.y + z[i] * f.t.z;
        const float ly = x[i] * f.b.x + y[i] * f.b.y + z[i] * f.b.z;
        const float lz = x[i] * f.n.x + y[i] * f.n.y + z[i] * f.n.z;
        const LocalValue v = Model(l, lx, ly, lz);
        value[i] = v.value;
        pdf[i] = v.pdf;
    }
}

// Local sample directions of each model from (u1, u2).
struct LocalDirection {
    float x, y, z;
};

inline LocalDirection sample_lambert(const BrdfBatch::Lobe&, float u1, float u2) {
    float s, c;
    fast_sincos(kTwoPi * u2, &s, &c);
    const float r = std::sqrt(u1);
    return {r * c, r * s, std::sqrt(std::max(0.0f, 1.0f - u1))};
}

inline LocalDirection sample_phong(const BrdfBatch::Lobe& l, float u1, float u2) {
    float s, c;
    fast_sincos(kTwoPi * u2, &s, &c);
    const float cos_a = fast_pow(u1, 1.0f / (l.exponent + 1.0f));
    const float sin_a = std::sqrt(std::max(0.0f, 1.0f - cos_a * cos_a));
    const Frame& f = l.phong_frame;
    const float vx = sin_a * c, vy = sin_a * s;
    return {vx * f.t.x + vy * f.b.x + cos_a * f.n.x, vx * f.t.y + vy * f.b.y + cos_a * f.n.y,
            vx * f.t.z + vy * f.b.z + cos_a * f.n.z};
}

template <bool Ggx>
inline LocalDirection sample_microfacet(const BrdfBatch::Lobe& l, float u1, float u2) {
    float s, c;
    fast_sincos(kTwoPi * u2, &s, &c);
    const float rest = std::max(1.0f - u1, 1e-12f);
    const float tan2 =
        Ggx ? l.alpha2 * u1 / rest : -l.alpha2 * fast_log2(rest) * 0.693147180559945309f;
    const float cos_h = 1.0f / std::sqrt(1.0f + tan2);
    const float sin_h = std::sqrt(std::max(0.0f, 1.0f - cos_h * cos_h));
    const float hx = sin_h * c, hy = sin_h * s;
    const float two_dot = 2.0f * (l.wo.x * hx + l.wo.y * hy + l.wo.z * cos_h);
    return {two_dot * hx - l.wo.x, two_dot * hy - l.wo.y, two_dot * cos_h - l.wo.z};
}

template <LocalDirection (*Sample)(const BrdfBatch::Lobe&, float, float),
          LocalValue (*Model)(const BrdfBatch::Lobe&, float, float, float)>
void sample_loop(const BrdfBatch::Lobe& l, const Frame& f, int n, const float* __restrict u1,
                 const float* __restrict u2, float* __restrict x, float* __restrict y,
                 float* __restrict z, float* __restrict value, float* __restrict pdf) {
    for (int i = 0; i < n; ++i) {
        const LocalDirection d = Sample(l, u1[i], u2[i]);
        const LocalValue v = Model(l, d.x, d.y, d.z);
        x[i] = d.x * f.t.x + d.y * f.b.x + d.z * f.n.x;
        y[i] = d.x * f.t.y + d.y * f.b.y + d.z * f.n.y;
        z[i] = d.x * f.t.z + d.y * f.b.z + d.z * f.n.z;
        value[i] = v.value;
        pdf[i] = v.pdf;
    }
}

}  // namespace

BrdfBatch::BrdfBatch(const Brdf& brdf, const vec3& wo_world) : frame_(brdf.frame()) {
    Lobe& l = lobe_;
    l.type = brdf.type();
    l.wo = frame_.to_local(wo_world);
    l.exponent = brdf.phong_exponent();
    l.alpha = brdf.roughness();
    l.alpha2 = l.alpha * l.alpha;
    l.valid = l.wo.z > 0.0f && l.type != BrdfType::Mirror;
    // Only what the model reads (this runs once per shaded point).
    if (l.type == BrdfType::Ggx) l.g1_wo = ggx_g1(l.wo.z, l.alpha2);
    if (l.type == BrdfType::Beckmann) l.g1_wo = beckmann_g1(l.wo.z, l.alpha);
    if (l.type == BrdfType::Phong) l.phong_frame = Frame(vec3(-l.wo.x, -l.wo.y, l.wo.z));
}

void BrdfBatch::eval(int n, const float* x, const float* y, const float* z, float* value,
                     float* pdf) const {
    if (!lobe_.valid) {
        std::fill(value, value + n, 0.0f);
        std::fill(pdf, pdf + n, 0.0f);
        return;
    }
    switch (lobe_.type) {
        case BrdfType::Lambert:
            return eval_loop<lambert>(lobe_, frame_, n, x, y, z, value, pdf);
        case BrdfType::Phong:
            return eval_loop<phong>(lobe_, frame_, n, x, y, z, value, pdf);
        case BrdfType::Beckmann:
            return eval_loop<microfacet<false>>(lobe_, frame_, n, x, y, z, value, pdf);
        case BrdfType::Ggx:
            return eval_loop<microfacet<true>>(lobe_, frame_, n, x, y, z, value, pdf);
        case BrdfType::Mirror:
            break;
    }
}

void BrdfBatch::sample(int n, const float* u1, const float* u2, float* x, float* y, float* z,
                       float* value, float* pdf) const {
    if (!lobe_.valid) {
        std::fill(x, x + n, 0.0f);
        std::fill(y, y + n, 0.0f);
        std::fill(z, z + n, 0.0f);
        std::fill(value, value + n, 0.0f);
        std::fill(pdf, pdf + n, 0.0f);
        return;
    }
    switch (lobe_.type) {
        case BrdfType::Lambert:
            return sample_loop<sample_lambert, lambert>(lobe_, frame_, n, u1, u2, x, y, z, value,
                                                        pdf);
        case BrdfType::Phong:
            return sample_loop<sample_phong, phong>(lobe_, frame_, n, u1, u2, x, y, z, value, pdf);
        case BrdfType::Beckmann:
            return sample_loop<sample_microfacet<false>, microfacet<false>>(
                lobe_, frame_, n, u1, u2, x, y, z, value, pdf);
        case BrdfType::Ggx:
            return sample_loop<sample_microfacet<true>, microfacet<true>>(lobe_, frame_, n, u1, u2,
                                                                          x, y, z, value, pdf);
        case BrdfType::Mirror:
            break;
    }
}

}  // namespace freqlab
