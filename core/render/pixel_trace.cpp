// --debug-pixel and the inspector's trace: re-runs one pixel's direct-lighting estimate with
// every sample recorded (strategy, direction, pdfs, MIS weight, contribution, visibility).
// The numbers are those of the render: same seed keys, same estimator.
#include <algorithm>
#include <cstdio>

#include "render/direct_lighting.h"
#include "render/frame_renderer.h"
#include "render/pixel_trace.h"
#include "render/points_pass.h"
#include "render/radiance_point.h"
#include "render/reconstruction.h"
#include "render/shading_pass.h"
#include "render/sparse_sampling.h"

namespace freqlab {

namespace {

template <class... Args>
void add_line(TraceLines& out, const char* format, Args... args) {
    char buf[512];
    std::snprintf(buf, sizeof buf, format, args...);
    out.push_back(buf);
}

}  // namespace

void trace_direct_lighting(const PixelTraceContext& c, TraceLines& out) {
    auto line = [&out](const char* format, auto... args) { add_line(out, format, args...); };
    [[maybe_unused]] const RenderConfig& config = c.config;
    [[maybe_unused]] const RayScene& rs = c.rays;
    [[maybe_unused]] const FrameResult& r = c.result;
    [[maybe_unused]] const int x = c.x, y = c.y;
    [[maybe_unused]] const CameraRayGenerator& cam = c.camera;
    [[maybe_unused]] const ShadingPoint& sp = c.point;
    [[maybe_unused]] const size_t max_samples = c.max_samples;
    DirectLighting lighting(rs, config.shading, config.sequence());
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
}

void trace_radiance_point(const PixelTraceContext& c, TraceLines& out) {
    auto line = [&out](const char* format, auto... args) { add_line(out, format, args...); };
    [[maybe_unused]] const RenderConfig& config = c.config;
    [[maybe_unused]] const RayScene& rs = c.rays;
    [[maybe_unused]] const FrameResult& r = c.result;
    [[maybe_unused]] const int x = c.x, y = c.y;
    [[maybe_unused]] const CameraRayGenerator& cam = c.camera;
    [[maybe_unused]] const ShadingPoint& sp = c.point;
    [[maybe_unused]] const size_t max_samples = c.max_samples;
    const SurfaceHit& hit = c.hit;
    {
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
        const RadiancePointIntegrator integrator(rs, config.shading, config.points, c.bandwidth);
        CounterRng rng(uint64_t(config.frame.seed) ^ kPointsStream, uint64_t(r.frame),
                       size_t(y) * r.layers.width() + x, 0);
        std::vector<std::string> chain;
        const RadiancePoint rp = integrator.integrate(sp, ctx, rng, &chain);
        if (c.radiance_point) *c.radiance_point = rp;
        out.insert(out.end(), chain.begin(), chain.end());
        return;
    }
}

void trace_reconstruction(const PixelTraceContext& c, TraceLines& out) {
    auto line = [&out](const char* format, auto... args) { add_line(out, format, args...); };
    [[maybe_unused]] const RenderConfig& config = c.config;
    [[maybe_unused]] const RayScene& rs = c.rays;
    [[maybe_unused]] const FrameResult& r = c.result;
    [[maybe_unused]] const int x = c.x, y = c.y;
    [[maybe_unused]] const CameraRayGenerator& cam = c.camera;
    [[maybe_unused]] const ShadingPoint& sp = c.point;
    [[maybe_unused]] const size_t max_samples = c.max_samples;
    if (!r.layers.find("samples")) return;
    {
        // Which radiance points the reconstruction used here, and with what weight (Eq. 6.2).
        const int w = r.layers.width(), h = r.layers.height();
        const double angle = radians_per_pixel(cam, w, h);
        auto feature_at = [&](int px, int py) {
            const Ray ray_p{cam.origin, cam.direction((px + 0.5f) / w, (py + 0.5f) / h)};
            return pixel_feature(rs.intersect(ray_p), ray_p.direction, angle);
        };
        const Layer& kind = r.layers.get("sampled");
        const Layer& samples = r.layers.get("samples");
        const Layer& mu = r.layers.get("mu_v");
        const Layer& sig = r.layers.get("sigma_v");
        const size_t i = size_t(y) * w + x;
        const float radius = r.layers.get("recon_radius").data[i];
        auto origin = [&](size_t j) {
            const size_t k = size_t(kind.data[j]);
            return k < kind.legend.size() ? kind.legend[k].c_str() : "?";
        };
        line("reconstruction: radius %.2f px, sum of weights %.4g, sampled here: %s", radius,
             r.layers.get("recon_weight").data[i], origin(i));
        const PixelFeature fi = feature_at(x, y);
        struct Contribution {
            int x, y;
            double weight;
        };
        std::vector<Contribution> used;
        double total = 0.0;
        const int ri = int(std::ceil(radius));
        for (int yy = std::max(0, y - ri); yy <= std::min(h - 1, y + ri); ++yy)
            for (int xx = std::max(0, x - ri); xx <= std::min(w - 1, x + ri); ++xx) {
                const size_t j = size_t(yy) * w + xx;
                if (kind.data[j] == 0.0f ||
                    float((xx - x) * (xx - x) + (yy - y) * (yy - y)) > radius * radius)
                    continue;
                const PixelFeature fj = feature_at(xx, yy);
                if (!fj.valid || fj.object != fi.object) continue;
                const double wgt = reconstruction_weight(fi, fj, mu.data[i], mu.data[j],
                                                         sig.data[i], sig.data[j], config.sparse);
                used.push_back({xx, yy, wgt});
                total += wgt;
            }
        std::sort(used.begin(), used.end(),
                  [](const Contribution& a, const Contribution& b) { return a.weight > b.weight; });
        line("%zu radiance points on this object within the radius", used.size());
        line("%-11s %-9s %10s %8s  %s", "pixel", "origin", "weight", "share",
             "the point's radiance (texture included)");
        for (size_t k = 0; k < used.size() && k < max_samples; ++k) {
            const size_t j = size_t(used[k].y) * w + used[k].x;
            line("(%4d,%4d) %-9s %10.4g %7.2f%%  (%.5g, %.5g, %.5g)", used[k].x, used[k].y,
                 origin(j), used[k].weight, total > 0 ? 100.0 * used[k].weight / total : 0.0,
                 samples.data[3 * j], samples.data[3 * j + 1], samples.data[3 * j + 2]);
        }
        return;
    }
}

void trace_cache(const PixelTraceContext& c, TraceLines& out) {
    const FrameResult& r = c.result;
    if (r.cache_records)
        for (const std::string& s :
             cache_entries_near(*r.cache_records, r.cache_snapshot.get(), c.x, c.y, 1,
                                r.layers.width(), c.config.cache, c.max_samples))
            out.push_back(s);
    trace_reconstruction(c, out);
}

std::vector<std::string> FrameRenderer::trace_pixel(const FrameResult& r, int x, int y,
                                                    size_t max_samples, RadiancePoint* point) {
    std::vector<std::string> out;
    auto line = [&out](const char* format, auto... args) {
        char buf[512];
        std::snprintf(buf, sizeof buf, format, args...);
        out.push_back(buf);
    };
    if (x < 0 || y < 0 || x >= r.layers.width() || y >= r.layers.height()) {
        line("pixel (%d, %d) is outside the %d x %d image", x, y, r.layers.width(),
             r.layers.height());
        return out;
    }
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
    const RenderMethodInfo& method = render_method_info(config.method);
    if (!method.render) {
        line("method %s: primary rays only, nothing is estimated", method.name.c_str());
        return out;
    }
    if (!hit.valid) {
        line("no hit: background radiance");
        return out;
    }
    DirectLighting lighting(rs, config.shading, config.sequence());
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
    if (!method.trace) {
        line("method %s has no per-pixel trace", method.name.c_str());
        return out;
    }
    const PixelTraceContext context{
        rs,          config, r, x, y, cam, hit, sp, method.env_bandwidth ? bandwidth() : nullptr,
        max_samples, point};
    method.trace(context, out);
    return out;
}

}  // namespace freqlab
