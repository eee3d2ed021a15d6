#include "math/noise.h"

#include "math/rng.h"

namespace freqlab {

namespace {

double lattice(uint32_t seed, int x, int y, int z) {
    const uint64_t h =
        mix64(uint64_t(seed) * 0x9E3779B97F4A7C15ULL ^ (uint64_t(uint32_t(x)) << 42) ^
              (uint64_t(uint32_t(y)) << 21) ^ uint64_t(uint32_t(z)));
    return double(h >> 11) * 0x1p-53;
}

}  // namespace

double value_noise(uint32_t seed, const glm::dvec3& p) {
    const glm::dvec3 f = glm::floor(p);
    const glm::dvec3 t = p - f;
    const glm::dvec3 s = t * t * (3.0 - 2.0 * t);
    const int x = int(f.x), y = int(f.y), z = int(f.z);
    double c[2][2][2];
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k) c[i][j][k] = lattice(seed, x + i, y + j, z + k);
    auto lerp = [](double a, double b, double w) { return a + (b - a) * w; };
    return lerp(lerp(lerp(c[0][0][0], c[1][0][0], s.x), lerp(c[0][1][0], c[1][1][0], s.x), s.y),
                lerp(lerp(c[0][0][1], c[1][0][1], s.x), lerp(c[0][1][1], c[1][1][1], s.x), s.y),
                s.z);
}

double fbm(uint32_t seed, double frequency, int octaves, const glm::dvec3& p) {
    double sum = 0.0, amplitude = 1.0, norm = 0.0, freq = frequency;
    for (int o = 0; o < octaves; ++o) {
        sum += amplitude * value_noise(seed + uint32_t(o) * 7919u, p * freq);
        norm += amplitude;
        amplitude *= 0.5;
        freq *= 2.0;
    }
    return sum / norm;
}

}  // namespace freqlab
