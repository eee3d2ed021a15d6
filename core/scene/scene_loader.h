// JSON scene files (format: scenes/README.md) and the built-in scene `builtin:default`.
#pragma once

#include <string>

#include "scene/scene.h"

namespace freqlab {

// `path` is a file path or "builtin:default". Throws Error naming file and JSON path.
Scene load_scene(const std::string& path);
// Parses scene JSON text; `origin` names it in errors, `scene_dir` anchors relative assets.
Scene parse_scene(const std::string& text, const std::string& origin, const std::string& scene_dir);

extern const char* const kBuiltinDefaultScene;  // the JSON text of builtin:default

}  // namespace freqlab
