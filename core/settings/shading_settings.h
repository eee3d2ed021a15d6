// Settings of the direct-lighting integrators (the MIS baseline and the reference).
#pragma once

#include "settings/schema.h"

namespace freqlab {

struct MisSettings {
    int spp = 16;  // spherical samples per pixel, split evenly between environment and BRDF
    static const SettingsSchema& schema();
};

struct ReferenceSettings {
    int spp = 1024;
    bool use_cache = true;
    static const SettingsSchema& schema();
};

// Shared by every method that shades surfaces.
struct ShadingSettings {
    int mirror_depth = 4;       // perfect-mirror bounces followed (Whitted style)
    float ray_epsilon = 1e-4f;  // shadow-ray offset, relative to max(1, |p|)
    static const SettingsSchema& schema();
};

}  // namespace freqlab
