#include "volume/media.h"

#include <tbb/parallel_for.h>

#include "base/error.h"
#include "math/noise.h"
#include "volume/vdb_reader.h"

namespace freqlab {

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
