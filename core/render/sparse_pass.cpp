#include "render/sparse_pass.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>

#include "render/points_pass.h"
#include "render/reconstruction.h"
#include "render/sparse_sampling.h"

namespace freqlab {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Per-channel demodulation by the texture value (textures multiply after reconstruction).
vec3 demodulate(const vec3& radiance, const vec3& texture) {
    vec3 out(0.0f);
    for (int c = 0; c < 3; ++c) out[c] = texture[c] > 1e-6f ? radiance[c] / texture[c] : 0.0f;
    return out;
}

// Chamfer distance (px; 1 and sqrt 2 steps) from each pixel to the nearest pixel of another
// object or of the background; two raster passes.
std::vector<float> distance_to_object_edge(int w, int h, const std::vector<PixelFeature>& f) {
    const float big = 1e9f, diag = 1.41421356f;
    std::vector<float> d(size_t(w) * h, big);
    auto id = [&](int x, int y) {
        return f[size_t(y) * w + x].valid ? f[size_t(y) * w + x].object : -1;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int o = id(x, y);
            bool edge = false;
            for (auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
                const int xx = x + dx, yy = y + dy;
                if (xx >= 0 && yy >= 0 && xx < w && yy < h && id(xx, yy) != o) edge = true;
            }
            if (edge) d[size_t(y) * w + x] = 1.0f;
        }
    auto relax = [&](int x, int y, int dx, int dy, float step) {
        const int xx = x + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= w || yy >= h) return;
        float& here = d[size_t(y) * w + x];
        here = std::min(here, d[size_t(yy) * w + xx] + step);
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            relax(x, y, -1, 0, 1.0f), relax(x, y, 0, -1, 1.0f);
            relax(x, y, -1, -1, diag), relax(x, y, 1, -1, diag);
        }
    for (int y = h - 1; y >= 0; --y)
        for (int x = w - 1; x >= 0; --x) {
            relax(x, y, 1, 0, 1.0f), relax(x, y, 0, 1, 1.0f);
            relax(x, y, 1, 1, diag), relax(x, y, -1, 1, diag);
        }
    return d;
}

}  // namespace

SparsePassOutput render_sparse(const RayScene& rs, const GBuffer& gb, int frame,
                               const FrameSettings& fs, const ShadingSettings& shading,
                               const PointsSettings& points, const SparseSettings& sparse,
                               const EnvBandwidthHierarchy* bandwidth, LayerSet& layers,
                               Progress& progress) {
    SparsePassOutput result;
    const int w = gb.width, h = gb.height;
    const size_t n = size_t(w) * h;
    const RadiancePointIntegrator integrator(rs, shading, points, bandwidth);
    const DirectLighting& lighting = integrator.lighting();
    const CameraRayGenerator camera(rs.scene().camera.at(rs.time()), w, h);
    const double pixel_angle = radians_per_pixel(camera, w, h);

    // Features of every pixel.
    std::vector<PixelFeature> features(n);
    std::vector<ShadingPoint> shading_points(n);
    std::vector<char> mirror(n, 0);
    for (size_t i = 0; i < n; ++i) {
        const SurfaceHit& hit = gb.hits[i];
        if (!hit.valid) continue;
        features[i] = pixel_feature(hit, gb.view_dirs[i], pixel_angle);
        shading_points[i] = lighting.shading_point(hit, -gb.view_dirs[i]);
        mirror[i] = shading_points[i].material->type == BrdfType::Mirror;
    }

    std::vector<RadiancePoint> point(n);
    std::vector<char> sampled(n, 0);
    std::vector<SampleKind> kind(n, SampleKind::None);
    std::atomic<long> rays{0};
    auto shade = [&](size_t i, uint64_t pass) {
        const int x = int(i % size_t(w)), y = int(i / size_t(w));
        CounterRng rng(uint64_t(fs.seed) ^ kPointsStream, uint64_t(frame), i, pass);
        RadiancePoint rp = integrator.integrate_hit(gb.hits[i], -gb.view_dirs[i],
                                                    point_context(gb, x, y, rs.time()), rng);
        if (!std::isfinite(rp.radiance.x + rp.radiance.y + rp.radiance.z)) rp = RadiancePoint{};
        rp.cone_samples.clear();
        rp.cone_samples.shrink_to_fit();
        rays.fetch_add(rp.rays, std::memory_order_relaxed);
        point[i] = std::move(rp);
        sampled[i] = 1;
    };
    auto shade_all = [&](const std::vector<int>& pixels, uint64_t pass) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 16),
                          [&](const tbb::blocked_range<size_t>& r) {
                              progress.checkpoint();
                              for (size_t k = r.begin(); k < r.end(); ++k)
                                  shade(size_t(pixels[k]), pass);
                          });
    };

    // 1. Initial uniform radiance points.
    auto t0 = Clock::now();
    const int k = std::max(sparse.initial_stride, 1);
    std::vector<int> initial;
    for (int y = k / 2; y < h; y += k)
        for (int x = k / 2; x < w; x += k)
            if (features[size_t(y) * w + x].valid) initial.push_back(y * w + x);
    progress.begin_stage("initial radiance points", 1);
    shade_all(initial, 0);
    for (int i : initial) kind[size_t(i)] = SampleKind::Initial;
    result.stats["stages"]["initial"] = ms_since(t0);

    // 2. Upsampled visibility statistics.
    t0 = Clock::now();
    std::vector<VisibilityStats> values;
    for (int i : initial) {
        const RadiancePoint& rp = point[size_t(i)];
        values.push_back({rp.pilot_occluded > 0 ? 1.0f : 0.0f,
                          float(std::log(std::max(rp.t_min, 1e-6))), float(rp.occlusion_ratio),
                          float(rp.sigma_V)});
    }
    std::vector<VisibilityStats> stats;
    std::vector<char> found;
    upsample_statistics(w, h, features, initial, values, k, stats, found);
    result.stats["stages"]["upsample"] = ms_since(t0);

    // 3. Density from the per-pixel screen-space bandwidth.
    t0 = Clock::now();
    const std::vector<float> to_edge = distance_to_object_edge(w, h, features);
    std::vector<float> density(n, 0.0f), mu_v(n, 0.0f), sigma_v(n, 0.0f), radius(n, 1.0f);
    tbb::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            if (!features[i].valid) continue;
            if (sampled[i]) {
                mu_v[i] = float(point[i].occlusion_ratio);
                sigma_v[i] = float(point[i].sigma_V);
            } else if (found[i]) {
                mu_v[i] = stats[i][2];
                sigma_v[i] = stats[i][3];
            }
            if (mirror[i] || !found[i]) {
                density[i] = 1.0f;  // followed reflections; or no statistics to predict from
            } else {
                const double t_min = stats[i][0] > 0.5f ? std::exp(double(stats[i][1]))
                                                        : integrator.large_distance();
                const double B_L = integrator.environment_bandwidth(shading_points[i]);
                const PointBandwidths b = integrator.bandwidths(
                    shading_points[i], point_context(gb, x, y, rs.time()), B_L, t_min);
                density[i] = float(sampling_density(b.B_S, pixel_angle, sparse));
                // Near an object's edge the reconstruction can only look inwards: samples there
                // keep it from extrapolating across the last (2 / d)^2 pixels.
                const float d = std::max(to_edge[i], 1.0f);
                density[i] = std::max(density[i], std::min(1.0f, 4.0f / (d * d)));
            }
            radius[i] =
                std::clamp(2.0f / std::sqrt(std::max(density[i], 1e-6f)), 1.0f, sparse.f_max);
        }
    });
    result.stats["stages"]["density"] = ms_since(t0);

    // 4. Rejection sampling and the adaptive radiance points.
    t0 = Clock::now();
    std::vector<int> adaptive;
    for (size_t i = 0; i < n; ++i) {
        if (!features[i].valid || sampled[i]) continue;
        CounterRng rng(uint64_t(fs.seed) ^ kSparseStream, uint64_t(frame), i, 0);
        if (rejection_sample(density[i], rng)) adaptive.push_back(int(i));
    }
    progress.begin_stage("adaptive radiance points", 1);
    shade_all(adaptive, 1);
    for (int i : adaptive) kind[size_t(i)] = SampleKind::Adaptive;
    result.stats["stages"]["shade"] = ms_since(t0);

    // 5. Reconstruction of the demodulated shading; fallbacks are shaded, then the texture.
    t0 = Clock::now();
    ReconstructionInput in;
    in.width = w;
    in.height = h;
    in.features = features;
    for (size_t i = 0; i < n; ++i)
        if (mirror[i]) in.features[i].object = -2 - int(i);  // never mixed with anything
    in.mu_v = mu_v;
    in.sigma_v = sigma_v;
    in.radius = radius;
    in.sampled = sampled;
    in.value.assign(n, vec3(0.0f));
    for (size_t i = 0; i < n; ++i)
        if (sampled[i]) in.value[i] = demodulate(point[i].radiance, shading_points[i].albedo);
    ReconstructionOutput rec = reconstruct(in, sparse);
    std::vector<int> fallback;
    for (size_t i = 0; i < n; ++i)
        if (rec.fallback[i]) fallback.push_back(int(i));
    shade_all(fallback, 2);
    for (int i : fallback) {
        kind[size_t(i)] = SampleKind::Fallback;
        rec.value[size_t(i)] =
            demodulate(point[size_t(i)].radiance, shading_points[size_t(i)].albedo);
    }
    result.stats["stages"]["reconstruct"] = ms_since(t0);

    // Layers.
    Layer& color = layers.add("color", LayerKind::Color, 3,
                              "direct lighting, sparse radiance points reconstructed");
    Layer& density_layer =
        layers.add("density", LayerKind::Continuous, 1, "sampling density (samples per pixel)");
    Layer& sampled_layer =
        layers.add("sampled", LayerKind::Categorical, 1, "radiance points by origin");
    sampled_layer.legend = {"none", "initial", "adaptive", "fallback"};
    sampled_layer.sparse = true;
    Layer& weight_layer =
        layers.add("recon_weight", LayerKind::Continuous, 1, "sum of reconstruction weights");
    Layer& radius_layer =
        layers.add("recon_radius", LayerKind::Continuous, 1, "reconstruction radius (px)");
    Layer& sample_layer = layers.add("samples", LayerKind::Color, 3,
                                     "the radiance points' own values (0 where none)");
    Layer& mu_layer =
        layers.add("mu_v", LayerKind::Continuous, 1, "reconstruction feature: occlusion ratio");
    Layer& sigma_layer =
        layers.add("sigma_v", LayerKind::Continuous, 1, "reconstruction feature: sigma_V (rad)");
    Layer& ray_layer =
        layers.add("rays", LayerKind::Continuous, 1, "rays cast for the pixel's radiance point");
    std::vector<Layer*> part1;
    for (const std::string& name : radiance_point_layer_names())
        part1.push_back(
            &layers.add(name, LayerKind::Continuous, 1, "at sampled pixels (0 elsewhere)"));
    long nonfinite = 0;
    for (size_t i = 0; i < n; ++i) {
        vec3 c(0.0f);
        if (!features[i].valid)
            c = rs.scene().background(gb.view_dirs[i]);
        else if (mirror[i])
            c = point[i].radiance;
        else
            c = rec.value[i] * shading_points[i].albedo;
        if (!std::isfinite(c.x + c.y + c.z)) {
            ++nonfinite;
            c = vec3(0.0f);
        }
        for (int ch = 0; ch < 3; ++ch) color.data[3 * i + size_t(ch)] = c[ch];
        density_layer.data[i] = density[i];
        sampled_layer.data[i] = float(int(kind[i]));
        weight_layer.data[i] = rec.weight[i];
        radius_layer.data[i] = rec.radius_used[i];
        mu_layer.data[i] = mu_v[i];
        sigma_layer.data[i] = sigma_v[i];
        if (!sampled[i]) continue;
        const RadiancePoint& rp = point[i];
        for (int ch = 0; ch < 3; ++ch) sample_layer.data[3 * i + size_t(ch)] = rp.radiance[ch];
        ray_layer.data[i] = float(rp.rays);
        const std::array<double, 10> v = radiance_point_fields(rp);
        for (size_t c2 = 0; c2 < part1.size(); ++c2)
            part1[c2]->data[i] = std::isfinite(v[c2]) ? float(v[c2]) : 0.0f;
    }
    result.rays = rays.load();
    result.nonfinite = nonfinite;
    long shaded = 0;
    for (char s : sampled) shaded += s;
    result.stats["pixels_initial"] = long(initial.size());
    result.stats["pixels_adaptive"] = long(adaptive.size());
    result.stats["fallback_pixels"] = rec.fallback_pixels;
    result.stats["pixels_shaded"] = shaded;
    return result;
}

}  // namespace freqlab
