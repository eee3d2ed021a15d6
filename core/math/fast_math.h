// Branch-free float sin/cos, log2/exp2 and pow for the direct-lighting integrator's sample
// loops (render/direct_lighting.cpp): libm calls stop the compiler from vectorizing a loop,
// and sincosf alone was 7.6 % of the MIS integrator's time on rotor.json (perf). Every
// function is straight-line code over floats and their bits, so a loop over arrays that calls
// them becomes SIMD code.
//
// | function          | domain                 | method                                | max error
// |
// |-------------------|------------------------|---------------------------------------|------------|
// | fast_sincos(x)    | |x| <= 400             | quadrant by round(2x/pi), Cody-Waite   | ~1 ulp |
// |                   |                        | reduction, Taylor to x^13 on pi/4      | | |
// fast_log2(x)      | normal x > 0           | exponent + 2 atanh((m-1)/(m+1)) series | ~2e-7 abs |
// |                   |                        | with m in [sqrt(1/2), sqrt(2))         | | |
// fast_exp2(y)      | any y (0 below -126)   | 2^round(y) by the exponent bits x      | ~2 ulp | |
// |                        | Taylor of e^(f ln 2), |f| <= 1/2       |            | | fast_pow(x, e)
// | x >= 0, e >= 0         | exp2(e log2 x); 0 when x <= 0          | ~e 2e-7 rel|
// (tests/test_fast_math.cpp checks the errors against libm over the domains.)
#pragma once

#include <cstdint>
#include <cstring>

namespace freqlab {

namespace fast_math_detail {
inline uint32_t bits(float x) {
    uint32_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
}
inline float from_bits(uint32_t b) {
    float x;
    std::memcpy(&x, &b, sizeof x);
    return x;
}
// Nearest integer as a float for |x| < 2^22, without a libm call (adding and removing 1.5 x
// 2^23 rounds to nearest in the default rounding mode).
inline float round_nearest(float x) {
    constexpr float kMagic = 12582912.0f;
    return (x + kMagic) - kMagic;
}
// c0 + x (c1 + x (c2 + ...)), by Horner's rule; coefficients from the constant term up.
inline float polynomial(float, float c0) {
    return c0;
}
template <class... Rest>
inline float polynomial(float x, float c0, float c1, Rest... rest) {
    return c0 + x * polynomial(x, c1, rest...);
}
}  // namespace fast_math_detail

inline void fast_sincos(float x, float* sin_out, float* cos_out) {
    using namespace fast_math_detail;
    const float q = round_nearest(x * 0.636619772367581343f);
    // pi/2 in three parts; the first two have 8 and 16 mantissa bits, so q * part is exact
    // for |q| < 256.
    const float r =
        ((x - q * 1.5703125f) - q * 4.83751296997070312e-4f) - q * 7.54978995489188216e-8f;
    const float r2 = r * r;
    // Taylor series to r^13 and r^12 (|r| <= pi/4).
    const float s = r + r * r2 *
                            polynomial(r2, -1.0f / 6.0f, 1.0f / 120.0f, -1.0f / 5040.0f,
                                       1.0f / 362880.0f, -1.0f / 39916800.0f, 1.0f / 6227020800.0f);
    const float c = 1.0f + r2 * polynomial(r2, -0.5f, 1.0f / 24.0f, -1.0f / 720.0f, 1.0f / 40320.0f,
                                           -1.0f / 3628800.0f, 1.0f / 479001600.0f);
    const int quadrant = int(q) & 3;
    const bool swap = (quadrant & 1) != 0;
    const float sv = swap ? c : s, cv = swap ? s : c;
    *sin_out = (quadrant & 2) ? -sv : sv;
    *cos_out = ((quadrant + 1) & 2) ? -cv : cv;
}

inline float fast_log2(float x) {
    using namespace fast_math_detail;
    const uint32_t b = bits(x);
    float e = float(int((b >> 23) & 255u) - 127);
    float m = from_bits((b & 0x007fffffu) | 0x3f800000u);  // [1, 2)
    const bool fold = m > 1.41421356237f;
    m = fold ? 0.5f * m : m;
    e = fold ? e + 1.0f : e;
    const float t = (m - 1.0f) / (m + 1.0f), t2 = t * t;  // |t| <= 0.1716
    // ln m = 2 atanh t = 2 (t + t^3/3 + t^5/5 + ...)
    const float p = polynomial(t2, 2.0f, 2.0f / 3.0f, 2.0f / 5.0f, 2.0f / 7.0f, 2.0f / 9.0f,
                               2.0f / 11.0f, 2.0f / 13.0f);
    return e + t * p * 1.44269504088896341f;  // ln m / ln 2
}

inline float fast_exp2(float y) {
    using namespace fast_math_detail;
    const bool underflow = y < -126.0f;
    const float yc = y > 127.0f ? 127.0f : (underflow ? -126.0f : y);
    const float n = round_nearest(yc), f = (yc - n) * 0.693147180559945309f;  // |f| <= ln2/2
    const float p = polynomial(f, 1.0f, 1.0f, 0.5f, 1.0f / 6.0f, 1.0f / 24.0f, 1.0f / 120.0f,
                               1.0f / 720.0f, 1.0f / 5040.0f, 1.0f / 40320.0f);  // e^f
    const float scale = from_bits(uint32_t(int(n) + 127) << 23);
    return underflow ? 0.0f : p * scale;
}

inline float fast_exp(float x) {
    return fast_exp2(x * 1.44269504088896341f);
}

inline float fast_pow(float x, float e) {
    const float safe = x > 1e-30f ? x : 1.0f;
    const float r = fast_exp2(e * fast_log2(safe));
    return x > 1e-30f ? r : (e == 0.0f ? 1.0f : 0.0f);
}

}  // namespace freqlab
