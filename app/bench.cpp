// `freqlab bench SCENE --study points`: method A's adaptive radiance points against the fixed-N
// MIS baseline at equal per-pixel error (issue "Method A, part 1", acceptance 6).
//
// Per pixel i (hits only): the adaptive estimate's mean squared error against the reference over
// --runs independent seeds, its mean ray count; the MIS estimator's per-sample variance v_i and
// rays per sample r_i from one 256-spp render of plain (independent-sample) MIS, whose error
// falls as 1/N. MIS reaches the adaptive error at N_i = v_i / MSE_i samples, so with rays
// N_i r_i. Reported:
//   - per pixel: adaptive rays / MIS rays at equal error (median, quartiles);
//   - fixed N (one count for every pixel, as the baseline renders): the N that reaches the
//     adaptive error on 50 / 90 / 95 % of the pixels, and its total rays over the adaptive's;
//   - at equal rays (the adaptive's total): the image RMSE of adaptive points, of plain MIS and
//     of stratified MIS (mis.stratified), which separates what the per-point sample counts
//     (allocation) buy from what stratified samples buy.
// The ruler: the adaptive points' stratified samples reach errors below the noise of a 1024-spp
// independent reference, so the reference here is stratified at --reference-spp (default 4096),
// cached like any reference, and its variance is NOT subtracted from the measured error: the
// adaptive error is over-stated by at most the reference's (reported as a share).
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "cluster.h"
#include "commands.h"
#include "render/frame_renderer.h"
#include "scene/scene_loader.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

double percentile(std::vector<double> v, double q) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const double at = q * (v.size() - 1);
    const size_t i = size_t(at);
    const double f = at - double(i);
    return i + 1 < v.size() ? (1 - f) * v[i] + f * v[i + 1] : v[i];
}

}  // namespace

int run_bench(const BenchArgs& a) {
    // Only the bake-thickness study splits its configurations over processes; every other
    // study measures times in one process, and N ranks would each run it whole.
    if (a.study != "bake-thickness") {
        if (Cluster::world().distributed())
            throw Error("--study", a.study,
                        "runs in one process (only bake-thickness splits over MPI ranks)");
        if (!a.part.empty())
            throw Error("--part", a.part, "only the bake-thickness study splits into parts");
    }
    if (a.study == "cache" || a.study == "cache-ablation") return run_bench_cache(a);
    if (a.study == "bake") return run_bench_bake(a);
    if (a.study == "bake-thickness") return run_bench_bake_thickness(a);
    if (a.study == "sparse") return run_bench_sparse(a);
    if (a.study == "stability") return run_bench_stability(a);
    if (a.study != "points")
        throw Error(
            "--study", a.study,
            "expected points, sparse, cache, cache-ablation, bake, bake-thickness or stability");
    if (a.runs < 1) throw Error("--runs", std::to_string(a.runs), "expected at least 1");
    if (a.out.empty()) throw Error("--out", "", "expected an output directory");
    const Scene scene = load_scene(a.scene);
    const std::pair<int, int> size = parse_size(a.size, "--size");
    const int w = size.first, h = size.second;
    if (a.frame < 0 || a.frame >= scene.frame_count)
        throw Error("--frame", std::to_string(a.frame), "expected a frame of the scene");
    EmbreeDevice device(0);
    if (a.reference_spp < 64)
        throw Error("--reference-spp", std::to_string(a.reference_spp), "expected at least 64");
    constexpr int kVarianceSpp = 256;  // of the plain MIS render that gives v_i and r_i
    auto config_for = [&](RenderMethod method, int seed) {
        RenderConfig c;
        c.method = method;
        SettingsGroup g = c.settings_group();
        for (const std::string& s : a.sets) g.apply_assignment(s);
        c.frame.width = w;
        c.frame.height = h;
        c.frame.seed = seed;
        c.mis.spp = kVarianceSpp;
        c.mis.stratified = false;  // the 1/N model of the fixed-N baseline
        c.reference.spp = a.reference_spp;
        c.reference.stratified = true;
        return c;
    };
    Progress progress;
    auto render = [&](const RenderConfig& c) {
        FrameRenderer renderer(scene, c, device);
        return renderer.render(a.frame, progress);
    };
    std::fprintf(stderr, "reference...\n");
    const FrameResult ref = render(config_for(RenderMethod::Reference, 0));
    std::fprintf(stderr, "MIS %d spp...\n", kVarianceSpp);
    const FrameResult mis = render(config_for(RenderMethod::Mis, 1));
    std::vector<FrameResult> adaptive;
    for (int k = 0; k < a.runs; ++k) {
        std::fprintf(stderr, "adaptive points, run %d/%d...\n", k + 1, a.runs);
        adaptive.push_back(render(config_for(RenderMethod::Points, 100 + k)));
    }
    const size_t n = size_t(w) * h;
    const Layer& ref_color = ref.layers.get("color");
    const Layer& ref_var = ref.layers.get("variance");
    const Layer& mis_var = mis.layers.get("variance");
    const Layer& mis_rays = mis.layers.get("rays");
    const Layer& depth = ref.layers.get("depth");
    auto lum = [](const Layer& c, size_t i) { return double(c.luminance_at(i)); };
    std::vector<size_t> pixels;
    std::vector<double> ratio, needed_n, rays_a_all, reference_share;
    double total_rays_a = 0, total_rays_per_sample = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!(depth.data[i] > 0) || !std::isfinite(depth.data[i])) continue;  // background
        const double r_i = mis_rays.data[i] / kVarianceSpp, v_i = mis_var.data[i] * kVarianceSpp;
        if (!(r_i > 0) || !(v_i > 0)) continue;  // nothing to estimate (mirrors, unlit)
        const double lum_ref = lum(ref_color, i);
        double mse = 0, rays = 0;
        for (const FrameResult& r : adaptive) {
            const double d = lum(r.layers.get("color"), i) - lum_ref;
            mse += d * d;
            rays += r.layers.get("rays").data[i];
        }
        mse = std::max(mse / a.runs, 1e-12);
        rays /= a.runs;
        const double n_i = v_i / mse;
        pixels.push_back(i);
        needed_n.push_back(n_i);
        ratio.push_back(rays / (n_i * r_i));
        rays_a_all.push_back(rays);
        // The reference's variance (the independent-sample formula: an upper bound for its
        // stratified samples) as a share of the error measured against it.
        reference_share.push_back(std::min(1.0, double(ref_var.data[i]) / mse));
        total_rays_a += rays;
        total_rays_per_sample += r_i;
    }
    if (ratio.empty()) throw Error(a.scene, "pixels", "no pixel with a surface to compare");

    // Equal rays: fixed-N MIS with the adaptive points' total, plain and stratified.
    const int equal_spp = std::max(1, int(std::lround(total_rays_a / total_rays_per_sample)));
    auto image_rmse = [&](const FrameResult& r) {
        double sum = 0;
        for (size_t i : pixels) {
            const double d = lum(r.layers.get("color"), i) - lum(ref_color, i);
            sum += d * d;
        }
        return std::sqrt(sum / double(pixels.size()));
    };
    std::vector<double> adaptive_rmse;
    for (const FrameResult& r : adaptive) adaptive_rmse.push_back(image_rmse(r));
    json equal_rays = {{"spp", equal_spp},
                       {"adaptive_rmse_median", percentile(adaptive_rmse, 0.5)}};
    for (bool stratified : {false, true}) {
        RenderConfig c = config_for(RenderMethod::Mis, 2 + int(stratified));
        c.mis.spp = equal_spp;
        c.mis.stratified = stratified;
        std::fprintf(stderr, "MIS %d spp%s...\n", equal_spp, stratified ? ", stratified" : "");
        equal_rays[stratified ? "stratified_mis_rmse" : "mis_rmse"] = image_rmse(render(c));
    }
    json fixed = json::object();
    for (double q : {0.5, 0.9, 0.95}) {
        const double n_q = std::ceil(percentile(needed_n, q));
        fixed[std::to_string(int(q * 100))] = {
            {"spp", n_q},
            {"rays", n_q * total_rays_per_sample},
            {"rays_over_adaptive", n_q * total_rays_per_sample / total_rays_a}};
    }
    const json report = {
        {"scene", a.scene},
        {"frame", a.frame},
        {"size", a.size},
        {"runs", a.runs},
        {"pixels", ratio.size()},
        {"adaptive_rays_total", total_rays_a},
        {"adaptive_rays_per_pixel_median", percentile(rays_a_all, 0.5)},
        {"per_pixel_adaptive_over_mis_rays",
         {{"p25", percentile(ratio, 0.25)},
          {"median", percentile(ratio, 0.5)},
          {"p75", percentile(ratio, 0.75)}}},
        {"mis_spp_needed_per_pixel",
         {{"median", percentile(needed_n, 0.5)}, {"p90", percentile(needed_n, 0.9)}}},
        {"fixed_n_mis_reaching_adaptive_error_on_pct_of_pixels", fixed},
        {"equal_rays_image_rmse", equal_rays},
        {"reference",
         {{"spp", a.reference_spp},
          {"stratified", true},
          {"variance_share_of_adaptive_error",
           {{"median", percentile(reference_share, 0.5)},
            {"p90", percentile(reference_share, 0.9)}}}}},
        {"settings", config_for(RenderMethod::Points, 0).settings_group().to_json()}};
    std::error_code ec;
    fs::create_directories(a.out, ec);
    write_text_atomically(fs::path(a.out) / "bench_points.json", report.dump(2) + "\n");
    std::cout << report.dump(2) << std::endl;
    return 0;
}

}  // namespace freqlab
