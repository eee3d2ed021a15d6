// `freqlab bench SCENE --study bake`: method B's baker as run time against error (issue
// "Method B, part 2", acceptance 2-5). In one process, sequentially:
//   - reference: VPT at --reference-spp (its own seed, so curves are not correlated with it);
//   - curves: impulse, extinction and VPT baked progressively (1, 2, 4, ... samples), relMSE of
//     lm_irradiance against the reference over all valid texels after every pass;
//   - for every pass of impulse's curve, the time VPT needs to reach that pass's error
//     (log-log interpolation on VPT's curve) over that pass's time: the speed-up curve, its
//     best point and its last (impulse's final error: its bias once converged);
//   - overhead: impulse (and extinction) over surface bake time at equal samples (median of the
//     ratios of 5 interleaved runs);
//   - re-bake: sigma_s of medium 0 scaled by 1.5, then the first pass (1 sample: the first
//     progressive preview) and the whole re-bake timed, tables untouched.
// Writes bench_bake.json, bench_bake.csv (every pass of every curve) and
// bench_bake_time_error.png.
//
// `--study bake-thickness`: where the tables stop describing the scene. Every medium's density
// scale times 1/4 ... 8; at each, a VPT reference, impulse and extinction at --max-spp, their
// lm_irradiance relMSE and the ratio of impulse's multiple scattering to VPT's (mean over
// valid texels), against the optical thickness across the scene's bounds (the least of the
// three axes through its centre). Writes bench_bake_thickness.json / .csv / .png.
//
// Both report the key light's shadowed texels separately (volume/shadowed_texels.h): texels
// whose connection to it is occluded, where the tables do not apply (relMSE there, and impulse's
// in-scattered irradiance over VPT's).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "base/file_io.h"
#include "base/stopwatch.h"
#include "bench_common.h"
#include "cluster.h"
#include "commands.h"
#include "image/line_plot.h"
#include "scene/scene_loader.h"
#include "settings/settings_group.h"
#include "volume/impulse_tables.h"
#include "volume/lightmap_baker.h"
#include "volume/shadowed_texels.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace freqlab {

namespace {

struct CurvePoint {
    int samples;
    double ms, relmse, relmse_lit;
};

// lm_irradiance's relMSE over all lightmaps' valid texels and over their lit ones
// (LightmapError::relmse_lit), texel-weighted.
struct RelMse {
    double all = 0.0, lit = 0.0;
};
RelMse relmse_against(const LightmapBaker& baker, const LightmapBaker& reference) {
    std::vector<LightmapError> maps;
    for (size_t i = 0; i < baker.lightmaps().size(); ++i)
        maps.push_back(compare_lightmaps(baker.layers(i), reference.layers(i), "lm_irradiance"));
    const LightmapError e = combine_lightmap_errors(maps);
    return {e.relmse, e.relmse_lit};
}

std::vector<CurvePoint> curve(LightmapBaker& baker, const LightmapBaker& reference, int max_spp) {
    std::vector<CurvePoint> points;
    for (int n = 1; baker.samples() < max_spp; n *= 2) {
        baker.run_pass(std::min(n, max_spp - baker.samples()));
        const RelMse e = relmse_against(baker, reference);
        points.push_back({baker.samples(), baker.stats().bake_ms, e.all, e.lit});
        std::fprintf(stderr, "  %-10s %6d spp %9.1f ms relMSE %.5f (lit texels %.5f)\n",
                     to_string(baker.method()), baker.samples(), baker.stats().bake_ms, e.all,
                     e.lit);
    }
    return points;
}

// The error over the key light's cast shadows (shadowed_texels.h) of all lightmaps.
RegionComparison shadowed_against(const LightmapBaker& baker, const LightmapBaker& reference,
                                  const RayScene& rays) {
    const BakeKeyLight key = bake_key_light(rays);
    std::vector<RegionComparison> parts;
    for (size_t i = 0; i < baker.lightmaps().size(); ++i)
        parts.push_back(compare_region(baker.layers(i), reference.layers(i),
                                       shadowed_texels(rays, baker.lightmaps()[i], key)));
    return combine_regions(parts);
}

json region_json(const RegionComparison& c) {
    return {{"texels", c.texels},
            {"lm_irradiance_relmse", c.irradiance_relmse},
            {"lm_irradiance_over_reference", c.irradiance_ratio},
            {"inscatter_over_reference", c.inscatter_ratio}};
}

// What both bake studies start from: the bake settings with --set applied, the scene and its
// media (an error without any), its rays at t = 0.
struct BakeStudy {
    BakeSettings settings;
    SettingsGroup group;
    Scene scene;
    Media media;
    EmbreeDevice device{0};
    RayScene rays;
    BakeStudy(const BenchArgs& a, const std::string& study)
        : scene(checked_scene(a, study)), media(scene.media, scene.source), rays(scene, device) {
        group.bind(BakeSettings::schema(), &settings);
        for (const std::string& s : a.sets) group.apply_assignment(s);
        rays.update(0.0f);
    }
    static Scene checked_scene(const BenchArgs& a, const std::string& study) {
        if (a.out.empty()) throw Error("--out", "", "expected an output directory");
        Scene s = load_scene(a.scene);
        if (s.media.empty())
            throw Error(a.scene, "media", "the " + study + " study needs a scene with media");
        return s;
    }
};

// A layer's luminance over the valid texels of all of a baker's lightmaps.
double layer_sum(const LightmapBaker& baker, const char* layer) {
    double sum = 0.0;
    for (size_t i = 0; i < baker.lightmaps().size(); ++i)
        sum += valid_texel_luminance_sum(baker.layers(i), layer);
    return sum;
}

// Optical thickness (extinction) across the scene: the least over the three axes of the
// segment through the centre of its bounds.
double thickness_across(const Media& media, const RayScene& rays) {
    const vec3 lo = rays.bounds_min(), hi = rays.bounds_max(), centre = 0.5f * (lo + hi);
    double least = INFINITY;
    for (int a = 0; a < 3; ++a) {
        vec3 o = centre, d(0.0f);
        o[a] = lo[a];
        d[a] = 1.0f;
        const SegmentOptics s = media.integrate(o, d, double(hi[a] - lo[a]));
        if (hi[a] > lo[a]) least = std::min(least, s.tau_s + s.tau_a);
    }
    return std::isfinite(least) ? least : 0.0;
}

// Time at which a curve first reaches `target` error: log-log interpolation between passes;
// negative when it never does.
double time_to_reach(const std::vector<CurvePoint>& c, double target) {
    for (size_t i = 0; i < c.size(); ++i) {
        if (c[i].relmse > target) continue;
        if (i == 0) return c[0].ms;
        const double a = std::log(c[i - 1].relmse), b = std::log(c[i].relmse);
        const double f = (std::log(target) - a) / (b - a);
        return std::exp(std::log(c[i - 1].ms) + f * (std::log(c[i].ms) - std::log(c[i - 1].ms)));
    }
    return -1.0;
}

}  // namespace

int run_bench_bake(const BenchArgs& a) {
    BakeStudy study(a, "bake");
    const Scene& scene = study.scene;
    const BakeSettings& settings = study.settings;
    const SettingsGroup& group = study.group;
    Media& media = study.media;
    const RayScene& rays = study.rays;
    const auto t_tables = Clock::now();
    const ImpulseTables tables = ImpulseTables::cached(kDefaultTableBounces);
    const double tables_ms = ms_since(t_tables);
    fs::create_directories(a.out);

    // --reference-spp 0: no reference and no curves (overhead and re-bake only).
    const bool curves = a.reference_spp > 0;
    BakeSettings ref_settings = settings;
    ref_settings.seed = settings.seed + 7919;
    LightmapBaker reference(rays, media, nullptr, BakeMethod::Vpt, ref_settings);
    // The curves bake progressively to --max-spp: bakes planned for that many samples (the
    // vertex correction field's prepass paths follow bake.spp; planned for the preset's 16 it
    // kept one path, and with texel_terms = field impulse stalled past 16 spp).
    BakeSettings planned = settings;
    planned.spp = a.max_spp;
    LightmapBaker impulse(rays, media, &tables, BakeMethod::Impulse, planned);
    LightmapBaker extinction(rays, media, nullptr, BakeMethod::Extinction, planned);
    LightmapBaker vpt(rays, media, nullptr, BakeMethod::Vpt, settings);
    std::vector<CurvePoint> c_impulse{{0, 0.0, NAN, NAN}}, c_extinction{{0, 0.0, NAN, NAN}}, c_vpt;
    if (curves) {
        std::fprintf(stderr, "reference: vpt at %d spp\n", a.reference_spp);
        reference.run_pass(a.reference_spp);
        c_impulse = curve(impulse, reference, a.max_spp);
        c_extinction = curve(extinction, reference, a.max_spp);
        c_vpt = curve(vpt, reference, a.reference_spp / 4);
    }
    const double impulse_error = c_impulse.back().relmse, impulse_ms = c_impulse.back().ms;
    json shadowed = json::object();
    if (curves) {
        const RegionComparison si = shadowed_against(impulse, reference, rays);
        const RegionComparison se = shadowed_against(extinction, reference, rays);
        shadowed = {{"impulse", region_json(si)}, {"extinction", region_json(se)}};
        std::fprintf(stderr,
                     "  shadowed texels: %ld, relMSE impulse %.4f extinction %.4f, impulse's "
                     "in-scattering over vpt's %.3f\n",
                     si.texels, si.irradiance_relmse, se.irradiance_relmse, si.inscatter_ratio);
    }
    const double vpt_ms = curves ? time_to_reach(c_vpt, impulse_error) : -1.0;
    // The speed-up at every impulse pass (NaN where VPT never reached that error).
    json speedup = json::array();
    double best_speedup = NAN;
    int best_spp = 0;
    for (const CurvePoint& p : c_impulse) {
        if (!curves || p.samples == 0) continue;
        const double t = time_to_reach(c_vpt, p.relmse);
        const double r = t > 0 ? t / p.ms : NAN;
        speedup.push_back({{"spp", p.samples},
                           {"impulse_ms", p.ms},
                           {"relmse", p.relmse},
                           {"vpt_ms", t > 0 ? t : NAN},
                           {"vpt_over_impulse_time", r}});
        if (r > 0 && (best_spp == 0 || r > best_speedup)) best_speedup = r, best_spp = p.samples;
    }

    // Overhead at equal samples: surface, extinction and impulse interleaved, 5 runs each; the
    // ratio is the median of the per-run ratios (this machine's speed drifts by +-20 % between
    // runs, less within one).
    BakeSettings equal = settings;
    equal.spp = a.overhead_spp;
    std::vector<double> t_surface, t_extinction, t_impulse, r_extinction, r_impulse;
    for (int run = 0; run < 5; ++run) {
        LightmapBaker s(rays, media, nullptr, BakeMethod::Surface, equal);
        s.run();
        t_surface.push_back(s.stats().bake_ms);
        LightmapBaker e(rays, media, nullptr, BakeMethod::Extinction, equal);
        e.run();
        t_extinction.push_back(e.stats().bake_ms);
        LightmapBaker i(rays, media, &tables, BakeMethod::Impulse, equal);
        i.run();
        t_impulse.push_back(i.stats().bake_ms);
        r_extinction.push_back(t_extinction.back() / t_surface.back());
        r_impulse.push_back(t_impulse.back() / t_surface.back());
    }

    // Re-bake after a sigma_s change: the atlas and tables stay, the sums restart.
    LightmapBaker rebake(rays, media, &tables, BakeMethod::Impulse, equal);
    rebake.run();
    const MediumDesc& d0 = media.desc(0);
    media.set_coefficients(0, d0.sigma_s * 1.5, d0.sigma_a, d0.g, d0.density_scale);
    rebake.reset();
    const auto t0 = Clock::now();
    rebake.run_pass(1);
    const double first_pass_ms = ms_since(t0);
    rebake.run();
    const double rebake_ms = ms_since(t0);

    long texels = 0;
    json maps = json::array();
    for (const ObjectLightmap& m : impulse.lightmaps()) {
        texels += long(m.count(TexelState::Valid));
        maps.push_back(
            {{"name", lightmap_name(scene, m)}, {"width", m.width}, {"height", m.height}});
    }
    auto curve_json = [](const std::vector<CurvePoint>& c) {
        json j = json::array();
        for (const CurvePoint& p : c)
            j.push_back({{"spp", p.samples},
                         {"ms", p.ms},
                         {"relmse", p.relmse},
                         {"relmse_lit", p.relmse_lit}});
        return j;
    };
    const json report = {
        {"scene", a.scene},
        {"settings", group.to_json()},
        {"tables_load_ms", tables_ms},
        {"texels_valid", texels},
        {"lightmaps", maps},
        {"reference",
         {{"method", "vpt"}, {"spp", a.reference_spp}, {"ms", reference.stats().bake_ms}}},
        {"curve_bake_spp", a.max_spp},  // bake.spp of the impulse / extinction curves' bakes
        {"impulse", curve_json(c_impulse)},
        {"extinction", curve_json(c_extinction)},
        {"vpt", curve_json(c_vpt)},
        {"impulse_final_relmse", impulse_error},
        {"extinction_final_relmse", c_extinction.back().relmse},
        {"vpt_ms_to_impulse_error", vpt_ms},
        {"vpt_over_impulse_time", vpt_ms > 0 ? vpt_ms / impulse_ms : NAN},
        {"vpt_reached_impulse_error", vpt_ms > 0},
        {"shadowed", shadowed},
        {"vpt_over_impulse_time_curve", speedup},
        {"vpt_over_impulse_time_best", {{"spp", best_spp}, {"ratio", best_speedup}}},
        {"overhead",
         {{"spp", a.overhead_spp},
          {"surface_ms_median", median(t_surface)},
          {"extinction_ms_median", median(t_extinction)},
          {"impulse_ms_median", median(t_impulse)},
          {"extinction_over_surface", median(r_extinction)},
          {"impulse_over_surface", median(r_impulse)},
          {"impulse_over_surface_runs", r_impulse}}},
        {"rebake",
         {{"change", "sigma_s x 1.5 of " + d0.name},
          {"spp", a.overhead_spp},
          {"first_pass_ms", first_pass_ms},
          {"total_ms", rebake_ms}}}};
    write_text_atomically(fs::path(a.out) / "bench_bake.json", report.dump(2) + "\n");
    std::string csv = "method,spp,ms,relmse\n";
    for (auto [name, c] : {std::pair{"impulse", &c_impulse}, std::pair{"extinction", &c_extinction},
                           std::pair{"vpt", &c_vpt}})
        for (const CurvePoint& p : *c)
            csv += std::string(name) + "," + std::to_string(p.samples) + "," +
                   std::to_string(p.ms) + "," + std::to_string(p.relmse) + "\n";
    write_text_atomically(fs::path(a.out) / "bench_bake.csv", csv);
    LinePlot plot;
    plot.title = "bake " + fs::path(a.scene).stem().string() + ": relMSE vs time";
    plot.x_label = "bake time (ms, log)";
    plot.y_label = "relMSE (log)";
    plot.log_x = plot.log_y = true;
    auto series = [](const char* name, vec3 colour, const std::vector<CurvePoint>& c) {
        PlotSeries s{name, colour, {}, {}};
        for (const CurvePoint& p : c)
            if (p.relmse > 0) s.x.push_back(std::max(p.ms, 1e-3)), s.y.push_back(p.relmse);
        return s;
    };
    plot.series = {series("impulse", {1.0f, 0.6f, 0.2f}, c_impulse),
                   series("extinction", {0.5f, 0.5f, 0.5f}, c_extinction),
                   series("vpt", {0.3f, 0.6f, 1.0f}, c_vpt)};
    if (curves) write_line_plot(fs::path(a.out) / "bench_bake_time_error.png", plot);
    std::printf("%s\n", report.dump(2).c_str());
    return 0;
}

namespace {

constexpr double kThicknessFactors[] = {0.25, 0.5, 1.0, 2.0, 4.0, 8.0};
constexpr int kThicknessRowTag = 31;

// One configuration of the sweep: every medium's density x `factor`, a VPT reference and
// impulse / extinction bakes there. The row carries everything the CSV and the plot show.
json thickness_row(const BenchArgs& a, BakeStudy& study, const ImpulseTables& tables,
                   const std::vector<MediumDesc>& original, int index) {
    const double factor = kThicknessFactors[index];
    Media& media = study.media;
    const RayScene& rays = study.rays;
    for (size_t i = 0; i < media.size(); ++i) {
        const MediumDesc& d = original[i];
        media.set_coefficients(i, d.sigma_s, d.sigma_a, d.g, d.density_scale * factor);
    }
    BakeSettings ref_settings = study.settings;
    ref_settings.seed = study.settings.seed + 7919;
    const double tau = thickness_across(media, rays);
    LightmapBaker reference(rays, media, nullptr, BakeMethod::Vpt, ref_settings);
    reference.run_pass(a.reference_spp);
    BakeSettings planned = study.settings;  // bakes of --max-spp samples (run_bench_bake)
    planned.spp = a.max_spp;
    LightmapBaker impulse(rays, media, &tables, BakeMethod::Impulse, planned);
    impulse.run_pass(a.max_spp);
    LightmapBaker extinction(rays, media, nullptr, BakeMethod::Extinction, planned);
    extinction.run_pass(a.max_spp);
    const double e_impulse = relmse_against(impulse, reference).all;
    const double e_extinction = relmse_against(extinction, reference).all;
    const double m_ref = layer_sum(reference, "lm_inscatter_multiple");
    const double m_ratio = m_ref > 0.0 ? layer_sum(impulse, "lm_inscatter_multiple") / m_ref : NAN;
    const RegionComparison sh_i = shadowed_against(impulse, reference, rays);
    const RegionComparison sh_e = shadowed_against(extinction, reference, rays);
    std::fprintf(stderr,
                 "  density x %-5g tau across %7.3f: relMSE impulse %.4f extinction %.4f, "
                 "multiple impulse / vpt %.3f; shadowed (%ld texels) relMSE impulse %.4f "
                 "extinction %.4f, in-scattering impulse / vpt %.3f\n",
                 factor, tau, e_impulse, e_extinction, m_ratio, sh_i.texels, sh_i.irradiance_relmse,
                 sh_e.irradiance_relmse, sh_i.inscatter_ratio);
    return {{"density_factor", factor},
            {"tau_across", tau},
            {"impulse_relmse", e_impulse},
            {"extinction_relmse", e_extinction},
            {"multiple_impulse_over_vpt", m_ratio},
            {"shadowed", {{"impulse", region_json(sh_i)}, {"extinction", region_json(sh_e)}}},
            {"reference_ms", reference.stats().bake_ms},
            {"impulse_ms", impulse.stats().bake_ms}};
}

// A NaN went through JSON as null (the ratio when VPT has no multiple scattering).
double row_number(const json& v) {
    return v.is_number() ? v.get<double>() : NAN;
}

}  // namespace

void write_bake_thickness_outputs(const std::string& out, const json& header, const json& rows) {
    std::string csv =
        "density_factor,tau_across,impulse_relmse,extinction_relmse,"
        "multiple_impulse_over_vpt,shadowed_texels,shadowed_impulse_relmse,"
        "shadowed_extinction_relmse,shadowed_inscatter_impulse_over_vpt,reference_ms,"
        "impulse_ms\n";
    PlotSeries s_impulse{"impulse", {1.0f, 0.6f, 0.2f}, {}, {}};
    PlotSeries s_extinction{"extinction", {0.5f, 0.5f, 0.5f}, {}, {}};
    for (const json& r : rows) {
        const double tau = r["tau_across"], e_impulse = r["impulse_relmse"],
                     e_extinction = r["extinction_relmse"];
        const json& sh_i = r["shadowed"]["impulse"];
        const json& sh_e = r["shadowed"]["extinction"];
        csv += std::to_string(r["density_factor"].get<double>()) + "," + std::to_string(tau) + "," +
               std::to_string(e_impulse) + "," + std::to_string(e_extinction) + "," +
               std::to_string(row_number(r["multiple_impulse_over_vpt"])) + "," +
               std::to_string(sh_i["texels"].get<long>()) + "," +
               std::to_string(row_number(sh_i["lm_irradiance_relmse"])) + "," +
               std::to_string(row_number(sh_e["lm_irradiance_relmse"])) + "," +
               std::to_string(row_number(sh_i["inscatter_over_reference"])) + "," +
               std::to_string(r["reference_ms"].get<double>()) + "," +
               std::to_string(r["impulse_ms"].get<double>()) + "\n";
        if (tau > 0.0 && e_impulse > 0.0 && e_extinction > 0.0) {
            s_impulse.x.push_back(float(tau)), s_impulse.y.push_back(float(e_impulse));
            s_extinction.x.push_back(float(tau)), s_extinction.y.push_back(float(e_extinction));
        }
    }
    json report = header;
    report["sweep"] = rows;
    write_text_atomically(fs::path(out) / "bench_bake_thickness.json", report.dump(2) + "\n");
    write_text_atomically(fs::path(out) / "bench_bake_thickness.csv", csv);
    if (s_impulse.x.size() >= 2) {
        LinePlot plot;
        plot.title = "bake " + fs::path(header["scene"].get<std::string>()).stem().string() +
                     ": relMSE vs optical thickness";
        plot.x_label = "optical thickness across the scene (log)";
        plot.y_label = "relMSE (log)";
        plot.log_x = plot.log_y = true;
        plot.series = {s_impulse, s_extinction};
        write_line_plot(fs::path(out) / "bench_bake_thickness.png", plot);
    }
}

int run_bench_bake_thickness(const BenchArgs& a) {
    // The configurations split like frames (app/cluster.h): MPI ranks send their rows to rank 0;
    // a Slurm array task (--part I/N) writes its rows for `freqlab merge`.
    Cluster& cluster = Cluster::world();
    const WorkPart part = bench_work_part(a);
    BakeStudy study(a, "bake-thickness");
    std::unique_ptr<ImpulseTables> loaded;
    cluster.rank0_first([&] {
        loaded = std::make_unique<ImpulseTables>(ImpulseTables::cached(kDefaultTableBounces));
    });
    const ImpulseTables& tables = *loaded;
    if (cluster.rank() == 0) fs::create_directories(a.out);
    std::vector<MediumDesc> original;
    for (size_t i = 0; i < study.media.size(); ++i) original.push_back(study.media.desc(i));
    const std::vector<int> mine = round_robin_items(0, int(std::size(kThicknessFactors)), part);
    cluster.set_work("density factors " + describe_items(mine));
    json rows = json::array();
    for (int index : mine) rows.push_back(thickness_row(a, study, tables, original, index));
    const json header = {{"scene", a.scene},
                         {"settings", study.group.to_json()},
                         {"reference", {{"method", "vpt"}, {"spp", a.reference_spp}}},
                         {"spp", a.max_spp}};
    if (cluster.distributed()) {
        const std::vector<std::string> all = cluster.gather(rows.dump(), kThicknessRowTag);
        if (cluster.rank() != 0) return 0;
        rows = json::array();
        for (const std::string& r : all)
            for (const json& row : json::parse(r)) rows.push_back(row);
    } else if (!part.whole()) {
        write_bench_part(a, part, header, rows);
        return 0;
    }
    std::sort(rows.begin(), rows.end(), [](const json& x, const json& y) {
        return x["density_factor"].get<double>() < y["density_factor"].get<double>();
    });
    write_bake_thickness_outputs(a.out, header, rows);
    json report = header;
    report["sweep"] = rows;
    std::printf("%s\n", report.dump(2).c_str());
    return 0;
}

}  // namespace freqlab
