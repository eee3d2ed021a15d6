// What made an output (issue "The workbench tells the truth"): every EXR header
// (freqlab:provenance), PNG text chunk and CSV header carries the same record, so a figure found
// on disk says which scene (path and content hash), method, settings, seed, media coefficients
// and freqlab version produced it — the values used, after every --set and slider.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/medium_desc.h"

namespace freqlab {

struct Scene;

// freqlab's version: the CMake project version and the git commit the build was configured at.
const char* freqlab_version();

// The record: {freqlab, scene, scene_hash, method, seed, settings, media[] (name, sigma_s,
// sigma_a, g, density_scale)}; `media` is what the bake used (sliders move it off the scene's).
nlohmann::json output_provenance(const Scene& scene, const std::string& method,
                                 const nlohmann::json& settings, long seed,
                                 const std::vector<MediumDesc>& media);
// The scene's own media.
nlohmann::json output_provenance(const Scene& scene, const std::string& method,
                                 const nlohmann::json& settings, long seed);

// "# key: value" lines for a CSV header (one per top-level field, values as compact JSON).
std::string provenance_csv_header(const nlohmann::json& provenance);

}  // namespace freqlab
