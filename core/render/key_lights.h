// Key lights for method A's cache (issue "Method A, part 3"; our reading of the seed's
// temporal test, §5.3): B_t sees only the occluders a radiance point saw when it was computed,
// so a point that was lit when computed never expires when a moving shadow reaches it (the
// seed's Fig. 14 failure in reverse). Each entry therefore records whether it saw the scene's
// key lights — the environment's sun (its brightest texel, when it stands out of the sky) and
// point / directional lights, at most three — and the temporal test discards it once that
// visibility changes. One shadow ray per key light per entry and frame, only when something
// moves.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/ray_scene.h"

namespace freqlab {

// A key light is a point or directional light (the environment's sun becomes a directional
// one): its visibility is sample_light's, like every other light's.
using KeyLight = Light;

// The key lights at rs.time() (a spinning environment turns its sun). The sun counts when its
// texel is 20 x brighter than the map's mean: a soft sky casts no shadow to track.
std::vector<KeyLight> key_lights(const RayScene& rs);
// Bit k set: key light k is unoccluded from p (offset along n against self-intersection).
uint8_t key_light_mask(const RayScene& rs, const std::vector<KeyLight>& keys, const vec3& p,
                       const vec3& n);

}  // namespace freqlab
