#include "volume/density_grid.h"

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace freqlab {

bool clip_to_box(const vec3& bmin, const vec3& bmax, const vec3& o, const vec3& d, double* t0,
                 double* t1) {
    // The slab test with the three axes side by side (one vector division, min / max without
    // branches: a segment's tracking is on every bake path). An axis the ray runs parallel to
    // clips nothing when the origin lies between its planes and everything otherwise.
    double lo = *t0, hi = *t1;
    const glm::dvec3 od(o), dd(d);
    const glm::dvec3 inv = 1.0 / dd;  // +-inf on a parallel axis
    const glm::dvec3 ta = (glm::dvec3(bmin) - od) * inv, tb = (glm::dvec3(bmax) - od) * inv;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) {
            if (o[a] < bmin[a] || o[a] > bmax[a]) return false;
            continue;
        }
        lo = std::max(lo, std::min(ta[a], tb[a]));
        hi = std::min(hi, std::max(ta[a], tb[a]));
    }
    *t0 = lo;
    *t1 = hi;
    return hi > lo;
}

DensityGrid::DensityGrid(vec3 box_min, vec3 box_max, ivec3 resolution, std::vector<float> voxels)
    : min_(box_min), max_corner_(box_max), res_(resolution), voxels_(std::move(voxels)) {
    voxel_ = (box_max - box_min) / vec3(resolution);
    for (float v : voxels_) max_ = std::max(max_, v);
    auto index = [&](int x, int y, int z) { return (size_t(z) * res_.y + y) * res_.x + x; };
    march_res_ = res_;
    for (int a = 0; a < 3; ++a) {
        bool constant = res_[a] > 1;
        for (int z = 0; z < res_.z && constant; ++z)
            for (int y = 0; y < res_.y && constant; ++y)
                for (int x = 0; x < res_.x && constant; ++x) {
                    ivec3 first(x, y, z);
                    first[a] = 0;
                    constant = voxels_[index(x, y, z)] == voxels_[index(first.x, first.y, first.z)];
                }
        if (constant) march_res_[a] = 1;
    }
    march_voxel_ = (box_max - box_min) / vec3(march_res_);
    march_inv_voxel_ = 1.0 / glm::dvec3(march_voxel_);
    const ivec3 padded = march_res_ + 2;
    march_voxels_.assign(size_t(padded.x) * padded.y * padded.z, 0.0f);
    for (int z = 0; z < march_res_.z; ++z)
        for (int y = 0; y < march_res_.y; ++y)
            for (int x = 0; x < march_res_.x; ++x)
                march_voxels_[(size_t(z + 1) * padded.y + y + 1) * padded.x + x + 1] =
                    voxels_[index(x, y, z)];
    int32_indices_ = march_voxels_.size() < size_t(1) << 31;
    int varying = 0;
    for (int a = 0; a < 3; ++a)
        if (march_res_[a] > 1) {
            ++varying;
            line_axis_ = a;
        }
    if (varying == 0) line_axis_ = 2;
    if (varying <= 1) {
        const int n = march_res_[line_axis_];
        line_.resize(size_t(n));
        prefix_.assign(size_t(n) + 1, 0.0);
        for (int k = 0; k < n; ++k) {
            ivec3 c(0);
            c[line_axis_] = k;
            line_[size_t(k)] = voxels_[index(c.x, c.y, c.z)];
            prefix_[size_t(k) + 1] =
                prefix_[size_t(k)] + line_[size_t(k)] * march_voxel_[line_axis_];
        }
    } else {
        line_axis_ = -1;
        if (march_voxels_.size() <= kMaxRunVoxels) build_runs();
    }
}

void DensityGrid::build_runs() {
    const ivec3 padded = march_res_ + 2;
    const size_t stride[3] = {1, size_t(padded.x), size_t(padded.x) * padded.y};
    for (int a = 0; a < 3; ++a) {
        if (march_res_[a] == 1) continue;
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const long row = padded[a] + 1;
        run_stride_[a][a] = 1;
        run_stride_[a][b] = row;
        run_stride_[a][c] = row * padded[b];
        std::vector<float>& run = runs_[a];
        run.resize(size_t(row) * padded[b] * padded[c]);
        const double size = march_voxel_[a];
        for (int jc = 0; jc < padded[c]; ++jc)
            for (int jb = 0; jb < padded[b]; ++jb) {
                const size_t first = jb * stride[b] + jc * stride[c];
                float* faces = &run[size_t(jb * run_stride_[a][b] + jc * run_stride_[a][c])];
                double prefix = 0.0;  // summed in double, each face rounded once
                faces[0] = 0.0f;
                for (int k = 0; k < padded[a]; ++k) {
                    prefix += double(march_voxels_[first + k * stride[a]]) * size;
                    faces[k + 1] = float(prefix);
                }
            }
    }
    has_runs_ = true;
}

double DensityGrid::integral(const vec3& o, const vec3& d, double t_begin, double t_end,
                             bool inside) const {
    if (line_axis_ < 0)
        return has_runs_ ? integral_by_runs(o, d, t_begin, t_end, inside)
                         : integral_by_jumps(o, d, t_begin, t_end, inside);
    double ta = t_begin, tb = t_end;
    if (!inside && !clip_to_box(min_, max_corner_, o, d, &ta, &tb)) return 0.0;
    const int a = line_axis_;
    const int n = int(line_.size());
    const double base = min_[a], size = march_voxel_[a];
    const double z0 = double(o[a]) + ta * double(d[a]), z1 = double(o[a]) + tb * double(d[a]);
    auto cell = [&](double z) { return std::clamp(int(std::floor((z - base) / size)), 0, n - 1); };
    const int c0 = cell(z0), c1 = cell(z1);
    // One cell: constant along the segment (also every ray parallel to the cells' faces).
    if (c0 == c1) return line_[size_t(c0)] * (tb - ta);
    // Otherwise d[a] != 0: the density integrated over z, divided by |dz / dt|.
    auto prefix = [&](double z, int c) {
        return prefix_[size_t(c)] + line_[size_t(c)] * (z - (base + c * size));
    };
    return std::abs(prefix(z1, c1) - prefix(z0, c0)) / std::abs(double(d[a]));
}

namespace {

// Axis b's crossings of a segment from voxel `first` to `last` (u0 + t du in voxels): plane q
// (between voxels q - 1 and q) is crossed from the voxel before to the one after, and the k-th
// crossing's time and the other two axes' (1, 2) coordinates are linear in k. `stride`: each
// axis's index step; the first crossing's pair is at base0 (+ the other axes' voxels' steps).
struct AxisCrossings {
    int count = 0;
    double t0 = 0.0, dt = 0.0;
    double u1 = 0.0, du1 = 0.0, u2 = 0.0, du2 = 0.0;
    int res1 = 0, res2 = 0;
    long stride1 = 0, stride2 = 0, base0 = 0, dbase = 0, before_offset = 0, after_offset = 0;
};

AxisCrossings axis_crossings(int b, int axis1, int axis2, const glm::dvec3& u0,
                             const glm::dvec3& du, const ivec3& first, const ivec3& last,
                             const ivec3& res, const long stride[3]) {
    AxisCrossings x;
    x.count = std::abs(last[b] - first[b]);
    if (x.count == 0) return x;
    const int step = last[b] > first[b] ? 1 : -1;
    const int q0 = step > 0 ? first[b] + 1 : first[b];
    const double inv_du = 1.0 / du[b];
    x.t0 = (double(q0) - u0[b]) * inv_du;
    x.dt = double(step) * inv_du;
    x.u1 = u0[axis1] + x.t0 * du[axis1];
    x.du1 = x.dt * du[axis1];
    x.u2 = u0[axis2] + x.t0 * du[axis2];
    x.du2 = x.dt * du[axis2];
    x.res1 = res[axis1];
    x.res2 = res[axis2];
    x.stride1 = stride[axis1];
    x.stride2 = stride[axis2];
    x.before_offset = step > 0 ? -stride[b] : 0;
    x.after_offset = step > 0 ? 0 : -stride[b];
    x.base0 = (q0 + 1) * stride[b] + x.stride1 + x.stride2;
    x.dbase = step * stride[b];
    return x;
}

}  // namespace

#if defined(__AVX2__)
namespace {

// The voxels of four coordinates, clamped to the border [lo, hi] (-1 and res).
__m128i voxel_of(__m256d u, __m128i lo, __m128i hi) {
    return _mm_min_epi32(_mm_max_epi32(_mm256_cvttpd_epi32(_mm256_floor_pd(u)), lo), hi);
}

double horizontal_sum(__m256d v) {
    const __m128d pair = _mm_add_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    return _mm_cvtsd_f64(_mm_add_sd(pair, _mm_unpackhi_pd(pair, pair)));
}

// Crossings k .. k + 3 of a line, one per lane: their voxels' index (the voxel before is at
// before_offset from it, the one after at after_offset) and their first coordinate's voxel.
class CrossingLanes {
  public:
    // (The grid's indices fit an int: the callers check.)
    explicit CrossingLanes(const AxisCrossings& x)
        : u1_(_mm256_set1_pd(x.u1)),
          du1_(_mm256_set1_pd(x.du1)),
          u2_(_mm256_set1_pd(x.u2)),
          du2_(_mm256_set1_pd(x.du2)),
          hi1_(_mm_set1_epi32(x.res1)),
          hi2_(_mm_set1_epi32(x.res2)),
          stride1_(_mm_set1_epi32(int(x.stride1))),
          stride2_(_mm_set1_epi32(int(x.stride2))),
          dbase4_(_mm_set1_epi32(int(4 * x.dbase))),
          base_(_mm_add_epi32(
              _mm_set1_epi32(int(x.base0)),
              _mm_mullo_epi32(_mm_setr_epi32(0, 1, 2, 3), _mm_set1_epi32(int(x.dbase))))) {}
    // kd: the lanes' k; *u1 and *c1 (optional): the first coordinate and its voxel.
    __m128i index(__m256d kd, __m256d* u1 = nullptr, __m128i* c1 = nullptr) const {
        const __m128i lo = _mm_set1_epi32(-1);
        const __m256d u = _mm256_fmadd_pd(kd, du1_, u1_);
        const __m128i first = voxel_of(u, lo, hi1_);
        const __m128i second = voxel_of(_mm256_fmadd_pd(kd, du2_, u2_), lo, hi2_);
        if (u1) *u1 = u;
        if (c1) *c1 = first;
        return _mm_add_epi32(base_, _mm_add_epi32(_mm_mullo_epi32(first, stride1_),
                                                  _mm_mullo_epi32(second, stride2_)));
    }
    void next() { base_ = _mm_add_epi32(base_, dbase4_); }
    // The lanes of crossings k .. k + 3 that exist (k < count), as 32-bit masks.
    static __m128i live(int k, int count) {
        return _mm_cmpgt_epi32(_mm_set1_epi32(count - k), _mm_setr_epi32(0, 1, 2, 3));
    }

  private:
    __m256d u1_, du1_, u2_, du2_;
    __m128i hi1_, hi2_, stride1_, stride2_, dbase4_, base_;
};

// The sum over crossings k < count of (t_k - ta) J_k, four at a time (the last four masked):
// t_k - ta = t0_minus_ta + k dt.
double sum_jumps_avx2(const AxisCrossings& x, double t0_minus_ta, const float* voxels) {
    const int count = x.count;
    const double dt = x.dt;
    const float* after = voxels + x.after_offset;
    const float* before = voxels + x.before_offset;
    CrossingLanes lanes(x);
    const __m256d t0 = _mm256_set1_pd(t0_minus_ta), dtv = _mm256_set1_pd(dt);
    __m256d kd = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
    __m256d sum = _mm256_setzero_pd();
    for (int k = 0; k < count; k += 4) {
        const __m128 live = _mm_castsi128_ps(CrossingLanes::live(k, count));
        const __m128i index = lanes.index(kd);
        const __m128 zero = _mm_setzero_ps();
        const __m128 jump = _mm_sub_ps(_mm_mask_i32gather_ps(zero, after, index, live, 4),
                                       _mm_mask_i32gather_ps(zero, before, index, live, 4));
        sum = _mm256_fmadd_pd(_mm256_fmadd_pd(kd, dtv, t0), _mm256_cvtps_pd(jump), sum);
        lanes.next();
        kd = _mm256_add_pd(kd, _mm256_set1_pd(4.0));
    }
    return horizontal_sum(sum);
}

}  // namespace
#endif

DensityGrid::RayInVoxels DensityGrid::in_voxels(const vec3& o, const vec3& d, double ta,
                                                double tb) const {
    RayInVoxels r;
    r.u0 = (glm::dvec3(o) - glm::dvec3(min_)) * march_inv_voxel_;
    r.du = glm::dvec3(d) * march_inv_voxel_;
    // Cells -1 and res are the empty border: where float rounding puts the box's faces past
    // the voxels' (march() does the same).
    const double margin = 1e-9 * (tb - ta);
    for (int a = 0; a < 3; ++a) {
        auto cell = [&](double t) {
            return std::clamp(int(std::floor(r.u0[a] + t * r.du[a])), -1, march_res_[a]);
        };
        r.first[a] = cell(ta + margin);
        r.last[a] = cell(tb - margin);
    }
    return r;
}

double DensityGrid::integral_by_jumps(const vec3& o, const vec3& d, double t_begin, double t_end,
                                      bool inside) const {
    double ta = t_begin, tb = t_end;
    if (!inside && !clip_to_box(min_, max_corner_, o, d, &ta, &tb)) return 0.0;
    // The density along the ray, f(t), is constant between voxel faces; with J_c its jump
    // f(t_c+) - f(t_c-) where the ray crosses a face at t_c, integration by parts gives
    //   int_ta^tb f = (tb - ta) f(tb-) - sum_c (t_c - ta) J_c.
    // Each crossing is independent of the others: its time is that of its plane, its two
    // voxels the cells of the other axes at that time. A DDA instead finds each next crossing
    // from the last, a dependency chain: 7.5 ns a voxel on smoke_room's grid against 4.5 ns a
    // crossing here, where the crossings of one axis pipeline (the loop is bound by its
    // instruction count: a second sum or a cheaper floor measured no faster). Same sum up to
    // the float rounding of the box's faces (test Media.GridIntegralByJumpsIsTheMarchedSum).
    const RayInVoxels ray = in_voxels(o, d, ta, tb);
    const glm::dvec3 &u0 = ray.u0, &du = ray.du;
    const ivec3 &first = ray.first, &last = ray.last;
    const ivec3 res = march_res_, padded = march_res_ + 2;
    const long axis_stride[3] = {1, long(padded.x), long(padded.x) * padded.y};
    const float* voxels = march_voxels_.data();
    auto index = [&](int x, int y, int z) {
        return (x + 1) * axis_stride[0] + (y + 1) * axis_stride[1] + (z + 1) * axis_stride[2];
    };
    double sum = (tb - ta) * double(voxels[index(last.x, last.y, last.z)]);
    for (int a = 0; a < 3; ++a) {
        const AxisCrossings x =
            axis_crossings(a, (a + 1) % 3, (a + 2) % 3, u0, du, first, last, res, axis_stride);
        if (x.count == 0) continue;
        double jumps = 0.0;
        int k = 0;
#if defined(__AVX2__)
        // Four crossings a step (AVX2 gathers of their two voxels); the scalar loop stays for
        // builds without AVX2.
        if (int32_indices_) {
            k = x.count;
            jumps = sum_jumps_avx2(x, x.t0 - ta, voxels);
        }
#endif
        for (; k < x.count; ++k) {
            const double kd = double(k);
            const int cb = std::clamp(int(std::floor(x.u1 + kd * x.du1)), -1, x.res1);
            const int cc = std::clamp(int(std::floor(x.u2 + kd * x.du2)), -1, x.res2);
            const long base = x.base0 + k * x.dbase + cb * x.stride1 + cc * x.stride2;
            jumps += (x.t0 + kd * x.dt - ta) *
                     double(voxels[base + x.after_offset] - voxels[base + x.before_offset]);
        }
        sum -= jumps;
    }
    return sum;
}

#if defined(__AVX2__)
namespace {

// The sum over crossings k < count of the prefix's jump, four at a time (the last four
// masked): a 64-bit gather of the voxel's two face prefixes on each side of the crossing.
// The line's first coordinate is the run axis's.
double sum_run_jumps_avx2(const AxisCrossings& x, const float* runs) {
    const int count = x.count;
    // The gathers' scale is a float's size: a 64-bit load at any float's index.
    const long long* after = reinterpret_cast<const long long*>(runs + x.after_offset);
    const long long* before = reinterpret_cast<const long long*>(runs + x.before_offset);
    CrossingLanes lanes(x);
    const __m256i split = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
    __m256d kd = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
    __m256d sum = _mm256_setzero_pd();
    for (int k = 0; k < count; k += 4) {
        const __m256i live = _mm256_cvtepi32_epi64(CrossingLanes::live(k, count));
        __m256d u;
        __m128i ca;
        const __m128i index = lanes.index(kd, &u, &ca);
        const __m256i zero = _mm256_setzero_si256();
        // Lanes 0-3: the voxels' near faces' prefixes; 4-7: their far faces'. Subtracted in
        // double, where a difference of floats is exact: a run of empty voxels then sums to
        // exactly 0, as the jumps do (a float difference left +-1e-7 where the density is 0,
        // and the vertex field divided by the tables of such a sliver of medium: 1e10
        // fireflies on smoke_room).
        const __m256 a = _mm256_permutevar8x32_ps(
            _mm256_castsi256_ps(_mm256_mask_i32gather_epi64(zero, after, index, live, 4)), split);
        const __m256 b = _mm256_permutevar8x32_ps(
            _mm256_castsi256_ps(_mm256_mask_i32gather_epi64(zero, before, index, live, 4)), split);
        const __m256d d0 = _mm256_sub_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(a)),
                                         _mm256_cvtps_pd(_mm256_castps256_ps128(b)));
        const __m256d d1 = _mm256_sub_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(a, 1)),
                                         _mm256_cvtps_pd(_mm256_extractf128_ps(b, 1)));
        const __m256d frac = _mm256_sub_pd(u, _mm256_cvtepi32_pd(ca));
        sum = _mm256_add_pd(sum, _mm256_fmadd_pd(frac, _mm256_sub_pd(d1, d0), d0));
        lanes.next();
        kd = _mm256_add_pd(kd, _mm256_set1_pd(4.0));
    }
    return horizontal_sum(sum);
}

}  // namespace
#endif

double DensityGrid::integral_by_runs(const vec3& o, const vec3& d, double t_begin, double t_end,
                                     bool inside) const {
    if (!has_runs_) return integral_by_jumps(o, d, t_begin, t_end, inside);
    double ta = t_begin, tb = t_end;
    if (!inside && !clip_to_box(min_, max_corner_, o, d, &ta, &tb)) return 0.0;
    // Along the ray, F(t) = P(row(t), u_a(t)), the row's prefix integral at the ray's
    // coordinate u_a on the run axis a, grows at rate f(t) d_a inside a row and jumps where the
    // row changes (a crossing of another axis; at a crossing of axis a itself P is continuous).
    // So int_ta^tb f = (F(tb) - F(ta) - sum_c J_c) / d_a, J_c = P(row after, u_a(t_c)) -
    // P(row before, u_a(t_c)): integral_by_jumps' sum without axis a's crossings. Axis a is the
    // one crossed most (largest |du|), so |d_a| is not small.
    const RayInVoxels ray = in_voxels(o, d, ta, tb);
    const glm::dvec3 &u0 = ray.u0, &du = ray.du;
    const ivec3 &first = ray.first, &last = ray.last;
    int a = -1;
    for (int i = 0; i < 3; ++i)
        if (!runs_[i].empty() && (a < 0 || std::abs(du[i]) > std::abs(du[a]))) a = i;
    if (du[a] == 0.0) return integral_by_jumps(o, d, ta, tb, true);  // in a plane of axis a
    const float* run = runs_[a].data();
    const long* run_stride = run_stride_[a];
    const ivec3 res = march_res_;
    // P at run-axis coordinate u in the row of voxel c (a border voxel: its faces are equal).
    auto prefix_at = [&](const ivec3& c, double u) {
        const float* faces =
            run + (c.x + 1) * run_stride[0] + (c.y + 1) * run_stride[1] + (c.z + 1) * run_stride[2];
        return double(faces[0]) + (u - double(c[a])) * (double(faces[1]) - double(faces[0]));
    };
    double sum = prefix_at(last, u0[a] + tb * du[a]) - prefix_at(first, u0[a] + ta * du[a]);
    for (int b = 0; b < 3; ++b) {
        if (b == a) continue;
        // The run axis first: its coordinate places the crossing within its voxel.
        const AxisCrossings x =
            axis_crossings(b, a, 3 - a - b, u0, du, first, last, res, run_stride);
        if (x.count == 0) continue;
        double jumps = 0.0;
        int k = 0;
#if defined(__AVX2__)
        // Four crossings a step; the scalar loop stays for builds without AVX2 (runs exist
        // only below kMaxRunVoxels, so the indices fit an int).
        jumps = sum_run_jumps_avx2(x, run);
        k = x.count;
#endif
        for (; k < x.count; ++k) {
            const double u = x.u1 + double(k) * x.du1;
            const int ca = std::clamp(int(std::floor(u)), -1, x.res1);
            const int cc = std::clamp(int(std::floor(x.u2 + double(k) * x.du2)), -1, x.res2);
            const long base = x.base0 + k * x.dbase + ca * x.stride1 + cc * x.stride2;
            const float* after = run + base + x.after_offset;
            const float* before = run + base + x.before_offset;
            const double d0 = double(after[0]) - double(before[0]);
            const double d1 = double(after[1]) - double(before[1]);
            jumps += d0 + (u - double(ca)) * (d1 - d0);
        }
        sum -= jumps;
    }
    return sum / double(d[a]);
}

float DensityGrid::at(const vec3& p) const {
    const vec3 rel = (p - min_) / voxel_;
    if (rel.x < 0 || rel.y < 0 || rel.z < 0 || rel.x >= res_.x || rel.y >= res_.y ||
        rel.z >= res_.z)
        return 0.0f;
    const ivec3 c = glm::min(ivec3(rel), res_ - 1);
    return voxels_[(size_t(c.z) * res_.y + c.y) * res_.x + c.x];
}

}  // namespace freqlab
