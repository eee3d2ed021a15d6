#include "render/sparse_pass.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>

#include "base/stopwatch.h"
#include "render/cache_pass.h"
#include "render/key_lights.h"
#include "render/points_pass.h"
#include "render/reconstruction.h"
#include "render/sparse_sampling.h"

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

SparsePassOutput render_sparse(const RayScene& rs, const GBuffer& gb, int frame,
                               const FrameSettings& fs, const ShadingSettings& shading,
                               const PointsSettings& points, const SparseSettings& sparse,
                               const EnvBandwidthHierarchy* bandwidth, LayerSet& layers,
                               Progress& progress, const CacheHook* cache) {
    SparsePassOutput result;
    const auto t_setup = Clock::now();
    const int w = gb.width, h = gb.height;
    const size_t n = size_t(w) * h;
    const Scene& scene = rs.scene();
    const RadiancePointIntegrator integrator(rs, shading, points, bandwidth);
    const DirectLighting& lighting = integrator.lighting();
    const CameraRayGenerator camera(scene.camera.at(rs.time()), w, h);
    const double pixel_angle = radians_per_pixel(camera, w, h);

    // Features of every pixel.
    std::vector<PixelFeature> features(n);
    std::vector<ShadingPoint> shading_points(n);
    std::vector<char> mirror(n, 0);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const SurfaceHit& hit = gb.hits[i];
        if (!hit.valid) return;
        features[i] = pixel_feature(hit, gb.view_dirs[i], pixel_angle);
        shading_points[i] = lighting.shading_point(hit, -gb.view_dirs[i]);
        mirror[i] = shading_points[i].material->type == BrdfType::Mirror;
    });

    // Per pixel: the fresh radiance point, or the reused cache record, and the value the
    // reconstruction reads (demodulated by the texture; mirrors: the radiance itself).
    // Radiance points are kept only where shaded: a frame-sized array of them (~170 MB at
    // 1280x720) took half a second to build and free.
    std::vector<int> point_slot(n, -1);
    std::vector<RadiancePoint> shaded_points;
    auto point_at = [&](size_t i) -> RadiancePoint& {
        return shaded_points[size_t(point_slot[i])];
    };
    std::vector<char> fresh(n, 0), sampled(n, 0);
    std::vector<vec3> value(n, vec3(0.0f));
    std::vector<SampleKind> kind(n, SampleKind::None);
    std::atomic<long> rays{0};
    // The upsampled visibility statistics (step 2); adaptive points (pass 1) plan their sample
    // count from them.
    std::vector<VisibilityStats> stats;
    std::vector<char> found;
    auto shade = [&](size_t i, uint64_t pass) {
        const int x = int(i % size_t(w)), y = int(i / size_t(w));
        CounterRng rng(uint64_t(fs.seed) ^ kPointsStream, uint64_t(frame), i, pass);
        std::optional<VisibilityPlan> plan;
        if (pass == 1 && sparse.plan_samples && found[i] && !mirror[i])
            plan = plan_from_neighbours(stats[i], integrator.large_distance(), cache != nullptr);
        RadiancePoint rp = integrator.integrate_hit(gb.hits[i], -gb.view_dirs[i],
                                                    point_context(gb, x, y, rs.time()), rng,
                                                    plan ? &*plan : nullptr);
        if (!std::isfinite(rp.radiance.x + rp.radiance.y + rp.radiance.z)) rp = RadiancePoint{};
        rp.cone_samples.clear();
        rp.cone_samples.shrink_to_fit();
        rays.fetch_add(rp.rays, std::memory_order_relaxed);
        value[i] = mirror[i] ? rp.radiance : demodulate(rp.radiance, shading_points[i].albedo);
        point_at(i) = std::move(rp);
        fresh[i] = sampled[i] = 1;
    };
    auto shade_all = [&](const std::vector<int>& pixels, uint64_t pass) {
        const size_t base = shaded_points.size();
        shaded_points.resize(base + pixels.size());
        for (size_t k = 0; k < pixels.size(); ++k) point_slot[size_t(pixels[k])] = int(base + k);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 16),
                          [&](const tbb::blocked_range<size_t>& r) {
                              progress.checkpoint();
                              for (size_t k = r.begin(); k < r.end(); ++k)
                                  shade(size_t(pixels[k]), pass);
                          });
    };

    result.stats["stages"]["setup"] = ms_since(t_setup);
    // 0. The cache: move, project and test every entry (all but the occlusion test).
    auto t0 = Clock::now();
    CacheFrameView view;
    std::vector<SurfaceHit> reflected;
    std::vector<float> footprint;
    std::vector<CacheRecord>& records = result.cache_records;
    std::vector<int> standin(n, -1);  // initial pixels a kept entry stands in for
    const bool moves = scene_has_motion(scene);
    // Method cache: the key lights whose visibility entries record (render/key_lights.h).
    const std::vector<KeyLight> keys = cache && moves ? key_lights(rs) : std::vector<KeyLight>{};
    if (cache) {
        reflected.resize(n);
        footprint.resize(n);
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            footprint[i] = features[i].footprint;
            if (mirror[i])
                reflected[i] = integrator.follow_mirrors(gb.hits[i], -gb.view_dirs[i]).hit;
        });
        view.width = w;
        view.height = h;
        view.camera = &camera;
        view.hits = &gb.hits;
        view.footprint = &footprint;
        view.reflected = &reflected;
        view.time = rs.time();
        for (size_t o = 0; o < scene.objects.size(); ++o)
            view.to_world.push_back(rs.object_to_world(int(o)));
        records = reproject_entries(cache->state.cache, view, cache->settings);
        if (!moves) standin = first_survivors(records, int(n), cache->state.cache);
        result.stats["stages"]["reproject"] = ms_since(t0);
    }

    // 1. Initial uniform radiance points (or the kept entries standing in for them).
    t0 = Clock::now();
    const int k = std::max(sparse.initial_stride, 1);
    std::vector<int> initial, initial_shaded;
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

    // 2. Upsampled visibility statistics.
    t0 = Clock::now();
    std::vector<VisibilityStats> values;
    std::vector<char> own(n, 0);  // the pixel's statistics are its own point's (or stand-in's)
    std::vector<int> initial_slot(n, -1);
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
            const CacheRecord& r = records[size_t(standin[size_t(i)])];
            const CacheEntry e = cache->state.cache.object(r.object).get(r.slot);
            values.push_back({e.occluded ? 1.0f : 0.0f,
                              float(std::log(std::max(double(e.t_min), 1e-6))), e.occlusion_ratio,
                              e.sigma_v, log_luminance(e.shading), finite_or_zero(e.B_t)});
            own[size_t(i)] = 1;
        }
    }
    upsample_statistics(w, h, features, initial, values, k, stats, found);
    std::vector<float> mu_v(n, 0.0f), sigma_v(n, 0.0f);
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

    // 2b. The cache: the occlusion test against this frame's statistics, then one entry per
    // pixel (merging the others where the rule allows).
    std::vector<int> keeper(n, -1), reused;
    // The upsampled occlusion ratio and log shading at every pixel: what the observed-change
    // tests compare between an entry's creation and now.
    std::vector<float> age(n, 0.0f), field(n, 0.0f), shading_field(n, 0.0f);
    if (cache) {
        t0 = Clock::now();
        for (size_t i = 0; i < n; ++i) {
            field[i] = found[i] ? stats[i][2] : mu_v[i];
            // Only when something moves can the shading change in time (the view's own changes
            // are the angular test's): a camera moving through a still scene expires nothing.
            shading_field[i] = found[i] && moves ? stats[i][4] : NAN;
        }
        apply_field_tests(records, field, shading_field, found, cache->settings);
        if (moves && cache->settings.test_temporal && !keys.empty()) {
            // The key-light half of the temporal test (render/key_lights.h).
            tbb::parallel_for(size_t(0), records.size(), [&](size_t k) {
                CacheRecord& r = records[k];
                if (r.decision != CacheDecision::Reused) return;
                const ObjectCache& oc = cache->state.cache.object(r.object);
                if (!oc.key_light_known(r.slot)) return;
                r.tests.key_lights_tested = true;
                r.tests.key_lights_then = oc.key_light_mask(r.slot);
                r.tests.key_lights_now = key_light_mask(rs, keys, r.world_position,
                                                        gb.hits[size_t(r.pixel)].geometric_normal);
                r.decision = decide_key_lights(r.tests, cache->settings);
            });
        }
        keeper = resolve_pixels(records, cache->state.cache, view, cache->settings);
        // Per pixel in parallel (each writes only its own pixel), then the list in pixel order.
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            if (keeper[i] < 0 || fresh[i]) return;
            const CacheRecord& r = records[size_t(keeper[i])];
            const CacheEntry e = cache->state.cache.object(r.object).get(r.slot);
            value[i] = e.shading;
            if (!found[i] && !own[i]) {  // as for new points: upsampled where known, else own
                mu_v[i] = e.occlusion_ratio;
                sigma_v[i] = e.sigma_v;
            }
            age[i] = float(r.tests.age);
            sampled[i] = 1;
        });
        for (size_t i = 0; i < n; ++i)
            if (keeper[i] >= 0 && !fresh[i]) reused.push_back(int(i));
        result.stats["stages"]["reproject"] =
            result.stats["stages"]["reproject"].get<double>() + ms_since(t0);
    }

    // 3. Density from the per-pixel screen-space bandwidth.
    t0 = Clock::now();
    const std::vector<float> to_edge = distance_to_object_edge(w, h, features);
    std::vector<float> density(n, 0.0f), radius(n, 1.0f);
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

    // 4. Rejection sampling (of what reused entries leave uncovered) and the adaptive points.
    t0 = Clock::now();
    const std::vector<float> coverage =
        cache ? splat_coverage(w, h, reused, density, features) : std::vector<float>();
    std::vector<int> adaptive;
    for (size_t i = 0; i < n; ++i) {
        if (!features[i].valid || sampled[i]) continue;
        const float wanted = cache ? std::max(density[i] - coverage[i], 0.0f) : density[i];
        CounterRng rng(uint64_t(fs.seed) ^ kSparseStream, cache ? 0 : uint64_t(frame), i, 0);
        if (rejection_sample(wanted, rng)) adaptive.push_back(int(i));
    }
    progress.begin_stage("adaptive radiance points", 1);
    shade_all(adaptive, 1);
    // Adaptive points keep the upsampled statistics as their reconstruction features (they
    // were chosen from them); only where none reached do they use their own.
    auto own_features_where_unknown = [&](const std::vector<int>& pixels) {
        for (int i : pixels)
            if (!found[size_t(i)]) {
                mu_v[size_t(i)] = float(point_at(size_t(i)).occlusion_ratio);
                sigma_v[size_t(i)] = float(point_at(size_t(i)).sigma_V);
            }
    };
    for (int i : adaptive) kind[size_t(i)] = SampleKind::Adaptive;
    own_features_where_unknown(adaptive);
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
    in.value = value;
    if (cache) {
        in.sample_features = in.features;
        for (int i : reused) {
            const CacheRecord& r = records[size_t(keeper[size_t(i)])];
            in.sample_features[size_t(i)].position = r.world_position;
        }
    }
    ReconstructionOutput rec = reconstruct(in, sparse);
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
        rec = reconstruct(in, sparse);
        rec.fallback_pixels = fallback_pixels;
    }
    result.stats["stages"]["reconstruct"] = ms_since(t0);

    // 6. The cache: batch discard, then every new point becomes an entry.
    if (cache) {
        t0 = Clock::now();
        RadianceCache& rc = cache->state.cache;
        const std::vector<long> counts = commit_decisions(records, rc);
        std::vector<std::vector<size_t>> by_object(scene.objects.size());
        for (size_t i = 0; i < n; ++i)
            if (fresh[i]) by_object[size_t(gb.hits[i].object)].push_back(i);
        // What each new entry sees of the key lights (only when something moves).
        std::vector<uint8_t> key_mask(moves && !keys.empty() ? n : 0, 0);
        if (!key_mask.empty())
            tbb::parallel_for(size_t(0), n, [&](size_t i) {
                if (fresh[i])
                    key_mask[i] =
                        key_light_mask(rs, keys, gb.hits[i].position, gb.hits[i].geometric_normal);
            });
        std::vector<CacheEntry> entries;
        for (size_t o = 0; o < by_object.size(); ++o) {
            ObjectCache& oc = rc.object(int(o));
            oc.reserve_for(by_object[o].size());
            const bool moving = !scene.objects[o].animation.is_static();
            // The entries in parallel, their insertion (slot allocation) in pixel order.
            const std::vector<size_t>& pixels = by_object[o];
            entries.resize(pixels.size());
            tbb::parallel_for(size_t(0), pixels.size(), [&](size_t m) {
                const size_t i = pixels[m];
                const SurfaceHit& refl = reflected[i];
                CacheEntry& entry = entries[m];
                entry = make_cache_entry(gb.hits[i], gb.view_dirs[i], view.to_world[o], point_at(i),
                                         value[i], field[i], shading_field[i], mirror[i], refl,
                                         refl.valid ? &view.to_world[size_t(refl.object)] : nullptr,
                                         moving, rs.time());
                if (!key_mask.empty()) {
                    entry.key_light_mask = key_mask[i];
                    entry.key_light_known = true;
                }
            });
            for (size_t m = 0; m < pixels.size(); ++m) oc.insert(entries[m]);
        }
        const long evicted = rc.evict_oldest(size_t(double(cache->settings.max_megabytes) * 1e6));
        result.stats["stages"]["insert"] = ms_since(t0);
        nlohmann::json cs = cache_stats(counts, rc);
        for (const auto& [key, v] : cs.items()) result.stats[key] = v;
        result.stats["evicted"] = evicted;
        result.stats["pixels_reused"] = long(reused.size());
        result.stats["pixels_standin"] = long(initial.size() - initial_shaded.size());
        std::vector<PixelDecision> decision(n, PixelDecision::None);
        for (size_t i = 0; i < n; ++i) {
            if (kind[i] != SampleKind::None)
                decision[i] = kind[i] == SampleKind::Initial    ? PixelDecision::NewInitial
                              : kind[i] == SampleKind::Adaptive ? PixelDecision::NewAdaptive
                                                                : PixelDecision::NewFallback;
            else if (sampled[i])
                decision[i] = PixelDecision::Reused;
        }
        add_cache_layers(layers, decision, age, records);
    }

    // Layers.
    t0 = Clock::now();
    Layer& color = layers.add("color", LayerKind::Color, 3,
                              "direct lighting, sparse radiance points reconstructed");
    Layer& density_layer =
        layers.add("density", LayerKind::Continuous, 1, "sampling density (samples per pixel)");
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
            &layers.add(name, LayerKind::Continuous, 1, "at sampled pixels (0 elsewhere)"));
    std::atomic<long> nonfinite{0};
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
        if (!fresh[i]) return;
        const RadiancePoint& rp = point_at(i);
        ray_layer.data[i] = float(rp.rays);
        const std::array<double, 10> v = radiance_point_fields(rp);
        for (size_t c2 = 0; c2 < part1.size(); ++c2)
            part1[c2]->data[i] = std::isfinite(v[c2]) ? float(v[c2]) : 0.0f;
    });
    result.stats["stages"]["layers"] = ms_since(t0);
    result.rays = rays.load();
    result.nonfinite = nonfinite.load();
    long shaded = 0;
    for (char s : fresh) shaded += s;
    result.stats["pixels_initial"] = long(initial_shaded.size());
    result.stats["pixels_adaptive"] = long(adaptive.size());
    result.stats["fallback_pixels"] = rec.fallback_pixels;
    result.stats["pixels_shaded"] = shaded;
    result.stats["pixels_new"] = shaded;
    return result;
}

}  // namespace freqlab
