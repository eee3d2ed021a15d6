#include "math/sobol.h"

namespace freqlab {

namespace {

uint32_t reverse_bits(uint32_t v) {
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
    return (v >> 16) | (v << 16);
}

// Each output bit flips depending only on the input bits below it (multiplications carry
// upwards only), which on the bit-reversed value is Owen's rule: a digit's flip depends on
// the digits before it.
uint32_t laine_karras_permutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

}  // namespace

uint32_t sobol_dimension0(uint32_t index) {
    return reverse_bits(index);
}

uint32_t sobol_dimension1(uint32_t index) {
    // Direction numbers v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1): the rows of Pascal's
    // triangle mod 2 (the primitive polynomial x + 1).
    uint32_t result = 0, v = 0x80000000u;
    for (; index; index >>= 1, v ^= v >> 1)
        if (index & 1u) result ^= v;
    return result;
}

uint32_t owen_scramble(uint32_t value, uint32_t seed) {
    return reverse_bits(laine_karras_permutation(reverse_bits(value), seed));
}

}  // namespace freqlab
