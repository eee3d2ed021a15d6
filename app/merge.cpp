// `freqlab merge OUT PART_DIR...`: the folders of a run split by `--part I/N` (Slurm array
// tasks, scripts/slurm/) joined into the folder one process would have written. A render: every
// frame's EXR and PNG copied as they are (byte for byte: a part renders its frames exactly as
// one process does) and one stats.json with the frames in order. A study (bake-thickness): its
// rows in order through the study's own writer. The parts must be the N parts of one run (same
// scene, method or study, settings, range), each once; nothing is written before every part
// has been checked.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "bench_common.h"
#include "commands.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct RenderPart {
    fs::path dir;
    json stats;
    std::vector<int> frames;
};

json read_json(const fs::path& file) {
    try {
        return json::parse(read_text_file(file));
    } catch (const json::exception& e) {
        throw Error(file.string(), "", std::string("not JSON: ") + e.what());
    }
}

RenderPart read_part(const std::string& dir) {
    const fs::path file = fs::path(dir) / "stats.json";
    RenderPart p;
    p.dir = dir;
    p.stats = read_json(file);
    if (!p.stats.contains("part") || !p.stats["part"].is_object())
        throw Error(file.string(), "part",
                    "expected the stats of `freqlab render --part I/N` (this folder holds a "
                    "whole run, or not a render)");
    try {
        p.frames = p.stats["part"]["frames_kept"].get<std::vector<int>>();
        (void)p.stats["part"]["index"].get<int>();
        (void)p.stats["part"]["count"].get<int>();
    } catch (const json::exception& e) {
        throw Error(file.string(), "part", std::string("malformed: ") + e.what());
    }
    return p;
}

// The fields that must agree between the parts of one run.
void check_same_run(const RenderPart& a, const RenderPart& b) {
    for (const char* key : {"scene", "method", "settings"})
        if (a.stats[key] != b.stats[key])
            throw Error(
                (b.dir / "stats.json").string(), key,
                "differs from " + (a.dir / "stats.json").string() + ": not a part of the same run");
    for (const char* key : {"count", "frames_range", "warm_frames"})
        if (a.stats["part"][key] != b.stats["part"][key])
            throw Error(
                (b.dir / "stats.json").string(), std::string("part.") + key,
                "differs from " + (a.dir / "stats.json").string() + ": not a part of the same run");
}

void copy_atomically(const fs::path& from, const fs::path& to) {
    write_atomically(to, [&](const fs::path& tmp) {
        std::error_code ec;
        fs::copy_file(from, tmp, fs::copy_options::overwrite_existing, ec);
        if (ec) throw Error(to.string(), "", describe_write_failure(tmp, ec.message()));
    });
}

// Checks that `parts` (index, count) are parts 0 .. count-1 of one run, each once.
void check_all_parts(const std::vector<std::pair<int, int>>& parts,
                     const std::vector<std::string>& dirs) {
    const int count = parts[0].second;
    std::set<int> seen;
    for (size_t i = 0; i < parts.size(); ++i) {
        if (parts[i].second != count)
            throw Error(dirs[i], "part.count", "differs from " + dirs[0] + "'s");
        if (!seen.insert(parts[i].first).second)
            throw Error(dirs[i], "part.index",
                        "part " + std::to_string(parts[i].first) + " given twice");
    }
    if (int(seen.size()) != count) {
        std::string missing;
        for (int i = 0; i < count; ++i)
            if (!seen.count(i)) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
        throw Error("merge", "parts",
                    "expected all " + std::to_string(count) + " parts; missing " + missing);
    }
}

int merge_study_parts(const std::string& out, const std::vector<std::string>& dirs) {
    std::vector<json> files;
    std::vector<std::pair<int, int>> indices;
    json rows = json::array();
    for (const std::string& d : dirs) {
        const fs::path file = fs::path(d) / "bench_part.json";
        files.push_back(read_json(file));
        const json& f = files.back();
        if (f["study"] != files[0]["study"] || f["header"] != files[0]["header"])
            throw Error(file.string(), "header",
                        "differs from " + dirs[0] + "'s: not a part of the same study");
        indices.push_back({f["part"]["index"].get<int>(), f["part"]["count"].get<int>()});
        for (const json& r : f["rows"]) rows.push_back(r);
    }
    check_all_parts(indices, dirs);
    if (files[0]["study"] != "bake-thickness")
        throw Error(dirs[0], "study", "only bake-thickness parts can be merged");
    std::sort(rows.begin(), rows.end(), [](const json& x, const json& y) {
        return x["density_factor"].get<double>() < y["density_factor"].get<double>();
    });
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out))
        throw Error(out, "out", "cannot create the output directory: " + ec.message());
    write_bake_thickness_outputs(out, files[0]["header"], rows);
    std::fprintf(stderr, "merged %zu part(s), %zu configuration(s) into %s\n", dirs.size(),
                 rows.size(), out.c_str());
    return 0;
}

}  // namespace

int run_merge(const std::string& out, const std::vector<std::string>& dirs) {
    if (fs::is_regular_file(fs::path(dirs[0]) / "bench_part.json"))
        return merge_study_parts(out, dirs);
    std::vector<RenderPart> parts;
    for (const std::string& d : dirs) parts.push_back(read_part(d));
    std::vector<std::pair<int, int>> indices;
    for (const RenderPart& p : parts) {
        check_same_run(parts[0], p);
        indices.push_back(
            {p.stats["part"]["index"].get<int>(), p.stats["part"]["count"].get<int>()});
        std::error_code same_ec;  // `out` need not exist yet
        if (fs::equivalent(p.dir, out, same_ec))
            throw Error(out, "out", "is one of the parts' folders: expected a new folder");
    }
    check_all_parts(indices, dirs);
    const int count = indices[0].second;
    // Every frame of the range exactly once, its files present.
    const auto range = parts[0].stats["part"]["frames_range"].get<std::vector<int>>();
    std::vector<std::pair<int, const RenderPart*>> frames;
    for (const RenderPart& p : parts)
        for (int f : p.frames) frames.push_back({f, &p});
    std::sort(frames.begin(), frames.end());
    for (int f = range.at(0), i = 0; f < range.at(1); ++f, ++i)
        if (i >= int(frames.size()) || frames[size_t(i)].first != f)
            throw Error("merge", "parts", "frame " + std::to_string(f) + " is in no part");
    if (int(frames.size()) != range.at(1) - range.at(0))
        throw Error("merge", "parts", "a frame is in two parts");
    auto file_of = [](const fs::path& dir, int f, const char* ext) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d.%s", f, ext);
        return dir / name;
    };
    for (const auto& [f, p] : frames)
        for (const char* ext : {"exr", "png"})
            if (!fs::is_regular_file(file_of(p->dir, f, ext)))
                throw Error(file_of(p->dir, f, ext).string(), "",
                            "missing: the part did not finish");

    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out))
        throw Error(out, "out", "cannot create the output directory: " + ec.message());
    json merged_frames = json::array(), part_list = json::array();
    for (const auto& [f, p] : frames) {
        for (const char* ext : {"exr", "png"})
            copy_atomically(file_of(p->dir, f, ext), file_of(out, f, ext));
        for (const json& s : p->stats["frames"])
            if (s["frame"] == f) merged_frames.push_back(s);
    }
    for (const RenderPart& p : parts)
        part_list.push_back({{"dir", p.dir.string()},
                             {"index", p.stats["part"]["index"]},
                             {"frames", p.frames},
                             {"time_ms", p.stats["part"]["time_ms"]}});
    json stats = parts[0].stats;
    stats.erase("part");
    stats["frames"] = merged_frames;
    stats["merged_parts"] = part_list;
    write_text_atomically(fs::path(out) / "stats.json", stats.dump(2) + "\n");
    std::fprintf(stderr, "merged %d part(s), %zu frame(s) into %s\n", count, frames.size(),
                 out.c_str());
    return 0;
}

}  // namespace freqlab
