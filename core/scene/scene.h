// The scene model: what a JSON scene file (or the built-in scene) describes. Loaded once,
// immutable afterwards; per-frame state (transforms at time t) is evaluated on demand.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/animation.h"
#include "scene/camera.h"
#include "scene/light.h"
#include "scene/material.h"
#include "scene/medium_desc.h"
#include "scene/mesh.h"

namespace freqlab {

enum class ShapeKind { Mesh, Sphere };

// An object's own lightmap options (scene format "lightmap": false | {"density_scale": s,
// "max_size": n}); method B's atlas builder reads them (volume/lightmap_atlas.h).
struct LightmapOptions {
    bool enabled = true;
    float density_scale = 1.0f;  // x bake.texel_density
    int max_size = 0;            // atlas side limit for this object; 0: bake.max_size
};

struct SceneObject {
    std::string name;
    ShapeKind shape = ShapeKind::Mesh;
    std::shared_ptr<const TriangleMesh> mesh;  // Mesh
    float sphere_radius = 1.0f;                // Sphere, centred at the local origin
    int material = 0;                          // index into Scene::materials
    std::vector<int> group_material;           // per mesh group (material_map); empty: `material`
    Animation animation;
    LightmapOptions lightmap;
};

struct Scene {
    std::string name;
    std::string source;         // file path or "builtin:default"
    uint64_t content_hash = 0;  // FNV-1a of the scene text (assets are not hashed)
    float fps = 24.0f;
    int frame_count = 1;
    Camera camera;
    std::vector<Material> materials;
    std::vector<SceneObject> objects;
    std::vector<Light> lights;
    std::vector<MediumDesc> media;  // method B's participating media (empty: none)
    // What the loader changed in the input, each naming where ("objects[2] 'x': 3 zero-area
    // triangles dropped"): the CLI prints them and writes them to stats.json, the workbench
    // shows them; nothing is changed silently.
    std::vector<std::string> load_notes;

    float time_of_frame(int frame) const { return float(frame) / fps; }
    bool is_static() const;  // nothing moves: no object animation, static camera
    // The environment-like light (envmap or baked sky), or null: what camera rays that miss see.
    const EnvironmentMap* environment() const;
    vec3 background(const vec3& direction) const;
};

}  // namespace freqlab
