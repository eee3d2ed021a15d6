// The scene's participating media at bake time (seed, Deuxième article §3.1, §4.4): density
// grids sampled from their descriptions, optical thickness along a segment, transmittance,
// the effective homogeneous medium of a segment (what the tables are queried with) and
// free-flight sampling for the volumetric path tracer.
//
// Grids are piecewise constant per voxel (the value at the voxel centre), so every quantity
// along a ray is exact: a 3D DDA visits the voxels and sums density x length ("exact ray
// marching of the grid"). Free flights invert the optical thickness exactly (regular
// tracking); several media superpose, and the first collision in their sum is the nearest of
// the per-medium first collisions (competing exponentials), so each is sampled on its own.
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
    // Calls fn(t0, t1, density) for the voxel runs the ray crosses inside [t_begin, t_end].
    template <class Fn>
    void march(const vec3& o, const vec3& d, double t_begin, double t_end, Fn&& fn) const;

  private:
    vec3 min_, max_corner_, voxel_;
    ivec3 res_;
    std::vector<float> voxels_;
    float max_ = 0.0f;
};

struct SegmentOptics {
    double length = 0.0;
    double tau_s = 0.0, tau_a = 0.0;
    double tau_gs = 0.0;  // integral of g sigma_s
    double transmittance() const { return std::exp(-(tau_s + tau_a)); }
    HomogeneousMedium effective() const;  // vacuum for a zero-length segment
};

struct MediumCollision {
    bool happened = false;
    double t = 0.0;
    double sigma_s = 0.0, sigma_t = 0.0, g = 0.0;  // of the medium collided with, at the point
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
    SegmentOptics integrate(const vec3& o, const vec3& d, double t_max) const;
    double transmittance(const vec3& o, const vec3& d, double t_max) const {
        return integrate(o, d, t_max).transmittance();
    }
    // The first real collision before t_max (none: happened = false), exact in distribution.
    MediumCollision sample_collision(const vec3& o, const vec3& d, double t_max,
                                     CounterRng& rng) const;
    // Where the ray leaves the last bounded medium it crosses; infinity when a medium fills
    // all space and the ray is not leaving anything (directional lights' query depth).
    double exit_distance(const vec3& o, const vec3& d) const;
    // Replaces the coefficients of medium i (sliders: no grid is resampled, nothing tabulated).
    void set_coefficients(size_t i, double sigma_s, double sigma_a, double g, double scale);

  private:
    struct Entry {
        MediumDesc desc;
        std::shared_ptr<const DensityGrid> grid;  // null: constant density inside bounds
    };
    // The part of [0, t_max] inside medium e's bounds; false when none.
    bool clip(const Entry& e, const vec3& o, const vec3& d, double t_max, double* t0,
              double* t1) const;
    std::vector<Entry> media_;
};

// Ray-box slab test; false when the ray misses [t_begin, t_end].
bool clip_to_box(const vec3& bmin, const vec3& bmax, const vec3& o, const vec3& d, double* t0,
                 double* t1);

template <class Fn>
void DensityGrid::march(const vec3& o, const vec3& d, double t_begin, double t_end, Fn&& fn) const {
    double ta = t_begin, tb = t_end;
    if (!clip_to_box(min_, max_corner_, o, d, &ta, &tb)) return;
    // Start voxel: the one holding a point just inside the clipped segment.
    const glm::dvec3 start = glm::dvec3(o) + glm::dvec3(d) * (ta + 1e-9 * (tb - ta));
    ivec3 cell;
    glm::dvec3 t_next, t_delta;
    ivec3 step;
    for (int a = 0; a < 3; ++a) {
        const double rel = (start[a] - min_[a]) / voxel_[a];
        cell[a] = std::clamp(int(std::floor(rel)), 0, res_[a] - 1);
        if (d[a] > 0) {
            step[a] = 1;
            t_delta[a] = voxel_[a] / d[a];
            t_next[a] = (min_[a] + (cell[a] + 1) * voxel_[a] - o[a]) / d[a];
        } else if (d[a] < 0) {
            step[a] = -1;
            t_delta[a] = -voxel_[a] / d[a];
            t_next[a] = (min_[a] + cell[a] * voxel_[a] - o[a]) / d[a];
        } else {
            step[a] = 0;
            t_delta[a] = std::numeric_limits<double>::infinity();
            t_next[a] = std::numeric_limits<double>::infinity();
        }
    }
    double t = ta;
    while (t < tb) {
        const int axis =
            t_next.x < t_next.y ? (t_next.x < t_next.z ? 0 : 2) : (t_next.y < t_next.z ? 1 : 2);
        const double t_exit = std::min(t_next[axis], tb);
        if (t_exit > t)
            fn(t, t_exit, voxels_[(size_t(cell.z) * res_.y + cell.y) * res_.x + cell.x]);
        t = std::max(t, t_exit);
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] >= res_[axis]) break;
        t_next[axis] += t_delta[axis];
    }
}

}  // namespace freqlab
