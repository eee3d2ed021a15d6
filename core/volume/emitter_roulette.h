// Per-emitter Russian roulette of method B's Monte Carlo terms (issue "Method B, part 4": the
// bake at production scale). The texel's terms through the real media (lit medium of occluded
// connections, single-scattering corrections), the walks' next-event estimation at scattering
// events and their light tracing from point lights visit every emitter of the scene: valley's
// 10 lights made one texel Monte Carlo run ~28 us and one vertex-field prepass path ~39 us,
// where a lone light near the vertex brings nearly all of the light. Each emitter is kept with
// a probability that follows its strength at the vertex and weighted by its inverse: the same
// expectation (roulette), about `budget` emitters instead of all of them.
//
//   keep_i = min(1, max(kEmitterKeepFloor, budget x s_i / sum_j s_j))
//
// s_i is the emitter's strength at the vertex without visibility or media (what a caller can
// know before paying for rays): I / d^2 for point and area samples, E for distant ones, and
// for a point light along a walk's segment the integral of I / r^2 over it. The floor bounds
// the weight of a faint emitter by 10 (its light may be the only light in a shadow).
//
// | parameter               | meaning                                                      |
// |-------------------------|--------------------------------------------------------------|
// | budget                  | bake.mc_emitter_budget (default 2); <= 0: every emitter kept |
// | kEmitterKeepFloor       | 0.1: the least chance of an emitter with any strength        |
// | strength 0 everywhere   | every emitter kept (nothing to rank by)                      |
#pragma once

#include <cstddef>
#include <vector>

#include "math/rng.h"

namespace freqlab {

constexpr float kEmitterKeepFloor = 0.1f;

// keep[i] for the strengths given (negative or NaN strengths count as 0). An emitter of
// strength 0 among stronger ones keeps the floor: its strength is a guess, not a bound.
void emitter_keep_probabilities(const std::vector<float>& strength, float budget,
                                std::vector<float>& keep);

// The roulette for one emitter: its weight, 1 / keep when kept, 0 when dropped. Draws one
// number only when keep < 1 (a kept-for-sure emitter leaves the stream as it was, so that
// scenes of one emitter bake exactly as without the roulette).
inline float emitter_roulette_weight(float keep, CounterRng& rng) {
    if (keep >= 1.0f) return 1.0f;
    return rng.next_float() < keep ? 1.0f / keep : 0.0f;
}

}  // namespace freqlab
