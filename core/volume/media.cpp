#include "volume/media.h"

#include <tbb/parallel_for.h>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "base/error.h"
#include "math/noise.h"
#include "volume/vdb_reader.h"

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
    }
}

double DensityGrid::integral(const vec3& o, const vec3& d, double t_begin, double t_end,
                             bool inside) const {
    if (line_axis_ < 0) return integral_by_jumps(o, d, t_begin, t_end, inside);
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

#if defined(__AVX2__)
namespace {

// One axis's crossings for sum_jumps_avx2: as in integral_by_jumps' scalar loop.
struct JumpAxis {
    double t0_minus_ta, dt, ub, dub, uc, duc;
    int res_b, res_c, stride_b, stride_c, base0, dbase, before_offset, after_offset;
};

// The sum over crossings k < count of (t_k - ta) J_k, four at a time (the last four masked).
double sum_jumps_avx2(const JumpAxis& a, const float* voxels, int count) {
    const float* after = voxels + a.after_offset;
    const float* before = voxels + a.before_offset;
    const __m256d dub = _mm256_set1_pd(a.dub), ub = _mm256_set1_pd(a.ub);
    const __m256d duc = _mm256_set1_pd(a.duc), uc = _mm256_set1_pd(a.uc);
    const __m256d dt = _mm256_set1_pd(a.dt), t0 = _mm256_set1_pd(a.t0_minus_ta);
    const __m128i lo = _mm_set1_epi32(-1), hi_b = _mm_set1_epi32(a.res_b),
                  hi_c = _mm_set1_epi32(a.res_c);
    const __m128i stride_b = _mm_set1_epi32(a.stride_b), stride_c = _mm_set1_epi32(a.stride_c);
    const __m128i dbase4 = _mm_set1_epi32(4 * a.dbase);
    __m128i base =
        _mm_add_epi32(_mm_set1_epi32(a.base0),
                      _mm_mullo_epi32(_mm_setr_epi32(0, 1, 2, 3), _mm_set1_epi32(a.dbase)));
    __m256d kd = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
    const __m256d four = _mm256_set1_pd(4.0);
    __m256d sum = _mm256_setzero_pd();
    const __m128i lanes = _mm_setr_epi32(0, 1, 2, 3);
    for (int k = 0; k < count; k += 4) {
        const __m128 live = _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_set1_epi32(count - k), lanes));
        const __m128i cb = _mm_min_epi32(
            _mm_max_epi32(_mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_fmadd_pd(kd, dub, ub))), lo),
            hi_b);
        const __m128i cc = _mm_min_epi32(
            _mm_max_epi32(_mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_fmadd_pd(kd, duc, uc))), lo),
            hi_c);
        const __m128i index = _mm_add_epi32(
            base, _mm_add_epi32(_mm_mullo_epi32(cb, stride_b), _mm_mullo_epi32(cc, stride_c)));
        const __m128 zero = _mm_setzero_ps();
        const __m128 jump = _mm_sub_ps(_mm_mask_i32gather_ps(zero, after, index, live, 4),
                                       _mm_mask_i32gather_ps(zero, before, index, live, 4));
        sum = _mm256_fmadd_pd(_mm256_fmadd_pd(kd, dt, t0), _mm256_cvtps_pd(jump), sum);
        base = _mm_add_epi32(base, dbase4);
        kd = _mm256_add_pd(kd, four);
    }
    const __m128d pair = _mm_add_pd(_mm256_castpd256_pd128(sum), _mm256_extractf128_pd(sum, 1));
    return _mm_cvtsd_f64(_mm_add_sd(pair, _mm_unpackhi_pd(pair, pair)));
}

}  // namespace
#endif

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
    const glm::dvec3 u0 = (glm::dvec3(o) - glm::dvec3(min_)) * march_inv_voxel_;
    const glm::dvec3 du = glm::dvec3(d) * march_inv_voxel_;
    const ivec3 res = march_res_, padded = march_res_ + 2;
    const long axis_stride[3] = {1, long(padded.x), long(padded.x) * padded.y};
    const float* voxels = march_voxels_.data();
    // Cells -1 and res are the empty border: where float rounding puts the box's faces past
    // the voxels' (march() does the same).
    auto cell = [&](double t, int a) {
        return std::clamp(int(std::floor(u0[a] + t * du[a])), -1, res[a]);
    };
    const double margin = 1e-9 * (tb - ta);
    ivec3 first, last;
    for (int a = 0; a < 3; ++a) {
        first[a] = cell(ta + margin, a);
        last[a] = cell(tb - margin, a);
    }
    auto index = [&](int x, int y, int z) {
        return (x + 1) * axis_stride[0] + (y + 1) * axis_stride[1] + (z + 1) * axis_stride[2];
    };
    double sum = (tb - ta) * double(voxels[index(last.x, last.y, last.z)]);
    for (int a = 0; a < 3; ++a) {
        const int n = std::abs(last[a] - first[a]);
        if (n == 0) continue;
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const int step = last[a] > first[a] ? 1 : -1;
        // Plane q (between cells q - 1 and q) is crossed from the cell before to the one after;
        // the k-th crossing's time and the other axes' coordinates are linear in k.
        const int q0 = step > 0 ? first[a] + 1 : first[a];
        const double inv_du = 1.0 / du[a];
        const double t0 = (double(q0) - u0[a]) * inv_du, dt = double(step) * inv_du;
        const double ub = u0[b] + t0 * du[b], dub = dt * du[b];
        const double uc = u0[c] + t0 * du[c], duc = dt * du[c];
        const int res_b = res[b], res_c = res[c];
        const long stride_b = axis_stride[b], stride_c = axis_stride[c];
        const long before_offset = step > 0 ? -axis_stride[a] : 0;
        const long after_offset = step > 0 ? 0 : -axis_stride[a];
        const long base0 = (q0 + 1) * axis_stride[a] + stride_b + stride_c;
        const long dbase = step * axis_stride[a];
        double jumps = 0.0;
        int k = 0;
#if defined(__AVX2__)
        // Four crossings a step (AVX2 gathers of their two voxels); the scalar loop stays for
        // builds without AVX2.
        if (int32_indices_) {
            const JumpAxis axis{t0 - ta,
                                dt,
                                ub,
                                dub,
                                uc,
                                duc,
                                res_b,
                                res_c,
                                int(stride_b),
                                int(stride_c),
                                int(base0),
                                int(dbase),
                                int(before_offset),
                                int(after_offset)};
            k = n;
            jumps = sum_jumps_avx2(axis, voxels, n);
        }
#endif
        for (; k < n; ++k) {
            const double kd = double(k);
            const int cb = std::clamp(int(std::floor(ub + kd * dub)), -1, res_b);
            const int cc = std::clamp(int(std::floor(uc + kd * duc)), -1, res_c);
            const long base = base0 + k * dbase + cb * stride_b + cc * stride_c;
            jumps += (t0 + kd * dt - ta) *
                     double(voxels[base + after_offset] - voxels[base + before_offset]);
        }
        sum -= jumps;
    }
    return sum;
}

float DensityGrid::at(const vec3& p) const {
    const vec3 rel = (p - min_) / voxel_;
    if (rel.x < 0 || rel.y < 0 || rel.z < 0 || rel.x >= res_.x || rel.y >= res_.y ||
        rel.z >= res_.z)
        return 0.0f;
    const ivec3 c = glm::min(ivec3(rel), res_ - 1);
    return voxels_[(size_t(c.z) * res_.y + c.y) * res_.x + c.x];
}

HomogeneousMedium SegmentOptics::effective() const {
    if (length <= 0.0) return {0.0, 0.0, 0.0};
    return {tau_s / length, tau_a / length, tau_s > 0.0 ? tau_gs / tau_s : 0.0};
}

namespace {

double procedural_density(const MediumDesc& m, const vec3& p) {
    switch (m.density) {
        case DensitySource::Noise: {
            const double n = fbm(m.seed, m.frequency, m.octaves, glm::dvec3(p));
            return std::max(0.0, n - m.threshold) / (1.0 - m.threshold);
        }
        case DensitySource::HeightFog:
            return p.z <= m.base ? 1.0 : std::exp(-(p.z - m.base) / m.falloff);
        case DensitySource::Brushes: {
            double d = 0.0;
            for (const DensityBrush& b : m.brushes) {
                const vec3 q = (p - b.center) / b.half_size;
                const bool inside = b.shape == DensityBrush::Shape::Box
                                        ? glm::all(glm::lessThanEqual(glm::abs(q), vec3(1.0f)))
                                        : glm::dot(q, q) <= 1.0f;
                if (inside) d += b.density;
            }
            return d;
        }
        default:
            return 1.0;
    }
}

std::shared_ptr<const DensityGrid> sample_grid(const MediumDesc& m) {
    const ivec3 res = m.resolution;
    std::vector<float> voxels(size_t(res.x) * res.y * res.z);
    const vec3 size = (m.box_max - m.box_min) / vec3(res);
    tbb::parallel_for(0, res.z, [&](int z) {
        for (int y = 0; y < res.y; ++y)
            for (int x = 0; x < res.x; ++x) {
                const vec3 p = m.box_min + (vec3(x, y, z) + 0.5f) * size;
                voxels[(size_t(z) * res.y + y) * res.x + x] = float(procedural_density(m, p));
            }
    });
    return std::make_shared<DensityGrid>(m.box_min, m.box_max, res, std::move(voxels));
}

}  // namespace

Media::Media(const std::vector<MediumDesc>& descs, const std::string& scene_file) {
    for (size_t i = 0; i < descs.size(); ++i) {
        Entry e{descs[i], nullptr};
        if (e.desc.density == DensitySource::Vdb) {
            const std::string field = "media[" + std::to_string(i) + "].density";
            VdbDensity vdb = read_vdb_density(e.desc.vdb_file, e.desc.vdb_grid, scene_file, field);
            e.desc.bounds = MediumBounds::Box;
            e.desc.box_min = vdb.box_min;
            e.desc.box_max = vdb.box_max;
            e.desc.resolution = vdb.resolution;
            e.grid = std::make_shared<DensityGrid>(vdb.box_min, vdb.box_max, vdb.resolution,
                                                   std::move(vdb.voxels));
        } else if (e.desc.is_grid()) {
            e.grid = sample_grid(e.desc);
        }
        e.grid_is_bounds = e.grid && e.desc.bounds == MediumBounds::Box &&
                           e.grid->box_min() == e.desc.box_min &&
                           e.grid->box_max() == e.desc.box_max;
        media_.push_back(std::move(e));
    }
    // The union of the media's bounds, where all are boxes or spheres.
    bounded_ = !media_.empty();
    union_min_ = vec3(std::numeric_limits<float>::max());
    union_max_ = vec3(-std::numeric_limits<float>::max());
    for (const Entry& e : media_) {
        vec3 lo, hi;
        if (e.desc.bounds == MediumBounds::Box) {
            lo = e.desc.box_min;
            hi = e.desc.box_max;
        } else if (e.desc.bounds == MediumBounds::Sphere) {
            lo = e.desc.center - vec3(e.desc.radius);
            hi = e.desc.center + vec3(e.desc.radius);
        } else {
            bounded_ = false;
            break;
        }
        union_min_ = glm::min(union_min_, lo);
        union_max_ = glm::max(union_max_, hi);
    }
}

void Media::set_coefficients(size_t i, double sigma_s, double sigma_a, double g, double scale) {
    MediumDesc& d = media_.at(i).desc;
    d.sigma_s = sigma_s;
    d.sigma_a = sigma_a;
    d.g = g;
    d.density_scale = scale;
    ++version_;
}

bool Media::clip(const Entry& e, const vec3& o, const vec3& d, double t_max, double* t0,
                 double* t1) const {
    *t0 = 0.0;
    *t1 = t_max;
    switch (e.desc.bounds) {
        case MediumBounds::Everywhere:
            return t_max > 0.0;
        case MediumBounds::Box:
            return clip_to_box(e.desc.box_min, e.desc.box_max, o, d, t0, t1);
        case MediumBounds::Sphere: {
            const glm::dvec3 oc = glm::dvec3(o) - glm::dvec3(e.desc.center);
            const double b = glm::dot(oc, glm::dvec3(d));
            const double c = glm::dot(oc, oc) - double(e.desc.radius) * e.desc.radius;
            const double disc = b * b - c;
            if (disc <= 0.0) return false;
            const double s = std::sqrt(disc);
            *t0 = std::max(0.0, -b - s);
            *t1 = std::min(t_max, -b + s);
            return *t1 > *t0;
        }
    }
    return false;
}

HomogeneousMedium Media::at(const vec3& p) const {
    HomogeneousMedium sum{0.0, 0.0, 0.0};
    double gs = 0.0;
    for (const Entry& e : media_) {
        bool inside = true;
        if (e.desc.bounds == MediumBounds::Box)
            inside = glm::all(glm::greaterThanEqual(p, e.desc.box_min)) &&
                     glm::all(glm::lessThanEqual(p, e.desc.box_max));
        else if (e.desc.bounds == MediumBounds::Sphere)
            inside = glm::distance(p, e.desc.center) <= e.desc.radius;
        if (!inside) continue;
        const double density = (e.grid ? e.grid->at(p) : 1.0) * e.desc.density_scale;
        sum.sigma_s += e.desc.sigma_s * density;
        sum.sigma_a += e.desc.sigma_a * density;
        gs += e.desc.g * e.desc.sigma_s * density;
    }
    sum.g = sum.sigma_s > 0.0 ? gs / sum.sigma_s : 0.0;
    return sum;
}

namespace {

// a x b where 0 x inf is 0: a medium whose coefficient (or density scale) is 0 adds nothing to
// an unbounded segment (a slider dragged to 0 on a medium without bounds), not NaN.
double times(double a, double b) {
    return a == 0.0 || b == 0.0 ? 0.0 : a * b;
}

// A medium's share of a segment's optics from the integral of its (unscaled) density.
void add_medium(const MediumDesc& m, double density_length, SegmentOptics& s) {
    const double scaled = times(density_length, m.density_scale);
    const double tau_s = times(m.sigma_s, scaled);
    if (tau_s > 0.0) ++s.scattering_media;
    s.tau_s += tau_s;
    s.tau_a += times(m.sigma_a, scaled);
    s.tau_gs += times(m.g * m.sigma_s, scaled);
}

}  // namespace

Media::SegmentBox Media::segment_box(const vec3& o, const vec3& d, double t_max) const {
    SegmentBox b;
    if (media_.size() < 2) return b;
    double t_end = t_max;
    if (!std::isfinite(t_max)) {
        // A ray to infinity crosses media only inside their union: it ends where it leaves it.
        if (!bounded_) return b;
        double t0 = 0.0, t1 = t_max;
        if (!clip_to_box(union_min_, union_max_, o, d, &t0, &t1)) {
            b.active = b.misses_all = true;
            return b;
        }
        t_end = t1;
    }
    const vec3 end = o + d * float(t_end);
    // Padded by the float rounding of `end` (the slab tests run in double).
    const vec3 ao = glm::abs(o);
    const float pad = 1e-5f * (std::max({ao.x, ao.y, ao.z}) + float(t_end) + 1.0f);
    b.active = true;
    b.lo = glm::min(o, end) - pad;
    b.hi = glm::max(o, end) + pad;
    return b;
}

bool Media::SegmentBox::misses(const MediumDesc& desc) const {
    if (!active) return false;
    if (misses_all) return true;
    return desc.bounds == MediumBounds::Box && (glm::any(glm::lessThan(hi, desc.box_min)) ||
                                                glm::any(glm::greaterThan(lo, desc.box_max)));
}

SegmentOptics Media::integrate(const vec3& o, const vec3& d, double t_max) const {
    SegmentOptics s;
    double exit = 0.0;
    // The segment's bounds first: most of a scene's boxes (valley's ten smoke volumes) lie off
    // a segment, and six comparisons reject them before the slab test's divisions.
    const SegmentBox box = segment_box(o, d, t_max);
    for (const Entry& e : media_) {
        if (box.misses(e.desc)) continue;
        double t0, t1;
        if (!clip(e, o, d, t_max, &t0, &t1)) continue;
        exit = std::max(exit, t1);
        double density_length = 0.0;  // integral of the density over the segment
        if (e.grid)
            density_length = e.grid->integral(o, d, t0, t1, e.grid_is_bounds);
        else
            density_length = t1 - t0;
        add_medium(e.desc, density_length, s);
    }
    s.length = std::isfinite(t_max) ? t_max : exit;
    return s;
}

SegmentOptics Media::track(const vec3& o, const vec3& d, double t_max, CounterRng& rng) const {
    SegmentOptics s;
    s.tau_t_exact = 0.0;
    double exit = 0.0;
    for (const Entry& e : media_) {
        double t0, t1;
        if (!clip(e, o, d, t_max, &t0, &t1)) continue;
        exit = std::max(exit, t1);
        const double mu = (e.desc.sigma_s + e.desc.sigma_a) * e.desc.density_scale;
        double density_length = 0.0;
        if (!e.grid) {
            density_length = t1 - t0;
            s.tau_t_exact += times(mu, density_length);
        } else {
            const double rho_max = e.grid->max_value();
            const double rate = mu * rho_max;
            double ta = t0, tb = t1;
            if (rate > 0.0 && clip_to_box(e.grid->box_min(), e.grid->box_max(), o, d, &ta, &tb)) {
                double sum = 0.0, ratio = 1.0;
                for (double t = ta - std::log1p(-rng.next_double()) / rate; t < tb;
                     t -= std::log1p(-rng.next_double()) / rate) {
                    const double rho = e.grid->at(o + d * float(t));
                    sum += rho;
                    ratio *= 1.0 - rho / rho_max;
                }
                density_length = sum / rate;  // of the unscaled density
                s.tracked_ratio *= ratio;
            }
        }
        add_medium(e.desc, density_length, s);
    }
    s.length = std::isfinite(t_max) ? t_max : exit;
    return s;
}

double Media::exit_distance(const vec3& o, const vec3& d) const {
    double exit = 0.0;
    const SegmentBox box = segment_box(o, d, std::numeric_limits<double>::infinity());
    for (const Entry& e : media_) {
        double t0, t1;
        if (e.desc.bounds == MediumBounds::Everywhere)
            return std::numeric_limits<double>::infinity();
        if (box.misses(e.desc)) continue;
        if (clip(e, o, d, std::numeric_limits<double>::infinity(), &t0, &t1))
            exit = std::max(exit, t1);
    }
    return exit;
}

}  // namespace freqlab
