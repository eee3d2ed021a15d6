#include "render/frame_checkpoint.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <regex>
#include <vector>

#include "base/byte_stream.h"
#include "base/error.h"
#include "base/file_io.h"
#include "base/hash.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {
constexpr uint32_t kMagic = 0x4b434c46;  // "FLCK"
const char* const kKeyFields[] = {"freqlab", "scene_hash", "method", "settings", "seed"};
}  // namespace

fs::path frame_checkpoint_path(const fs::path& dir, int frame) {
    char name[48];
    std::snprintf(name, sizeof name, "state_before_%04d.bin", frame);
    return dir / "checkpoints" / name;
}

json frame_checkpoint_key(const json& provenance) {
    json key = json::object();
    for (const char* field : kKeyFields)
        if (provenance.contains(field)) key[field] = provenance[field];
    // How often checkpoints are written does not change the state they hold.
    if (key.contains("settings") && key["settings"].contains("cache"))
        key["settings"]["cache"].erase("checkpoint_every");
    return key;
}

void write_frame_checkpoint(const fs::path& file, const json& key, int frame,
                            const std::string& state) {
    ByteWriter w;
    w.put(kMagic);
    w.put(kFrameCheckpointVersion);
    w.put_string(key.dump());
    w.put<int32_t>(frame);
    w.put_string(state);
    w.put<uint64_t>(fnv1a(w.bytes()));
    std::error_code ec;
    fs::create_directories(file.parent_path(), ec);
    write_text_atomically(file, w.bytes());
}

FrameCheckpoint read_frame_checkpoint(const fs::path& file, const json& key) {
    const std::string bytes = read_text_file(file);
    const std::string source = file.string();
    if (bytes.size() < 2 * sizeof(uint32_t) + sizeof(uint64_t))
        throw Error(source, "header",
                    "not a freqlab checkpoint (" + std::to_string(bytes.size()) + " bytes)");
    ByteReader r(bytes, source, "checkpoint");
    if (r.get<uint32_t>() != kMagic) throw Error(source, "header", "not a freqlab checkpoint");
    const uint32_t version = r.get<uint32_t>();
    if (version != kFrameCheckpointVersion)
        throw Error(source, "version",
                    "format " + std::to_string(version) + ", this freqlab reads " +
                        std::to_string(kFrameCheckpointVersion));
    uint64_t stored = 0;
    std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
    if (stored != fnv1a(bytes.substr(0, bytes.size() - sizeof stored)))
        throw Error(source, "checksum", "the file is damaged or truncated");
    json found;
    try {
        found = json::parse(r.get_string());
    } catch (const json::exception& e) {
        throw Error(source, "key", std::string("unreadable: ") + e.what());
    }
    for (const char* field : kKeyFields)
        if (found.value(field, json()) != key.value(field, json()))
            throw Error(source, std::string("key.") + field,
                        "written by another run: " + found.value(field, json()).dump() +
                            ", this run has " + key.value(field, json()).dump());
    FrameCheckpoint c;
    c.frame = r.get<int32_t>();
    c.state = r.get_string();
    return c;
}

fs::path run_store_directory(const json& key) {
    char hex[24];
    std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)fnv1a(key.dump()));
    return cache_directory() / "runs" / hex;
}

int trim_run_store(const fs::path& keep) {
    double cap_mb = 4096.0;
    if (const char* env = std::getenv("FREQLAB_RUN_STORE_MB"); env && *env) cap_mb = std::atof(env);
    const uint64_t cap = uint64_t(std::max(0.0, cap_mb) * 1024.0 * 1024.0);
    struct Run {
        fs::path dir;
        fs::file_time_type written;
        uint64_t bytes = 0;
    };
    std::vector<Run> runs;
    uint64_t total = 0;
    std::error_code ec;
    for (fs::directory_iterator it(keep.parent_path(), ec), end; !ec && it != end;
         it.increment(ec)) {
        if (!it->is_directory()) continue;
        Run run{it->path(), fs::file_time_type::min(), 0};
        for (fs::recursive_directory_iterator f(run.dir, ec), fend; !ec && f != fend;
             f.increment(ec)) {
            if (!f->is_regular_file()) continue;
            run.bytes += f->file_size();
            run.written = std::max(run.written, f->last_write_time());
        }
        total += run.bytes;
        runs.push_back(run);
    }
    std::sort(runs.begin(), runs.end(),
              [](const Run& a, const Run& b) { return a.written < b.written; });
    int removed = 0;
    for (const Run& run : runs) {
        if (total <= cap) break;
        if (fs::equivalent(run.dir, keep, ec)) continue;
        fs::remove_all(run.dir, ec);
        total -= run.bytes;
        ++removed;
    }
    return removed;
}

int latest_frame_checkpoint(const fs::path& dir, int frame) {
    std::error_code ec;
    const fs::path folder = dir / "checkpoints";
    int best = -1;
    const std::regex name(R"(state_before_(\d+)\.bin)");
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        std::smatch m;
        const std::string file = it->path().filename().string();
        if (!std::regex_match(file, m, name)) continue;
        const long f = std::stol(m[1]);
        if (f <= frame && f > best) best = int(f);
    }
    return best;
}

}  // namespace freqlab
