#include "render/direct_lighting.h"

#include <cmath>
#include <vector>

#include "math/sobol.h"
#include "scene/brdf_batch.h"

namespace freqlab {

namespace {

// One strategy's samples as structure of arrays: the operands of the vectorized loops.
struct SampleArrays {
    std::vector<float> u1, u2;          // BRDF strategy: its uniforms
    std::vector<float> x, y, z;         // world direction
    std::vector<float> pdf, other_pdf;  // this strategy's density, the other one's
    std::vector<float> value;           // f / albedo
    std::vector<float> weight, factor;  // MIS weight; f/albedo x cos x w / pdf (0: no ray)
    std::vector<vec3> radiance;         // of the environment along the direction
    std::vector<int> texel;
    std::vector<float> sin_theta;  // of the direction (for the lat-long density)
    void resize(int n) {
        const size_t m = size_t(n);
        if (x.size() >= m) return;
        for (std::vector<float>* v :
             {&u1, &u2, &x, &y, &z, &pdf, &other_pdf, &value, &weight, &factor, &sin_theta})
            v->resize(m);
        radiance.resize(m);
        texel.resize(m);
    }
    vec3 direction(int i) const { return vec3(x[size_t(i)], y[size_t(i)], z[size_t(i)]); }
    // Cosine at the shading normal, power-heuristic weight and the sample's scalar factor.
    void weigh(int n, const vec3& ns, float n_self, float n_other) {
        const float* __restrict xs = x.data(), * __restrict ys = y.data(), * __restrict zs = z.data();
        const float* __restrict ps = pdf.data(), * __restrict qs = other_pdf.data();
        const float* __restrict vs = value.data();
        float* __restrict ws = weight.data(), * __restrict fs = factor.data();
        for (int i = 0; i < n; ++i) {
            const float cos_i = xs[i] * ns.x + ys[i] * ns.y + zs[i] * ns.z;
            const float w = power_heuristic(n_self, ps[i], n_other, qs[i]);
            ws[i] = w;
            const float f = vs[i] * cos_i * w / ps[i];
            fs[i] = ps[i] > 0.0f && cos_i > 0.0f ? f : 0.0f;
        }
    }
};

// Per-thread scratch so that shading a pixel allocates nothing after warm-up.
struct Scratch {
    std::vector<Ray> rays;
    std::vector<vec3> contributions;
    std::vector<int> unit;  // >= 0: environment unit; < 0: BRDF unit -(j + 1)
    std::unique_ptr<bool[]> occluded;
    size_t occluded_size = 0;
    std::vector<vec3> env_units, brdf_units;
    // The uniforms of the environment and quad-light samples, drawn up front in the order the
    // sample loop consumes them, and the texels they pick (see EnvironmentMap::prefetch_alias).
    std::vector<vec4> env_u;
    std::vector<vec2> light_u;
    std::vector<Distribution2D::Inversion> inversions;  // stratified environment samples
    SampleArrays env, brdf;
    std::vector<float> uniforms;  // a block of the pixel's stream
};

Scratch& scratch() {
    thread_local Scratch s;
    return s;
}

// Sample variance of the luminance of `units`, divided by their count (variance of the mean).
// Two passes (mean, then squared deviations): no division in the loop (Welford's running
// mean divided per unit, a chain of divisions profiled at 3.5 % of a 16-spp pixel).
float variance_of_mean(const std::vector<vec3>& units, int n) {
    if (n < 2) return 0.0f;
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += luminance(units[size_t(i)]);
    const double mean = sum / n;
    double m2 = 0;
    for (int i = 0; i < n; ++i) {
        const double d = luminance(units[size_t(i)]) - mean;
        m2 += d * d;
    }
    return float(m2 / (n - 1) / n);
}

// The estimate's samples before any ray: the uniforms of the environment, quad-light and BRDF
// samples (drawn in the order the unit loop consumes them), their directions, texels, values,
// pdfs, MIS weights and factors, staged so that the texels' cache misses overlap.
void draw_samples(Scratch& s, const EnvironmentMap* env, const std::vector<const Light*>& lights,
                  bool quad_lights, SampleSequence sequence, const BrdfBatch& lobe, const vec3& ns,
                  CounterRng& rng, int n_env, int n_units, int n_brdf) {
    // Stratified: the strategies' sequences are seeded from the stream first (the independent
    // path draws nothing here, so its numbers are what they always were).
    const bool sobol = sequence == SampleSequence::ScrambledSobol;
    uint32_t seeds[4] = {0, 0, 0, 0};
    if (sobol)
        for (uint32_t& seed : seeds) seed = rng.next_u32();
    const ScrambledSobol2D env_points(seeds[0], seeds[1]), brdf_points(seeds[2], seeds[3]);

    // The random numbers first (same order as drawing them inside the loop), so that the
    // environment's table reads of all samples can be in flight together.
    SampleArrays& e = s.env;  // its texels: e.texel
    s.env_u.clear();
    s.light_u.clear();
    if (env && sobol) {
        // CDF inversion in stages across all samples (each stage prefetches the next's reads).
        s.inversions.clear();
        for (int i = 0; i < n_env; ++i)
            s.inversions.push_back(env->invert_begin(env_points.at(uint32_t(i))));
        for (Distribution2D::Inversion& inv : s.inversions) env->invert_guide(inv);
        for (size_t i = 0; i < s.inversions.size(); ++i) {
            Distribution2D::Inversion& inv = s.inversions[i];
            e.texel[i] = env->invert_finish(inv);
            env->prefetch_texel(e.texel[i]);
            // The texel is chosen; only zw (the place inside it) are read from here on.
            s.env_u.emplace_back(0.0f, 0.0f, inv.within);
        }
    }
    if (env && !sobol && !quad_lights) {
        // Without quad lights the environment's uniforms are one block of the stream: drawn in
        // one vectorized call, in the same order as the loop below.
        s.uniforms.resize(size_t(4 * n_env));
        rng.fill_floats(s.uniforms.data(), 4 * n_env);
        for (int i = 0; i < n_env; ++i) {
            const float* f = &s.uniforms[size_t(4 * i)];
            s.env_u.emplace_back(f[0], f[1], f[2], f[3]);
            env->prefetch_alias(s.env_u.back());
        }
    } else
        for (int i = 0; i < n_units; ++i) {
            if (env && !sobol) {
                const vec4 u(rng.next_float(), rng.next_float(), rng.next_float(),
                             rng.next_float());
                s.env_u.push_back(u);
                env->prefetch_alias(u);
            }
            for (const Light* l : lights)
                if (light_sample_dimensions(*l) == 2) {
                    const float u1 = rng.next_float(), u2 = rng.next_float();
                    s.light_u.emplace_back(u1, u2);
                }
        }
    // The BRDF samples next: their directions and texels are computed while the alias
    // entries load, and their texels load while the environment samples are computed.
    SampleArrays& b = s.brdf;
    if (sobol) {
        for (int j = 0; j < n_brdf; ++j) {
            const vec2 u = brdf_points.at(uint32_t(j));
            b.u1[size_t(j)] = u.x;
            b.u2[size_t(j)] = u.y;
        }
    } else {
        s.uniforms.resize(size_t(2 * n_brdf));
        rng.fill_floats(s.uniforms.data(), 2 * n_brdf);
        for (int j = 0; j < n_brdf; ++j) {
            b.u1[size_t(j)] = s.uniforms[size_t(2 * j)];
            b.u2[size_t(j)] = s.uniforms[size_t(2 * j + 1)];
        }
    }
    if (n_brdf > 0) {
        lobe.sample(n_brdf, b.u1.data(), b.u2.data(), b.x.data(), b.y.data(), b.z.data(),
                    b.value.data(), b.pdf.data());
        env->lookup_texels(n_brdf, b.x.data(), b.y.data(), b.z.data(), b.texel.data(),
                           b.sin_theta.data());
    }
    if (env && !sobol) {
        for (size_t i = 0; i < s.env_u.size(); ++i) {
            e.texel[i] = env->sample_texel(s.env_u[i]);
            env->prefetch_texel(e.texel[i]);
        }
    }
    if (n_env > 0) {
        env->sample_directions(n_env, e.texel.data(), s.env_u.data(), e.x.data(), e.y.data(),
                               e.z.data(), e.sin_theta.data());
        lobe.eval(n_env, e.x.data(), e.y.data(), e.z.data(), e.value.data(), e.other_pdf.data());
    }
    // Now the texels' radiance and densities, then each sample's MIS weight and its scalar
    // factor f/albedo x cos x w / pdf (0: no ray).
    if (n_brdf > 0) {
        env->texel_values(n_brdf, b.texel.data(), b.sin_theta.data(), b.other_pdf.data(),
                          b.radiance.data());
        b.weigh(n_brdf, ns, float(n_brdf), float(n_env));
    }
    if (n_env > 0) {
        env->texel_values(n_env, e.texel.data(), e.sin_theta.data(), e.pdf.data(),
                          e.radiance.data());
        e.weigh(n_env, ns, float(n_env), float(n_brdf));
    }
}

}  // namespace

DirectLighting::DirectLighting(const RayScene& scene, const ShadingSettings& settings,
                               SampleSequence sequence)
    : scene_(scene), environment_(scene.environment()), settings_(settings), sequence_(sequence) {
    for (const Light& l : scene.scene().lights)
        if (!l.environment) lights_.push_back(&l);
    for (const Light* l : lights_) quad_lights_ = quad_lights_ || light_sample_dimensions(*l) > 0;
}

vec3 DirectLighting::offset_origin(const vec3& p, const vec3& n) const {
    return spawn_point(p, n, settings_.ray_epsilon);
}

ShadingPoint DirectLighting::shading_point(const SurfaceHit& hit, const vec3& wo) const {
    const Scene& scene = scene_.scene();
    const Material& m = scene.materials[size_t(hit.material)];
    return ShadingPoint{hit.position, hit.geometric_normal, hit.shading_normal, wo,
                        &m,           m.albedo.eval(hit.uv)};
}

RadianceEstimate DirectLighting::trace(const Ray& ray, int spp, CounterRng& rng, int depth) const {
    const SurfaceHit hit = scene_.intersect(ray);
    if (!hit.valid) {
        RadianceEstimate e;
        e.radiance = environment_ ? environment_->eval_smooth(ray.direction) : vec3(0.0f);
        return e;
    }
    return shade_hit(hit, -ray.direction, spp, rng, depth);
}

RadianceEstimate DirectLighting::shade_hit(const SurfaceHit& hit, const vec3& wo, int spp,
                                           CounterRng& rng, int depth) const {
    const ShadingPoint sp = shading_point(hit, wo);
    if (sp.material->type != BrdfType::Mirror) return estimate(sp, spp, rng);
    RadianceEstimate e;
    if (depth >= settings_.mirror_depth) return e;
    const vec3 r = reflect_about(wo, sp.shading_normal);
    if (glm::dot(r, sp.geometric_normal) <= 0.0f) return e;
    e = trace(Ray{offset_origin(sp.position, sp.geometric_normal), r}, spp, rng, depth + 1);
    e.radiance *= sp.albedo;
    e.variance *= luminance(sp.albedo) * luminance(sp.albedo);
    e.rays += 1;
    return e;
}

RadianceEstimate DirectLighting::estimate(const ShadingPoint& sp, int spp, CounterRng& rng,
                                          std::vector<CastSample>* cast) const {
    RadianceEstimate result;
    const Brdf brdf(*sp.material, sp.albedo, sp.shading_normal);
    const BrdfBatch lobe(brdf, sp.wo);
    const int n_env = environment_ ? (spp + 1) / 2 : 0;
    const int n_units = (spp + 1) / 2;  // environment sample units (lights take one each too)
    const int n_brdf = environment_ ? spp / 2 : 0;  // BRDF rays only ever find the environment
    const vec3 origin = offset_origin(sp.position, sp.geometric_normal);
    const vec3& ng = sp.geometric_normal;
    const vec3& ns = sp.shading_normal;

    Scratch& s = scratch();
    s.env.resize(n_env);
    s.brdf.resize(n_brdf);
    // The rays are written in place (at most one per sample and light unit).
    const size_t max_rays = size_t(n_env + n_brdf) + size_t(n_units) * lights_.size();
    if (s.rays.size() < max_rays) {
        s.rays.resize(max_rays);
        s.contributions.resize(max_rays);
        s.unit.resize(max_rays);
    }
    size_t n_rays = 0;
    const size_t traced_before = traced_ ? traced_->size() : 0;
    auto candidate = [&](const vec3& dir, float tfar, const vec3& value, int unit, float pdf = 0,
                         float other_pdf = 0, float w = 1) {
        if (!(luminance(value) > 0.0f) || glm::dot(dir, ng) <= 0.0f) return;
        s.rays[n_rays] = Ray{origin, dir, 0.0f, tfar};
        s.contributions[n_rays] = value;
        s.unit[n_rays] = unit;
        ++n_rays;
        if (traced_)
            traced_->push_back(SampleTrace{unit >= 0, unit >= 0 ? unit : -unit - 1, dir, pdf,
                                           other_pdf, w, value, false});
    };

    draw_samples(s, environment_, lights_, quad_lights_, sequence_, lobe, ns, rng, n_env, n_units,
                 n_brdf);
    const SampleArrays& e = s.env;
    const SampleArrays& b = s.brdf;

    // The shadow rays, in the order of the units: environment sample i, the lights' unit i,
    // then the BRDF samples.
    const vec3& albedo = brdf.albedo();
    size_t next_light_u = 0;
    for (int i = 0; i < n_units; ++i) {
        if (i < n_env && e.factor[size_t(i)] > 0.0f)
            candidate(e.direction(i), INFINITY,
                      e.radiance[size_t(i)] * albedo * e.factor[size_t(i)], i, e.pdf[size_t(i)],
                      e.other_pdf[size_t(i)], e.weight[size_t(i)]);
        for (const Light* l : lights_) {
            const vec2 u = light_sample_dimensions(*l) ? s.light_u[next_light_u++] : vec2(0.0f);
            const LightSample ls = sample_light(*l, sp.position, u);
            if (!ls.valid) continue;
            const vec3& dir = ls.direction;
            const float cos_i = glm::dot(dir, ns);
            if (cos_i <= 0.0f) continue;
            const float tfar = shadow_ray(origin, dir, ls.distance).tfar;
            candidate(dir, tfar, ls.irradiance * brdf.eval(sp.wo, dir) * cos_i, i);
        }
    }
    for (int j = 0; j < n_brdf; ++j)
        if (b.factor[size_t(j)] > 0.0f)
            candidate(b.direction(j), INFINITY,
                      b.radiance[size_t(j)] * albedo * b.factor[size_t(j)], -(j + 1),
                      b.pdf[size_t(j)], b.other_pdf[size_t(j)], b.weight[size_t(j)]);
    if (s.occluded_size < n_rays) {
        s.occluded.reset(new bool[n_rays]);
        s.occluded_size = n_rays;
    }
    scene_.occluded_stream(s.rays.data(), int(n_rays), s.occluded.get());
    if (recorded_) recorded_->insert(recorded_->end(), s.rays.begin(), s.rays.begin() + n_rays);
    if (cast)
        for (size_t k = 0; k < n_rays; ++k)
            cast->push_back(CastSample{s.rays[k], s.occluded[k], s.unit[k] < 0,
                                       s.unit[k] >= 0 ? s.unit[k] : -s.unit[k] - 1});
    if (traced_)
        for (size_t k = 0; k < n_rays; ++k) (*traced_)[traced_before + k].occluded = s.occluded[k];
    result.rays = long(n_rays);

    s.env_units.assign(size_t(n_units), vec3(0.0f));
    s.brdf_units.assign(size_t(n_brdf), vec3(0.0f));
    for (size_t k = 0; k < n_rays; ++k) {
        if (s.occluded[k]) continue;
        const int u = s.unit[k];
        if (u >= 0)
            s.env_units[size_t(u)] += s.contributions[k];
        else
            s.brdf_units[size_t(-u - 1)] += s.contributions[k];
    }
    vec3 sum_env(0.0f), sum_brdf(0.0f);
    for (const vec3& v : s.env_units) sum_env += v;
    for (const vec3& v : s.brdf_units) sum_brdf += v;
    result.radiance = (n_units ? sum_env / float(n_units) : vec3(0.0f)) +
                      (n_brdf ? sum_brdf / float(n_brdf) : vec3(0.0f));
    result.variance =
        variance_of_mean(s.env_units, n_units) + variance_of_mean(s.brdf_units, n_brdf);
    return result;
}

}  // namespace freqlab
