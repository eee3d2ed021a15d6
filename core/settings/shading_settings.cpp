#include "settings/shading_settings.h"

namespace freqlab {

const SettingsSchema& MisSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<MisSettings>("mis", "MIS baseline")
            .field(&MisSettings::spp, "spp", 1, 1 << 20, "samples/px", kInvalidatesShading,
                   "Spherical samples per pixel, half drawn from the environment's pdf and half "
                   "from the BRDF's, combined with the power heuristic (seed Premier §4, §7). "
                   "An odd count gives the environment the extra sample.")
            .field(&MisSettings::stratified, "stratified", 0, 1, "", kInvalidatesShading,
                   "Draw each strategy's samples from an Owen-scrambled Sobol sequence (the "
                   "environment by CDF inversion) instead of independently. Off by default: the "
                   "baseline is plain MIS, the estimator the reference converges.")
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
            .field(&ReferenceSettings::cache_megabytes, "cache_megabytes", 0.01, 1 << 20, "MB",
                   kInvalidatesNothing,
                   "The reference cache's size on disk: after each store, the least recently "
                   "used references are removed until the folder fits (a reference larger "
                   "than the cap is not kept).")
            .field(&ReferenceSettings::stratified, "stratified", 0, 1, "", kInvalidatesShading,
                   "Owen-scrambled Sobol samples: the same unbiased estimate with far less "
                   "noise where the integrand is smooth. Off by default (the reference is plain "
                   "MIS); `bench --study points` turns it on to measure errors below what a "
                   "1024-spp independent reference resolves.")
            .build();
    return s;
}

const SettingsSchema& PointsSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<PointsSettings>("points", "Radiance points")
            .field(&PointsSettings::max_samples, "max_samples", 2, 1 << 16, "samples",
                   kInvalidatesShading,
                   "N_max: the spherical sampling budget of one radiance point; occlusion adds up "
                   "to N_max - N_L samples (seed Eq. 4.3, f_V).")
            .field(&PointsSettings::min_samples, "min_samples", 2, 1 << 16, "samples",
                   kInvalidatesShading,
                   "Lower bound of N_L = 4 B^2: a smooth environment still needs samples to "
                   "find occluders.")
            .field(&PointsSettings::max_pilot, "max_pilot", 2, 1 << 16, "samples",
                   kInvalidatesShading,
                   "Upper bound of N_L = 4 B^2. Real HDR maps have sharp lights: their 95th-"
                   "percentile bandwidth asks for thousands of samples, which would leave no "
                   "budget for f_V's occlusion samples (seed Eq. 4.3).")
            .field(&PointsSettings::stride, "stride", 1, 64, "px", kInvalidatesShading,
                   "A radiance point every k-th pixel in x and y; the k x k block shows it.")
            .field(&PointsSettings::large_distance, "large_distance", 0.01, 1e6, "x scene radius",
                   kInvalidatesShading,
                   "Occluder distance assumed when no pilot sample is occluded, in units of the "
                   "scene's bounding radius (the transport operator's t_min).")
            .field(&PointsSettings::reuse_pilot, "reuse_pilot", 0, 1, "", kInvalidatesShading,
                   "Average the N_L pilot samples into the estimate as the seed does. The "
                   "sample count then depends on the samples it averages, which biases the "
                   "estimate; off, the pilot only decides and N_Omega fresh samples estimate.")
            .field(&PointsSettings::stratified, "stratified", 0, 1, "", kInvalidatesShading,
                   "Draw each strategy's samples from an Owen-scrambled Sobol sequence (the "
                   "environment by CDF inversion): N_Omega = 4 B^2 is a sampling rate, which "
                   "stratified samples honour and independent ones only on average. Each point "
                   "stays uniform, so the estimate stays unbiased.")
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
