// `freqlab bench SCENE --study cache | cache-ablation`: method A's cache over an animation
// (issue "Method A, part 3", acceptance 3 and 4).
//
// cache: `--method sparse` (the no-cache baseline) and `--method cache` over --frames, frame by
//   frame in turn (two renderers, so the machine's drift hits both alike); RMSE against the
//   reference every --error-every frames; the MIS baseline at equal time (equal_time_mis_spp at the
//   cache's mean frame time) on the same frames. Writes regions.exr, bench_cache.csv (per frame),
//   bench_cache.json (summary over frames >= 5) and cumulative_time.png.
// cache-ablation: the cache with and without the temporal test; RMSE over the pixels the moving
//   shadows sweep: pixels whose first surface belongs to a static object in every frame and
//   whose visibility of a key light (the sun, point / directional lights; key_lights.h)
//   changes somewhere in --frames — found geometrically, one shadow ray per key light, pixel
//   and frame, so reference noise and glossy reflections of the moving parts stay out of it.
//   Also over the looser region where the reference varies by more than 10 % over the measured
//   frames (`changed`: it includes those reflections).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "bench_common.h"
#include "commands.h"
#include "image/image_io.h"
#include "image/line_plot.h"
#include "image/metrics.h"
#include "render/frame_renderer.h"
#include "render/gbuffer.h"
#include "render/key_lights.h"
#include "scene/scene_loader.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct FrameRecord {
    int frame = 0;
    double time_ms = 0.0;
    json stats;
    double rmse = NAN, rmse_swept = NAN, rmse_changed = NAN;
};

double mean(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? NAN : s / double(v.size());
}

double rmse_over(const Layer& a, const Layer& b, const std::vector<char>& mask) {
    double se = 0;
    long n = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
        if (!mask[i]) continue;
        for (int c = 0; c < 3; ++c) {
            const double d = double(a.data[3 * i + size_t(c)]) - b.data[3 * i + size_t(c)];
            se += d * d;
        }
        n += 3;
    }
    return n ? std::sqrt(se / double(n)) : NAN;
}

}  // namespace

int run_bench_cache(const BenchArgs& a) {
    if (a.out.empty()) throw Error("--out", "", "expected an output directory");
    if (a.error_every < 1)
        throw Error("--error-every", std::to_string(a.error_every), "expected >= 1");
    const Scene scene = load_scene(a.scene);
    const std::pair<int, int> size = parse_size(a.size, "--size");
    const int w = size.first, h = size.second;
    const std::pair<int, int> range = parse_frame_range(
        a.frames.empty() ? "0:" + std::to_string(scene.frame_count) : a.frames, scene.frame_count);
    const int first = range.first, last = range.second;
    EmbreeDevice device(0);
    auto config_for = [&](RenderMethod method, const std::vector<std::string>& extra) {
        return bench_config(method, a.sets, extra, w, h);
    };
    Progress progress;

    // References (from the reference cache when rendered before), colour only.
    std::map<int, LayerSet> reference;
    {
        FrameRenderer renderer(scene, config_for(RenderMethod::Reference, {}), device);
        for (int f = first; f < last; f += a.error_every) {
            std::fprintf(stderr, "reference frame %d...\n", f);
            const FrameResult r = renderer.render(f, progress);
            LayerSet keep(w, h);
            keep.add("color", LayerKind::Color, 3).data = r.layers.get("color").data;
            reference.emplace(f, std::move(keep));
        }
    }
    // The regions, over pixels whose first surface is a static object in every frame.
    const size_t n = size_t(w) * h;
    auto is_static = [&](int object_index) {
        return object_index >= 0 && object_index < int(scene.objects.size()) &&
               scene.objects[size_t(object_index)].animation.is_static();
    };
    std::vector<char> swept(n, 0), changed(n, 0);
    size_t key_light_count = 0;
    {
        // Swept: the key-light visibility of the pixel's first surface changes over the frames.
        std::vector<char> moving(n, 0);
        std::vector<uint8_t> lit_any(n, 0), lit_all(n, 0xff);
        const RenderConfig gc = config_for(RenderMethod::GBuffer, {});
        RayScene rs(scene, device);
        for (int f = first; f < last; ++f) {
            rs.update(scene.time_of_frame(f));
            const GBufferOutput g = render_gbuffer(rs, f, gc.frame, gc.gbuffer, progress);
            const std::vector<KeyLight> keys = key_lights(rs);
            key_light_count = std::max(key_light_count, keys.size());
            tbb::parallel_for(size_t(0), n, [&](size_t i) {
                const SurfaceHit& hit = g.gbuffer.hits[i];
                if (!hit.valid || !is_static(hit.object)) {
                    moving[i] = 1;
                    return;
                }
                const uint8_t m = key_light_mask(rs, keys, hit.position, hit.geometric_normal);
                lit_any[i] |= m;
                lit_all[i] &= m;
            });
        }
        // Changed: the reference varies by more than 10 % over the measured frames.
        std::vector<float> lo(n, INFINITY), hi(n, -INFINITY);
        for (const auto& [f, ref] : reference) {
            const Layer& c = ref.get("color");
            for (size_t i = 0; i < n; ++i) {
                lo[i] = std::min(lo[i], c.luminance_at(i));
                hi[i] = std::max(hi[i], c.luminance_at(i));
            }
        }
        for (size_t i = 0; i < n; ++i) {
            swept[i] = !moving[i] && lit_any[i] != lit_all[i];
            changed[i] = !moving[i] && hi[i] - lo[i] > 0.1f * hi[i];
        }
    }
    long swept_pixels = 0, changed_pixels = 0;
    for (size_t i = 0; i < n; ++i) swept_pixels += swept[i], changed_pixels += changed[i];

    auto render_record = [&](FrameRenderer& renderer, const std::string& label, int f) {
        FrameRecord rec;
        rec.frame = f;
        const FrameResult r = renderer.render(f, progress);
        rec.stats = r.stats;
        rec.time_ms = r.stats["time_ms"].get<double>();
        if (auto it = reference.find(f); it != reference.end()) {
            rec.rmse = compare_layers(r.layers, it->second).rmse;
            rec.rmse_swept = rmse_over(r.layers.get("color"), it->second.get("color"), swept);
            rec.rmse_changed = rmse_over(r.layers.get("color"), it->second.get("color"), changed);
        }
        std::fprintf(stderr, "%s frame %d: %.0f ms%s\n", label.c_str(), f, rec.time_ms,
                     std::isfinite(rec.rmse) ? (", rmse " + std::to_string(rec.rmse)).c_str() : "");
        return rec;
    };
    // The runs render frame by frame in turn (this machine's speed drifts by several percent
    // between minutes: a whole run after another would carry that drift into the time ratio).
    struct RunSpec {
        std::string label;
        RenderMethod method;
        std::vector<std::string> extra;
    };
    auto run_interleaved = [&](const std::vector<RunSpec>& specs) {
        std::vector<std::unique_ptr<FrameRenderer>> renderers;
        for (const RunSpec& s : specs)
            renderers.push_back(
                std::make_unique<FrameRenderer>(scene, config_for(s.method, s.extra), device));
        std::vector<std::pair<std::string, std::vector<FrameRecord>>> out;
        for (const RunSpec& s : specs) out.push_back({s.label, {}});
        for (int f = first; f < last; ++f)
            for (size_t k = 0; k < specs.size(); ++k)
                out[k].second.push_back(render_record(*renderers[k], specs[k].label, f));
        return out;
    };
    auto summary = [&](const std::vector<FrameRecord>& recs) {
        std::vector<double> rmse, swept_rmse, changed_rmse, new_pct, swept_warm, changed_warm;
        double total = 0, bytes_per_point = 0;
        for (const FrameRecord& r : recs) {
            total += r.time_ms;
            if (std::isfinite(r.rmse)) {
                rmse.push_back(r.rmse);
                swept_rmse.push_back(r.rmse_swept);
                changed_rmse.push_back(r.rmse_changed);
                if (r.frame >= first + 5) {
                    swept_warm.push_back(r.rmse_swept);
                    changed_warm.push_back(r.rmse_changed);
                }
            }
            if (r.frame >= first + 5)
                new_pct.push_back(100.0 * r.stats["pixels_new"].get<double>() /
                                  r.stats["pixels_total"].get<double>());
            if (r.stats.contains("cache_bytes_per_point"))
                bytes_per_point =
                    std::max(bytes_per_point, r.stats["cache_bytes_per_point"].get<double>());
        }
        json j = {{"cumulative_ms", total},
                  {"mean_frame_ms", total / double(recs.size())},
                  {"mean_rmse", mean(rmse)},
                  {"mean_rmse_swept", mean(swept_rmse)},
                  {"mean_rmse_changed", mean(changed_rmse)},
                  {"mean_rmse_swept_from_frame_5", mean(swept_warm)},
                  {"mean_rmse_changed_from_frame_5", mean(changed_warm)},
                  {"mean_new_pixels_pct_from_frame_5", mean(new_pct)}};
        if (bytes_per_point > 0) j["max_cache_bytes_per_point"] = bytes_per_point;
        return j;
    };
    std::error_code ec;
    fs::create_directories(a.out, ec);
    {
        LayerSet regions(w, h);
        Layer& r = regions.add("region", LayerKind::Categorical, 1,
                               "the pixels the errors are measured over");
        r.legend = {"outside", "changed", "swept", "swept and changed"};
        for (size_t i = 0; i < n; ++i) r.data[i] = float(changed[i] + 2 * swept[i]);
        write_exr(fs::path(a.out) / "regions.exr", regions, {{"scene", a.scene}});
    }

    std::vector<std::pair<std::string, std::vector<FrameRecord>>> runs;
    json report = {{"scene", a.scene},
                   {"size", a.size},
                   {"frames", std::to_string(first) + ":" + std::to_string(last)},
                   {"error_every", a.error_every},
                   {"key_lights", key_light_count},
                   {"swept_pixels", swept_pixels},
                   {"changed_pixels", changed_pixels}};
    if (a.study == "cache-ablation") {
        runs = run_interleaved(
            {{"cache", RenderMethod::Cache, {}},
             {"cache_no_temporal", RenderMethod::Cache, {"cache.test_temporal=false"}}});
        for (auto& [label, recs] : runs) report[label] = summary(recs);
        // The ratios over frames >= 5 (the cache's warm-up, as for the new-pixel rate): on the
        // first frame both runs are the same render (nothing is cached yet).
        auto ratio = [&](const char* key) {
            return report["cache"][key].get<double>() /
                   report["cache_no_temporal"][key].get<double>();
        };
        report["swept_rmse_with_over_without_temporal"] = ratio("mean_rmse_swept_from_frame_5");
        report["changed_rmse_with_over_without_temporal"] = ratio("mean_rmse_changed_from_frame_5");
        report["swept_rmse_with_over_without_temporal_all_frames"] = ratio("mean_rmse_swept");
    } else {
        runs = run_interleaved(
            {{"sparse", RenderMethod::Sparse, {}}, {"cache", RenderMethod::Cache, {}}});
        for (auto& [label, recs] : runs) report[label] = summary(recs);
        const double t_cache = report["cache"]["mean_frame_ms"].get<double>();
        // MIS at equal time: the spp whose frame takes the cache's mean frame time.
        const int spp = equal_time_mis_spp(
            scene,
            [&](int n) { return config_for(RenderMethod::Mis, {"mis.spp=" + std::to_string(n)}); },
            device, first, t_cache, progress);
        std::vector<FrameRecord> mis;
        FrameRenderer mis_renderer(
            scene, config_for(RenderMethod::Mis, {"mis.spp=" + std::to_string(spp)}), device);
        for (const auto& [f, ref] : reference) {
            FrameRecord rec;
            rec.frame = f;
            const FrameResult r = mis_renderer.render(f, progress);
            rec.time_ms = r.stats["time_ms"].get<double>();
            rec.rmse = compare_layers(r.layers, ref).rmse;
            rec.rmse_swept = rmse_over(r.layers.get("color"), ref.get("color"), swept);
            mis.push_back(rec);
        }
        std::vector<double> mis_rmse, mis_frame_ms;
        for (const FrameRecord& r : mis)
            mis_rmse.push_back(r.rmse), mis_frame_ms.push_back(r.time_ms);
        report["mis_equal_time"] = {
            {"spp", spp}, {"mean_frame_ms", mean(mis_frame_ms)}, {"mean_rmse", mean(mis_rmse)}};
        const json &s = report["sparse"], &c = report["cache"];
        report["cache_over_sparse"] = {
            {"mean_rmse", c["mean_rmse"].get<double>() / s["mean_rmse"].get<double>()},
            {"cumulative_time",
             c["cumulative_ms"].get<double>() / s["cumulative_ms"].get<double>()}};
        report["cache_over_mis_equal_time_rmse"] = c["mean_rmse"].get<double>() / mean(mis_rmse);
    }
    for (const std::string& s : a.sets) report["sets"].push_back(s);

    // Per-frame CSV and the cumulative-time plot.
    std::string csv =
        "run,frame,time_ms,cumulative_ms,rmse,rmse_swept,pixels_new,pixels_reused,pixels_total,"
        "cache_points,cache_bytes,merged,discard_zbuffer,discard_frustum,discard_spatial,"
        "discard_angular,discard_temporal,discard_occlusion\n";
    LinePlot plot;
    plot.title = "Cumulative render time, " + fs::path(a.scene).filename().string() + " " + a.size;
    plot.x_label = "frame";
    plot.y_label = "seconds";
    const vec3 colours[] = {vec3(0.3f, 0.55f, 1.0f), vec3(1.0f, 0.35f, 0.25f)};
    for (size_t k = 0; k < runs.size(); ++k) {
        const auto& [label, recs] = runs[k];
        PlotSeries series{label, colours[k % 2], {}, {}};
        double cumulative = 0;
        for (const FrameRecord& r : recs) {
            cumulative += r.time_ms;
            series.x.push_back(r.frame);
            series.y.push_back(cumulative / 1000.0);
            auto get = [&](const char* key) {
                return r.stats.contains(key) ? std::to_string(r.stats[key].get<long>()) : "";
            };
            auto discard = [&](const char* key) {
                return r.stats.contains("discards")
                           ? std::to_string(r.stats["discards"][key].get<long>())
                           : "";
            };
            char head[160];
            std::snprintf(head, sizeof head, "%s,%d,%.3f,%.3f,", label.c_str(), r.frame, r.time_ms,
                          cumulative);
            csv += head + (std::isfinite(r.rmse) ? std::to_string(r.rmse) : "") + "," +
                   (std::isfinite(r.rmse_swept) ? std::to_string(r.rmse_swept) : "") + "," +
                   get("pixels_new") + "," + get("pixels_reused") + "," + get("pixels_total") +
                   "," + get("cache_points") + "," + get("cache_bytes") + "," + get("merged") +
                   "," + discard("zbuffer") + "," + discard("frustum") + "," + discard("spatial") +
                   "," + discard("angular") + "," + discard("temporal") + "," +
                   discard("occlusion") + "\n";
        }
        plot.series.push_back(std::move(series));
    }
    const std::string stem = a.study == "cache-ablation" ? "bench_cache_ablation" : "bench_cache";
    write_text_atomically(fs::path(a.out) / (stem + ".csv"), csv);
    write_text_atomically(fs::path(a.out) / (stem + ".json"), report.dump(2) + "\n");
    write_line_plot(fs::path(a.out) / (stem + "_cumulative_time.png"), plot);
    std::cout << report.dump(2) << std::endl;
    return 0;
}

}  // namespace freqlab
