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
#include "render/frame_renderer.h"

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
    // Settings that change no result (how often checkpoints are written, the exposure, ...)
    // do not make another run.
    if (key.contains("settings") && key["settings"].is_object()) {
        RenderConfig config;
        key["settings"] = config.settings_group().affecting_results(key["settings"]);
    }
    return key;
}

uint64_t read_run_file_frame(ByteReader& r, std::string_view bytes, const std::string& source,
                             uint32_t magic, uint32_t version, const std::string& what) {
    if (bytes.size() < 2 * sizeof(uint32_t) + sizeof(uint64_t))
        throw Error(source, "header",
                    "not a freqlab " + what + " (" + std::to_string(bytes.size()) + " bytes)");
    if (r.get<uint32_t>() != magic) throw Error(source, "header", "not a freqlab " + what);
    const uint32_t found = r.get<uint32_t>();
    if (found != version)
        throw Error(
            source, "version",
            "format " + std::to_string(found) + ", this freqlab reads " + std::to_string(version));
    uint64_t trailer = 0;
    std::memcpy(&trailer, bytes.data() + bytes.size() - sizeof trailer, sizeof trailer);
    return trailer;
}

void check_run_key(const json& found, const json& key, const std::string& source) {
    for (const char* field : kKeyFields)
        if (found.value(field, json()) != key.value(field, json()))
            throw Error(source, std::string("key.") + field,
                        "written by another run: " + found.value(field, json()).dump() +
                            ", this run has " + key.value(field, json()).dump());
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
    ByteReader r(bytes, source, "checkpoint");
    const uint64_t stored =
        read_run_file_frame(r, bytes, source, kMagic, kFrameCheckpointVersion, "checkpoint");
    if (stored != fnv1a(bytes.substr(0, bytes.size() - sizeof stored)))
        throw Error(source, "checksum", "the file is damaged or truncated");
    json found;
    try {
        found = json::parse(r.get_string());
    } catch (const json::exception& e) {
        throw Error(source, "key", std::string("unreadable: ") + e.what());
    }
    check_run_key(found, key, source);
    FrameCheckpoint c;
    c.frame = r.get<int32_t>();
    c.state = r.get_string();
    return c;
}

fs::path run_store_directory(const json& key) {
    char hex[24];
    std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)fnv1a(key.dump()));
    const char* dir = std::getenv("FREQLAB_RUN_STORE_DIR");
    return (dir && *dir ? fs::path(dir) : cache_directory() / "runs") / hex;
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
