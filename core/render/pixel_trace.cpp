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
    const size_t max_samples = c.max_samples;
    DirectLighting lighting(c.rays, c.config.shading, c.config.sequence());
    std::vector<DirectLighting::SampleTrace> samples;
    lighting.trace_samples(&samples);
    CounterRng rng(uint64_t(c.config.frame.seed) ^ kShadingStream, uint64_t(c.result.frame),
                   size_t(c.y) * c.result.layers.width() + c.x, 0);
    const RadianceEstimate e = lighting.estimate(c.point, c.config.spp(), rng);
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
    const RenderConfig& config = c.config;
    const FrameResult& r = c.result;
    const int x = c.x, y = c.y;
    const CameraRayGenerator& cam = c.camera;
    const SurfaceHit& hit = c.hit;
    {
        // The radiance point's whole chain, with the render's seed keys and G-buffer context.
        auto hit_at = [&](int px, int py) {
            return c.rays.intersect(Ray{
                cam.origin,
                cam.direction((px + 0.5f) / r.layers.width(), (py + 0.5f) / r.layers.height())});
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
        const RadiancePointIntegrator integrator(c.rays, config.shading, config.points,
                                                 c.bandwidth);
        CounterRng rng(uint64_t(config.frame.seed) ^ kPointsStream, uint64_t(r.frame),
                       size_t(y) * r.layers.width() + x, 0);
        std::vector<std::string> chain;
        const RadiancePoint rp = integrator.integrate(c.point, ctx, rng, &chain);
        if (c.radiance_point) *c.radiance_point = rp;
        out.insert(out.end(), chain.begin(), chain.end());
        return;
    }
}

ReconstructionRecord rebuild_reconstruction(const RayScene& rs, const RenderConfig& config,
                                            const FrameResult& r, const CameraRayGenerator& camera,
                                            int x, int y) {
    ReconstructionRecord record;
    record.x = x;
    record.y = y;
    const int w = r.layers.width(), h = r.layers.height();
    const Layer* radius_layer = r.layers.find("recon_radius");
    if (!radius_layer || x < 0 || y < 0 || x >= w || y >= h) return record;
    const float radius = radius_layer->data[size_t(y) * w + x];
    if (!(radius > 0.0f)) return record;  // not reconstructed: background or a mirror
    // The render's inputs over the window the radius reaches: features from the same centre
    // rays as the G-buffer (mirrors never mixed), features and samples from the layers, and
    // the reused entries' own positions.
    const int reach = int(std::ceil(radius)) + 1;
    const int x0 = std::max(0, x - reach), x1 = std::min(w - 1, x + reach);
    const int y0 = std::max(0, y - reach), y1 = std::min(h - 1, y + reach);
    ReconstructionInput in;
    in.width = x1 - x0 + 1;
    in.height = y1 - y0 + 1;
    const size_t m = size_t(in.width) * in.height;
    in.features.resize(m);
    in.mu_v.resize(m);
    in.sigma_v.resize(m);
    in.sampled.resize(m);
    in.value.assign(m, vec3(0.0f));
    in.radius.assign(m, radius);
    const double angle = radians_per_pixel(camera, w, h);
    const Layer& sampled = r.layers.get("sampled");
    const Layer& mu = r.layers.get("mu_v");
    const Layer& sigma = r.layers.get("sigma_v");
    for (int yy = y0; yy <= y1; ++yy)
        for (int xx = x0; xx <= x1; ++xx) {
            const size_t j = size_t(yy) * w + xx, k = size_t(yy - y0) * in.width + (xx - x0);
            const Ray ray{camera.origin, camera.direction((xx + 0.5f) / w, (yy + 0.5f) / h)};
            const SurfaceHit hit = rs.intersect(ray);
            PixelFeature f = pixel_feature(hit, ray.direction, angle);
            if (hit.valid && rs.scene().materials[size_t(hit.material)].type == BrdfType::Mirror)
                f.object = -2 - int(k);
            in.features[k] = f;
            in.mu_v[k] = mu.data[j];
            in.sigma_v[k] = sigma.data[j];
            in.sampled[k] = sampled.data[j] != 0.0f;
        }
    if (r.sample_positions) {
        in.sample_features = in.features;
        for (const auto& [pixel, position] : *r.sample_positions) {
            const int px = pixel % w, py = pixel / w;
            if (px >= x0 && px <= x1 && py >= y0 && py <= y1)
                in.sample_features[size_t(py - y0) * in.width + (px - x0)].position = position;
        }
    }
    reconstruct_pixel_at(in, x - x0, y - y0, radius, config.sparse, record);
    record.x = x;
    record.y = y;
    for (ReconstructionRecord::Contribution& c : record.used) c.x += x0, c.y += y0;
    return record;
}

void trace_reconstruction(const PixelTraceContext& c, TraceLines& out) {
    auto line = [&out](const char* format, auto... args) { add_line(out, format, args...); };
    const FrameResult& r = c.result;
    if (!r.layers.find("samples")) return;
    // Which radiance points the reconstruction used here, and with what weight (Eq. 6.2).
    const int w = r.layers.width();
    const Layer& kind = r.layers.get("sampled");
    const Layer& samples = r.layers.get("samples");
    const size_t i = size_t(c.y) * w + c.x;
    auto origin = [&](size_t j) {
        const size_t k = size_t(kind.data[j]);
        return k < kind.legend.size() ? kind.legend[k].c_str() : "?";
    };
    ReconstructionRecord record = rebuild_reconstruction(c.rays, c.config, r, c.camera, c.x, c.y);
    line("reconstruction: radius %.2f px, sum of weights %.4g, sampled here: %s", record.radius,
         record.sum, origin(i));
    std::vector<ReconstructionRecord::Contribution>& used = record.used;
    std::stable_sort(used.begin(), used.end(),
                     [](const auto& a, const auto& b) { return a.weight > b.weight; });
    line("%zu radiance points on this object within the radius", used.size());
    line("%-11s %-9s %10s %8s  %s", "pixel", "origin", "weight", "share",
         "the point's radiance (texture included)");
    for (size_t k = 0; k < used.size() && k < c.max_samples; ++k) {
        const size_t j = size_t(used[k].y) * w + used[k].x;
        line("(%4d,%4d) %-9s %10.4g %7.2f%%  (%.5g, %.5g, %.5g)", used[k].x, used[k].y, origin(j),
             used[k].weight, record.sum > 0 ? 100.0 * used[k].weight / record.sum : 0.0,
             samples.data[3 * j], samples.data[3 * j + 1], samples.data[3 * j + 2]);
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

ReconstructionRecord FrameRenderer::reconstruction_weights(const FrameResult& r, int x, int y) {
    ray_scene_.update(r.time_s);
    const CameraRayGenerator camera(ray_scene_.scene().camera.at(r.time_s), r.layers.width(),
                                    r.layers.height());
    return rebuild_reconstruction(ray_scene_, config_, r, camera, x, y);
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
