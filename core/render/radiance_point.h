// Method A's adaptive radiance point (seed, Premier article §4 Eq. 4.1-4.5, §5.1 Eq. 5.1-5.3,
// Appendix 9): the spherical sample count chosen from the environment's bandwidth inside the
// BRDF's footprint and from the occlusion a pilot finds there, and the point's spatio-angular
// bandwidths for image-space sampling.
//
// | quantity        | definition here                                                         |
// |-----------------|-------------------------------------------------------------------------|
// | mu_rho, sigma_rho | footprint axis (mirror direction; the normal for Lambert) and its angular |
// |                 | standard deviation: atan(sqrt(Var[e])) (Eq. 4.2), 0.8566 rad for the       |
// |                 | clamped cosine (sqrt(E[theta^2] / 2) over the cosine-weighted hemisphere)  |
// | B_L             | environment bandwidth (cycles/rad) queried at (mu_rho, atan(3 sigma))     |
// | N_L             | 4 B^2 with B = B_L x the footprint's width 2 r (cycles across it),        |
// |                 | clamped to [points.min_samples, points.max_pilot], even                 |
// | mu_o, Sigma_o   | Eq. 4.4's mean over the pilot's occluded samples, weights rho_i = BRDF pdf,|
// |                 | and their weighted covariance (reliability weights; the printed          |
// |                 | normalisation divides the spread by the occluded count, see the .cpp), on |
// |                 | the samples' angular coordinates theta (cos phi, sin phi) in the cone frame|
// |                 | (so sigma_V compares with sigma_rho: the seed's hit points have units)    |
// | sigma_V         | Eq. 4.5: the larger tangent / binormal deviation of Sigma_o               |
// | f_V, N_Omega    | (N_max - N_L) exp(-(x - 1/2)^2 / 2), x = sigma_V / sigma_rho; 0 when no   |
// |                 | pilot sample is occluded; N_Omega = min(N_max, N_L + f_V) (Eq. 4.3)       |
// | t_min           | Eq. 5.1 on the occluders' 3D hit points: mu_t - 3 sigma_t; when that is   |
// |                 | <= 0 (spread-out occluders) the nearest pilot hit distance instead        |
// | B_S, B_x, B_theta | 3 sqrt of the image covariance's angular variance (Eq. 5.2-5.3), and of |
// |                 | the object-space covariance's spatial and angular variances (App. 9)    |
// | B_t             | Eq. 5.14: mean + 3 deviations (BRDF-pdf weighted, as Eq. 4.4) of |v'| B_L |
// |                 | over occluded pilot samples, |v'| the occluder's angular speed relative  |
// |                 | to the receiver; 0 when nothing occluding moves (the environment is      |
// |                 | static in the scene model, so its rotation term omega B_L is 0)          |
// | samples         | points.stratified (default): each strategy's 2D samples are an Owen-      |
// |                 | scrambled Sobol sequence (the environment by CDF inversion), so N_Omega  |
// |                 | samples cover the footprint evenly as a sampling rate assumes; any prefix |
// |                 | (the pilot's or the plan's first N_L) is itself well stratified           |
// | estimate        | points.reuse_pilot off: N_Omega fresh MIS samples (the pilot only         |
// |                 | decides, so the count cannot bias the mean); on: the seed's reuse        |
// | planned point   | (sparse pipeline, sparse.plan_samples) N_Omega = N_L + f_V with f_V from |
// |                 | the neighbours' upsampled statistics (planned_extra_samples); no pilot:  |
// |                 | one estimate of N_Omega samples, occlusion statistics on its first N_L,  |
// |                 | t_min and B_t the occluded neighbours' (the point measures its own only  |
// |                 | for the cache, VisibilityPlan::own_distances, or when no neighbour saw   |
// |                 | occlusion)                                                               |
#pragma once

#include <string>
#include <vector>

#include "freq/env_bandwidth.h"
#include "render/direct_lighting.h"
#include "settings/shading_settings.h"

namespace freqlab {

struct RadiancePoint {
    vec3 radiance{0.0f};
    float variance = 0.0f;
    long rays = 0;
    double B_L = 0.0, sigma_rho = 0.0, N_L = 0.0, N_omega = 0.0, sigma_V = 0.0;
    double occlusion_ratio = 0.0, t_min = 0.0, B_S = 0.0, B_x = 0.0, B_theta = 0.0, B_t = 0.0;
    int pilot_rays = 0, pilot_occluded = 0;
    // The pilot's samples in the cone frame (for the inspector): angular coordinates, occluded.
    struct ConeSample {
        float u, v;
        bool occluded;
    };
    std::vector<ConeSample> cone_samples;
    double footprint_radius = 0.0;  // the query radius, rad (the inspector's circle)
    double mu_o[2] = {0, 0};        // Eq. 4.4 mean, cone angles
    double sigma_o[3] = {0, 0, 0};  // Eq. 4.4 covariance: tt, tb, bb
};

// Geometry of the pixel the point shades, from the G-buffer.
struct PointContext {
    double curvature = 0.0;     // screen-space estimate (1 / scene units)
    double eye_distance = 1.0;  // from the camera
    float time = 0.0f;          // of the frame (for occluder velocities)
    int object = -1;            // the receiver's object (its own motion is subtracted)
};

// What the neighbours' pilots found near a pixel (the sparse pipeline's upsampled statistics):
// enough to plan a point's sample count N_Omega without a pilot of its own.
struct VisibilityPlan {
    double occluded_fraction = 0.0;  // weighted share of neighbours whose pilot saw occlusion
    double sigma_V = 0.0;            // their weighted mean sigma_V (0 for unoccluded ones), rad
    // The occluded neighbours' t_min (geometric mean) and B_t: the point's own when it finds
    // occlusion, so that it casts no ray for occluder distances ...
    double t_min_occluded = 0.0, B_t_occluded = 0.0;
    // ... unless the point measures its own (the cache: its lifespan and reuse radii come from
    // them, and neighbours' values measured 15 % more temporal discards on creatures.json).
    bool own_distances = false;
};

// f_V of Eq. 4.3 expected from a plan: the occluded fraction times f_V at the occluded
// neighbours' mean sigma_V; `room` = N_max - N_L.
double planned_extra_samples(const VisibilityPlan& plan, double sigma_rho, int room);

// |n1 - n0| / |p1 - p0| over the pixel's neighbours on the same object (the larger of x, y).
double screen_space_curvature(const SurfaceHit& centre, const SurfaceHit* neighbours, int count);

struct PointBandwidths {
    double B_S = 0.0, B_x = 0.0, B_theta = 0.0;
};

// A pixel's chain of perfect mirrors: the first non-mirror hit (invalid when the chain escapes,
// is cut by mirror_depth or reflects below a mirror), seen from `wo`, through `bounces` mirrors
// whose albedos multiply into `throughput`.
struct MirrorPath {
    SurfaceHit hit;
    vec3 wo{0.0f};
    vec3 throughput{1.0f};
    int bounces = 0;
    long rays = 0;
    bool escaped = false;         // left the scene towards the environment along -wo
    double extra_distance = 0.0;  // path length after the first hit
};

class RadiancePointIntegrator {
  public:
    // `bandwidth` may be null (no environment map: B_L = 0).
    RadiancePointIntegrator(const RayScene& scene, const ShadingSettings& shading,
                            const PointsSettings& settings, const EnvBandwidthHierarchy* bandwidth);
    // With `chain`, every input, operator and intermediate value is appended as text.
    // With `plan`, N_Omega comes from the plan and no pilot is cast: one estimate of N_Omega
    // samples, whose first N_L (by strategy) give the visibility statistics. The count then
    // depends only on other pixels' samples, so the estimate stays unbiased and the pilot's
    // N_L rays are saved.
    RadiancePoint integrate(const ShadingPoint& point, const PointContext& context, CounterRng& rng,
                            std::vector<std::string>* chain = nullptr,
                            const VisibilityPlan* plan = nullptr) const;
    // The point seen at a G-buffer hit: perfect mirrors are followed (Whitted, up to
    // shading.mirror_depth) and the radiance point is integrated at the first non-mirror hit,
    // times the mirrors' albedos; its frequency fields are that point's. A ray that escapes
    // sees the environment.
    RadiancePoint integrate_hit(const SurfaceHit& hit, const vec3& wo, const PointContext& context,
                                CounterRng& rng, const VisibilityPlan* plan = nullptr) const;
    MirrorPath follow_mirrors(const SurfaceHit& hit, const vec3& wo) const;
    const DirectLighting& lighting() const { return lighting_; }
    // B_L in the point's BRDF footprint (cycles/rad; 0 without an environment).
    double environment_bandwidth(const ShadingPoint& point) const;
    // The covariance chain alone (Eq. 5.2-5.3) for given B_L and t_min: what the sparse
    // pipeline evaluates at every pixel from upsampled visibility statistics.
    PointBandwidths bandwidths(const ShadingPoint& point, const PointContext& context, double B_L,
                               double t_min, std::vector<std::string>* chain = nullptr) const;
    double large_distance() const { return large_distance_; }

  private:
    const RayScene& scene_;
    DirectLighting lighting_;
    PointsSettings settings_;
    const EnvBandwidthHierarchy* bandwidth_;
    double large_distance_;
    int mirror_depth_;
    double environment_spin_ = 0.0;    // rad/s
    double environment_turned_ = 0.0;  // rad, at the scene's time
    vec3 to_map_frame(const vec3& direction) const;
    // Eq. 4.4-4.5, 5.1, 5.14 on the cast samples (rp.N_L set): fills the occlusion fields,
    // t_min and B_t of `rp` (one extra ray per occluded sample for its distance; without
    // `distances` only the angular statistics, t_min and B_t untouched) and returns the f_V
    // they call for.
    double visibility_statistics(const ShadingPoint& point, const PointContext& context,
                                 const glm::dvec3& mu,
                                 const std::vector<DirectLighting::CastSample>& cast,
                                 bool distances, RadiancePoint& rp,
                                 std::vector<std::string>* chain) const;
};

}  // namespace freqlab
