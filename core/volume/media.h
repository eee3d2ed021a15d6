// The scene's participating media at bake time (seed, Deuxième article §3.1, §4.4): density
// grids sampled from their descriptions, optical thickness along a segment, transmittance,
// the effective homogeneous medium of a segment (what the tables are queried with) and
// free-flight sampling for the volumetric path tracer.
//
// Grids (density_grid.h) are piecewise constant per voxel, so every quantity along a ray is
// exact. Free flights invert the optical thickness exactly (regular tracking); several media
// superpose, and the first collision in their sum is the nearest of the per-medium first
// collisions (competing exponentials), so each is sampled on its own.
//
// | quantity              | definition                                                     |
// |-----------------------|----------------------------------------------------------------|
// | density               | grid voxel (0 outside its box) x density_scale; 1 when constant |
// | sigma_s(x), sigma_a(x)| sum over media of sigma_{s,a} x density                         |
// | g(x)                  | sum of g sigma_s over sum of sigma_s (scattering-weighted mean)  |
// | tau_s, tau_a          | integrals of sigma_s, sigma_a along the segment                 |
// | effective medium      | tau_s / L, tau_a / L, g = int g sigma_s / tau_s (§4.4, Fig. 25)  |
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "math/rng.h"
#include "scene/medium_desc.h"
#include "volume/density_grid.h"
#include "volume/medium.h"

namespace freqlab {

struct SegmentOptics {
    double length = 0.0;
    double tau_s = 0.0, tau_a = 0.0;
    double tau_gs = 0.0;  // integral of g sigma_s
    // How many media scatter along it: more than one is a mixture, whose effective g and
    // albedo vary continuously (impulse_irradiance.h: ImpulseIrradianceCache::blend).
    int scattering_media = 0;
    // Ratio tracking (Media::track): the optical thickness of the media integrated exactly and
    // the ratio-tracking estimate of the others' transmittance; NaN: everything exact.
    double tau_t_exact = std::numeric_limits<double>::quiet_NaN();
    double tracked_ratio = 1.0;
    double transmittance() const {
        return std::isnan(tau_t_exact) ? std::exp(-(tau_s + tau_a))
                                       : std::exp(-tau_t_exact) * tracked_ratio;
    }
    // The same in float (1 ulp) for the bakers, which store float (the double exp was 4 % of an
    // extinction bake).
    float transmittance_float() const {
        return std::isnan(tau_t_exact) ? std::exp(-float(tau_s + tau_a))
                                       : std::exp(-float(tau_t_exact)) * float(tracked_ratio);
    }
    HomogeneousMedium effective() const;  // vacuum for a zero-length segment
};

struct MediumCollision {
    bool happened = false;
    double t = 0.0;
    double sigma_s = 0.0, sigma_t = 0.0, g = 0.0;  // of the medium collided with, at the point
    double sigma_t_all = 0.0;  // every medium's at the point (the collision density's rate)
    double pdf = 0.0;          // forced collisions: t's density, sigma_t_all T(t) / P
};

class Media {
  public:
    Media() = default;
    // Samples every grid; throws Error naming the medium's field (a VDB file or grid that is
    // missing, a non-finite or negative voxel).
    explicit Media(const std::vector<MediumDesc>& descs, const std::string& scene_file = "");

    bool empty() const { return media_.empty(); }
    size_t size() const { return media_.size(); }
    const MediumDesc& desc(size_t i) const { return media_[i].desc; }
    const DensityGrid* grid(size_t i) const { return media_[i].grid.get(); }

    // Coefficients at a point (sigma_s, sigma_a and g of the mixture).
    HomogeneousMedium at(const vec3& p) const;
    // t_max may be infinite: the segment then ends where the ray leaves the last bounded
    // medium (exit_distance(), in the result's length; a directional light's connection).
    SegmentOptics integrate(const vec3& o, const vec3& d, double t_max) const;
    // The same by ratio tracking through density grids (homogeneous media stay exact and draw
    // nothing): points of a Poisson process at the grid's majorant rate mu rho_max give the
    // transmittance prod (1 - rho_i / rho_max) and the density integral sum rho_i / (mu rho_max),
    // both unbiased (Campbell's theorem for the second).
    SegmentOptics track(const vec3& o, const vec3& d, double t_max, CounterRng& rng) const;
    double transmittance(const vec3& o, const vec3& d, double t_max) const {
        return integrate(o, d, t_max).transmittance();
    }
    // The first real collision before t_max (none: happened = false), exact in distribution.
    MediumCollision sample_collision(const vec3& o, const vec3& d, double t_max,
                                     CounterRng& rng) const;
    // A collision before t_max given that one happens (a forced collision), weighted so that
    // E[weight f(t); found] = P E[f(t) | collision], P = 1 - T(t_max) the probability of a
    // collision: the conditioned law inverted through all the media crossed (T(t) = 1 - u P,
    // media_collisions.cpp), weight P, and t's density in the result's pdf. Not found (no medium,
    // or rounding short of the target): happened = false, *weight = 0.
    MediumCollision sample_forced_collision(const vec3& o, const vec3& d, double t_max,
                                            CounterRng& rng, double* weight) const;
    // Where the ray leaves the last bounded medium it crosses; infinity when a medium fills
    // all space and the ray is not leaving anything (directional lights' query depth).
    double exit_distance(const vec3& o, const vec3& d) const;
    // Replaces the coefficients of medium i (sliders: no grid is resampled, nothing tabulated).
    // Not while a bake runs on these media.
    void set_coefficients(size_t i, double sigma_s, double sigma_a, double g, double scale);
    // Counts set_coefficients() calls: what a baker resolved per medium is valid while it holds.
    uint64_t version() const { return version_; }

  private:
    struct Entry {
        MediumDesc desc;
        std::shared_ptr<const DensityGrid> grid;  // null: constant density inside bounds
        // The grid's box is the medium's bounds: clip() has clipped a segment to it already.
        bool grid_is_bounds = false;
    };
    // The part of [0, t_max] inside medium e's bounds; false when none.
    // Where in [t0, t1] medium e's optical thickness from t0 reaches `target` (> 0): false
    // when it does not; else *out holds that point's collision.
    bool collide(const Entry& e, const vec3& o, const vec3& d, double t0, double t1, double target,
                 MediumCollision* out) const;
    bool clip(const Entry& e, const vec3& o, const vec3& d, double t_max, double* t0,
              double* t1) const;
    // Medium e's optical thickness over [t0, t1] (inside its bounds).
    double thickness(const Entry& e, const vec3& o, const vec3& d, double t0, double t1) const;
    // Where in [a, b] the summed thickness of `active` (all of which cover [a, b]) from a
    // reaches target, and which of them collides there (u_pick by their sigma_t).
    MediumCollision collide_mixture(const std::vector<const Entry*>& active, const vec3& o,
                                    const vec3& d, double a, double b, double target,
                                    double u_pick) const;
    // A segment's axis-aligned bounds, to reject the boxes it cannot cross before their slab
    // tests (valley: 11 media on every segment). A ray to infinity ends where it leaves the
    // media's union (misses_all: it never enters it). Inactive: nothing is rejected.
    struct SegmentBox {
        bool active = false, misses_all = false;
        vec3 lo{0.0f}, hi{0.0f};
        bool misses(const MediumDesc& desc) const;
    };
    SegmentBox segment_box(const vec3& o, const vec3& d, double t_max) const;
    std::vector<Entry> media_;
    // The union of the media's bounds (bounded_: all are boxes or spheres).
    bool bounded_ = false;
    vec3 union_min_{0.0f}, union_max_{0.0f};
    uint64_t version_ = 0;
};

}  // namespace freqlab
