// Free-flight collisions through a scene's media (Media, media.h): the analog draw of every
// walk segment, and the forced first collision of impulse's texel walks (bake_walk.cpp) and of
// its lit-medium points for distant lights (bake_lit_medium.cpp).
//
// A forced collision is drawn from the law conditioned on a collision before t_max, with
// density sigma_t(t) T(t) / P, P = 1 - T(t_max), weight P: the total optical thickness
// tau(t) = sum over media of tau_m(t) is inverted at -log(1 - u P), and the medium collided
// with is the one whose sigma_t at that point a second uniform picks (sigma_t,m / sigma_t; the
// analog draw's law, where each medium's own flight is exponential in its own thickness).
// The first version drew analog flights up to 8 times when several media were present, weight
// P / (1 - (1 - P)^8): in valley's 0.03-unit gaps under houses (P ~ 2e-4) one walk in ~600
// collided and carried ~1/8 instead of P, a second moment 1 / (8 P) ~ 600x the inverted law's,
// before bake.texel_mc_rate's 1 / 0.02 multiplied it again.
//
// | step                         | how                                                      |
// |------------------------------|----------------------------------------------------------|
// | media crossed                | slab tests after the segment's bounds (segment_box)      |
// | intervals                    | between the crossings' sorted ends: a fixed set of media |
// | thickness of an interval     | exact: k x length, or the grid's density integral        |
// | the point, one medium active | collide() (its march stops at the voxel)                 |
// | the point, homogeneous media | closed form                                              |
// | the point, grids overlapping | TOMS 748 on the summed thickness (Boost.Math), 48 bits   |
#include <algorithm>
#include <boost/math/tools/roots.hpp>
#include <cmath>

#include "volume/media.h"

namespace freqlab {

namespace {

// sigma_t per unit of the grid's density (1 for a homogeneous medium).
double extinction_scale(const MediumDesc& m) {
    return (m.sigma_s + m.sigma_a) * m.density_scale;
}

}  // namespace

bool Media::collide(const Entry& e, const vec3& o, const vec3& d, double t0, double t1,
                    double target, MediumCollision* out) const {
    const double sigma_t = e.desc.sigma_s + e.desc.sigma_a;
    const double k = extinction_scale(e.desc);
    if (!(k > 0.0)) return false;
    double hit = -1.0, density = 1.0;
    if (e.grid) {
        double acc = 0.0;
        // Stops at the voxel where the thickness is reached.
        e.grid->march(o, d, t0, t1, [&](double a, double b, float v) {
            if (v <= 0.0f) return true;
            const double tau = (b - a) * v * k;
            if (acc + tau < target) {
                acc += tau;
                return true;
            }
            hit = a + (target - acc) / (v * k);
            density = v;
            return false;
        });
    } else if ((t1 - t0) * k >= target) {
        hit = t0 + target / k;
    }
    if (hit < 0.0) return false;
    out->happened = true;
    out->t = hit;
    out->sigma_t = sigma_t * density * e.desc.density_scale;
    out->sigma_t_all = out->sigma_t;
    out->sigma_s = e.desc.sigma_s * density * e.desc.density_scale;
    out->g = e.desc.g;
    return true;
}

MediumCollision Media::sample_collision(const vec3& o, const vec3& d, double t_max,
                                        CounterRng& rng) const {
    MediumCollision best;
    best.t = t_max;
    const SegmentBox box = segment_box(o, d, t_max);
    for (const Entry& e : media_) {
        // One uniform per medium whether or not it is crossed: the stream stays aligned.
        const double target = -std::log1p(-rng.next_double());
        if (box.misses(e.desc)) continue;
        double t0, t1;
        MediumCollision c;
        if (clip(e, o, d, std::min(t_max, best.t), &t0, &t1) &&
            collide(e, o, d, t0, t1, target, &c) && c.t < best.t)
            best = c;
    }
    return best;
}

double Media::thickness(const Entry& e, const vec3& o, const vec3& d, double t0, double t1) const {
    const double k = extinction_scale(e.desc);
    if (!(k > 0.0) || !(t1 > t0)) return 0.0;
    return k * (e.grid ? e.grid->integral(o, d, t0, t1, e.grid_is_bounds) : t1 - t0);
}

MediumCollision Media::collide_mixture(const std::vector<const Entry*>& active, const vec3& o,
                                       const vec3& d, double a, double b, double target,
                                       double u_pick) const {
    // The point where the active media's summed thickness from a reaches target.
    bool homogeneous = true;
    double k_sum = 0.0;
    for (const Entry* e : active) {
        homogeneous = homogeneous && !e->grid;
        k_sum += extinction_scale(e->desc);
    }
    double t = 0.0;
    if (homogeneous) {
        t = std::min(b, a + target / k_sum);
    } else {
        const auto excess = [&](double s) {
            double sum = 0.0;
            for (const Entry* e : active) sum += thickness(*e, o, d, a, s);
            return sum - target;
        };
        // The caller found the summed thickness over [a, b] at least target, but the same sum
        // may round a hair below it: the point is then b (TOMS 748 needs a sign change).
        const double at_b = excess(b);
        if (at_b <= 0.0) {
            t = b;
        } else {
            boost::uintmax_t iterations = 64;
            const std::pair<double, double> root = boost::math::tools::toms748_solve(
                excess, a, b, -target, at_b, boost::math::tools::eps_tolerance<double>(48),
                iterations);
            t = 0.5 * (root.first + root.second);
        }
    }
    // The medium collided with: in proportion to its sigma_t at the point.
    const vec3 x = o + d * float(t);
    double total = 0.0;
    thread_local std::vector<double> sigma;
    sigma.clear();
    for (const Entry* e : active) {
        const double density = (e->grid ? double(e->grid->at(x)) : 1.0) * e->desc.density_scale;
        sigma.push_back((e->desc.sigma_s + e->desc.sigma_a) * density);
        total += sigma.back();
    }
    MediumCollision c;
    if (!(total > 0.0)) return c;  // on a voxel face between empty voxels: rounding
    double pick = u_pick * total;
    size_t m = 0;
    while (m + 1 < active.size() && pick >= sigma[m]) pick -= sigma[m++];
    const MediumDesc& desc = active[m]->desc;
    const double scale = sigma[m] / (desc.sigma_s + desc.sigma_a);  // density x density_scale
    c.happened = true;
    c.t = t;
    c.sigma_t = sigma[m];
    c.sigma_t_all = total;
    c.sigma_s = desc.sigma_s * scale;
    c.g = desc.g;
    return c;
}

MediumCollision Media::sample_forced_collision(const vec3& o, const vec3& d, double t_max,
                                               CounterRng& rng, double* weight) const {
    *weight = 0.0;
    const double p = 1.0 - transmittance(o, d, t_max);
    if (!(p > 0.0)) return {};
    const double target = -std::log1p(-rng.next_double() * p);
    if (!(target > 0.0)) return {};  // u P rounded to 0
    // The media the segment crosses and where.
    struct Crossing {
        const Entry* entry;
        double t0, t1;
    };
    thread_local std::vector<Crossing> crossings;
    thread_local std::vector<double> ends;
    crossings.clear();
    ends.clear();
    const SegmentBox box = segment_box(o, d, t_max);
    for (const Entry& e : media_) {
        double t0, t1;
        if (box.misses(e.desc) || !clip(e, o, d, t_max, &t0, &t1)) continue;
        crossings.push_back({&e, t0, t1});
        ends.push_back(t0);
        ends.push_back(t1);
    }
    std::sort(ends.begin(), ends.end());
    ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
    // Interval by interval (a fixed set of media in each) until the thickness reaches target.
    thread_local std::vector<const Entry*> active;
    double reached = 0.0;
    for (size_t i = 0; i + 1 < ends.size(); ++i) {
        const double a = ends[i], b = ends[i + 1];
        active.clear();
        double tau = 0.0;
        for (const Crossing& c : crossings)
            if (c.t0 <= a && c.t1 >= b) {
                active.push_back(c.entry);
                tau += thickness(*c.entry, o, d, a, b);
            }
        if (reached + tau < target) {
            reached += tau;
            continue;
        }
        const double rest = target - reached;
        MediumCollision c;
        if (active.size() == 1) {
            if (!collide(*active[0], o, d, a, b, rest, &c)) return {};  // short by rounding
        } else {
            c = collide_mixture(active, o, d, a, b, rest, rng.next_double());
            if (!c.happened) return {};
        }
        *weight = p;
        c.pdf = c.sigma_t_all * std::exp(-target) / p;
        return c;
    }
    return {};  // the thickness short of target by rounding
}

}  // namespace freqlab
