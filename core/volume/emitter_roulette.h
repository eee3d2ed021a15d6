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
//
// The point lights' own strategies (light tracing towards surfaces they light, their light
// along a walk's segments) compete with the distant lights as well: the directional lights'
// irradiance and the environment's (a quarter of its radiance integrated over the sphere: a
// plane's irradiance under a uniform sky of that power), D below, appended to the point lights'
// strengths (times the segment's length along a segment). Valley's six lamps 4 above the ground
// under a sun of irradiance 2.8: a walk's light tracing ran for about two of them at every
// scattering event, ~1 s of a 33 s bake, and bringing nothing the walk's own landings did not
// (bake.surface_light_mis=0 read relMSE 1.54 / 1.86 / 1.59 against 1.63 / 1.89 / 1.60). D is read
// when the estimator is built: a sky changed since only moves the roulette's odds, never its
// mean.
#pragma once

#include <cstddef>
#include <vector>

#include "math/rng.h"

namespace freqlab {

class EnvironmentMap;
struct Light;

constexpr float kEmitterKeepFloor = 0.1f;

// keep[i] for the strengths given (negative or NaN strengths count as 0). An emitter of
// strength 0 among stronger ones keeps the floor: its strength is a guess, not a bound.
void emitter_keep_probabilities(const std::vector<float>& strength, float budget,
                                std::vector<float>& keep);

// D: the luminance of the directional lights' irradiance plus a quarter of the environment's
// radiance integrated over the sphere (by 1024 fixed samples of its importance sampling: the
// same D on every run).
float distant_light_strength(const std::vector<Light>& lights, const EnvironmentMap* environment);

// The roulette for one emitter: its weight, 1 / keep when kept, 0 when dropped. Draws one
// number only when keep < 1 (a kept-for-sure emitter leaves the stream as it was, so that
// scenes of one emitter bake exactly as without the roulette).
inline float emitter_roulette_weight(float keep, CounterRng& rng) {
    if (keep >= 1.0f) return 1.0f;
    return rng.next_float() < keep ? 1.0f / keep : 0.0f;
}

}  // namespace freqlab
