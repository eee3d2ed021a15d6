// Value noise and its fractal sum (fBm): the procedural density of media (volume/media.cpp)
// and the height of terrain meshes (scene/mesh.cpp) share it.
//
// | parameter | meaning                                                  |
// |-----------|----------------------------------------------------------|
// | seed      | lattice hash seed; octave o uses seed + 7919 o           |
// | frequency | lattice cells per scene unit of the first octave         |
// | octaves   | octaves summed, each at twice the frequency, half weight |
#pragma once

#include <cstdint>

#include "math/types.h"

namespace freqlab {

// Value noise on the integer lattice (a hash of each corner), smoothstep-interpolated; in
// [0, 1).
double value_noise(uint32_t seed, const glm::dvec3& p);

// fBm normalised to [0, 1).
double fbm(uint32_t seed, double frequency, int octaves, const glm::dvec3& p);

}  // namespace freqlab
