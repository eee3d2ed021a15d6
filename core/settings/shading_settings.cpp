#include "settings/shading_settings.h"

namespace freqlab {

const SettingsSchema& MisSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<MisSettings>("mis", "MIS baseline")
            .field(&MisSettings::spp, "spp", 1, 1 << 20, "samples/px", kInvalidatesShading,
                   "Spherical samples per pixel, half drawn from the environment's pdf and half "
                   "from the BRDF's, combined with the power heuristic (seed Premier §4, §7). "
                   "An odd count gives the environment the extra sample.")
            .build();
    return s;
}

const SettingsSchema& ReferenceSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<ReferenceSettings>("reference", "Reference")
            .field(&ReferenceSettings::spp, "spp", 1, 1 << 24, "samples/px", kInvalidatesShading,
                   "Samples per pixel of the converged reference (same estimator as mis).")
            .field(&ReferenceSettings::use_cache, "use_cache", 0, 1, "", kInvalidatesNothing,
                   "Reuse a reference rendered before with the same scene text and settings "
                   "(cached under $FREQLAB_CACHE_DIR, default ~/.cache/freqlab).")
            .build();
    return s;
}

const SettingsSchema& ShadingSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<ShadingSettings>("shading", "Shading")
            .field(&ShadingSettings::mirror_depth, "mirror_depth", 0, 64, "bounces",
                   kInvalidatesShading,
                   "Perfect-mirror reflections followed before giving up (black).")
            .field(&ShadingSettings::ray_epsilon, "ray_epsilon", 1e-7, 1e-1, "",
                   kInvalidatesShading,
                   "Offset of shadow and reflection rays along the geometric normal, relative to "
                   "max(1, |p|): avoids self-intersection.")
            .build();
    return s;
}

}  // namespace freqlab
