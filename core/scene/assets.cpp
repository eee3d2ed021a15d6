#include "scene/assets.h"

#include <cstdlib>
#include <sstream>

#include "base/error.h"

namespace freqlab {

namespace fs = std::filesystem;

namespace {

struct PackageRoot {
    const char* root;
    const char* package;
};
const PackageRoot kPackageRoots[] = {
    {"/usr/share/blender/datafiles", "blender-data"},
    {"/usr/share/assimp/models", "assimp-testmodels"},
};

}  // namespace

std::vector<fs::path> asset_search_path(const fs::path& scene_dir) {
    std::vector<fs::path> dirs;
    if (!scene_dir.empty()) dirs.push_back(scene_dir);
    if (const char* env = std::getenv("FREQLAB_ASSET_PATH")) {
        std::stringstream ss(env);
        std::string dir;
        while (std::getline(ss, dir, ':'))
            if (!dir.empty()) dirs.push_back(dir);
    }
    for (const PackageRoot& r : kPackageRoots) dirs.push_back(r.root);
    return dirs;
}

fs::path resolve_asset(const std::string& name, const fs::path& scene_dir,
                       const std::string& origin, const std::string& field) {
    if (name.empty()) throw Error(origin, field, "expected a file name, got an empty string");
    const fs::path p(name);
    std::error_code ec;
    if (p.is_absolute()) {
        if (fs::is_regular_file(p, ec)) return p;
    } else {
        for (const fs::path& dir : asset_search_path(scene_dir))
            if (fs::is_regular_file(dir / p, ec)) return dir / p;
    }
    std::string searched;
    if (!p.is_absolute())
        for (const fs::path& dir : asset_search_path(scene_dir))
            searched += (searched.empty() ? "" : ", ") + dir.string();
    std::string hint;
    const std::string first = p.begin() == p.end() ? "" : p.begin()->string();
    if (first == "studiolights" || name.find("/usr/share/blender") == 0)
        hint = "; it is provided by the Debian package blender-data (apt-get install blender-data)";
    else if (name.find("/usr/share/assimp") == 0 ||
             fs::is_directory(fs::path("/usr/share/assimp/models") / first, ec) ||
             first == "glTF2" || first == "PLY" || first == "OBJ" || first == "Collada")
        hint =
            "; it is provided by the Debian package assimp-testmodels "
            "(apt-get install assimp-testmodels)";
    throw Error(origin, field,
                "file not found: \"" + name + "\"" +
                    (searched.empty() ? "" : " (searched " + searched + ")") + hint);
}

}  // namespace freqlab
