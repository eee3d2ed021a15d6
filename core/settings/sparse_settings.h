// Settings of method A's sparse image-space sampling and reconstruction (seed, Premier article
// Algorithm 1, §5.1, §6, §7).
#pragma once

#include "settings/schema.h"

namespace freqlab {

struct SparseSettings {
    int initial_stride = 8;       // the uniform initial radiance points, every k-th pixel
    float f_max = 8.0f;           // maximum reconstruction radius (px); B_min = 1 / (2 f_max)
    float density_scale = 0.5f;   // multiplies B_S (cycles per pixel) before clamping (calibrated)
    float sigma_position = 2.0f;  // reconstruction: world distance, in pixel footprints
    float sigma_normal = 0.1f;    // |n_i - n_p|
    float sigma_mu_v = 0.15f;     // occlusion ratio
    float sigma_sigma_v = 0.25f;  // sigma_V (rad)
    bool plan_samples = true;     // adaptive points take N_Omega from the upsampled statistics
    static const SettingsSchema& schema();
};

}  // namespace freqlab
