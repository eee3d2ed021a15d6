#include "settings/cache_settings.h"

namespace freqlab {

const SettingsSchema& CacheSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<CacheSettings>("cache", "Radiance cache")
            .field(&CacheSettings::q_eps_x, "q_eps_x", 1e-9, 1, "", kInvalidatesCache,
                   "Spatial quality threshold: a cached point stays valid within r_x = 2 pi "
                   "acos(1 - q) / B_x of where it was computed (seed §5.2; 1e-4 in §7).")
            .field(&CacheSettings::q_eps_theta, "q_eps_theta", 1e-9, 1, "", kInvalidatesCache,
                   "Angular quality threshold: the view may move r_theta = 2 pi acos(1 - q) / "
                   "B_theta away from the view it was computed for (seed §5.2; 1e-4 in §7).")
            .field(&CacheSettings::q_eps_t, "q_eps_t", 1e-12, 1, "", kInvalidatesCache,
                   "Temporal quality threshold: lifespan 2 pi acos(1 - q) / B_t (seed §5.2-5.3). "
                   "The seed's 1e-7 (§7) gives ~1e-4 s wherever a moving occluder shows (B_t = "
                   "|v| B_L with the sun's B_L), so every such point expires each frame; 0.1 "
                   "keeps them ~0.1 s and leaves shadows to the observed-change and key-light "
                   "tests (120-frame bench: new pixels 17% -> 11%, RMSE unchanged).")
            .field(&CacheSettings::occlusion_threshold, "occlusion_threshold", 0, 1, "",
                   kInvalidatesCache,
                   "A cached point whose occlusion ratio differs from the one measured at its "
                   "pixel by more than this is discarded (seed §5.3: 0.125).")
            .field(&CacheSettings::shading_change, "shading_change", 1e-3, 10, "",
                   kInvalidatesCache,
                   "The observed half of the temporal test: an entry expires when the initial "
                   "points' upsampled shading at its pixel changed by more than this (relative) "
                   "since it was computed; catches moving shadows reaching points lit when "
                   "computed, which B_t cannot see.")
            .field(&CacheSettings::test_spatial, "test_spatial", 0, 1, "", kInvalidatesCache,
                   "Ablation: the spatial validity test (r_x).")
            .field(&CacheSettings::test_angular, "test_angular", 0, 1, "", kInvalidatesCache,
                   "Ablation: the angular validity test (r_theta).")
            .field(&CacheSettings::test_temporal, "test_temporal", 0, 1, "", kInvalidatesCache,
                   "Ablation: the temporal test (lifespan from B_t and the observed change); "
                   "off reproduces the seed's Fig. 14 failure (stale moving shadows).")
            .field(&CacheSettings::test_occlusion, "test_occlusion", 0, 1, "", kInvalidatesCache,
                   "Ablation: the occlusion-ratio test.")
            .field(&CacheSettings::merge, "merge", 0, 1, "", kInvalidatesCache,
                   "Merge valid cached points that land on one pixel when each lies inside the "
                   "other's spatial and angular validity (seed §5.2, Fig. 13).")
            .field(&CacheSettings::depth_tolerance, "depth_tolerance", 1e-5, 1, "",
                   kInvalidatesCache,
                   "Z-buffer test: relative depth difference between a reprojected point and "
                   "the surface seen at its pixel that still counts as visible.")
            .field(&CacheSettings::max_megabytes, "max_megabytes", 0.1, 65536, "MB",
                   kInvalidatesCache,
                   "Memory cap of all caches' live points together; beyond it the oldest are "
                   "evicted after each frame (the slot storage, cache_bytes in the stats, may "
                   "hold one frame's new points more: they are inserted before the eviction).")
            .field(&CacheSettings::checkpoint_every, "checkpoint_every", 0, 10000, "frames",
                   kInvalidatesNothing,
                   "The workbench saves the cache before every K-th frame in the run store "
                   "($FREQLAB_CACHE_DIR/runs); a jump to a frame not rendered yet resumes from "
                   "the newest one at or before it, the frames byte-identical to rendering "
                   "from frame 0 (0: none; `render --checkpoint-every K` on the command line).")
            .field(&CacheSettings::cold_start, "cold_start", 0, 1, "", kInvalidatesCache,
                   "Comparison: every frame starts from an empty cache (a cold start here), so "
                   "frames are independent and render alone; what the cache's reuse saves is "
                   "this run against the warm one (A/B runs). Each frame's stats say how it "
                   "started: cache_start.")
            .build();
    return s;
}

}  // namespace freqlab
