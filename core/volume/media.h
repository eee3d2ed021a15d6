// The scene's participating media at bake time (seed, Deuxième article §3.1, §4.4): density
// grids sampled from their descriptions, optical thickness along a segment, transmittance,
// the effective homogeneous medium of a segment (what the tables are queried with) and
// free-flight sampling for the volumetric path tracer.
//
// Grids are piecewise constant per voxel (the value at the voxel centre), so every quantity
// along a ray is exact: the density integral sums its jumps at the voxel faces the ray crosses
// (each crossing independent of the others: integral_by_jumps), a grid that varies along one
// axis only (height fog) is integrated in O(1) from prefix sums along that axis, and a 3D DDA
// visits the voxels in order where the order matters (free flights). Free flights invert the
// optical thickness exactly (regular tracking); several media superpose, and the first collision in
// their sum is the nearest of the per-medium first collisions (competing exponentials), so each is
// sampled on its own.
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
#include <type_traits>
#include <vector>

#include "math/rng.h"
#include "scene/medium_desc.h"
#include "volume/medium.h"

namespace freqlab {

class DensityGrid {
  public:
    DensityGrid(vec3 box_min, vec3 box_max, ivec3 resolution, std::vector<float> voxels);
    float at(const vec3& p) const;  // nearest voxel, 0 outside
    float max_value() const { return max_; }
    vec3 box_min() const { return min_; }
    vec3 box_max() const { return max_corner_; }
    ivec3 resolution() const { return res_; }
    const std::vector<float>& voxels() const { return voxels_; }
    // Calls fn(t0, t1, density) for the voxel runs the ray crosses inside [t_begin, t_end];
    // an fn that returns bool stops the walk by returning false.
    template <class Fn>
    void march(const vec3& o, const vec3& d, double t_begin, double t_end, Fn&& fn) const;
    // The integral of the density over [t_begin, t_end]: march() summed, or, for a grid that
    // varies along one axis only (a height-fog ramp), in O(1) from prefix sums along it.
    // `inside`: [t_begin, t_end] is known to lie in the grid's box (not clipped again).
    double integral(const vec3& o, const vec3& d, double t_begin, double t_end,
                    bool inside = false) const;
    // The same for any grid, from the density's jumps at the voxel faces (media.cpp).
    double integral_by_jumps(const vec3& o, const vec3& d, double t_begin, double t_end,
                             bool inside = false) const;

  private:
    vec3 min_, max_corner_, voxel_;
    ivec3 res_;
    std::vector<float> voxels_;
    float max_ = 0.0f;
    // What march() walks: the grid with every axis along which it does not vary collapsed to
    // one voxel (a height-fog ramp marches in z only; same values, so the same integrals), with
    // a border of one empty voxel on every side.
    vec3 march_voxel_;
    glm::dvec3 march_inv_voxel_;
    ivec3 march_res_;
    std::vector<float> march_voxels_;
    bool int32_indices_ = false;  // the padded grid's indices fit an int (the AVX2 loop's)
    // Grids that vary along one axis only: that axis, its values and their prefix integrals
    // (prefix_[k] = sum over cells j < k of value x cell size); line_axis_ < 0 otherwise.
    int line_axis_ = -1;
    std::vector<double> line_, prefix_;
};

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

// Ray-box slab test; false when the ray misses [t_begin, t_end].
bool clip_to_box(const vec3& bmin, const vec3& bmax, const vec3& o, const vec3& d, double* t0,
                 double* t1);

template <class Fn>
void DensityGrid::march(const vec3& o, const vec3& d, double t_begin, double t_end, Fn&& fn) const {
    double ta = t_begin, tb = t_end;
    if (!clip_to_box(min_, max_corner_, o, d, &ta, &tb)) return;
    // A 3D DDA (Amanatides & Woo): next crossings kept in registers, the voxel moved by a linear
    // index step (~7 ns a voxel on smoke_room; a fully branch-free update measured no faster).
    // The grid has a border of empty voxels, so a step past the last face (float rounding
    // between the box and the voxel faces) reads 0; the walk ends at tb.
    const glm::dvec3 start = glm::dvec3(o) + glm::dvec3(d) * (ta + 1e-9 * (tb - ta));
    const ivec3 padded = march_res_ + 2;
    const long axis_stride[3] = {1, long(padded.x), long(padded.x) * padded.y};
    double t_next[3], t_delta[3];
    long stride[3];
    long index = 0;
    for (int a = 0; a < 3; ++a) {
        const double rel = (start[a] - min_[a]) / march_voxel_[a];
        const int cell = std::clamp(int(std::floor(rel)), 0, march_res_[a] - 1);
        index += (cell + 1) * axis_stride[a];
        if (d[a] != 0.0f) {
            const double inv = 1.0 / double(d[a]);
            const int next = d[a] > 0.0f ? cell + 1 : cell;
            t_next[a] = (double(min_[a]) + next * double(march_voxel_[a]) - o[a]) * inv;
            t_delta[a] = std::abs(double(march_voxel_[a]) * inv);
            stride[a] = d[a] > 0.0f ? axis_stride[a] : -axis_stride[a];
        } else {
            t_next[a] = t_delta[a] = std::numeric_limits<double>::infinity();
            stride[a] = 0;
        }
    }
    double tx = t_next[0], ty = t_next[1], tz = t_next[2], t = ta;
    const float* voxels = march_voxels_.data();
    // At most one step per voxel face crossed, and one past the grid.
    for (long steps = long(march_res_.x) + march_res_.y + march_res_.z; steps >= 0; --steps) {
        const double t_xy = std::min(tx, ty), t_axis = std::min(t_xy, tz);
        if (t_axis >= tb) break;
        const bool x = tx == t_axis, y = !x && ty == t_axis, z = !x && !y;
        if constexpr (std::is_same_v<std::invoke_result_t<Fn&, double, double, float>, bool>) {
            if (!fn(t, t_axis, voxels[index])) return;
        } else {
            fn(t, t_axis, voxels[index]);
        }
        t = t_axis;
        index += x ? stride[0] : (y ? stride[1] : stride[2]);
        tx += x ? t_delta[0] : 0.0;
        ty += y ? t_delta[1] : 0.0;
        tz += z ? t_delta[2] : 0.0;
    }
    if (tb > t) fn(t, tb, voxels[index]);
}

}  // namespace freqlab
