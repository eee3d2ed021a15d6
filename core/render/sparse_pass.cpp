#include "render/sparse_pass.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>

#include "base/stopwatch.h"
#include "render/points_pass.h"
#include "render/sparse_frame.h"

namespace freqlab {

namespace {

// Per-channel demodulation by the texture value (textures multiply after reconstruction).
float log_luminance(const vec3& shading) {
    return std::log(luminance(shading) + 1e-4f);
}

float finite_or_zero(double x) {
    return std::isfinite(x) ? float(x) : 0.0f;
}

// What the upsampled statistics say for a point here. Unoccluded neighbours hold t_min = the
// large distance and B_t = 0: taken out, the means are the occluded neighbours' (what an
// occluded point here would measure).
VisibilityPlan plan_from_neighbours(const VisibilityStats& v, double large, bool own_distances) {
    VisibilityPlan plan;
    const double f = v[0];
    plan.occluded_fraction = f;
    plan.sigma_V = v[3];
    plan.own_distances = own_distances;
    if (f > 0) {
        plan.t_min_occluded = std::exp((v[1] - (1.0 - f) * std::log(std::max(large, 1e-6))) / f);
        plan.B_t_occluded = v[5] / f;
    }
    return plan;
}

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

SparseFrame::SparseFrame(const RayScene& rs_, const GBuffer& gb_, int frame_,
                         const FrameSettings& fs_, const ShadingSettings& shading,
                         const PointsSettings& points, const SparseSettings& sparse_,
                         const EnvBandwidthHierarchy* bandwidth, LayerSet& layers_,
                         Progress& progress_, const CacheHook* cache_,
                         ReconstructionRecord* record_)
    : rs(rs_),
      gb(gb_),
      frame(frame_),
      fs(fs_),
      sparse(sparse_),
      layers(layers_),
      progress(progress_),
      cache(cache_),
      record(record_),
      w(gb_.width),
      h(gb_.height),
      n(size_t(gb_.width) * gb_.height),
      scene(rs_.scene()),
      integrator(rs_, shading, points, bandwidth),
      camera(rs_.scene().camera.at(rs_.time()), gb_.width, gb_.height),
      pixel_angle(radians_per_pixel(camera, gb_.width, gb_.height)),
      features(n),
      shading_points(n),
      mirror(n, 0),
      point_slot(n, -1),
      fresh(n, 0),
      sampled(n, 0),
      value(n, vec3(0.0f)),
      kind(n, SampleKind::None),
      standin(n, -1),
      moves(scene_has_motion(rs_.scene())),
      keeper(n, -1),
      age(n, 0.0f),
      field(n, 0.0f),
      shading_field(n, 0.0f) {
    const auto t_setup = Clock::now();
    if (cache && moves) keys = key_lights(rs);
    // Features of every pixel.
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const SurfaceHit& hit = gb.hits[i];
        if (!hit.valid) return;
        features[i] = pixel_feature(hit, gb.view_dirs[i], pixel_angle);
        shading_points[i] = integrator.lighting().shading_point(hit, -gb.view_dirs[i]);
        mirror[i] = shading_points[i].material->type == BrdfType::Mirror;
    });

    result.stats["stages"]["setup"] = ms_since(t_setup);
}

bool SparseFrame::shade(size_t i, uint64_t pass, const ShadingMemo::FrameTable* table,
                        ShadingMemo::Entry* added) {
    const int x = int(i % size_t(w)), y = int(i / size_t(w));
    std::optional<VisibilityPlan> plan;
    if (pass == 1 && sparse.plan_samples && found[i] && !mirror[i])
        plan = plan_from_neighbours(stats[i], integrator.large_distance(), cache != nullptr);
    const VisibilityPlan* p = plan ? &*plan : nullptr;
    const RadiancePoint* known = table ? table->find(uint32_t(i), uint8_t(pass), p) : nullptr;
    RadiancePoint rp;
    if (known) {
        rp = *known;
        recalled.fetch_add(1, std::memory_order_relaxed);
        recalled_rays.fetch_add(rp.rays, std::memory_order_relaxed);
    } else {
        CounterRng rng(uint64_t(fs.seed) ^ kPointsStream, uint64_t(frame), i, pass);
        rp = integrator.integrate_hit(gb.hits[i], -gb.view_dirs[i],
                                      point_context(gb, x, y, rs.time()), rng, p);
        if (!std::isfinite(rp.radiance.x + rp.radiance.y + rp.radiance.z)) rp = RadiancePoint{};
        rp.cone_samples.clear();
        rp.cone_samples.shrink_to_fit();
        rays.fetch_add(rp.rays, std::memory_order_relaxed);
        if (added) {
            added->pixel = uint32_t(i);
            added->pass = uint8_t(pass);
            added->planned = p != nullptr;
            if (p) added->plan = *p;
            added->point = rp;
        }
    }
    value[i] = mirror[i] ? rp.radiance : demodulate(rp.radiance, shading_points[i].albedo);
    point_at(i) = std::move(rp);
    fresh[i] = sampled[i] = 1;
    return known != nullptr;
}

void SparseFrame::shade_all(const std::vector<int>& pixels, uint64_t pass) {
    const size_t base = shaded_points.size();
    shaded_points.resize(base + pixels.size());
    for (size_t k = 0; k < pixels.size(); ++k) point_slot[size_t(pixels[k])] = int(base + k);
    const std::shared_ptr<const ShadingMemo::FrameTable> table =
        memo ? memo->frame(frame) : nullptr;
    std::vector<ShadingMemo::Entry> added(memo ? pixels.size() : 0);
    std::vector<char> was_recalled(pixels.size(), 0);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, pixels.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
            progress.checkpoint();
            for (size_t k = r.begin(); k < r.end(); ++k)
                was_recalled[k] =
                    shade(size_t(pixels[k]), pass, table.get(), memo ? &added[k] : nullptr);
        });
    if (!memo) return;
    size_t kept = 0;
    for (size_t k = 0; k < added.size(); ++k)
        if (!was_recalled[k]) added[kept++] = std::move(added[k]);
    added.resize(kept);
    memo->add(frame, std::move(added));
}

void SparseFrame::own_features_where_unknown(const std::vector<int>& pixels) {
    for (int i : pixels)
        if (!found[size_t(i)]) {
            mu_v[size_t(i)] = float(point_at(size_t(i)).occlusion_ratio);
            sigma_v[size_t(i)] = float(point_at(size_t(i)).sigma_V);
        }
}

void SparseFrame::initial_points() {
    // 1. Initial uniform radiance points (or the kept entries standing in for them).
    const auto t0 = Clock::now();
    const int k = std::max(sparse.initial_stride, 1);
    for (int y = k / 2; y < h; y += k)
        for (int x = k / 2; x < w; x += k) {
            const int i = y * w + x;
            if (!features[size_t(i)].valid) continue;
            initial.push_back(i);
            if (standin[size_t(i)] < 0) initial_shaded.push_back(i);
        }
    progress.begin_stage("initial radiance points", 1);
    shade_all(initial_shaded, 0);
    for (int i : initial_shaded) kind[size_t(i)] = SampleKind::Initial;
    result.stats["stages"]["initial"] = ms_since(t0);
}

LayerSet SparseFrame::preview_image() const {
    LayerSet out(w, h);
    Layer& color = out.add("color", LayerKind::Color, 3,
                           "first image: the initial grid's points alone (refined next)");
    const int k = std::max(sparse.initial_stride, 1);
    // The value at initial pixel j: its fresh point's, or the cache entry standing in for it.
    auto grid_value = [&](size_t j, vec3* v) {
        if (fresh[j]) {
            *v = value[j];
            return true;
        }
        if (standin.empty() || standin[j] < 0) return false;
        const CacheRecord& r = result.cache_records[size_t(standin[j])];
        *v = cache->state.cache.object(r.object).get(r.slot).shading;
        return true;
    };
    const int gw = (w - k / 2 + k - 1) / k, gh = (h - k / 2 + k - 1) / k;
    tbb::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            vec3 c(0.0f);
            if (!features[i].valid) {
                c = rs.background(gb.view_dirs[i]);
            } else {
                const float fx = float(x - k / 2) / float(k), fy = float(y - k / 2) / float(k);
                const int gx = std::clamp(int(std::floor(fx)), 0, std::max(gw - 2, 0));
                const int gy = std::clamp(int(std::floor(fy)), 0, std::max(gh - 2, 0));
                vec3 sum(0.0f);
                float weight = 0.0f;
                for (int dy = 0; dy <= 1; ++dy)
                    for (int dx = 0; dx <= 1; ++dx) {
                        const int px = k / 2 + k * (gx + dx), py = k / 2 + k * (gy + dy);
                        if (px >= w || py >= h) continue;
                        const size_t j = size_t(py) * w + px;
                        vec3 v;
                        if (!features[j].valid || features[j].object != features[i].object ||
                            mirror[j] != mirror[i] || !grid_value(j, &v))
                            continue;
                        const float wx = 1.0f - std::min(std::fabs(fx - float(gx + dx)), 1.0f);
                        const float wy = 1.0f - std::min(std::fabs(fy - float(gy + dy)), 1.0f);
                        const float wgt = std::max(wx * wy, 1e-4f);
                        sum += wgt * v;
                        weight += wgt;
                    }
                if (weight > 0.0f) c = sum / weight;
                if (!mirror[i]) c *= shading_points[i].albedo;
            }
            if (!std::isfinite(c.x + c.y + c.z)) c = vec3(0.0f);
            for (int ch = 0; ch < 3; ++ch) color.data[3 * i + size_t(ch)] = c[ch];
        }
    });
    return out;
}

void SparseFrame::upsample() {
    // 2. Upsampled visibility statistics.
    const auto t0 = Clock::now();
    const int k = std::max(sparse.initial_stride, 1);
    own.assign(n, 0);
    initial_slot.assign(n, -1);
    for (size_t i = 0; i < n; ++i) own[i] = fresh[i];
    for (int i : initial) {
        initial_slot[size_t(i)] = int(values.size());
        if (fresh[size_t(i)]) {
            const RadiancePoint& rp = point_at(size_t(i));
            values.push_back({rp.pilot_occluded > 0 ? 1.0f : 0.0f,
                              float(std::log(std::max(rp.t_min, 1e-6))), float(rp.occlusion_ratio),
                              float(rp.sigma_V), log_luminance(value[size_t(i)]),
                              finite_or_zero(rp.B_t)});
        } else {
            const CacheRecord& r = result.cache_records[size_t(standin[size_t(i)])];
            const CacheEntry e = cache->state.cache.object(r.object).get(r.slot);
            values.push_back({e.occluded ? 1.0f : 0.0f,
                              float(std::log(std::max(double(e.t_min), 1e-6))), e.occlusion_ratio,
                              e.sigma_v, log_luminance(e.shading), finite_or_zero(e.B_t)});
            own[size_t(i)] = 1;
        }
    }
    upsample_statistics(w, h, features, initial, values, k, stats, found);
    mu_v.assign(n, 0.0f);
    sigma_v.assign(n, 0.0f);
    for (size_t i = 0; i < n; ++i) {
        if (fresh[i]) {
            mu_v[i] = float(point_at(i).occlusion_ratio);
            sigma_v[i] = float(point_at(i).sigma_V);
        } else if (own[i]) {
            mu_v[i] = values[size_t(initial_slot[i])][2];
            sigma_v[i] = values[size_t(initial_slot[i])][3];
        } else if (found[i]) {
            mu_v[i] = stats[i][2];
            sigma_v[i] = stats[i][3];
        }
    }
    result.stats["stages"]["upsample"] = ms_since(t0);
}

void SparseFrame::compute_density() {
    // 3. Density from the per-pixel screen-space bandwidth.
    const auto t0 = Clock::now();
    const std::vector<float> to_edge = distance_to_object_edge(w, h, features);
    density.assign(n, 0.0f);
    radius.assign(n, 1.0f);
    tbb::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            if (!features[i].valid) continue;
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
}

void SparseFrame::adaptive_points() {
    // 4. Rejection sampling (of what reused entries leave uncovered) and the adaptive points.
    const auto t0 = Clock::now();
    const std::vector<float> coverage =
        cache ? splat_coverage(w, h, reused, density, features) : std::vector<float>();
    for (size_t i = 0; i < n; ++i) {
        if (!features[i].valid || sampled[i]) continue;
        const float wanted = cache ? std::max(density[i] - coverage[i], 0.0f) : density[i];
        CounterRng rng(uint64_t(fs.seed) ^ kSparseStream, cache ? 0 : uint64_t(frame), i, 0);
        if (rejection_sample(wanted, rng)) adaptive.push_back(int(i));
    }
    progress.begin_stage("adaptive radiance points", 1);
    shade_all(adaptive, 1);
    for (int i : adaptive) kind[size_t(i)] = SampleKind::Adaptive;
    own_features_where_unknown(adaptive);
    result.stats["stages"]["shade"] = ms_since(t0);
}

void SparseFrame::reconstruct_image() {
    // 5. Reconstruction of the demodulated shading; fallbacks are shaded, then the texture.
    const auto t0 = Clock::now();
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
    in.value = value;
    if (cache) {
        in.sample_features = in.features;
        for (int i : reused) {
            const CacheRecord& r = result.cache_records[size_t(keeper[size_t(i)])];
            in.sample_features[size_t(i)].position = r.world_position;
            result.moved_samples.emplace_back(i, r.world_position);
        }
    }
    rec = reconstruct(in, sparse, record);
    std::vector<int> fallback;
    for (size_t i = 0; i < n; ++i)
        if (rec.fallback[i]) fallback.push_back(int(i));
    shade_all(fallback, 2);
    if (!fallback.empty()) {
        // The fallback points are samples too: reconstruct again with them, so that a pixel
        // near one sees it now as it will when the point is reused from the cache.
        for (int i : fallback) kind[size_t(i)] = SampleKind::Fallback;
        own_features_where_unknown(fallback);
        in.mu_v = mu_v;
        in.sigma_v = sigma_v;
        in.sampled = sampled;
        in.value = value;
        const long fallback_pixels = rec.fallback_pixels;
        rec = reconstruct(in, sparse, record);
        rec.fallback_pixels = fallback_pixels;
    }
    result.stats["stages"]["reconstruct"] = ms_since(t0);
}

void SparseFrame::write_layers() {
    // Layers.
    const auto t0 = Clock::now();
    Layer& color = layers.add("color", LayerKind::Color, 3,
                              "direct lighting, sparse radiance points reconstructed");
    Layer& density_layer =
        layers.add("density", LayerKind::Continuous, 1,
                   "sampling density: radiance points per pixel (1 every pixel, 0.25 one in "
                   "4; the initial grid's is 1 / stride^2)");
    Layer& sampled_layer =
        layers.add("sampled", LayerKind::Categorical, 1, "radiance points by origin");
    sampled_layer.legend = {"none", "initial", "adaptive", "fallback", "reused"};
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
            &layers.add(name, LayerKind::Continuous, 1,
                        "at sampled pixels, reused ones the cache entry's (B_L, sigma_rho, "
                        "N_omega, B_S are not kept in entries: 0 there); 0 elsewhere"));

    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        vec3 c(0.0f);
        if (!features[i].valid)
            c = rs.background(gb.view_dirs[i]);
        else if (mirror[i])
            c = sampled[i] ? value[i] : rec.value[i];
        else
            c = rec.value[i] * shading_points[i].albedo;
        if (!std::isfinite(c.x + c.y + c.z)) {
            nonfinite.fetch_add(1, std::memory_order_relaxed);
            c = vec3(0.0f);
        }
        for (int ch = 0; ch < 3; ++ch) color.data[3 * i + size_t(ch)] = c[ch];
        density_layer.data[i] = density[i];
        sampled_layer.data[i] = float(kind[i] != SampleKind::None ? int(kind[i])
                                      : sampled[i]                ? 4
                                                                  : 0);
        weight_layer.data[i] = rec.weight[i];
        radius_layer.data[i] = rec.radius_used[i];
        mu_layer.data[i] = mu_v[i];
        sigma_layer.data[i] = sigma_v[i];
        if (!sampled[i]) return;
        const vec3 own = mirror[i] ? value[i] : value[i] * shading_points[i].albedo;
        for (int ch = 0; ch < 3; ++ch) sample_layer.data[3 * i + size_t(ch)] = own[ch];
        if (!fresh[i]) {
            // A reused point: the cache entry's own values, as its pixel was when shaded.
            const int slot = reused_field_slot.empty() ? -1 : reused_field_slot[i];
            if (slot >= 0)
                for (size_t c2 = 0; c2 < part1.size(); ++c2)
                    part1[c2]->data[i] = finite_or_zero(reused_fields[size_t(slot)][c2]);
            return;
        }
        const RadiancePoint& rp = point_at(i);
        ray_layer.data[i] = float(rp.rays);
        const std::array<double, 10> v = radiance_point_fields(rp);
        for (size_t c2 = 0; c2 < part1.size(); ++c2)
            part1[c2]->data[i] = std::isfinite(v[c2]) ? float(v[c2]) : 0.0f;
    });
    result.stats["stages"]["layers"] = ms_since(t0);
}

SparsePassOutput SparseFrame::finish() {
    result.rays = rays.load();
    result.nonfinite = nonfinite.load();
    long shaded = 0;
    for (char s : fresh) shaded += s;
    result.stats["pixels_initial"] = long(initial_shaded.size());
    result.stats["pixels_adaptive"] = long(adaptive.size());
    result.stats["fallback_pixels"] = rec.fallback_pixels;
    result.stats["pixels_shaded"] = shaded;
    result.stats["pixels_new"] = shaded;
    if (memo) {
        // Recalled points cast no ray now: `rays` counts what this frame cast.
        result.stats["shading_memo"] = {{"recalled", recalled.load()},
                                        {"shaded", shaded - recalled.load()},
                                        {"rays_recalled", recalled_rays.load()}};
        memo->count_recalled(recalled.load());
    }
    return std::move(result);
}

SparsePassOutput render_sparse(const RayScene& rs, const GBuffer& gb, int frame,
                               const FrameSettings& fs, const ShadingSettings& shading,
                               const PointsSettings& points, const SparseSettings& sparse,
                               const EnvBandwidthHierarchy* bandwidth, LayerSet& layers,
                               Progress& progress, const SparseHooks& hooks) {
    SparseFrame f(rs, gb, frame, fs, shading, points, sparse, bandwidth, layers, progress,
                  hooks.cache, hooks.record);
    f.memo = hooks.memo;
    const bool cache = hooks.cache != nullptr;
    if (cache) f.cache_reproject();
    f.initial_points();
    if (hooks.preview && *hooks.preview) (*hooks.preview)(f.preview_image());
    f.upsample();
    if (cache) f.cache_resolve();
    f.compute_density();
    f.adaptive_points();
    f.reconstruct_image();
    if (cache) f.cache_insert();
    f.write_layers();
    return f.finish();
}

}  // namespace freqlab
