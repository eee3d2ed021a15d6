// `freqlab bench SCENE --study sparse`: method A's sparse image-space sampling against radiance
// points at every pixel, on one frame (issue "Method A, part 2", acceptance 3 and 4).
//
// `points` and `sparse` are rendered --runs times, interleaved (this machine's timing drifts by
// tens of percent between minutes, so each run's ratio compares neighbours in time); reported:
// per-run and median time ratio, the ray ratio (a stable measure of the work), RMSE of each
// against the reference and their ratio, the fraction of pixels shaded, the sparse stages'
// medians and reconstruction's share of the frame, and the equal-time MIS RMSE (spp fitted to
// the sparse median time). Writes bench_sparse.json and bench_sparse.csv (one row per render).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "base/error.h"
#include "bench_common.h"
#include "commands.h"
#include "image/metrics.h"
#include "render/frame_renderer.h"
#include "scene/scene_loader.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

int run_bench_sparse(const BenchArgs& a) {
    if (a.out.empty()) throw Error("--out", "", "expected an output directory");
    if (a.runs < 1) throw Error("--runs", std::to_string(a.runs), "expected >= 1");
    const Scene scene = load_scene(a.scene);
    const std::pair<int, int> size = parse_size(a.size, "--size");
    const int w = size.first, h = size.second;
    if (a.frame < 0 || a.frame >= scene.frame_count)
        throw Error("--frame", std::to_string(a.frame),
                    "expected a frame in 0.." + std::to_string(scene.frame_count - 1));
    EmbreeDevice device(0);
    auto config_for = [&](RenderMethod method, const std::vector<std::string>& extra) {
        return bench_config(method, a.sets, extra, w, h);
    };
    Progress progress;
    std::fprintf(stderr, "reference frame %d...\n", a.frame);
    const LayerSet reference = FrameRenderer(scene, config_for(RenderMethod::Reference, {}), device)
                                   .render(a.frame, progress)
                                   .layers;

    struct Run {
        std::string method;
        int run = 0;
        json stats;
        double rmse = NAN;
    };
    std::vector<Run> runs;
    std::map<std::string, std::vector<double>> times;
    std::vector<double> time_ratio;  // sparse over the points run just before it
    std::map<std::string, std::vector<double>> stage_ms;
    for (int k = 0; k < a.runs; ++k) {
        double t_points = NAN;
        for (RenderMethod m : {RenderMethod::Points, RenderMethod::Sparse}) {
            const std::string name = m == RenderMethod::Points ? "points" : "sparse";
            // A fresh renderer per run: nothing carries over but the OS's caches.
            const FrameResult r =
                FrameRenderer(scene, config_for(m, {}), device).render(a.frame, progress);
            Run run{name, k, r.stats, compare_layers(r.layers, reference).rmse};
            const double t = r.stats["time_ms"].get<double>();
            times[name].push_back(t);
            if (m == RenderMethod::Points) {
                t_points = t;
            } else {
                time_ratio.push_back(t / t_points);
                for (const auto& [stage, ms] : r.stats["stages"].items())
                    stage_ms[stage].push_back(ms.get<double>());
            }
            std::fprintf(stderr, "run %d %s: %.0f ms, rmse %.5f\n", k + 1, name.c_str(), t,
                         run.rmse);
            runs.push_back(std::move(run));
        }
    }
    const Run& points = runs[0];
    const Run& sparse = runs[1];  // RMSE, rays and pixels do not change between runs
    const double t_sparse = median(times["sparse"]);
    const int spp = equal_time_mis_spp(
        scene,
        [&](int n) { return config_for(RenderMethod::Mis, {"mis.spp=" + std::to_string(n)}); },
        device, a.frame, t_sparse, progress);
    const FrameResult mis =
        FrameRenderer(scene, config_for(RenderMethod::Mis, {"mis.spp=" + std::to_string(spp)}),
                      device)
            .render(a.frame, progress);
    const double mis_rmse = compare_layers(mis.layers, reference).rmse;

    json stages = json::object();
    for (const auto& [stage, v] : stage_ms) stages[stage] = median(v);
    const double shaded =
        sparse.stats["pixels_shaded"].get<double>() / sparse.stats["pixels_total"].get<double>();
    json report = {
        {"scene", a.scene},
        {"frame", a.frame},
        {"size", a.size},
        {"runs", a.runs},
        {"points",
         {{"median_ms", median(times["points"])},
          {"rmse", points.rmse},
          {"rays", points.stats["rays"]}}},
        {"sparse",
         {{"median_ms", t_sparse},
          {"rmse", sparse.rmse},
          {"rays", sparse.stats["rays"]},
          {"pixels_shaded_fraction", shaded},
          {"median_stage_ms", stages},
          {"reconstruct_share",
           stage_ms.count("reconstruct") ? median(stage_ms["reconstruct"]) / t_sparse : NAN}}},
        {"sparse_over_points",
         {{"time_per_run", time_ratio},
          {"time_median", median(time_ratio)},
          {"rays", sparse.stats["rays"].get<double>() / points.stats["rays"].get<double>()},
          {"rmse", sparse.rmse / points.rmse}}},
        {"mis_equal_time", {{"spp", spp}, {"time_ms", mis.stats["time_ms"]}, {"rmse", mis_rmse}}},
    };
    std::error_code ec;
    fs::create_directories(a.out, ec);
    const fs::path json_path = fs::path(a.out) / "bench_sparse.json";
    std::ofstream(json_path) << report.dump(2) << "\n";
    std::ofstream csv(fs::path(a.out) / "bench_sparse.csv");
    csv << "run,method,time_ms,rays,pixels_shaded,rmse\n";
    for (const Run& r : runs)
        csv << r.run << "," << r.method << "," << r.stats["time_ms"].get<double>() << ","
            << r.stats["rays"].get<long>() << ","
            << (r.stats.contains("pixels_shaded") ? r.stats["pixels_shaded"].get<long>() : 0L)
            << "," << r.rmse << "\n";
    std::printf("%s\n", report.dump(2).c_str());
    std::fprintf(stderr, "wrote %s\n", json_path.string().c_str());
    return 0;
}

}  // namespace freqlab
