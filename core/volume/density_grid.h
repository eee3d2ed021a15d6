// A density grid of a participating medium (seed, Deuxième article §4.4: what a segment's
// effective medium integrates): piecewise constant per voxel (the value at the voxel centre), so
// the integral along a ray is exact up to float rounding. Three ways: a grid that varies along
// one axis only (height fog) from prefix sums along that axis, in O(1); others from prefix
// integrals along the ray's dominant axis, summing only the other two axes' crossings
// (integral_by_runs), or from the density's jumps at every voxel face the ray crosses, each
// crossing independent of the others (integral_by_jumps: grids too large for runs). A 3D DDA
// visits the voxels in order where the order matters (free flights, media_collisions.cpp).
//
// | parameter      | meaning                                                               |
// |----------------|-----------------------------------------------------------------------|
// | kMaxRunVoxels  | the largest padded grid that keeps runs (4 M voxels: 4 bytes a voxel  |
// |                | per varying axis, 48 MB at most)                                      |
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include "math/types.h"

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
    // varies along one axis only (a height-fog ramp), in O(1) from prefix sums along it;
    // integral_by_runs where the grid has runs, integral_by_jumps otherwise.
    // `inside`: [t_begin, t_end] is known to lie in the grid's box (not clipped again).
    double integral(const vec3& o, const vec3& d, double t_begin, double t_end,
                    bool inside = false) const;
    // The same for any grid, from the density's jumps at the voxel faces (density_grid.cpp).
    double integral_by_jumps(const vec3& o, const vec3& d, double t_begin, double t_end,
                             bool inside = false) const;
    // The same from prefix integrals along the ray's dominant axis (the grid's runs): only the
    // crossings of the two other axes are summed, about half of the jumps' (density_grid.cpp).
    // Float prefixes: within a few float roundings of the row integrals per crossing. Grids
    // without runs (has_runs() false) fall back to integral_by_jumps.
    double integral_by_runs(const vec3& o, const vec3& d, double t_begin, double t_end,
                            bool inside = false) const;
    // Runs are kept for grids that vary along two or more axes and have at most
    // kMaxRunVoxels padded voxels (4 bytes a voxel per varying axis).
    static constexpr size_t kMaxRunVoxels = size_t(1) << 22;
    bool has_runs() const { return has_runs_; }

  private:
    void build_runs();
    // A clipped segment [ta, tb] in march voxels: origin and direction, first and last voxel.
    struct RayInVoxels {
        glm::dvec3 u0, du;
        ivec3 first, last;
    };
    RayInVoxels in_voxels(const vec3& o, const vec3& d, double ta, double tb) const;
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
    // Along axis a: each row of the padded grid along a as its prefix integrals at the voxel
    // faces (padded[a] + 1 of them, the row contiguous), so that a voxel's two faces are one
    // 64-bit load and a point u of the row (in voxels) has the prefix integral
    // p0 + (u - voxel) (p1 - p0). run_stride_[a][i]: the index step of axis i in runs_[a].
    // Empty for an axis along which the grid does not vary.
    std::vector<float> runs_[3];
    long run_stride_[3][3] = {};
    bool has_runs_ = false;
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
