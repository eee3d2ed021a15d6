// atan2 for direction -> lat-long conversions, the hottest libm call of method A (profiled:
// atanf + atan2f were 12 % of a sparse frame on truck.json once the environment's table reads
// were prefetched). atan(a) = a P(a^2) on [0, 1] with an 8-term polynomial we fitted by
// iteratively reweighted least squares (Lawson) in double: max error 3.7e-8 rad, below a float
// ulp of pi, so texel lookups agree with std::atan2 except within rounding of a texel edge
// (tests/test_sampling.cpp).
#pragma once

#include <algorithm>
#include <cmath>

namespace freqlab {

inline float fast_atan2(float y, float x) {
    const float ax = std::fabs(x), ay = std::fabs(y);
    const float hi = std::max(ax, ay), lo = std::min(ax, ay);
    // Straight-line code (selects, no early return) so that loops calling it vectorize.
    const float a = hi > 0.0f ? lo / std::max(hi, 1e-38f) : 0.0f, s = a * a;
    float r = -0.004054550247309302f;
    r = r * s + 0.021862903755919413f;
    r = r * s - 0.05591226182732162f;
    r = r * s + 0.09642193829084508f;
    r = r * s - 0.1390862885842888f;
    r = r * s + 0.19946565712673095f;
    r = r * s - 0.3332986081863995f;
    r = r * s + 0.9999993356019522f;
    r *= a;
    r = ay > ax ? 1.57079632679489662f - r : r;
    r = x < 0.0f ? 3.14159265358979324f - r : r;
    return y < 0.0f ? -r : r;
}

}  // namespace freqlab
