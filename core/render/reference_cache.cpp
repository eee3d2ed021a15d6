#include "render/reference_cache.h"

#include <cstdio>
#include <cstdlib>

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
        return read_exr(p).layers;
    } catch (const Error&) {
        return std::nullopt;  // a damaged cache entry is re-rendered, not fatal
    }
}

void ReferenceCache::store(const std::string& key, const LayerSet& layers,
                           const nlohmann::json& provenance) const {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) return;  // caching is an optimisation; an unwritable cache only costs time
    try {
        write_exr(dir_ / (key + ".exr"), layers, provenance);
    } catch (const Error&) {
    }
}

}  // namespace freqlab
