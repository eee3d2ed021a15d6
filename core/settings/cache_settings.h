// Settings of method A's object-space radiance cache (seed, Premier article §5.2, §5.3, §7).
#pragma once

#include "settings/schema.h"

namespace freqlab {

struct CacheSettings {
    // Quality thresholds: eps = acos(1 - q) (seed §5.2); the seed's values (§7).
    float q_eps_x = 1e-4f;               // spatial: r_x = 2 pi eps_x / B_x
    float q_eps_theta = 1e-4f;           // angular: r_theta = 2 pi eps_theta / B_theta
    float q_eps_t = 0.1f;                // temporal: lifespan 2 pi eps_t / B_t (calibrated)
    float occlusion_threshold = 0.125f;  // |occlusion ratio change| that discards (§5.3)
    float shading_change = 0.1f;  // observed relative change of the shading around it (temporal)
    // Ablation switches: each validity test can be turned off.
    bool test_spatial = true;
    bool test_angular = true;
    bool test_temporal = true;
    bool test_occlusion = true;
    bool merge = true;
    float depth_tolerance = 0.01f;  // z-buffer test: relative depth difference allowed
    float max_megabytes = 256.0f;   // memory cap: the oldest entries are evicted beyond it
    int checkpoint_every = 10;      // the workbench's checkpoints (render/frame_checkpoint.h)
    bool cold_start = false;        // comparison: every frame from an empty cache
    static const SettingsSchema& schema();
};

}  // namespace freqlab
