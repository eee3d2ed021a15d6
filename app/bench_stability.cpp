// `freqlab bench --study stability [--full]` (issue "Reliability", acceptance 3): every case of
// stability_cases.h rendered by its render methods (two frames: method A's cache sees a
// change) and baked by its bake methods (lightmaps and probes), counting non-finite values
// per output layer and per stats entry. A value the code guarded (replaced and counted as
// "nonfinite" / "guarded" in the stats) is reported, not a failure; a NaN/Inf that reaches a
// layer or a number in the stats is. A case whose input is invalid must be refused with an
// Error naming its file; a case within the declared ranges must run.
//
// Writes <out>/stability.json: the configurations run, per layer the non-finite count, per
// case its outcome and time. Exit code 1 when anything leaked, crashed into a non-Error
// exception, was refused within its declared range or was accepted though invalid.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>

#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "commands.h"
#include "render/frame_renderer.h"
#include "render/method.h"
#include "scene/scene_loader.h"
#include "settings/bake_settings.h"
#include "settings/settings_group.h"
#include "stability_cases.h"
#include "volume/bake_estimators.h"
#include "volume/impulse_tables.h"
#include "volume/lightmap_baker.h"
#include "volume/media.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct SweepTally {
    long configurations = 0, refused_as_expected = 0, failures = 0;
    long guarded = 0;
    std::map<std::string, long> nonfinite_by_layer;  // every layer seen, leaked counts
    json cases = json::array();
};

long count_layer_nonfinite(const Layer& layer) {
    long n = 0;
    for (float v : layer.data) n += !std::isfinite(v);
    return n;
}

// Non-finite numbers in a stats object (nlohmann keeps NaN/Inf as floats until dumped).
long count_json_nonfinite(const json& j) {
    if (j.is_number_float()) return !std::isfinite(j.get<double>());
    long n = 0;
    if (j.is_structured())
        for (const auto& v : j) n += count_json_nonfinite(v);
    return n;
}

void tally_layers(const LayerSet& layers, const std::string& prefix, SweepTally& t, long& leaked,
                  json& bad) {
    for (const Layer& layer : layers.layers()) {
        const long n = count_layer_nonfinite(layer);
        t.nonfinite_by_layer[prefix + layer.name] += n;
        if (n) bad[prefix + layer.name] = n;
        leaked += n;
    }
}

void tally_stats(const json& stats, const std::string& name, SweepTally& t, long& leaked,
                 json& bad) {
    const long n = count_json_nonfinite(stats);
    t.nonfinite_by_layer[name] += n;
    if (n) bad[name] = n;
    leaked += n;
}

struct RunOutcome {
    long leaked = 0, guarded = 0;
    json bad = json::object();
};

RunOutcome render_case(const Scene& scene, const StabilityCase& c, const std::string& method,
                       const EmbreeDevice& device, SweepTally& t) {
    RenderConfig config;
    config.method = parse_render_method(method);
    SettingsGroup g = config.settings_group();
    for (const std::string& s : stability_base_render_sets()) g.apply_assignment(s, "stability");
    for (const std::string& s : c.sets)
        if (s.rfind("bake.", 0) != 0) g.apply_assignment(s, "stability");
    FrameRenderer renderer(scene, config, device);
    RunOutcome o;
    const int frames = std::min(2, scene.frame_count);
    for (int f = 0; f < frames; ++f) {
        Progress progress;
        const FrameResult r = renderer.render(f, progress);
        tally_layers(r.layers, "render:", t, o.leaked, o.bad);
        tally_stats(r.stats, "render:stats", t, o.leaked, o.bad);
        if (r.stats.contains("nonfinite") && r.stats["nonfinite"].is_number())
            o.guarded += r.stats["nonfinite"].get<long>();
    }
    return o;
}

RunOutcome bake_case(const RayScene& rays, const Media& media, const ImpulseTables& tables,
                     const StabilityCase& c, const std::string& method, SweepTally& t) {
    BakeSettings settings;
    SettingsGroup g;
    g.bind(BakeSettings::schema(), &settings);
    for (const std::string& s : stability_base_bake_sets()) g.apply_assignment(s, "stability");
    for (const std::string& s : c.sets)
        if (s.rfind("bake.", 0) == 0) g.apply_assignment(s, "stability");
    const BakeMethod m = parse_bake_method(method);
    LightmapBaker baker(rays, media, media.empty() ? nullptr : &tables, m, settings);
    baker.run();
    RunOutcome o;
    for (size_t i = 0; i < baker.lightmaps().size(); ++i)
        tally_layers(baker.layers(i), "bake:", t, o.leaked, o.bad);
    tally_stats(baker.probes_json(), "bake:probes", t, o.leaked, o.bad);
    tally_stats(baker.stats().to_json(), "bake:stats", t, o.leaked, o.bad);
    o.guarded += baker.stats().guarded;
    return o;
}

// Runs one case over its methods; records each method's run as one configuration.
void run_case(const StabilityCase& c, const fs::path& asset_dir, const EmbreeDevice& device,
              const ImpulseTables& tables, SweepTally& t, bool verbose) {
    const std::string origin = (asset_dir / "stability.json").string();
    json record = {{"group", c.group}, {"name", c.name}, {"sets", c.sets}};
    auto fail = [&](const std::string& why) {
        ++t.failures;
        record["failure"] = why;
        std::fprintf(stderr, "stability: FAIL %s [%s]: %s\n", c.group.c_str(), c.name.c_str(),
                     why.c_str());
    };
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<Scene> scene;
    try {
        scene.emplace(parse_scene(c.scene.dump(), origin, asset_dir.string()));
    } catch (const Error& e) {
        if (!c.expect_refusal) {
            fail(std::string("refused: ") + e.what());
        } else if (e.file().empty() ||
                   std::string(e.what()).find(c.refusal_contains) == std::string::npos) {
            fail(std::string("refused without naming the file or '") + c.refusal_contains +
                 "': " + e.what());
        } else {
            ++t.refused_as_expected;
            ++t.configurations;
            record["refused"] = e.what();
        }
        t.cases.push_back(record);
        return;
    }
    if (c.expect_refusal) fail("accepted an invalid input");
    record["load_notes"] = scene->load_notes;
    if (!c.note_contains.empty()) {
        bool said = false;
        for (const std::string& n : scene->load_notes)
            said |= n.find(c.note_contains) != std::string::npos;
        if (!said) fail("no load note saying '" + c.note_contains + "'");
    }
    json runs = json::object();
    auto attempt = [&](const std::string& method, const std::string& label,
                       const std::function<RunOutcome()>& body) {
        ++t.configurations;
        const auto refusal = c.method_refusals.find(method);
        try {
            const RunOutcome o = body();
            if (refusal != c.method_refusals.end())
                fail(label + ": accepted an input it cannot represent");
            t.guarded += o.guarded;
            runs[label] = {{"leaked", o.leaked}, {"guarded", o.guarded}};
            if (o.leaked) {
                runs[label]["layers"] = o.bad;
                fail(label + ": " + std::to_string(o.leaked) + " non-finite values in " +
                     o.bad.dump());
            }
        } catch (const Error& e) {
            if (refusal != c.method_refusals.end() &&
                std::string(e.what()).find(refusal->second) != std::string::npos) {
                ++t.refused_as_expected;
                runs[label] = {{"refused", e.what()}};
                return;
            }
            // Within the declared ranges, a refusal means the range is wrong.
            fail(label + " refused: " + e.what());
        }
    };
    for (const std::string& m : c.render_methods)
        attempt(m, "render:" + m, [&] { return render_case(*scene, c, m, device, t); });
    if (!c.bake_methods.empty()) {
        const Media media(scene->media, scene->source);
        RayScene rays(*scene, device);
        rays.update(0.0f);
        for (const std::string& m : c.bake_methods)
            attempt(m, "bake:" + m, [&] { return bake_case(rays, media, tables, c, m, t); });
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    record["runs"] = runs;
    record["ms"] = ms;
    if (verbose) std::printf("  %-12s %-58s %9.1f ms\n", c.group.c_str(), c.name.c_str(), ms);
    t.cases.push_back(record);
}

}  // namespace

int run_bench_stability(const BenchArgs& a) {
    if (a.out.empty()) throw Error("--out", "", "expected an output directory");
    std::error_code ec;
    const fs::path asset_dir = fs::path(a.out) / "stability_assets";
    fs::create_directories(asset_dir, ec);
    if (ec || !fs::is_directory(asset_dir))
        throw Error(a.out, "--out", "cannot create the output directory: " + ec.message());
    const std::vector<StabilityCase> cases = stability_cases(asset_dir, a.full);
    std::printf("stability sweep (%s): %zu cases\n", a.full ? "full" : "lean", cases.size());
    const ImpulseTables tables = ImpulseTables::cached(kDefaultTableBounces);
    EmbreeDevice device(0);
    SweepTally t;
    const auto t0 = std::chrono::steady_clock::now();
    for (const StabilityCase& c : cases) run_case(c, asset_dir, device, tables, t, !a.quiet);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    long leaked = 0;
    json by_layer = json::object();
    for (const auto& [layer, n] : t.nonfinite_by_layer) {
        by_layer[layer] = n;
        leaked += n;
    }
    const json report = {{"study", "stability"},
                         {"sweep", a.full ? "full" : "lean"},
                         {"cases", cases.size()},
                         {"configurations", t.configurations},
                         {"refused_as_expected", t.refused_as_expected},
                         {"failures", t.failures},
                         {"nonfinite_leaked", leaked},
                         {"nonfinite_guarded", t.guarded},
                         {"nonfinite_by_layer", by_layer},
                         {"seconds", seconds},
                         {"runs", t.cases}};
    write_text_atomically(fs::path(a.out) / "stability.json", report.dump(1) + "\n");
    std::printf(
        "stability: %ld configurations over %zu cases in %.0f s: %ld non-finite values "
        "leaked into %zu layers/stats checked, %ld guarded, %ld refused as expected, "
        "%ld failures\n",
        t.configurations, cases.size(), seconds, leaked, t.nonfinite_by_layer.size(), t.guarded,
        t.refused_as_expected, t.failures);
    return t.failures == 0 && leaked == 0 ? 0 : 1;
}

}  // namespace freqlab
