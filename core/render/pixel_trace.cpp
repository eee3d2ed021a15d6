// --debug-pixel and the inspector's trace: re-runs one pixel's direct-lighting estimate with
// every sample recorded (strategy, direction, pdfs, MIS weight, contribution, visibility).
// The numbers are those of the render: same seed keys, same estimator.
#include <cstdio>

#include "render/direct_lighting.h"
#include "render/frame_renderer.h"
#include "render/points_pass.h"
#include "render/radiance_point.h"
#include "render/shading_pass.h"

namespace freqlab {

std::vector<std::string> FrameRenderer::trace_pixel(const FrameResult& r, int x, int y,
                                                    size_t max_samples, RadiancePoint* point) {
    std::vector<std::string> out;
    auto line = [&out](const char* format, auto... args) {
        char buf[512];
        std::snprintf(buf, sizeof buf, format, args...);
        out.push_back(buf);
    };
    const RenderConfig& config = config_;
    ray_scene_.update(r.time_s);  // the pixel's frame, whatever was rendered last
    const RayScene& rs = ray_scene_;
    const CameraRayGenerator cam(rs.scene().camera.at(r.time_s), r.layers.width(),
                                 r.layers.height());
    const Ray ray{cam.origin,
                  cam.direction((x + 0.5f) / r.layers.width(), (y + 0.5f) / r.layers.height())};
    const SurfaceHit hit = rs.intersect(ray);
    line("camera ray o = (%.4f, %.4f, %.4f) d = (%.4f, %.4f, %.4f)", ray.origin.x, ray.origin.y,
         ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z);
    if (config.method == RenderMethod::GBuffer) {
        line("method gbuffer: primary rays only, nothing is estimated");
        return out;
    }
    if (!hit.valid) {
        line("no hit: background radiance");
        return out;
    }
    DirectLighting lighting(rs, config.shading);
    const ShadingPoint sp = lighting.shading_point(hit, -ray.direction);
    line("hit object %d \"%s\" t = %.5f, material \"%s\" (%s), uv = (%.4f, %.4f)", hit.object,
         rs.scene().objects[size_t(hit.object)].name.c_str(), hit.distance,
         sp.material->name.c_str(), to_string(sp.material->type), hit.uv.x, hit.uv.y);
    line(
        "p = (%.5f, %.5f, %.5f) n_g = (%.4f, %.4f, %.4f) n_s = (%.4f, %.4f, %.4f) albedo = "
        "(%.4f, %.4f, %.4f)",
        sp.position.x, sp.position.y, sp.position.z, sp.geometric_normal.x, sp.geometric_normal.y,
        sp.geometric_normal.z, sp.shading_normal.x, sp.shading_normal.y, sp.shading_normal.z,
        sp.albedo.x, sp.albedo.y, sp.albedo.z);
    if (sp.material->type == BrdfType::Mirror) {
        line("perfect mirror: followed up to shading.mirror_depth = %d bounces",
             config.shading.mirror_depth);
        return out;
    }
    if (config.method == RenderMethod::Points) {
        // The radiance point's whole chain, with the render's seed keys and G-buffer context.
        auto hit_at = [&](int px, int py) {
            return rs.intersect(Ray{cam.origin, cam.direction((px + 0.5f) / r.layers.width(),
                                                              (py + 0.5f) / r.layers.height())});
        };
        SurfaceHit neighbours[4];
        int count = 0;
        if (x + 1 < r.layers.width()) neighbours[count++] = hit_at(x + 1, y);
        if (x > 0) neighbours[count++] = hit_at(x - 1, y);
        if (y + 1 < r.layers.height()) neighbours[count++] = hit_at(x, y + 1);
        if (y > 0) neighbours[count++] = hit_at(x, y - 1);
        PointContext ctx;
        ctx.curvature = screen_space_curvature(hit, neighbours, count);
        ctx.eye_distance = hit.distance;
        ctx.time = r.time_s;
        ctx.object = hit.object;
        line("screen-space curvature k = %.5g, eye distance %.5g", ctx.curvature, ctx.eye_distance);
        const RadiancePointIntegrator integrator(rs, config.shading, config.points, bandwidth());
        CounterRng rng(uint64_t(config.frame.seed) ^ kPointsStream, uint64_t(r.frame),
                       size_t(y) * r.layers.width() + x, 0);
        std::vector<std::string> chain;
        const RadiancePoint rp = integrator.integrate(sp, ctx, rng, &chain);
        if (point) *point = rp;
        out.insert(out.end(), chain.begin(), chain.end());
        return out;
    }
    std::vector<DirectLighting::SampleTrace> samples;
    lighting.trace_samples(&samples);
    CounterRng rng(uint64_t(config.frame.seed) ^ kShadingStream, uint64_t(r.frame),
                   size_t(y) * r.layers.width() + x, 0);
    const RadianceEstimate e = lighting.estimate(sp, config.spp(), rng);
    line("estimate (%.6g, %.6g, %.6g), variance %.4g, %ld shadow rays, %zu candidate samples",
         e.radiance.x, e.radiance.y, e.radiance.z, e.variance, e.rays, samples.size());
    line("%-5s %4s %-26s %10s %10s %7s %-30s %s", "strat", "unit", "direction", "pdf", "other_pdf",
         "w_mis", "contribution (unoccluded)", "visible");
    for (size_t k = 0; k < samples.size() && k < max_samples; ++k) {
        const auto& t = samples[k];
        line("%-5s %4d (%7.4f,%7.4f,%7.4f) %10.4g %10.4g %7.4f (%9.4g,%9.4g,%9.4g) %s",
             t.environment_strategy ? "env" : "brdf", t.unit, t.direction.x, t.direction.y,
             t.direction.z, t.pdf, t.other_pdf, t.mis_weight, t.contribution.x, t.contribution.y,
             t.contribution.z, t.occluded ? "occluded" : "yes");
    }
    if (samples.size() > max_samples) line("... %zu more samples", samples.size() - max_samples);
    return out;
}

}  // namespace freqlab
