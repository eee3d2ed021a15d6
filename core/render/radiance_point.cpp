#include "render/radiance_point.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "freq/brdf_footprint.h"
#include "freq/covariance.h"
#include "math/sampling.h"

namespace freqlab {

namespace {

// sqrt(E[theta^2] / 2) for the cosine-weighted hemisphere: E[theta^2] = pi^2 / 4 - 1.
const double kLambertSigma = std::sqrt(0.5 * (kPiD * kPiD / 4.0 - 1.0));

double phong_like_exponent(const Material& m) {
    switch (m.type) {
        case BrdfType::Phong:
            return m.phong_exponent;
        case BrdfType::Beckmann:
        case BrdfType::Ggx:
            return phong_exponent_of_roughness(m.roughness);
        default:
            return 1.0;
    }
}

// mu_rho: the mirror direction of a glossy lobe, the normal for the whole hemisphere.
glm::dvec3 footprint_axis(const ShadingPoint& sp, const BrdfFootprint& footprint) {
    return footprint.whole_hemisphere ? glm::dvec3(sp.shading_normal)
                                      : glm::dvec3(reflect_about(sp.wo, sp.shading_normal));
}

void frame_of(const glm::dvec3& n, glm::dvec3& t, glm::dvec3& b) {
    t = glm::normalize(std::fabs(n.z) < 0.9 ? glm::cross(glm::dvec3(0, 0, 1), n)
                                            : glm::cross(glm::dvec3(1, 0, 0), n));
    b = glm::cross(n, t);
}

template <class... Args>
void say(std::vector<std::string>* chain, const char* format, Args... args) {
    if (!chain) return;
    char buf[512];
    std::snprintf(buf, sizeof buf, format, args...);
    chain->push_back(buf);
}

// Eq. 4.3's extra samples at x = sigma_V / sigma_rho; `room` = N_max - N_L.
double extra_samples(double x, int room) {
    return room * std::exp(-0.5 * (x - 0.5) * (x - 0.5));
}

void say_matrix(std::vector<std::string>* chain, const char* name, const Mat2& m) {
    say(chain, "  %-16s [[%.6g, %.6g], [%.6g, %.6g]]", name, m[0][0], m[1][0], m[0][1], m[1][1]);
}

}  // namespace

double screen_space_curvature(const SurfaceHit& c, const SurfaceHit* neighbours, int count) {
    double k = 0.0;
    for (int i = 0; i < count; ++i) {
        const SurfaceHit& o = neighbours[i];
        if (!o.valid || o.object != c.object) continue;
        const double dp = glm::length(glm::dvec3(o.position - c.position));
        if (dp <= 0) continue;
        k = std::max(k, glm::length(glm::dvec3(o.shading_normal - c.shading_normal)) / dp);
    }
    return k;
}

RadiancePointIntegrator::RadiancePointIntegrator(const RayScene& scene,
                                                 const ShadingSettings& shading,
                                                 const PointsSettings& settings,
                                                 const EnvBandwidthHierarchy* bandwidth)
    : scene_(scene),
      lighting_(scene, shading, sample_sequence(settings.stratified)),
      settings_(settings),
      bandwidth_(bandwidth) {
    const double radius = 0.5 * glm::length(glm::dvec3(scene.bounds_max() - scene.bounds_min()));
    large_distance_ = settings.large_distance * std::max(radius, 1e-3);
    mirror_depth_ = shading.mirror_depth;
    const EnvironmentMap *base = scene.scene().environment(), *now = scene.environment();
    if (base && now) {
        environment_spin_ = glm::radians(double(base->spin_deg_per_s()));
        environment_turned_ = glm::radians(double(now->rotation_deg()) - base->rotation_deg());
    }
}

RadiancePoint RadiancePointIntegrator::integrate_hit(const SurfaceHit& first, const vec3& first_wo,
                                                     const PointContext& context, CounterRng& rng,
                                                     const VisibilityPlan* plan) const {
    const MirrorPath path = follow_mirrors(first, first_wo);
    if (!path.hit.valid) {
        RadiancePoint rp;
        rp.rays = path.rays;
        if (path.escaped) {
            const EnvironmentMap* env = scene_.environment();
            rp.radiance = path.throughput * (env ? env->eval_smooth(-path.wo) : vec3(0.0f));
        }
        return rp;
    }
    PointContext ctx = context;
    if (path.bounces > 0) {
        ctx.curvature = 0.0;  // the screen-space estimate was the mirror's
        ctx.eye_distance += path.extra_distance;
        ctx.object = path.hit.object;
    }
    // A plan describes the pixel's own surface: not the one its mirrors show.
    RadiancePoint rp = integrate(lighting_.shading_point(path.hit, path.wo), ctx, rng, nullptr,
                                 path.bounces == 0 ? plan : nullptr);
    rp.radiance *= path.throughput;
    rp.variance *= luminance(path.throughput) * luminance(path.throughput);
    rp.rays += path.rays;
    return rp;
}

MirrorPath RadiancePointIntegrator::follow_mirrors(const SurfaceHit& first,
                                                   const vec3& first_wo) const {
    MirrorPath path;
    path.hit = first;
    path.wo = first_wo;
    for (int depth = 0;; ++depth) {
        const ShadingPoint sp = lighting_.shading_point(path.hit, path.wo);
        if (sp.material->type != BrdfType::Mirror) return path;
        path.hit.valid = false;
        if (depth >= mirror_depth_) return path;
        const vec3 r = reflect_about(path.wo, sp.shading_normal);
        if (glm::dot(r, sp.geometric_normal) <= 0.0f) return path;
        path.throughput *= sp.albedo;
        const Ray ray{lighting_.offset_origin(sp.position, sp.geometric_normal), r};
        path.hit = scene_.intersect(ray);
        ++path.rays;
        ++path.bounces;
        path.wo = -r;
        if (!path.hit.valid) {
            path.escaped = true;
            return path;
        }
        path.extra_distance += path.hit.distance;
    }
}

RadiancePoint RadiancePointIntegrator::integrate(const ShadingPoint& sp, const PointContext& ctx,
                                                 CounterRng& rng, std::vector<std::string>* chain,
                                                 const VisibilityPlan* plan) const {
    RadiancePoint rp;
    const Material& material = *sp.material;
    const BrdfFootprint footprint = brdf_footprint(material);
    const glm::dvec3 mu = footprint_axis(sp, footprint);
    const double radius = footprint.query_radius();
    rp.footprint_radius = radius;
    rp.sigma_rho = footprint.whole_hemisphere ? kLambertSigma : std::atan(footprint.sigma);
    rp.B_L = bandwidth_ ? bandwidth_->query(to_map_frame(vec3(mu)), radius) : 0.0;
    const double b_cone = rp.B_L * 2.0 * radius;
    const int n_max = std::max(settings_.max_samples, 2);
    int n_l = int(std::ceil(4.0 * b_cone * b_cone));
    const int pilot_max = std::clamp(settings_.max_pilot, 2, n_max);
    n_l = std::clamp(n_l, std::min(settings_.min_samples, pilot_max), pilot_max);
    n_l += n_l % 2;
    n_l = std::min(n_l, n_max);
    rp.N_L = n_l;
    say(chain,
        "footprint: %s, mu_rho = (%.4f, %.4f, %.4f), query radius %.4f rad, sigma_rho %.5f rad",
        footprint.whole_hemisphere ? "whole hemisphere" : "Phong-like lobe", mu.x, mu.y, mu.z,
        radius, rp.sigma_rho);
    say(chain,
        "B_L = %.5g cycles/rad -> %.4g cycles across the footprint -> N_L = 4 B^2 = %d "
        "(clamped to [%d, %d])",
        rp.B_L, b_cone, n_l, settings_.min_samples, pilot_max);

    // The samples the visibility statistics are gathered on: a pilot of N_L MIS samples, or,
    // with a plan, the first N_L of the planned estimate's own samples (the same distribution).
    std::vector<DirectLighting::CastSample> cast;
    int n_omega = n_l;
    if (plan) {
        const double f_v = planned_extra_samples(*plan, rp.sigma_rho, n_max - n_l);
        n_omega = std::min(n_max, n_l + int(std::lround(f_v)));
        say(chain,
            "planned from neighbours: occluded fraction %.3f, sigma_V %.5f rad -> f_V = %.2f, "
            "N_Omega = %d (no pilot)",
            plan->occluded_fraction, plan->sigma_V, f_v, n_omega);
    }
    // With a plan this is the point's whole estimate; without, its pilot.
    const RadianceEstimate first = lighting_.estimate(sp, n_omega, rng, &cast);
    rp.rays += first.rays;
    if (plan) {
        const int n_env = (n_l + 1) / 2, n_brdf = n_l / 2;
        cast.erase(std::remove_if(cast.begin(), cast.end(),
                                  [&](const DirectLighting::CastSample& c) {
                                      return c.unit >= (c.brdf_strategy ? n_brdf : n_env);
                                  }),
                   cast.end());
    }
    rp.pilot_rays = int(cast.size());
    const bool distances = !plan || plan->own_distances || !(plan->occluded_fraction > 0.0);
    const double f_v = visibility_statistics(sp, ctx, mu, cast, distances, rp, chain);
    if (!distances) {
        const bool occluded = rp.pilot_occluded > 0;
        rp.t_min = occluded ? plan->t_min_occluded : large_distance_;
        rp.B_t = occluded ? plan->B_t_occluded : 0.0;
        say(chain, "t_min %.5g and B_t %.5g (1/s) from the occluded neighbours", rp.t_min, rp.B_t);
    }
    if (!plan) n_omega = std::min(n_max, n_l + int(std::lround(f_v)));
    if (environment_spin_ != 0.0) {
        // Egan et al.'s lighting term: the environment turning at omega moves the lighting in
        // the footprint at most that fast; B_t is the larger of the two terms (seed §5.2).
        const double lighting = std::abs(environment_spin_) * rp.B_L;
        rp.B_t = std::max(rp.B_t, lighting);
        say(chain, "environment spins at %.4g rad/s: |omega| B_L = %.5g -> B_t = %.5g (1/s)",
            environment_spin_, lighting, rp.B_t);
    }
    rp.N_omega = n_omega;
    say(chain,
        plan ? "N_Omega = %d as planned (the f_V above is the point's own, not used)"
             : "N_Omega = min(N_max, N_L + f_V) = %d",
        n_omega);

    // The estimate (see the header on reuse_pilot and plans).
    if (plan) {
        rp.radiance = first.radiance;
        rp.variance = first.variance;
    } else if (settings_.reuse_pilot) {
        const RadianceEstimate& pilot = first;
        const int extra = n_omega - n_l;
        if (extra > 0) {
            const RadianceEstimate more = lighting_.estimate(sp, extra, rng);
            rp.rays += more.rays;
            const float a = float(n_l) / n_omega, c = 1.0f - a;
            rp.radiance = a * pilot.radiance + c * more.radiance;
            rp.variance = a * a * pilot.variance + c * c * more.variance;
        } else {
            rp.radiance = pilot.radiance;
            rp.variance = pilot.variance;
        }
    } else {
        const RadianceEstimate e = lighting_.estimate(sp, n_omega, rng);
        rp.rays += e.rays;
        rp.radiance = e.radiance;
        rp.variance = e.variance;
    }
    say(chain, "estimate (%.6g, %.6g, %.6g), variance %.4g, %ld rays in all", rp.radiance.x,
        rp.radiance.y, rp.radiance.z, rp.variance, rp.rays);

    const PointBandwidths bands = bandwidths(sp, ctx, rp.B_L, rp.t_min, chain);
    rp.B_S = bands.B_S;
    rp.B_x = bands.B_x;
    rp.B_theta = bands.B_theta;
    return rp;
}

double planned_extra_samples(const VisibilityPlan& plan, double sigma_rho, int room) {
    if (!(plan.occluded_fraction > 0.0) || room <= 0) return 0.0;
    const double fraction = std::min(plan.occluded_fraction, 1.0);
    // The upsampled sigma_V averages unoccluded neighbours' zeros in: divided by the occluded
    // fraction it is the occluded neighbours' mean, the value a pilot here would see if it
    // found occlusion; that happens about `fraction` of the time.
    return fraction * extra_samples(plan.sigma_V / fraction / sigma_rho, room);
}

double RadiancePointIntegrator::visibility_statistics(
    const ShadingPoint& sp, const PointContext& ctx, const glm::dvec3& mu,
    const std::vector<DirectLighting::CastSample>& cast, bool distances, RadiancePoint& rp,
    std::vector<std::string>* chain) const {
    const Material& material = *sp.material;
    const int n_max = std::max(settings_.max_samples, 2);
    const int n_l = int(rp.N_L);
    const Brdf brdf(material, sp.albedo, sp.shading_normal);
    glm::dvec3 t, b;
    frame_of(mu, t, b);
    double a_o = 0.0, w_all = 0.0, nearest = INFINITY;
    glm::dvec2 mean_q(0.0);
    glm::dvec3 mean_p(0.0);
    struct Occluder {
        glm::dvec2 q;
        glm::dvec3 p;
        double w;
        double angular_speed;  // rad/s, relative to the receiver
    };
    const Scene& scene = scene_.scene();
    const glm::dvec3 receiver_velocity =
        ctx.object >= 0 ? glm::dvec3(scene.objects[size_t(ctx.object)].animation.velocity_of(
                              sp.position, ctx.time))
                        : glm::dvec3(0.0);
    std::vector<Occluder> occluders;
    for (const auto& c : cast) {
        const glm::dvec3 d(c.ray.direction);
        const double w = std::max(double(brdf.pdf(sp.wo, c.ray.direction)), 0.0);
        const double theta = std::acos(std::clamp(glm::dot(d, mu), -1.0, 1.0));
        const glm::dvec2 tb(glm::dot(d, t), glm::dot(d, b));
        const double len = glm::length(tb);
        const glm::dvec2 q = len > 0 ? theta * tb / len : glm::dvec2(0.0);
        rp.cone_samples.push_back({float(q.x), float(q.y), c.occluded});
        w_all += w;
        if (!c.occluded) continue;
        ++rp.pilot_occluded;
        a_o += w;
        mean_q += w * q;
        if (!distances) {
            occluders.push_back({q, glm::dvec3(0.0), w, 0.0});
            continue;
        }
        // The occluder's hit point (one more ray: occlusion rays do not report distances).
        const SurfaceHit hit = scene_.intersect(c.ray);
        ++rp.rays;
        const double dist = hit.valid ? hit.distance : large_distance_;
        nearest = std::min(nearest, dist);
        const glm::dvec3 p = d * dist;  // relative to the shading point, world axes
        double angular_speed = 0.0;
        if (hit.valid) {
            const glm::dvec3 v = glm::dvec3(scene.objects[size_t(hit.object)].animation.velocity_of(
                                     hit.position, ctx.time)) -
                                 receiver_velocity;
            angular_speed = glm::length(v - glm::dot(v, d) * d) / std::max(dist, 1e-9);
        }
        occluders.push_back({q, p, w, angular_speed});
        mean_p += w * p;
    }
    rp.occlusion_ratio = w_all > 0 ? a_o / w_all : 0.0;
    say(chain, "pilot: %d shadow rays, %d occluded, BRDF-weighted occlusion ratio %.4f",
        rp.pilot_rays, rp.pilot_occluded, rp.occlusion_ratio);
    double f_v = 0.0;
    if (rp.pilot_occluded > 0 && a_o > 0) {
        mean_q /= a_o;
        mean_p /= a_o;
        // Weighted covariance with reliability weights. The printed Eq. 4.4 weighs squared
        // weights by N / ((N_L - 1) A_o^2), which for equal weights is the spread divided by the
        // number of occluded samples: sigma_V would shrink as occluders cover more of the
        // footprint, the opposite of the coverage measure the text describes.
        glm::dmat2 sigma_q(0.0);
        glm::dmat3 sigma_p(0.0);
        double w2_sum = 0.0;
        for (const Occluder& o : occluders) {
            sigma_q += o.w * glm::outerProduct(o.q - mean_q, o.q - mean_q);
            sigma_p += o.w * glm::outerProduct(o.p - mean_p, o.p - mean_p);
            w2_sum += o.w * o.w;
        }
        const double denominator = a_o - w2_sum / a_o;
        const double norm = denominator > 0 ? 1.0 / denominator : 0.0;
        sigma_q *= norm;
        sigma_p *= norm;
        rp.sigma_V = std::sqrt(std::max(sigma_q[0][0], sigma_q[1][1]));
        rp.mu_o[0] = mean_q.x;
        rp.mu_o[1] = mean_q.y;
        rp.sigma_o[0] = sigma_q[0][0];
        rp.sigma_o[1] = sigma_q[1][0];
        rp.sigma_o[2] = sigma_q[1][1];
        const double x = rp.sigma_V / rp.sigma_rho;
        f_v = extra_samples(x, n_max - n_l);
        const double mu_t = glm::length(mean_p);
        const glm::dvec3 axis = mu_t > 0 ? mean_p / mu_t : mu;
        const double sigma_t = std::sqrt(std::max(glm::dot(axis, sigma_p * axis), 0.0));
        rp.t_min = mu_t - 3.0 * sigma_t;
        say(chain, "mu_o (cone angles) = (%.5f, %.5f), Sigma_o = [[%.4g, %.4g], [%.4g, %.4g]]",
            mean_q.x, mean_q.y, sigma_q[0][0], sigma_q[1][0], sigma_q[0][1], sigma_q[1][1]);
        say(chain, "sigma_V = %.5f rad, x = sigma_V / sigma_rho = %.4f, f_V = %.2f", rp.sigma_V, x,
            f_v);
        if (!distances) return f_v;  // t_min and B_t are the caller's
        say(chain, "occluder distance mu_t = %.5f, sigma_t = %.5f, mu_t - 3 sigma_t = %.5f%s", mu_t,
            sigma_t, rp.t_min, rp.t_min <= 0 ? " <= 0: nearest pilot hit used" : "");
        if (!(rp.t_min > 0)) rp.t_min = nearest;
        // Eq. 5.14 with the same weights as Eq. 4.4.
        double m1 = 0.0, m2 = 0.0;
        for (const Occluder& o : occluders) {
            const double a = o.angular_speed * rp.B_L;
            m1 += o.w * a;
            m2 += o.w * a * a;
        }
        m1 /= a_o;
        const double sd = std::sqrt(std::max(m2 / a_o - m1 * m1, 0.0));
        rp.B_t = m1 + 3.0 * sd;
        say(chain, "occluders' |v'| B_L: mean %.5g, deviation %.5g -> B_t = %.5g (1/s)", m1, sd,
            rp.B_t);
    } else if (distances) {
        rp.t_min = large_distance_;
        say(chain, "no occluded pilot sample: f_V = 0, t_min = large distance %.4g", rp.t_min);
    }
    return f_v;
}

double RadiancePointIntegrator::environment_bandwidth(const ShadingPoint& sp) const {
    const BrdfFootprint footprint = brdf_footprint(*sp.material);
    const glm::dvec3 mu = footprint_axis(sp, footprint);
    return bandwidth_ ? bandwidth_->query(to_map_frame(vec3(mu)), footprint.query_radius()) : 0.0;
}

vec3 RadiancePointIntegrator::to_map_frame(const vec3& d) const {
    // The hierarchy was built on the map at its base rotation: turn the direction back by
    // what the environment has spun since.
    if (environment_turned_ == 0.0) return d;
    const float c = float(std::cos(environment_turned_)), s = float(std::sin(environment_turned_));
    return vec3(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
}

PointBandwidths RadiancePointIntegrator::bandwidths(const ShadingPoint& sp, const PointContext& ctx,
                                                    double B_L, double t_min,
                                                    std::vector<std::string>* chain) const {
    // Eq. 5.2-5.3 and Appendix 9.
    const BrdfFootprint footprint = brdf_footprint(*sp.material);
    const glm::dvec3 n(sp.shading_normal), wo(sp.wo);
    const glm::dvec3 mu = footprint_axis(sp, footprint);
    CovarianceInputs in;
    in.sigma_l2 = (B_L / 3.0) * (B_L / 3.0);
    in.cos_in = std::max(glm::dot(n, mu), 0.05);
    in.curvature = ctx.curvature;
    in.b = phong_bandwidth_b(phong_like_exponent(*sp.material));
    in.inv_cos_view = 1.0 / std::max(glm::dot(n, wo), 0.05);
    in.eye_distance = ctx.eye_distance;
    in.t_min = t_min;
    const CovarianceResult cov = occluded_covariance_limit(in);
    PointBandwidths out;
    out.B_S = 3.0 * std::sqrt(std::max(cov.image[1][1], 0.0));
    out.B_x = 3.0 * std::sqrt(std::max(cov.object[0][0], 0.0));
    out.B_theta = 3.0 * std::sqrt(std::max(cov.object[1][1], 0.0));
    say(chain,
        "covariance inputs: sigma_L^2 = %.5g, c_i = %.4f, k = %.4g, b = %.5g, c_v = %.4f, d = "
        "%.5g, "
        "t_min = %.5g",
        in.sigma_l2, in.cos_in, in.curvature, in.b, in.inv_cos_view, in.eye_distance, in.t_min);
    if (chain) {
        say_matrix(chain, "T_{V->x}(t_min)", travel_operator(in.t_min));
        say_matrix(chain, "C_L", surface_in_operator(in.cos_in, in.curvature));
        say_matrix(chain, "B_rho", brdf_operator(in.b));
        say_matrix(chain, "C_v", surface_out_operator(in.inv_cos_view, in.curvature));
        say_matrix(chain, "T_{x->v}(d)", travel_operator(in.eye_distance));
        say_matrix(chain, "Sigma^o (object)", cov.object);
        say_matrix(chain, "Sigma (image)", cov.image);
    }
    say(chain, "B_S = 3 sqrt(Sigma_theta) = %.5g, B_x = %.5g, B_theta = %.5g", out.B_S, out.B_x,
        out.B_theta);
    return out;
}

}  // namespace freqlab
