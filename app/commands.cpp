#include "commands.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <regex>

#include "base/error.h"
#include "base/file_io.h"
#include "image/colormap.h"
#include "image/figure.h"
#include "image/image_io.h"
#include "image/metrics.h"
#include "render/direct_lighting.h"
#include "render/frame_renderer.h"
#include "render/shading_pass.h"
#include "scene/scene_loader.h"
#include "volume/impulse_query.h"
#include "volume/impulse_tables.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

int parse_count(const std::string& text, const std::string& flag, const std::string& whole) {
    int value = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (text.empty() || ec == std::errc::invalid_argument || ptr != end || value < 0)
        throw Error(flag, whole.empty() ? text : whole, "expected a whole number >= 0");
    if (ec == std::errc::result_out_of_range)
        throw Error(flag, whole.empty() ? text : whole,
                    "expected a number up to " + std::to_string(INT_MAX));
    return value;
}

std::pair<int, int> parse_frame_range(const std::string& text, int frame_count) {
    std::smatch m;
    int a = 0, b = 0;
    if (std::regex_match(text, m, std::regex(R"((\d+):(\d+))"))) {
        a = parse_count(m[1], "--frames", text), b = parse_count(m[2], "--frames", text);
    } else if (std::regex_match(text, m, std::regex(R"((\d+))"))) {
        a = parse_count(m[1], "--frames", text), b = a + 1;
    } else {
        throw Error("--frames", text, "expected A:B (frames A to B-1) or a single frame N");
    }
    if (b <= a) throw Error("--frames", text, "expected B > A in A:B");
    if (b > frame_count)
        throw Error("--frames", text,
                    "the scene has " + std::to_string(frame_count) +
                        " frames (0:" + std::to_string(frame_count) + ")");
    return {a, b};
}

std::pair<int, int> parse_size(const std::string& text, const std::string& flag) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex(R"((\d{1,5})x(\d{1,5}))")))
        throw Error(flag, text, "expected WIDTHxHEIGHT, e.g. 640x360");
    const int w = std::stoi(m[1]), h = std::stoi(m[2]);
    if (w < 1 || h < 1 || w > 16384 || h > 16384)
        throw Error(flag, text, "expected sizes in [1, 16384]");
    return {w, h};
}

void print_load_notes(const Scene& scene) {
    for (const std::string& note : scene.load_notes)
        std::fprintf(stderr, "note: %s: %s\n", scene.source.c_str(), note.c_str());
}

int run_compare(const CompareArgs& args) {
    const ExrFile test = read_exr(args.test);
    const ExrFile ref = read_exr(args.ref);
    ImageMetrics m;
    try {
        m = compare_layers(test.layers, ref.layers, args.layer);
    } catch (const Error& e) {
        throw Error(args.test + " vs " + args.ref, e.field(), e.message());
    }
    const json all = {{"rmse", m.rmse},
                      {"relmse", m.relmse},
                      {"ssim", m.ssim},
                      {"max_abs", m.max_abs},
                      {"nonfinite", m.nonfinite}};
    json out = json::object();
    std::stringstream ss(args.metrics);
    std::string key;
    while (std::getline(ss, key, ',')) {
        if (!all.contains(key))
            throw Error("--metrics", key,
                        "unknown metric; expected rmse, relmse, ssim, max_abs, nonfinite");
        out[key] = all[key];
    }
    out["nonfinite"] = m.nonfinite;  // always reported: NaN/Inf never pass silently
    out["relmse_form"] = "mean((I-R)^2/(R+0.01)^2)";
    out["layer"] = args.layer;
    std::cout << out.dump(2) << std::endl;
    return 0;
}

int run_figure(const FigureArgs& args) {
    const ExrFile file = read_exr(args.input);
    FigureSpec spec;
    spec.layer = args.layer;
    spec.scale = args.scale;
    spec.title = args.title;
    spec.display.exposure_ev = args.exposure;
    for (const std::string& text : args.insets) {
        FigureInset in;
        if (std::sscanf(text.c_str(), "%d,%d,%d,%d", &in.x, &in.y, &in.width, &in.height) != 4)
            throw Error("--inset", text, "expected X,Y,W,H in layer pixels");
        spec.insets.push_back(in);
    }
    write_figure(args.out, file.layers, spec);
    std::fprintf(stderr, "wrote %s\n", args.out.c_str());
    return 0;
}

int run_tables_query(const TablesQueryArgs& a) {
    ImpulseQuery q;
    q.emitter = parse_emitter(a.emitter);
    q.variant = parse_variant(a.variant);
    q.receiver = parse_receiver(a.receiver);
    q.distance = a.distance;
    q.shift = a.shift;
    q.medium = HomogeneousMedium{a.sigma_s, a.sigma_a, a.g};
    if (a.bounces == "all") {
        q.last_bounce = kDefaultTableBounces;
    } else {
        char* end = nullptr;
        q.last_bounce = int(std::strtol(a.bounces.c_str(), &end, 10));
        if (!end || *end || a.bounces.empty())
            throw Error("--bounces", a.bounces,
                        "expected all or 1 to " + std::to_string(kDefaultTableBounces));
    }
    if (q.emitter != EmitterKind::Area && a.shift != 0.0)
        throw Error("--shift", std::to_string(a.shift), "only area emitters take a shift");
    validate(q, kDefaultTableBounces);
    std::string path;
    const ImpulseTables tables = ImpulseTables::cached(kDefaultTableBounces, &path);
    const ImpulseResponse r = query_impulse(tables, q);
    json out = {{"emitter", a.emitter},
                {"variant", a.variant},
                {"receiver", a.receiver},
                {"distance", a.distance},
                {"medium", {{"sigma_s", a.sigma_s}, {"sigma_a", a.sigma_a}, {"g", a.g}}},
                {"bounces", a.bounces},
                {"normalization", normalization_of(q.emitter)},
                {"order", kImpulseOrder},
                {"tables", path},
                {"direct", r.direct},
                {"single", r.single},
                {"multiple", r.multiple},
                {"total", r.total}};
    if (q.emitter == EmitterKind::Area) {
        out["shift"] = a.shift;
        out["axis_tilt_radians"] = r.axis_tilt;
    }
    std::cout << out.dump(2) << std::endl;
    return 0;
}

int run_tables_generate(const std::string& out_arg, int bounces) {
    using Clock = std::chrono::steady_clock;
    const std::string out =
        out_arg.empty() ? ImpulseTables::default_path(bounces).string() : out_arg;
    auto t0 = Clock::now();
    const ImpulseTables built = ImpulseTables::build(bounces);
    const double build_s = std::chrono::duration<double>(Clock::now() - t0).count();
    built.save(out);
    t0 = Clock::now();
    ImpulseTables loaded = ImpulseTables::load(out);
    // Load time: the median of 5 loads (the first one also faults the file into the page cache).
    std::vector<double> load_times;
    for (int i = 0; i < 5; ++i) {
        t0 = Clock::now();
        loaded = ImpulseTables::load(out);
        load_times.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    std::sort(load_times.begin(), load_times.end());
    const double load_ms = load_times[2];
    // Queries against direct computation at the medium.
    const ImpulseTables::Verification verified = loaded.verify();
    const double worst = verified.worst();
    const json report = {
        {"file", out},
        {"bytes", std::filesystem::file_size(out)},
        {"bounces", bounces},
        {"build_s", build_s},
        {"load_ms", load_ms},
        {"verify_worst_relative_error", worst},
        {"verify_worst_relative_error_point", verified.worst_point},
        {"verify_worst_relative_error_directional", verified.worst_directional},
        {"verify_queries", verified.queries},
        {"estimated_error_relative_to_dc",
         {{"point_single", loaded.point_single().worst_relative_error()},
          {"directional_single", loaded.directional_single().worst_relative_error()},
          {"area_single", loaded.area_single().worst_relative_error()}}}};
    std::cout << report.dump(2) << std::endl;
    if (worst > ImpulseTables::kVerifyTolerance)
        throw Error(out, "verify", "table queries are off by more than 0.5 %");
    return 0;
}

}  // namespace freqlab
