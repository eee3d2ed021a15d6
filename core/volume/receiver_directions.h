// How a receiver's Monte Carlo terms draw the direction of their medium point
// (BakeEstimator::draw_medium_point): the cosine by default, a strategy shaped by what the term
// integrates where the cosine's variance is large (single_scatter_lobe.h, near_light_directions.h).
#pragma once

#include "math/types.h"

namespace freqlab {

class ReceiverDirections {
  public:
    virtual ~ReceiverDirections() = default;
    // A direction over the receiver's hemisphere and its weight cos / pdf (pi for the cosine);
    // false when the draw fell outside the hemisphere (weight 0: measure zero).
    virtual bool sample(float u1, float u2, vec3* w, double* weight) const = 0;
};

}  // namespace freqlab
