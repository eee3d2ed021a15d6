#include "settings/sparse_settings.h"

namespace freqlab {

const SettingsSchema& SparseSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<SparseSettings>("sparse", "Sparse sampling")
            .field(&SparseSettings::initial_stride, "initial_stride", 2, 64, "px",
                   kInvalidatesShading,
                   "Initial uniform radiance points every k-th pixel: they gather the visibility "
                   "statistics the density is computed from (Algorithm 1, first step).")
            .field(&SparseSettings::f_max, "f_max", 1, 64, "px", kInvalidatesShading,
                   "Largest reconstruction radius; the smallest density is B_min = 1 / (2 f_max) "
                   "(seed §7, f_max = 8).")
            .field(&SparseSettings::density_scale, "density_scale", 0.01, 100, "",
                   kInvalidatesShading,
                   "Multiplies the screen-space bandwidth (cycles per pixel) before it is clamped "
                   "to [B_min, 1] as the sampling density. 0.5 by default: at 1280x720 it shades "
                   "24-30 % of rotor/truck with RMSE half that of points at every pixel.")
            .field(&SparseSettings::sigma_position, "sigma_position", 0.01, 100, "px footprints",
                   kInvalidatesShading,
                   "Cross-bilateral sigma of the world-space distance, in units of the pixel's "
                   "footprint on the surface (Eq. 6.2, feature p).")
            .field(&SparseSettings::sigma_normal, "sigma_normal", 0.001, 10, "",
                   kInvalidatesShading,
                   "Cross-bilateral sigma of |n_i - n_p| (Eq. 6.2, feature n).")
            .field(&SparseSettings::sigma_mu_v, "sigma_mu_v", 0.001, 10, "", kInvalidatesShading,
                   "Cross-bilateral sigma of the occlusion ratio (Eq. 6.2, feature mu_v).")
            .field(&SparseSettings::sigma_sigma_v, "sigma_sigma_v", 0.001, 10, "rad",
                   kInvalidatesShading,
                   "Cross-bilateral sigma of sigma_V (Eq. 6.2, feature sigma_v).")
            .field(&SparseSettings::plan_samples, "plan_samples", 0, 1, "", kInvalidatesShading,
                   "Adaptive points take their sample count N_Omega from the upsampled "
                   "visibility statistics instead of a pilot of their own: the N_L pilot rays are "
                   "saved and, the count coming from other pixels, the estimate stays unbiased. "
                   "Their own statistics come from their estimate's first N_L samples.")
            .build();
    return s;
}

}  // namespace freqlab
