// Owen-scrambled 2D Sobol points: the stratified spherical samples of method A's radiance
// points (seed, Premier article §4: N_Omega = 4 B^2 is a sampling *rate* from Shannon's theorem,
// which presumes samples spread evenly over the footprint, not independent ones).
//
// | part        | choice                                                                  |
// |-------------|-------------------------------------------------------------------------|
// | sequence    | the first two Sobol dimensions, a (0,2)-sequence: every prefix of 2^m    |
// |             | points is a (0,m,2)-net (one point in each of the 2^m elementary boxes   |
// |             | of any shape 2^-a x 2^-(m-a)); dimension 0 is the van der Corput radical |
// |             | inverse, dimension 1 has the Pascal matrix mod 2 as generator            |
// | scrambling  | nested uniform (Owen) scrambling by a hash of the bits above each bit    |
// |             | (Laine-Karras form with Vegdahl's constants, as Burley 2020 describes),  |
// |             | an independent seed per dimension: each point is uniform on [0,1)^2, so  |
// |             | estimates stay unbiased, and the net property survives                   |
// | index       | not shuffled: a prefix of any length is the best-stratified subset,      |
// |             | which the adaptive count (N_L first, then f_V more) relies on            |
#pragma once

#include <cstdint>

#include "math/types.h"

namespace freqlab {

// The n-th point of the unscrambled sequence, as 32-bit fixed point per dimension.
uint32_t sobol_dimension0(uint32_t index);
uint32_t sobol_dimension1(uint32_t index);
// Owen scrambling of a 32-bit fixed-point coordinate (bit 31 is the first binary digit).
uint32_t owen_scramble(uint32_t value, uint32_t seed);

class ScrambledSobol2D {
  public:
    ScrambledSobol2D(uint32_t seed_x, uint32_t seed_y) : seed_x_(seed_x), seed_y_(seed_y) {}
    // In [0, 1)^2 with 24-bit floats (1 - 2^-24 the largest coordinate).
    vec2 at(uint32_t index) const {
        return vec2(float(owen_scramble(sobol_dimension0(index), seed_x_) >> 8) * 0x1p-24f,
                    float(owen_scramble(sobol_dimension1(index), seed_y_) >> 8) * 0x1p-24f);
    }

  private:
    uint32_t seed_x_, seed_y_;
};

}  // namespace freqlab
