// Converged references are expensive: they are cached on disk, keyed by the scene text, the
// settings, the frame and the renderer version, so a study (bench, compare, the GUI's split
// view) renders each reference frame once. Directory: $FREQLAB_CACHE_DIR, else
// $XDG_CACHE_HOME/freqlab, else ~/.cache/freqlab; files reference/<key>.exr.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "image/layers.h"

namespace freqlab {

class ReferenceCache {
  public:
    ReferenceCache();  // resolves the directory; an unusable one disables the cache
    std::string key(uint64_t scene_hash, const nlohmann::json& settings, int frame) const;
    // A hit counts as a use: the file's time is renewed (the cap removes the least recent).
    std::optional<LayerSet> load(const std::string& key) const;
    // Writes the reference, then removes the least recently used ones until the folder's
    // references take at most `max_bytes` (the new one too when it alone exceeds them).
    // Returns how many files were removed.
    long store(const std::string& key, const LayerSet& layers, const nlohmann::json& provenance,
               double max_bytes) const;
    double bytes_on_disk() const;  // of the references in the folder
    const std::filesystem::path& directory() const { return dir_; }

  private:
    std::filesystem::path dir_;
};

}  // namespace freqlab
