// Method A's cache validity decisions (seed, Premier article §5.2 "Validating Reprojected Cache
// Points", "Cache Point Discard and Merging", §5.3 lifespan and the 0.125 occlusion rule).
// Every cached radiance point gets exactly one decision per frame; the values each test
// compared are kept so that the workbench can say why.
//
// | test      | discards when (first failing test in this order wins)                       |
// |-----------|-----------------------------------------------------------------------------|
// | frustum   | the point, moved with its object, projects behind the camera or off screen   |
// | zbuffer   | the pixel it lands on sees another object, nothing, or a depth differing by  |
// |           | more than cache.depth_tolerance (relative) + the pixel's footprint           |
// | spatial   | |x_now - x_created| > r_x = 2 pi eps_x / B_x, eps = acos(1 - q) (world;      |
// |           | mirrors: the point their pixel reflects now against the one reflected then)  |
// | angular   | angle(view now, view at creation; object space) > r_theta = 2 pi eps_th / B_th|
// | temporal  | age > lifespan 2 pi eps_t / B_t (B_t = 0: infinite), or the observed change: |
// |           | the initial points' upsampled shading at its pixel changed by more than      |
// |           | cache.shading_change (relative) since it was computed                        |
// | occlusion | |occlusion ratio at the pixel now - at creation| > 0.125 (both upsampled)    |
//
// Reading taken where §5.2 is terse: the spatial test compares where the entry is now (moved
// with its object) with the world position it was computed at, i.e. how far a point of a
// moving object has travelled through the static world's lighting and shadows. A reused entry
// keeps its own position as its reconstruction feature, so landing off a pixel centre under
// camera motion is no error (a first reading, testing that snap against r_x, discarded 93 %
// of truck.json's entries each frame of its camera orbit at 160 x 90).
// B_t only sees occluders that occlude the pilot already: a point lit when computed never
// expires when a moving shadow reaches it, and the occlusion ratio (BRDF-weighted) hardly moves
// when a thin occluder crosses the bright part of the sky. The initial points are shaded anew
// every frame of a moving scene (Algorithm 1); the change of their upsampled shading at the
// entry's pixel is the evidence the temporal test adds. Measured on rotor.json at 640 x 360,
// 60 frames, without it: RMSE in the swept region grew from 0.027 (frame 0) to 0.090 (frame 50).
// The occlusion test compares like with like: the upsampled occlusion ratio at the entry's
// pixel now against the upsampled one at its pixel when it was computed. The literal reading
// (the entry's own ratio against the pixel's upsampled one) discards every adaptive point on a
// static shadow edge each frame, its own ratio being sharp and the upsampled one blurred by the
// stride-k grid: measured 7 % of all entries per frame on rotor.json with nothing moving.
#pragma once

#include <string>
#include <vector>

#include "math/types.h"
#include "settings/cache_settings.h"

namespace freqlab {

enum class CacheDecision : int {
    Reused = 0,
    Merged,
    DiscardZbuffer,
    DiscardFrustum,
    DiscardSpatial,
    DiscardAngular,
    DiscardTemporal,
    DiscardOcclusion,
};
constexpr int kCacheDecisionCount = 8;

const char* to_string(CacheDecision d);  // "reused", "merged", "discard_zbuffer", ...
bool is_discard(CacheDecision d);
// The seed's Fig. 12(a) palette: spatial blue, angular red, temporal orange, occlusion purple;
// reused white (the seed's black on white, turned for a dark viewer); z-buffer grey, frustum
// teal, merged green.
vec3 decision_colour(CacheDecision d);

double validity_epsilon(double q);                   // acos(1 - q)
double validity_radius(double q, double bandwidth);  // 2 pi eps / B; +inf when B <= 0

// What the tests compared for one entry at one frame.
struct CacheTestValues {
    bool in_frustum = false;
    int px = -1, py = -1;                     // the pixel it lands on
    int surface_object = -1;                  // seen at that pixel (-1: background)
    double depth = 0.0, surface_depth = 0.0;  // camera distances: entry, surface
    double depth_slack = 0.0;                 // allowed |depth - surface_depth|
    int reflected_object = -1;                // mirrors: what the pixel's reflection sees now
    double spatial_distance = 0.0, r_x = 0.0;
    double angular_distance = 0.0, r_theta = 0.0;         // rad
    double age = 0.0, lifespan = 0.0;                     // s
    double occlusion_entry = 0.0, occlusion_pixel = 0.0;  // upsampled: at creation, now
    bool occlusion_tested = false;
    double shading_then = 0.0, shading_now = 0.0;  // upsampled log luminance: at creation, now
    bool shading_tested = false;
    // Visibility towards the key lights (bit per light): at creation, now.
    int key_lights_then = 0, key_lights_now = 0;
    bool key_lights_tested = false;
};

// Every test but the occlusion one (it needs this frame's statistics at the pixel).
CacheDecision decide_geometric(const CacheTestValues& v, int entry_object,
                               const CacheSettings& settings);
// The tests against this frame's upsampled statistics, on an entry the others kept: the
// observed half of the temporal test, then the occlusion test.
CacheDecision decide_observed(const CacheTestValues& v, const CacheSettings& settings);
// The key-light half of the temporal test: a shadow came or went between the entry and a key
// light (render/key_lights.h) since it was computed.
CacheDecision decide_key_lights(const CacheTestValues& v, const CacheSettings& settings);

// One sentence per test ("angular: view moved 2.3° outside a 1.1° cone").
std::vector<std::string> explain(const CacheTestValues& v, int entry_object,
                                 const CacheSettings& settings);

}  // namespace freqlab
