// Settings of the direct-lighting integrators (the MIS baseline and the reference).
#pragma once

#include "settings/schema.h"

namespace freqlab {

struct MisSettings {
    int spp = 16;  // spherical samples per pixel, split evenly between environment and BRDF
    bool stratified = false;  // Owen-scrambled Sobol samples instead of independent ones
    static const SettingsSchema& schema();
};

struct ReferenceSettings {
    int spp = 1024;
    bool use_cache = true;
    // The reference cache's cap on disk: beyond it the least recently used files are removed.
    float cache_megabytes = 4096.0f;
    bool stratified = false;  // Owen-scrambled Sobol samples (benches that need a finer ruler)
    static const SettingsSchema& schema();
};

// Method A's adaptive radiance points (seed, Premier article §4, Eq. 4.3-4.5; §5.1).
struct PointsSettings {
    int max_samples = 256;  // N_max: the spherical sampling budget
    int min_samples = 8;    // N_L never falls below this (a constant environment has B_L = 0)
    int max_pilot = 64;     // nor rises above this: the rest of N_max is occlusion's (f_V)
    int stride = 1;         // a radiance point every `stride` pixels in x and y
    float large_distance = 10.0f;  // x the scene's bounding radius: t_min when nothing occludes
    bool reuse_pilot = false;      // the seed's reuse of the N_L pilot samples (biased, see .cpp)
    bool stratified = true;        // Owen-scrambled Sobol samples per strategy (math/sobol.h)
    static const SettingsSchema& schema();
};

// Shared by every method that shades surfaces.
struct ShadingSettings {
    int mirror_depth = 4;       // perfect-mirror bounces followed (Whitted style)
    float ray_epsilon = 1e-4f;  // shadow-ray offset relative to max(1, |p|); = kRayEpsilon
    static const SettingsSchema& schema();
};

}  // namespace freqlab
