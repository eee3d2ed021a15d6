// `freqlab bake`: method B's lightmap bakers from the command line (issue "Method B, part 2").
// Writes DIR/<lightmap>.exr (every lm_* layer and texel_valid), DIR/<lightmap>.png (lm_total)
// and DIR/stats.json: per-stage times, rays, texels, table queries, and when asked the overhead
// against a surface bake at equal samples and the error against a reference bake directory.
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "base/error.h"
#include "base/file_io.h"
#include "base/stopwatch.h"
#include "cluster.h"
#include "commands.h"
#include "image/colormap.h"
#include "image/image_io.h"
#include "scene/provenance.h"
#include "scene/scene_loader.h"
#include "settings/settings_group.h"
#include "volume/impulse_tables.h"
#include "volume/lightmap_baker.h"
#include "volume/lightmap_preview.h"
#include "volume/shadowed_texels.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace freqlab {

namespace {

// Two reference directories must be halves of one reference: the same scene, method and
// samples (their stats.json), two seeds. Checked before anything is baked or written.
void check_reference_halves(const std::vector<std::string>& dirs) {
    json stats[2];
    for (int k = 0; k < 2; ++k) {
        const fs::path file = fs::path(dirs[size_t(k)]) / "stats.json";
        try {
            stats[k] = json::parse(read_text_file(file));
        } catch (const json::exception& e) {
            throw Error(file.string(), "--reference", std::string("unreadable: ") + e.what());
        }
    }
    const std::string second = (fs::path(dirs[1]) / "stats.json").string();
    for (const char* key : {"/scene", "/method", "/stats/spp"}) {
        const json a = stats[0].value(json::json_pointer(key), json());
        const json b = stats[1].value(json::json_pointer(key), json());
        if (a != b)
            throw Error(second, key + 1,
                        "the two references differ (" + a.dump() + " vs " + b.dump() +
                            "): expected two seeds of one bake");
    }
    const json::json_pointer seed("/settings/bake/seed");
    for (int k = 0; k < 2; ++k)
        if (!stats[k].contains(seed))
            throw Error((fs::path(dirs[size_t(k)]) / "stats.json").string(), "settings.bake.seed",
                        "missing: expected a stats.json written by freqlab bake");
    if (stats[0][seed] == stats[1][seed])
        throw Error(second, "settings.bake.seed",
                    "both references have seed " + stats[0][seed].dump() +
                        ": halves must be independent (bake one with another --seed)");
}

// The reference bake's lightmap: one directory's, or two independent halves' (their mean for
// the measures that take one reference).
struct ReferenceLightmap {
    LayerSet layers;               // the first half, or the only reference
    std::optional<LayerSet> half;  // the second half
    LayerSet mean;                 // of the halves (layers when there is one)
};

ReferenceLightmap read_reference(const std::vector<std::string>& dirs, const std::string& name) {
    ReferenceLightmap r;
    for (size_t k = 0; k < dirs.size(); ++k) {
        const fs::path file = fs::path(dirs[k]) / (name + ".exr");
        if (!fs::exists(file))
            throw Error(file.string(), "--reference", "no reference lightmap for '" + name + "'");
        LayerSet layers = read_exr(file).layers;
        if (k == 0)
            r.layers = std::move(layers);
        else
            r.half = std::move(layers);
    }
    r.mean = r.layers;
    if (r.half)
        for (Layer& m : r.mean.layers())
            if (const Layer* h = r.half->find(m.name); h && h->data.size() == m.data.size())
                for (size_t k = 0; k < m.data.size(); ++k)
                    m.data[k] = 0.5f * (m.data[k] + h->data[k]);
    return r;
}

// `irradiance` receives the lm_irradiance measure (error_over_lightmaps combines them).
json error_against(const std::vector<std::string>& reference_dirs, const std::string& name,
                   const LayerSet& test, const std::vector<uint8_t>& shadowed,
                   LightmapError* irradiance) {
    const ReferenceLightmap ref = read_reference(reference_dirs, name);
    const LayerSet* half = ref.half ? &*ref.half : nullptr;
    json out = json::object();
    for (const char* layer : {"lm_irradiance", "lm_total", "lm_surface", "lm_inscatter_single",
                              "lm_inscatter_multiple"}) {
        if (!ref.layers.find(layer) || !test.find(layer)) continue;
        constexpr size_t kWorstTexels = 8;
        const LightmapError e =
            compare_lightmaps(test, ref.layers, layer, nullptr, kWorstTexels, half);
        if (std::string(layer) == "lm_irradiance") *irradiance = e;
        json worst = json::array();
        for (const TexelError& t : e.worst)
            worst.push_back({{"x", t.x},
                             {"y", t.y},
                             {"luminance", t.test},
                             {"reference_luminance", t.ref},
                             {"relmse_share", t.relmse_share}});
        out[layer] = {{"relmse", e.relmse},         {"relmse_lit", e.relmse_lit},
                      {"texels_lit", e.texels_lit}, {"rmse", e.rmse},
                      {"rel_l2", e.rel_l2},         {"texels", e.texels},
                      {"worst_texels", worst}};
        if (half) {
            out[layer]["reference_noise"] = e.reference_noise;
            out[layer]["reference_noise_lit"] = e.reference_noise_lit;
        }
    }
    if (ref.layers.find("lm_inscatter_single") && test.find("lm_inscatter_single")) {
        const RegionComparison c = compare_region(test, ref.mean, shadowed);
        out["shadowed"] = {{"texels", c.texels},
                           {"lm_irradiance_relmse", c.irradiance_relmse},
                           {"lm_irradiance_mean", c.test_irradiance},
                           {"reference_lm_irradiance_mean", c.ref_irradiance},
                           {"lm_irradiance_ratio", c.irradiance_ratio},
                           {"inscatter_ratio", c.inscatter_ratio}};
    }
    return out;
}

// The error of the whole bake: each lightmap's lm_irradiance measures, texel-weighted (the
// lit ones by their lit texels), with the reference's own noise when it came in halves.
json error_over_lightmaps(const std::vector<LightmapError>& maps) {
    const LightmapError e = combine_lightmap_errors(maps);
    json out = {{"texels", e.texels},
                {"texels_lit", e.texels_lit},
                {"relmse", e.relmse},
                {"relmse_lit", e.relmse_lit}};
    if (e.reference_noise >= 0.0) {
        out["reference_noise"] = e.reference_noise;
        out["reference_noise_lit"] = e.reference_noise_lit;
    }
    return {{"lm_irradiance", out}};
}

// Every method's mean estimate at one texel, side by side (same samples count, same keys).
// The texel's own paths as the bake ran them: each path's estimate, and on the paths that ran
// the Monte Carlo terms what each term brought (x the path's weight 1 / rate in the sum).
void print_texel_paths(const Scene& scene, const TexelFilterUse& use) {
    if (use.paths.empty()) return;
    auto parts = [](const IrradianceParts& p) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%.4g / %.4g / %.4g", double(luminance(p.surface)),
                      double(luminance(p.single)), double(luminance(p.multiple)));
        return std::string(buf);
    };
    auto print_bounce = [&](const TexelPathRecord& r) {
        if (!r.bounce.hit) return;
        const TexelPathRecord::Bounce& b = r.bounce;
        const std::string name = b.object >= 0 && size_t(b.object) < scene.objects.size()
                                     ? scene.objects[size_t(b.object)].name
                                     : "?";
        char field[96] = "";
        if (b.field_read)
            std::snprintf(
                field, sizeof field, " (the field added %.4g%s)", double(luminance(b.field)),
                b.drew_corrections ? "; no ratio there: it drew its own corrections" : "");
        std::printf("      bounce: '%s' at (%.3f, %.3f, %.3f), %.3f away; it gathered %s%s\n",
                    name.c_str(), b.position.x, b.position.y, b.position.z, double(b.distance),
                    parts(b.vertex).c_str(), field);
    };
    std::printf("  the texel's paths (surface / single / multiple, luminance):\n");
    if (const TexelPathRecord::TexelField& f = use.paths.front().texel_field; f.read)
        std::printf(
            "    the texel reads the field at itself (bake.texel_terms = field): to path 0 "
            "it added %.4g (its value, and its ratio x the path's tables)%s%s\n",
            double(luminance(f.added)),
            f.holds ? ""
                    : " (its shadows differ from the field's there: nothing, and "
                      "the tables' multiple scattering kept)",
            f.drew_corrections ? "; no ratio there: the paths drew their own corrections" : "");
    int quiet = 0;
    for (size_t s = 0; s < use.paths.size(); ++s) {
        const TexelPathRecord& r = use.paths[s];
        if (!r.mc_ran) {
            ++quiet;
            continue;
        }
        std::printf("    path %zu: %s; Monte Carlo terms ran, weight %g, deferred %s\n", s,
                    parts(r.path).c_str(), double(r.mc_weight), parts(r.deferred).c_str());
        for (const TexelPathRecord::Term& t : r.terms) {
            const Light& light = scene.lights.at(size_t(t.light));
            std::printf(
                "      light %d (%s) %s, roulette weight %.3g: %s\n", t.light,
                to_string(light.type),
                t.occluded ? "occluded: lit medium" : "unoccluded: real single scattering drawn",
                double(t.roulette), parts(t.value).c_str());
        }
        std::printf("      texel walk (multiple scattering, surface light): %s\n",
                    parts(r.walk).c_str());
        print_bounce(r);
        if (luminance(r.hidden.total()) != 0.0f)
            std::printf("      hidden surfaces' light: %s\n", parts(r.hidden).c_str());
    }
    if (quiet > 0) {
        IrradianceParts sum;
        for (const TexelPathRecord& r : use.paths)
            if (!r.mc_ran) sum += r.path;
        // The bounces that brought the most of those paths' light.
        std::vector<size_t> order;
        for (size_t s = 0; s < use.paths.size(); ++s)
            if (!use.paths[s].mc_ran && use.paths[s].bounce.hit) order.push_back(s);
        std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
            return luminance(use.paths[a].path.total()) > luminance(use.paths[b].path.total());
        });
        for (size_t k = 0; k < std::min<size_t>(order.size(), 3); ++k) {
            std::printf("    path %zu: %s\n", order[k], parts(use.paths[order[k]].path).c_str());
            print_bounce(use.paths[order[k]]);
        }
        std::printf("    %d other paths (no Monte Carlo terms), summed: %s\n", quiet,
                    parts(sum).c_str());
    }
    std::printf(
        "    sums over %zu paths: unfiltered %s; deferred %s, filtered over %d texel(s) %s; "
        "single-scattering corrections: %.4g x the texel's tables %.4g\n",
        use.paths.size(), parts(use.sum).c_str(), parts(use.deferred).c_str(), use.texels,
        parts(use.filtered).c_str(),
        luminance(use.tables_single) > 0.0f
            ? double(luminance(use.ratio_correction) / luminance(use.tables_single))
            : 0.0,
        double(luminance(use.tables_single)));
}

void print_debug_texel(const RayScene& rays, const Media& media, const ImpulseTables* tables,
                       const BakeSettings& settings, const LightmapBaker& baker,
                       const std::string& spec) {
    const Scene& scene = rays.scene();
    std::string name, xy = spec;
    if (const size_t colon = spec.find(':'); colon != std::string::npos) {
        name = spec.substr(0, colon);
        xy = spec.substr(colon + 1);
    }
    int x = -1, y = -1;
    if (std::sscanf(xy.c_str(), "%d,%d", &x, &y) != 2)
        throw Error("--debug-texel", spec, "expected [LIGHTMAP:]X,Y");
    const ObjectLightmap* map = nullptr;
    size_t lightmap_index = 0;
    for (size_t i = 0; i < baker.lightmaps().size(); ++i)
        if (name.empty() || lightmap_name(scene, baker.lightmaps()[i]) == name) {
            map = &baker.lightmaps()[i];
            lightmap_index = i;
            break;
        }
    if (!map) throw Error("--debug-texel", spec, "no lightmap named '" + name + "'");
    if (x < 0 || y < 0 || x >= map->width || y >= map->height)
        throw Error("--debug-texel", spec,
                    "expected a texel inside " + std::to_string(map->width) + "x" +
                        std::to_string(map->height));
    const LightmapTexel& t = map->texels[size_t(y) * map->width + x];
    std::printf(
        "texel %d,%d of %s: state %s, position (%g, %g, %g), normal (%g, %g, %g), "
        "albedo (%g, %g, %g)\n",
        x, y, lightmap_name(scene, *map).c_str(), texel_state_legend()[size_t(t.state)].c_str(),
        t.position.x, t.position.y, t.position.z, t.normal.x, t.normal.y, t.normal.z, t.albedo.x,
        t.albedo.y, t.albedo.z);
    if (t.state != TexelState::Valid) return;
    const HomogeneousMedium here = media.at(t.position);
    std::printf("  medium here: sigma_s %g, sigma_a %g, g %g\n", here.sigma_s, here.sigma_a,
                here.g);
    std::printf(
        "  irradiance (luminance) over %d paths:   surface      single    multiple"
        "       total\n",
        settings.spp);
    std::unique_ptr<VertexCorrectionField> own_field;
    for (BakeMethod m :
         {BakeMethod::Surface, BakeMethod::Extinction, BakeMethod::Impulse, BakeMethod::Vpt}) {
        if (m == BakeMethod::Impulse && !tables && !media.empty()) continue;
        BakeEstimator estimator(rays, media, tables, m, settings);
        // Impulse as a bake runs it: with the baker's vertex correction field, or one built
        // here when another method was baked.
        if (uses_vertex_corrections(m, settings, tables, media)) {
            if (!baker.vertex_corrections())
                own_field = std::make_unique<VertexCorrectionField>(rays, media, tables, settings,
                                                                    baker.lightmaps());
            estimator.set_vertex_corrections(baker.vertex_corrections() ? baker.vertex_corrections()
                                                                        : own_field.get());
        }
        if (const VertexCorrectionField* field = estimator.vertex_corrections()) {
            const auto here = field->at_texel(lightmap_index, size_t(y) * map->width + x);
            const float emitters = luminance(here.value(false));
            std::printf(
                "  %-10s field here (what deeper vertices landing here add): emitters' "
                "terms %g, with surface light %g, and %g x their tables' single scattering of "
                "unoccluded connections\n",
                "", emitters, luminance(here.value(true)), luminance(here.single_ratio()));
        }
        TexelFilterUse filter;
        const IrradianceParts mean =
            texel_estimate(estimator, baker.lightmaps(), lightmap_index, size_t(y) * map->width + x,
                           settings.seed, settings.spp, &filter);
        std::printf("  %-10s %31.6g %11.6g %11.6g %11.6g\n", to_string(m), luminance(mean.surface),
                    luminance(mean.single), luminance(mean.multiple), luminance(mean.total()));
        if (m == BakeMethod::Impulse && texel_filter_radius(estimator) > 0)
            std::printf(
                "  %-10s its Monte Carlo terms ran at rate %g (weight %g) and the filter averaged "
                "%d texel(s) within %d of it\n",
                "", double(filter.mc_rate), 1.0 / double(filter.mc_rate), filter.texels,
                texel_filter_radius(estimator));
        if (m == BakeMethod::Impulse) print_texel_paths(scene, filter);
    }
    // The baked method's record of the texel's first path (what the workbench's trace shows).
    CounterRng rng = texel_random(settings.seed, lightmap_index, size_t(y) * map->width + x, 0);
    std::printf("  trace of %s, path 0:\n", to_string(baker.method()));
    for (const std::string& line :
         baker.estimator().trace_texel(t.position, t.normal, t.albedo, rng))
        std::printf("    %s\n", line.c_str());
}

}  // namespace

int run_bake(const BakeArgs& args) {
    const BakeMethod method = parse_bake_method(args.method);
    BakeSettings settings;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &settings);
    for (const std::string& s : args.sets) group.apply_assignment(s);
    if (args.spp > 0) group.apply_assignment("bake.spp=" + std::to_string(args.spp), "--spp");
    if (args.seed >= 0) group.apply_assignment("bake.seed=" + std::to_string(args.seed), "--seed");
    if (args.out.empty()) throw Error("--out", "", "expected an output directory");
    for (const std::string& dir : args.reference)
        if (!fs::is_directory(dir))
            throw Error(dir, "--reference", "expected a directory written by freqlab bake");
    if (args.reference.size() == 2) check_reference_halves(args.reference);

    // Under mpirun every rank bakes its share of the texel rows (lightmap_baker.h) and rank 0
    // gathers them and writes everything: the same bytes as one process.
    Cluster& cluster = Cluster::world();
    if (cluster.distributed()) {
        if (args.compare_surface)
            throw Error("--compare-surface", "", "measures one process's overhead: run it alone");
        if (!args.debug_texel.empty())
            throw Error("--debug-texel", args.debug_texel, "traces one process: run it alone");
    }

    // Everything that can be wrong with the input is checked before any output exists.
    const Scene scene = load_scene(args.scene);
    if (cluster.rank() == 0) print_load_notes(scene);
    const Media media(scene.media, scene.source);
    std::unique_ptr<tbb::global_control> limit;
    if (args.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      size_t(args.threads));
    EmbreeDevice device(args.threads);
    RayScene rays(scene, device);
    rays.update(0.0f);

    // No media: no tables are loaded or built (the impulse bake is then the surface bake).
    std::unique_ptr<ImpulseTables> tables;
    double tables_ms = 0.0;
    if (method == BakeMethod::Impulse && !media.empty()) {
        cluster.rank0_first([&] {
            const auto t0 = Clock::now();
            tables = std::make_unique<ImpulseTables>(ImpulseTables::cached(kDefaultTableBounces));
            tables_ms = ms_since(t0);
        });
    }
    if (cluster.rank() == 0) {
        std::error_code ec;
        fs::create_directories(args.out, ec);
        if (ec || !fs::is_directory(args.out))
            throw Error(args.out, "--out", "cannot create the output directory: " + ec.message());
    }

    LightmapBaker baker(rays, media, tables.get(), method, settings);
    if (cluster.rank() == 0)
        for (const std::string& note : baker.stats().atlas_notes)
            std::fprintf(stderr, "%s: %s\n", args.scene.c_str(), note.c_str());
    if (cluster.distributed()) {
        baker.set_share(cluster.rank(), cluster.size());
        cluster.set_work("texel rows and probes = " + std::to_string(cluster.rank()) + " mod " +
                         std::to_string(cluster.size()));
    }
    Progress progress;
    {
        TerminalProgressBar bar(progress,
                                cluster.rank() == 0 && !args.quiet && stderr_is_terminal());
        baker.run(&progress);
    }
    json ranks = json::array();
    if (cluster.distributed()) {
        constexpr int kShareTag = 21;
        const double own_ms = baker.stats().bake_ms;
        const std::vector<std::string> shares = cluster.gather(baker.encode_share(), kShareTag);
        const std::vector<std::string> times =
            cluster.gather(std::to_string(own_ms), kShareTag + 1);
        if (cluster.rank() != 0) return 0;
        for (int r = 1; r < cluster.size(); ++r)
            baker.add_share(shares[size_t(r)], r, "bake share of rank " + std::to_string(r));
        for (int r = 0; r < cluster.size(); ++r)
            ranks.push_back({{"rank", r}, {"bake_ms", std::stod(times[size_t(r)])}});
    }
    BakeStats stats = baker.stats();
    stats.tables_ms = tables_ms;
    json report = {{"scene", args.scene},
                   {"method", to_string(method)},
                   {"media", long(media.size())},
                   {"tables_loaded", bool(tables)},
                   {"threads", args.threads},
                   {"settings", group.to_json()},
                   {"load_notes", scene.load_notes},
                   {"stats", stats.to_json()}};
    if (!ranks.empty()) report["ranks"] = ranks;
    if (args.compare_surface && method != BakeMethod::Surface) {
        LightmapBaker surface(rays, media, nullptr, BakeMethod::Surface, settings);
        surface.run(nullptr);
        report["surface_bake_ms"] = surface.stats().bake_ms;
        report["overhead"] = stats.bake_ms / surface.stats().bake_ms;
    }
    json maps = json::array();
    std::vector<LightmapError> errors;  // lm_irradiance's, per lightmap
    const BakeKeyLight key = bake_key_light(rays);
    const json bake_provenance =
        output_provenance(scene, to_string(method), group.to_json(), long(settings.seed));
    // Every lightmap's layers (the preview reads them too).
    const std::vector<LayerSet> baked = baker.all_layers();
    for (size_t i = 0; i < baker.lightmaps().size(); ++i) {
        const ObjectLightmap& map = baker.lightmaps()[i];
        const std::string name = lightmap_name(scene, map);
        const LayerSet& layers = baked[i];
        json provenance = bake_provenance;
        provenance["lightmap"] = name;
        write_exr(fs::path(args.out) / (name + ".exr"), layers, provenance);
        DisplayParams display;
        write_png(fs::path(args.out) / (name + ".png"), layers.width(), layers.height(),
                  layer_to_rgb8(layers, layers.get("lm_total"), display), provenance);
        json entry = {{"name", name},
                      {"object", map.object},
                      {"width", map.width},
                      {"height", map.height},
                      {"charts", map.charts},
                      {"requested_density", map.requested_density},
                      {"texel_density", map.texel_density},
                      {"texels_valid", long(map.count(TexelState::Valid))},
                      {"texels_inside_geometry", long(map.count(TexelState::InsideGeometry))}};
        if (!args.reference.empty()) {
            entry["error"] = error_against(args.reference, name, layers,
                                           shadowed_texels(rays, map, key), &errors.emplace_back());
        }
        maps.push_back(entry);
    }
    report["lightmaps"] = maps;
    if (!args.reference.empty()) report["error"] = error_over_lightmaps(errors);
    if (!baker.probes().empty()) {
        write_text_atomically(fs::path(args.out) / "probes.json",
                              baker.probes_json().dump(1) + "\n");
        report["probes"] = long(baker.probes().size());
    }
    {
        // The lightmapped scene from the scene's camera (volume/lightmap_preview.h).
        const auto [w, h] = parse_size(args.preview_size, "--preview-size");
        const LayerSet preview =
            render_lightmap_preview(rays, scene.camera.at(0.0f), w, h, baker.lightmaps(), baked);
        write_exr(fs::path(args.out) / "preview.exr", preview, bake_provenance);
        DisplayParams display;
        write_png(fs::path(args.out) / "preview.png", w, h,
                  layer_to_rgb8(preview, preview.get("color"), display), bake_provenance);
    }
    if (!args.debug_texel.empty())
        print_debug_texel(rays, media, tables.get(), settings, baker, args.debug_texel);
    write_text_atomically(fs::path(args.out) / "stats.json", report.dump(2) + "\n");
    if (!args.quiet)
        std::printf("baked %zu lightmap(s) with %s at %d spp in %.0f ms -> %s\n",
                    baker.lightmaps().size(), to_string(method), stats.samples, stats.bake_ms,
                    args.out.c_str());
    return 0;
}

}  // namespace freqlab
