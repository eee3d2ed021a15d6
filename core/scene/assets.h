// Where asset files are found: next to the scene file, then each directory of the
// FREQLAB_ASSET_PATH environment variable (':'-separated), then the Debian asset packages
// that set-up installs (blender-data's studio lights, assimp-testmodels' meshes).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace freqlab {

std::vector<std::filesystem::path> asset_search_path(const std::filesystem::path& scene_dir);

// Resolves `name`; a missing file is an Error naming origin/field, the directories searched
// and, when the name looks like one of theirs, the Debian package that provides it.
std::filesystem::path resolve_asset(const std::string& name, const std::filesystem::path& scene_dir,
                                    const std::string& origin, const std::string& field);

}  // namespace freqlab
