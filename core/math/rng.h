// Counter-based random numbers (DESIGN.md "Determinism"). A stream is keyed by
// (seed, frame, pixel, sample index); the n-th number of a stream is a pure hash of the key
// and n, so the value never depends on which thread asked or in what order.
//
// The hash is the SplitMix64 finaliser applied to a Weyl sequence of the key; it passes
// the uniformity test in tests/math/test_rng.cpp.
#pragma once

#include <cstdint>

namespace freqlab {

inline uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

class CounterRng {
  public:
    CounterRng(uint64_t seed, uint64_t frame, uint64_t pixel, uint64_t sample)
        : key_(mix64(mix64(mix64(mix64(seed) ^ frame) ^ pixel) ^ sample)) {}

    uint32_t next_u32() { return draw(++counter_); }
    // Uniform in [0, 1): 24 random bits, so 1 - 2^-24 is the largest value.
    float next_float() { return to_float(next_u32()); }
    double next_double() {
        const uint64_t hi = next_u32(), lo = next_u32();
        return double(((hi << 32) | lo) >> 11) * 0x1p-53;
    }
    // next_float() n times, in a loop the compiler vectorizes (the draws are independent).
    void fill_floats(float* out, int n) {
        const uint64_t base = counter_;
        for (int i = 0; i < n; ++i) out[i] = to_float(draw(base + uint64_t(i) + 1));
        counter_ += uint64_t(n);
    }
    uint64_t counter() const { return counter_; }

  private:
    // The stream's number at position `index` (1-based): counter-based, so any order works.
    uint32_t draw(uint64_t index) const {
        return uint32_t(mix64(key_ + 0x9e3779b97f4a7c15ULL * index) >> 32);
    }
    static float to_float(uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }
    uint64_t key_;
    uint64_t counter_ = 0;
};

}  // namespace freqlab
