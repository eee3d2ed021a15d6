// Direct lighting at a surface point: the Monte Carlo estimator of the reflection equation
// (seed, Premier article §4, Eq. 4.1) with binary visibility through Embree occlusion rays,
// used by the MIS baseline and the reference, and the estimator method A's radiance points
// build on.
//
// | term                      | how it is estimated                                          |
// |---------------------------|--------------------------------------------------------------|
// | environment / sky         | n_env = ceil(N/2) samples from the map's pdf and n_brdf =    |
// |                           | floor(N/2) from the BRDF's, power heuristic (Veach; seed §7) |
// | point, directional lights | one deterministic shadow ray per environment sample unit     |
// | quad area light           | one uniform area sample per environment sample unit (light   |
// |                           | sampling only: BRDF rays do not see quads, so no MIS)        |
// | perfect mirror            | Whitted recursion up to shading.mirror_depth, then black     |
// | textures                  | the albedo at the hit scales the BRDF exactly                |
//
// The variance returned is that of the estimate (of its luminance): s²_env / n_env +
// s²_brdf / n_brdf from the per-sample terms; 0 when a strategy has fewer than 2 samples
// (with stratified samples that is the independent-sample formula: an over-estimate).
//
// Speed: a point's samples go through each stage together, as structure of arrays in loops the
// compiler vectorizes (scene/brdf_batch.h, EnvironmentMap's batch calls, math/fast_math.h),
// ordered so that every table read (alias entries, the texels of both strategies) is started
// well before it is used; the environment's tables sit in 2 MB pages (base/huge_pages.h).
// Profiled on rotor.json, those reads, not arithmetic, are what a sample costs.
//
// Sample sequences: Independent draws every uniform from the pixel's counter stream (the
// environment through its alias table). ScrambledSobol gives each strategy one Owen-scrambled
// 2D Sobol sequence (math/sobol.h), seeded from the stream, and inverts the environment's
// CDFs instead, so the samples stay stratified over the sphere; quad lights stay independent.
#pragma once

#include "accel/ray_scene.h"
#include "math/rng.h"
#include "scene/brdf.h"
#include "settings/shading_settings.h"

namespace freqlab {

enum class SampleSequence { Independent, ScrambledSobol };
inline SampleSequence sample_sequence(bool stratified) {
    return stratified ? SampleSequence::ScrambledSobol : SampleSequence::Independent;
}

struct RadianceEstimate {
    vec3 radiance{0.0f};
    float variance = 0.0f;  // of the luminance of `radiance`
    long rays = 0;          // shadow + reflection rays cast
};

// A surface point to shade, in world space.
struct ShadingPoint {
    vec3 position;
    vec3 geometric_normal;  // facing wo
    vec3 shading_normal;
    vec3 wo;  // unit, towards the viewer
    const Material* material;
    vec3 albedo;  // texture value at the point
};

class DirectLighting {
  public:
    DirectLighting(const RayScene& scene, const ShadingSettings& settings,
                   SampleSequence sequence = SampleSequence::Independent);

    // Radiance along `ray` (towards its origin): the environment when it escapes, mirrors
    // followed, and the direct-lighting estimate with `spp` samples at the first non-mirror hit.
    RadianceEstimate trace(const Ray& ray, int spp, CounterRng& rng, int depth = 0) const;
    RadianceEstimate shade_hit(const SurfaceHit& hit, const vec3& wo, int spp, CounterRng& rng,
                               int depth = 0) const;
    // One cast shadow ray of estimate(): what method A's radiance points gather statistics on.
    struct CastSample {
        Ray ray;
        bool occluded;
        bool brdf_strategy;
        int unit;  // the strategy's sample index (0-based) the ray belongs to
    };
    // The estimator at a point (no mirror handling): what trace() uses and tests call. With
    // `cast`, every shadow ray and its visibility is appended (thread-safe: caller's vector).
    RadianceEstimate estimate(const ShadingPoint& point, int spp, CounterRng& rng,
                              std::vector<CastSample>* cast = nullptr) const;

    ShadingPoint shading_point(const SurfaceHit& hit, const vec3& wo) const;
    // --debug-pixel: every sample of estimate() is appended here (single-threaded use).
    struct SampleTrace {
        bool environment_strategy;  // else BRDF strategy; lights count as environment units
        int unit;
        vec3 direction;
        float pdf, other_pdf, mis_weight;
        vec3 contribution;  // before visibility
        bool occluded = false;
    };
    void trace_samples(std::vector<SampleTrace>* sink) { traced_ = sink; }
    // Benchmarks only: every shadow ray cast is appended here (single-threaded use).
    void record_rays(std::vector<Ray>* sink) { recorded_ = sink; }
    vec3 offset_origin(const vec3& p, const vec3& n) const;

  private:
    const RayScene& scene_;
    const EnvironmentMap* environment_;
    std::vector<const Light*> lights_;  // point, directional, quad
    bool quad_lights_ = false;          // (they draw uniforms between environment samples)
    ShadingSettings settings_;
    SampleSequence sequence_;
    std::vector<Ray>* recorded_ = nullptr;
    std::vector<SampleTrace>* traced_ = nullptr;
};

}  // namespace freqlab
