#include "render/points_pass.h"

#include <tbb/parallel_for.h>

#include <array>
#include <atomic>
#include <cmath>

namespace freqlab {

const std::vector<std::string>& radiance_point_layer_names() {
    static const std::vector<std::string> names = {
        "B_L",   "sigma_rho", "N_omega", "sigma_V", "occlusion_ratio",
        "t_min", "B_S",       "B_x",     "B_theta", "B_t"};
    return names;
}

std::array<double, 10> radiance_point_fields(const RadiancePoint& rp) {
    return {rp.B_L,   rp.sigma_rho, rp.N_omega, rp.sigma_V, rp.occlusion_ratio,
            rp.t_min, rp.B_S,       rp.B_x,     rp.B_theta, rp.B_t};
}

PointContext point_context(const GBuffer& gb, int x, int y, float time) {
    PointContext ctx;
    ctx.time = time;
    ctx.object = gb.at(x, y).object;
    const SurfaceHit& c = gb.at(x, y);
    SurfaceHit neighbours[4];
    int count = 0;
    if (x + 1 < gb.width) neighbours[count++] = gb.at(x + 1, y);
    if (x > 0) neighbours[count++] = gb.at(x - 1, y);
    if (y + 1 < gb.height) neighbours[count++] = gb.at(x, y + 1);
    if (y > 0) neighbours[count++] = gb.at(x, y - 1);
    ctx.curvature = screen_space_curvature(c, neighbours, count);
    ctx.eye_distance = c.valid ? c.distance : 1.0;
    return ctx;
}

PointsPassOutput render_points(const RayScene& scene, const GBuffer& gb, int frame,
                               const FrameSettings& fs, const ShadingSettings& shading,
                               const PointsSettings& settings,
                               const EnvBandwidthHierarchy* bandwidth, LayerSet& layers,
                               Progress& progress) {
    const RadiancePointIntegrator integrator(scene, shading, settings, bandwidth);
    Layer& color =
        layers.add("color", LayerKind::Color, 3, "direct lighting, adaptive radiance points");
    Layer& variance = layers.add("variance", LayerKind::Continuous, 1,
                                 "variance of the point's luminance estimate (the independent-"
                                 "sample formula: an upper bound with stratified samples)");
    const char* descriptions[] = {
        "environment bandwidth in the BRDF footprint (cycles/rad)",
        "BRDF footprint's angular standard deviation (rad)",
        "spherical samples N_Omega (Eq. 4.3)",
        "occlusion spread in the footprint (rad, Eq. 4.5)",
        "BRDF-weighted fraction of occluded pilot samples",
        "minimum occluder distance (Eq. 5.1; large distance when unoccluded)",
        "screen-space bandwidth B_S (Eq. 5.3)",
        "object-space spatial bandwidth B_x",
        "object-space angular bandwidth B_theta",
        "temporal bandwidth B_t from moving occluders (Eq. 5.14, 1/s)"};
    Layer& ray_count =
        layers.add("rays", LayerKind::Continuous, 1, "rays cast for the radiance point");
    std::vector<Layer*> extra;
    for (size_t i = 0; i < radiance_point_layer_names().size(); ++i)
        extra.push_back(&layers.add(radiance_point_layer_names()[i], LayerKind::Continuous, 1,
                                    descriptions[i]));
    const int w = gb.width, h = gb.height, k = std::max(settings.stride, 1);
    const int bw = (w + k - 1) / k, bh = (h + k - 1) / k;
    std::atomic<long> rays{0}, nonfinite{0};
    progress.begin_stage("radiance points", bh);
    tbb::parallel_for(0, bh, [&](int by) {
        progress.checkpoint();
        long task_rays = 0, task_bad = 0;
        for (int bx = 0; bx < bw; ++bx) {
            const int x = std::min(bx * k + k / 2, w - 1), y = std::min(by * k + k / 2, h - 1);
            const size_t p = size_t(y) * w + x;
            CounterRng rng(uint64_t(fs.seed) ^ kPointsStream, uint64_t(frame), p, 0);
            const SurfaceHit& hit = gb.hits[p];
            RadiancePoint rp;
            if (hit.valid) {
                rp = integrator.integrate_hit(hit, -gb.view_dirs[p],
                                              point_context(gb, x, y, scene.time()), rng);
            } else {
                rp.radiance = scene.background(gb.view_dirs[p]);
            }
            std::array<double, 10> vals = radiance_point_fields(rp);
            bool bad = !std::isfinite(rp.radiance.x + rp.radiance.y + rp.radiance.z) ||
                       !std::isfinite(rp.variance);
            for (double v : vals) bad |= !std::isfinite(v);
            if (bad) {  // counted and zeroed, never kept silently
                ++task_bad;
                rp = RadiancePoint{};
                vals = radiance_point_fields(rp);
            }
            task_rays += rp.rays;
            for (int yy = by * k; yy < std::min(h, (by + 1) * k); ++yy)
                for (int xx = bx * k; xx < std::min(w, (bx + 1) * k); ++xx) {
                    const size_t q = size_t(yy) * w + xx;
                    for (int c = 0; c < 3; ++c) color.data[3 * q + c] = rp.radiance[c];
                    variance.data[q] = rp.variance;
                    ray_count.data[q] = float(rp.rays);
                    for (size_t i = 0; i < extra.size(); ++i) extra[i]->data[q] = float(vals[i]);
                }
        }
        rays.fetch_add(task_rays, std::memory_order_relaxed);
        nonfinite.fetch_add(task_bad, std::memory_order_relaxed);
        progress.advance();
    });
    return PointsPassOutput{rays.load(), nonfinite.load(), long(bw) * long(bh)};
}

}  // namespace freqlab
