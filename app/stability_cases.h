// The configurations of `freqlab bench --study stability` (issue "Reliability", acceptance 3):
// every numeric setting at its declared minimum, maximum and points between, medium
// coefficients over their whole ranges, Phong exponents, grazing cameras, degenerate
// triangles, damaged and extreme environment maps, empty scenes and single-pixel images.
// Each case is a scene (JSON), --set assignments and the methods it runs; the runner
// (bench_stability.cpp) renders / bakes each and counts non-finite values per output layer.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace freqlab {

struct StabilityCase {
    std::string group;  // "setting", "medium", "material", "camera", "geometry", "environment", ...
    std::string name;   // what is varied, e.g. "bake.spp=1048576"
    nlohmann::json scene;
    std::vector<std::string> sets;  // after the sweep's small-workload base assignments
    std::vector<std::string> render_methods, bake_methods;
    // The input is invalid (a NaN texel): a clear Error naming the file is the right outcome,
    // and accepting it a failure.
    bool expect_refusal = false;
    std::string refusal_contains;  // what that error must say
    // Methods that must refuse this valid input (beyond what the method can represent, e.g.
    // method B's tables past |g| = 0.95), and what their error must say; the others must run.
    std::map<std::string, std::string> method_refusals;
    std::string note_contains;  // non-empty: a load note (Scene::load_notes) must say this
};

// The sweep's base scene: a floor, an animated Phong box, a mirror sphere and a sliver quad;
// a constant environment, point, directional and quad lights; a homogeneous and a noise-grid
// medium. Method A's renders see its environment, method B's bakes everything.
nlohmann::json stability_base_scene();

// The small workload every case starts from (tiny images, few samples, coarse atlases), so
// that a setting's maximum is affordable; a case's own assignments come after these.
std::vector<std::string> stability_base_render_sets();
std::vector<std::string> stability_base_bake_sets();

// All cases. Files a case needs (OBJ meshes, EXR maps) are written into `asset_dir`. `full`:
// every declared extreme, including the sample-count maxima that take minutes; otherwise a
// lean sweep (each field's minimum, maximum and middle at the small workload, and every other
// group whole) for CI.
std::vector<StabilityCase> stability_cases(const std::filesystem::path& asset_dir, bool full);

}  // namespace freqlab
