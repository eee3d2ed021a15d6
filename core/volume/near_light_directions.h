// Walk directions that aim past point lights (issue "Method B, part 3"; the walks of
// volume/bake_estimators.cpp, which take a point light's light scattered along every segment
// by equiangular sampling, BakeEstimator::point_lights_along).
//
// A segment passing at distance h from a point light gathers light proportional to 1 / h
// (the integral of 1 / r^2 along a line). Drawn by the phase function or the cosine, a
// direction passes within h of the light with probability ~ h^2, so the estimate's variance
// grows like the integral of h^-2 h dh: unbounded (logarithmically). One prepass path of a
// cornell_fog floor texel by the short box brought 41.9 against a mean of ~0.1, and the box's
// bottom row, reading that texel, stood 30 % above VPT. This strategy draws a point on the
// disk through the light facing the walk's vertex x, at a radius uniform in [0, R]: its
// density in the disk is 1 / (2 pi rho R), so that the directions passing within h of the
// light have density ~ 1 / h, which cancels the segment's 1 / h. One-sample MIS: the walk
// picks it with probability `fraction` (a light chosen uniformly) and the phase function or
// cosine otherwise, and weighs every direction by the mixture's density (balance heuristic):
// unbiased, whatever the walk then does with the direction.
//
// | parameter            | meaning                                                         |
// |----------------------|-----------------------------------------------------------------|
// | fraction             | bake.near_light_fraction: the chance a walk vertex aims at a    |
// |                      | point light (0: never)                                          |
// | kDiskRadiusOverDistance | R / |L - x|: the disk's radius, a fraction of the distance   |
#pragma once

#include <vector>

#include "math/types.h"
#include "scene/light.h"
#include "volume/receiver_directions.h"

namespace freqlab {

// The strategy for one point: a direction from x towards the disk about `light` (u1, u2),
// and its density (solid angle); false when x is at the light.
bool sample_towards_point(const vec3& x, const vec3& light, float u1, float u2, vec3* dir);
double towards_point_pdf(const vec3& x, const vec3& light, const vec3& dir);

class NearLightDirections {
  public:
    // The point lights of `lights`; none when fraction is 0 (then active() is false).
    NearLightDirections(const std::vector<Light>& lights, float fraction);
    bool active() const { return !lights_.empty(); }
    float fraction() const { return active() ? fraction_ : 0.0f; }

    // A direction from x towards the disk of light `u_pick` in [0, 1) picks; false when x is
    // at the light.
    bool sample(const vec3& x, float u_pick, float u1, float u2, vec3* dir) const;
    // The strategy's density of `dir` from x (solid angle), its lights' mean.
    double pdf(const vec3& x, const vec3& dir) const;
    // The mixture's density given the other strategy's: (1 - fraction) base + fraction pdf.
    double mixture_pdf(const vec3& x, const vec3& dir, double base_pdf) const {
        return active() ? (1.0 - fraction_) * base_pdf + fraction_ * pdf(x, dir) : base_pdf;
    }

  private:
    std::vector<vec3> lights_;
    float fraction_ = 0.0f;
};

// A receiver's directions for light scattered about one point emitter (its single-scattering
// correction, BakeEstimator::local_single_correction): the cosine about n mixed with the disk
// towards the point (kPointFraction of them; one-sample MIS, balance heuristic). The cosine
// alone passes within h of the point with probability ~ h^2 and the equiangular estimate
// along the direction weighs ~ 1 / h: unbounded variance (valley's field read +58 at a statue
// texel); the disk's density ~ 1 / h cancels it.
class CosineAndPointDirections final : public ReceiverDirections {
  public:
    static constexpr float kPointFraction = 0.5f;
    CosineAndPointDirections(const vec3& x, const vec3& n, const vec3& point)
        : x_(x), n_(n), point_(point) {}
    bool sample(float u1, float u2, vec3* w, double* weight) const override;

  private:
    vec3 x_, n_, point_;
};

}  // namespace freqlab
