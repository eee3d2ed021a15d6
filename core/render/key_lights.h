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

struct KeyLight {
    bool distant = true;  // a direction (sun, directional light), else a position
    vec3 direction{0.0f, 0.0f, 1.0f};
    vec3 position{0.0f};
};

// The key lights at rs.time() (a spinning environment turns its sun). The sun counts when its
// texel is 20 x brighter than the map's mean: a soft sky casts no shadow to track.
std::vector<KeyLight> key_lights(const RayScene& rs);
// Bit k set: key light k is unoccluded from p (offset along n against self-intersection).
uint8_t key_light_mask(const RayScene& rs, const std::vector<KeyLight>& keys, const vec3& p,
                       const vec3& n);

}  // namespace freqlab
