#include "render/reference_cache.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "base/error.h"
#include "base/file_io.h"
#include "base/hash.h"
#include "image/image_io.h"

namespace freqlab {

namespace fs = std::filesystem;

namespace {
// Bump when the estimator changes what it computes: old references become invalid.
constexpr const char* kRendererVersion = "direct-lighting-1";
}  // namespace

ReferenceCache::ReferenceCache() : dir_(cache_directory() / "reference") {}

std::string ReferenceCache::key(uint64_t scene_hash, const nlohmann::json& settings,
                                int frame) const {
    const uint64_t h =
        fnv1a(settings.dump() + "|" + std::to_string(frame) + "|" + kRendererVersion, scene_hash);
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

std::optional<LayerSet> ReferenceCache::load(const std::string& key) const {
    const fs::path p = dir_ / (key + ".exr");
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) return std::nullopt;
    try {
        LayerSet layers = read_exr(p).layers;
        fs::last_write_time(p, fs::file_time_type::clock::now(), ec);
        return layers;
    } catch (const Error&) {
        return std::nullopt;  // a damaged cache entry is re-rendered, not fatal
    }
}

namespace {

struct CachedFile {
    fs::path path;
    fs::file_time_type time;
    double bytes;
};

std::vector<CachedFile> cached_files(const fs::path& dir) {
    std::vector<CachedFile> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        if (e.path().extension() != ".exr" || !e.is_regular_file(ec)) continue;
        files.push_back({e.path(), e.last_write_time(ec), double(e.file_size(ec))});
    }
    return files;
}

}  // namespace

double ReferenceCache::bytes_on_disk() const {
    double total = 0.0;
    for (const CachedFile& f : cached_files(dir_)) total += f.bytes;
    return total;
}

long ReferenceCache::store(const std::string& key, const LayerSet& layers,
                           const nlohmann::json& provenance, double max_bytes) const {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) return 0;  // caching is an optimisation; an unwritable cache only costs time
    try {
        write_exr(dir_ / (key + ".exr"), layers, provenance);
    } catch (const Error&) {
        return 0;
    }
    std::vector<CachedFile> files = cached_files(dir_);
    std::sort(files.begin(), files.end(),
              [](const CachedFile& a, const CachedFile& b) { return a.time < b.time; });
    double total = 0.0;
    for (const CachedFile& f : files) total += f.bytes;
    long removed = 0;
    for (const CachedFile& f : files) {
        if (total <= max_bytes) break;
        if (fs::remove(f.path, ec)) {
            total -= f.bytes;
            ++removed;
        }
    }
    return removed;
}

}  // namespace freqlab
