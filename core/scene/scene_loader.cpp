#include "scene/scene_loader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include <glm/gtc/matrix_transform.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "base/hash.h"
#include "scene/assets.h"
#include "scene/json_reader.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

const char* const kBuiltinDefaultScene = R"JSON({
  "name": "builtin:default",
  "fps": 24, "frames": 48,
  "camera": {"position": [0, -9, 3.2], "look_at": [0, 0, 0.8], "fov": 38},
  "materials": {
    "ground": {"type": "lambert", "albedo": {"checker": {"a": 0.8, "b": 0.15, "scale": 1}}},
    "clay":   {"type": "lambert", "albedo": [0.75, 0.45, 0.3]},
    "glossy": {"type": "ggx", "roughness": 0.2, "albedo": [0.3, 0.5, 0.8]},
    "chrome": {"type": "mirror", "albedo": 0.9},
    "plastic": {"type": "phong", "exponent": 60, "albedo": [0.8, 0.75, 0.2]}
  },
  "objects": [
    {"name": "ground", "shape": {"type": "plane", "size": [40, 40]}, "material": "ground"},
    {"name": "sphere", "shape": {"type": "sphere", "radius": 1}, "material": "glossy",
     "transform": {"translate": [-1.8, 0.5, 1]}},
    {"name": "box", "shape": {"type": "box", "size": [1.4, 1.4, 1.4]}, "material": "clay",
     "transform": {"translate": [1.9, 1.2, 0.7], "rotate": {"axis": [0, 0, 1], "deg": 25}}},
    {"name": "mirror", "shape": {"type": "disk", "radius": 1.2}, "material": "chrome",
     "transform": {"translate": [0.3, 3.2, 1.3], "rotate": {"axis": [1, 0, 0], "deg": 80}}},
    {"name": "torus", "shape": {"type": "torus", "major": 0.7, "minor": 0.22}, "material": "plastic",
     "animation": {"spin_axis": [1, 0, 0], "spin_deg_per_s": 90,
       "keyframes": [{"t": 0, "translate": [0, -1.5, 0.9]},
                     {"t": 2, "translate": [0.4, -0.5, 1.4]}]}}
  ],
  "lights": [{"type": "sky", "sun_direction": [0.5, -0.4, 0.55]}],
  "media": []
})JSON";

namespace {

struct LoadContext {
    std::string origin;
    fs::path dir;
    std::map<std::string, std::shared_ptr<const RgbImage>> images;
    // Objects naming the same file share one mesh (a level instancing a house 12 times reads
    // it once).
    std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes;

    std::shared_ptr<const TriangleMesh> mesh(const JsonReader& field) {
        const fs::path p = resolve_asset(field.string(), dir, origin, field.path());
        auto it = meshes.find(p.string());
        if (it != meshes.end()) return it->second;
        auto m = std::make_shared<const TriangleMesh>(load_mesh_file(p, origin, field.path()));
        meshes[p.string()] = m;
        return m;
    }

    std::shared_ptr<const RgbImage> image(const JsonReader& field) {
        const fs::path p = resolve_asset(field.string(), dir, origin, field.path());
        auto it = images.find(p.string());
        if (it != images.end()) return it->second;
        std::shared_ptr<const RgbImage> img;
        try {
            img = std::make_shared<RgbImage>(read_rgb_image(p, true));
        } catch (const Error& e) {
            // Keep the scene location in front; the image's own complaint follows.
            throw Error(origin, field.path(), e.what());
        }
        return images[p.string()] = img;
    }
};

quat read_rotation(const JsonReader& r) {
    r.only_keys({"axis", "deg"});
    const vec3 axis = r.get("axis").direction();
    const float deg = float(r.get("deg").number());
    return glm::angleAxis(glm::radians(deg), axis);
}

Trs read_trs(const JsonReader& r, std::initializer_list<const char*> extra_keys = {}) {
    std::vector<const char*> keys = {"translate", "rotate", "scale"};
    keys.insert(keys.end(), extra_keys.begin(), extra_keys.end());
    if (!r.is_object()) r.fail("expected an object with translate / rotate / scale");
    for (const auto& item : r.raw().items()) {
        const std::string& key = item.key();  // a structured binding: not capturable in C++17
        if (std::find_if(keys.begin(), keys.end(), [&](const char* k) { return key == k; }) ==
            keys.end())
            throw Error(r.file(), r.path() + "." + key,
                        "unknown field; expected one of: translate, rotate, scale");
    }
    Trs t;
    if (r.has("translate")) t.translate = r.get("translate").vector3();
    if (r.has("rotate")) t.rotate = read_rotation(r.get("rotate"));
    if (r.has("scale")) {
        const JsonReader s = r.get("scale");
        if (s.raw().is_number())
            t.scale = vec3(float(s.number_in(0, 1e9, true)));
        else {
            t.scale = s.vector3();
            if (t.scale.x <= 0 || t.scale.y <= 0 || t.scale.z <= 0)
                s.fail("expected positive scale factors");
        }
    }
    return t;
}

Texture read_texture(const JsonReader& r, LoadContext& ctx) {
    Texture t;
    if (r.raw().is_number() || r.raw().is_array()) {
        t.color = r.color();
        return t;
    }
    if (!r.is_object()) r.fail("expected a colour, {\"checker\": ...} or {\"texture\": file}");
    r.only_keys({"checker", "texture", "scale"});
    if (r.has("checker")) {
        const JsonReader c = r.get("checker");
        c.only_keys({"a", "b", "scale"});
        t.kind = Texture::Kind::Checker;
        t.color = c.get("a").color();
        t.color_b = c.get("b").color();
        t.scale = float(c.number_or("scale", 1.0, 1e-6, 1e6));
    } else if (r.has("texture")) {
        t.kind = Texture::Kind::Image;
        t.image = ctx.image(r.get("texture"));
        t.source = r.get("texture").string();
        t.scale = float(r.number_or("scale", 1.0, 1e-6, 1e6));
    } else {
        r.fail("expected \"checker\" or \"texture\"");
    }
    return t;
}

Material read_material(const JsonReader& r, const std::string& name, LoadContext& ctx) {
    r.only_keys({"type", "albedo", "exponent", "roughness"});
    Material m;
    m.name = name;
    m.type = r.get("type").one_of(kBrdfTypeNames);
    if (r.has("albedo")) m.albedo = read_texture(r.get("albedo"), ctx);
    if (m.type == BrdfType::Phong)
        m.phong_exponent = float(r.get("exponent").number_in(0, 1e6, true));
    else if (r.has("exponent"))
        r.get("exponent").fail("only phong materials take an exponent");
    if (m.type == BrdfType::Beckmann || m.type == BrdfType::Ggx)
        m.roughness = float(r.get("roughness").number_in(0, 1, true, false));
    else if (r.has("roughness"))
        r.get("roughness").fail("only beckmann and ggx materials take a roughness");
    return m;
}

CameraPose read_pose(const JsonReader& r, const CameraPose& fallback) {
    CameraPose p = fallback;
    if (r.has("position")) p.position = r.get("position").vector3();
    if (r.has("look_at")) p.look_at = r.get("look_at").vector3();
    if (r.has("up")) p.up = r.get("up").direction();
    if (r.has("fov")) p.fov_deg = float(r.get("fov").number_in(0, 180, true, true));
    const vec3 forward = p.look_at - p.position;
    if (glm::length(forward) < 1e-6f)
        throw Error(r.file(), r.path() + ".look_at",
                    "look_at coincides with position (zero-length view direction); expected a "
                    "point away from the camera");
    if (glm::length(glm::cross(glm::normalize(forward), p.up)) < 1e-4f)
        throw Error(r.file(), r.path() + ".up", "up is parallel to the view direction");
    return p;
}

Camera read_camera(const JsonReader& r) {
    r.only_keys({"position", "look_at", "up", "fov", "keyframes", "orbit_deg_per_s"});
    Camera cam;
    const CameraPose base = read_pose(r, CameraPose{});
    if (r.has("keyframes")) {
        const JsonReader keys = r.get("keyframes");
        const size_t n = keys.array_size();
        if (n == 0) keys.fail("expected at least one keyframe");
        CameraPose prev = base;
        for (size_t i = 0; i < n; ++i) {
            const JsonReader k = keys.at(i);
            k.only_keys({"t", "position", "look_at", "up", "fov"});
            CameraKey key;
            key.time = float(k.get("t").number());
            if (i > 0 && key.time <= cam.keys.back().time)
                k.get("t").fail("expected keyframe times in increasing order");
            key.pose = prev = read_pose(k, prev);
            cam.keys.push_back(key);
        }
    } else {
        cam.keys.push_back({0.0f, base});
    }
    if (r.has("orbit_deg_per_s"))
        cam.orbit_rad_per_s = glm::radians(float(r.get("orbit_deg_per_s").number()));
    return cam;
}

// "lightmap": true | false | {"density_scale": s, "max_size": n}.
LightmapOptions read_lightmap_options(const JsonReader& r) {
    LightmapOptions l;
    if (r.raw().is_boolean()) {
        l.enabled = r.boolean();
        return l;
    }
    if (!r.is_object()) r.fail("expected true, false or {\"density_scale\": s, \"max_size\": n}");
    r.only_keys({"density_scale", "max_size"});
    if (r.has("density_scale"))
        l.density_scale = float(r.get("density_scale").number_in(0, 1e4, true));
    if (r.has("max_size")) l.max_size = r.get("max_size").integer_in(16, 8192);
    return l;
}

// A flat shape's optional "size": [width, depth], both > 0.
vec2 width_depth_or(const JsonReader& r, vec2 fallback) {
    if (!r.has("size")) return fallback;
    const JsonReader s = r.get("size");
    if (!s.is_array() || s.array_size() != 2) s.fail("expected [width, depth]");
    return vec2(float(s.at(0).number_in(0, 1e9, true)), float(s.at(1).number_in(0, 1e9, true)));
}

std::shared_ptr<const TriangleMesh> read_shape(const JsonReader& r, SceneObject& obj) {
    const std::string type =
        r.get("type").one_of({"plane", "box", "sphere", "disk", "torus", "terrain"});
    auto positive = [&](const char* key, double fallback) {
        return float(r.has(key) ? r.get(key).number_in(0, 1e9, true) : fallback);
    };
    TriangleMesh mesh;
    if (type == "sphere") {
        r.only_keys({"type", "radius"});
        obj.shape = ShapeKind::Sphere;
        obj.sphere_radius = positive("radius", 1.0);
        return nullptr;
    } else if (type == "plane") {
        r.only_keys({"type", "size", "uv_scale"});
        mesh = make_plane(width_depth_or(r, vec2(10.0f)), positive("uv_scale", 1.0));
    } else if (type == "box") {
        r.only_keys({"type", "size"});
        const vec3 size = r.vector3_or("size", vec3(1.0f));
        if (size.x <= 0 || size.y <= 0 || size.z <= 0)
            r.get("size").fail("expected positive sizes");
        mesh = make_box(size);
    } else if (type == "disk") {
        r.only_keys({"type", "radius", "segments"});
        mesh = make_disk(positive("radius", 1.0),
                         r.has("segments") ? r.get("segments").integer_in(3, 1 << 16) : 64);
    } else if (type == "terrain") {
        r.only_keys({"type", "size", "cells", "height", "frequency", "octaves", "seed", "uv_scale",
                     "skirt"});
        TerrainShape t;
        t.size = width_depth_or(r, t.size);
        if (r.has("cells")) {
            const JsonReader c = r.get("cells");
            if (!c.is_array() || c.array_size() != 2) c.fail("expected [cells along x, along y]");
            t.cells = ivec2(c.at(0).integer_in(1, 4096), c.at(1).integer_in(1, 4096));
        }
        t.height = float(r.number_or("height", t.height, 0, 1e9));
        t.frequency = positive("frequency", t.frequency);
        t.octaves = r.has("octaves") ? r.get("octaves").integer_in(1, 12) : t.octaves;
        t.seed = r.has("seed") ? uint32_t(r.get("seed").integer_in(0, 1 << 30)) : t.seed;
        t.uv_scale = positive("uv_scale", 1.0);
        t.skirt = float(r.number_or("skirt", t.skirt, 0, 1e9));
        mesh = make_terrain(t);
    } else {
        r.only_keys({"type", "major", "minor", "segments", "sides"});
        mesh = make_torus(positive("major", 1.0), positive("minor", 0.25),
                          r.has("segments") ? r.get("segments").integer_in(3, 1 << 14) : 96,
                          r.has("sides") ? r.get("sides").integer_in(3, 1 << 14) : 32);
    }
    clean_mesh(mesh, r.file(), r.path());
    return std::make_shared<TriangleMesh>(std::move(mesh));
}

Light read_light(const JsonReader& r, LoadContext& ctx) {
    Light l;
    l.type = r.get("type").one_of(kLightTypeNames);
    if (l.type == LightType::Environment) {
        r.only_keys({"type", "file", "radiance", "rotation_deg", "rotation_deg_per_s", "scale"});
        if (r.has("file") == r.has("radiance"))
            r.fail(
                "expected exactly one of \"file\" (a lat-long EXR) or \"radiance\" (a constant)");
        std::shared_ptr<const RgbImage> image;
        std::string source;
        if (r.has("file")) {
            image = ctx.image(r.get("file"));
            source = r.get("file").string();
            if (image->width != 2 * image->height)
                r.get("file").fail("expected a lat-long map with width = 2 x height, got " +
                                   std::to_string(image->width) + "x" +
                                   std::to_string(image->height));
        } else {
            const vec3 c = r.get("radiance").color();
            image = constant_latlong(c);
            source = "constant";
        }
        l.environment = std::make_shared<EnvironmentMap>(
            source, image, float(r.number_or("rotation_deg", 0.0, -1e6, 1e6)),
            float(r.number_or("scale", 1.0, 0.0, 1e9)),
            float(r.number_or("rotation_deg_per_s", 0.0, -1e6, 1e6)));
    } else if (l.type == LightType::Sky) {
        r.only_keys({"type", "sun_direction", "sun_radius_deg", "sun_radiance", "zenith", "horizon",
                     "ground", "resolution"});
        if (r.has("sun_direction")) l.sky.sun_direction = r.get("sun_direction").direction();
        l.sky.sun_angular_radius_deg = float(r.number_or("sun_radius_deg", 0.53, 0.01, 45));
        l.sky.sun_radiance = r.color_or("sun_radiance", l.sky.sun_radiance);
        l.sky.zenith = r.color_or("zenith", l.sky.zenith);
        l.sky.horizon = r.color_or("horizon", l.sky.horizon);
        l.sky.ground = r.color_or("ground", l.sky.ground);
        const int height = r.has("resolution") ? r.get("resolution").integer_in(8, 8192) : 1024;
        l.environment =
            std::make_shared<EnvironmentMap>("sky", l.sky.bake(2 * height, height), 0.0f, 1.0f);
    } else if (l.type == LightType::Point) {
        r.only_keys({"type", "position", "intensity"});
        l.position = r.get("position").vector3();
        l.intensity = r.get("intensity").color();
    } else if (l.type == LightType::Directional) {
        r.only_keys({"type", "direction", "irradiance"});
        l.direction = r.get("direction").direction();
        l.intensity = r.get("irradiance").color();
    } else {
        r.only_keys({"type", "corner", "edge_u", "edge_v", "radiance"});
        l.corner = r.get("corner").vector3();
        l.edge_u = r.get("edge_u").vector3();
        l.edge_v = r.get("edge_v").vector3();
        if (glm::length(glm::cross(l.edge_u, l.edge_v)) < 1e-12f)
            r.get("edge_v").fail("quad edges are parallel or zero (the quad has no area)");
        l.intensity = r.get("radiance").color();
    }
    return l;
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& origin,
                  const std::string& scene_dir) {
    const json doc = JsonReader::parse(text, origin);
    const JsonReader root(doc, origin, "");
    root.only_keys({"name", "fps", "frames", "camera", "materials", "objects", "lights", "media"});
    LoadContext ctx{origin, scene_dir, {}, {}};
    Scene scene;
    scene.source = origin;
    scene.content_hash = fnv1a(text);
    scene.name = root.has("name") ? root.get("name").string() : fs::path(origin).stem().string();
    scene.fps = float(root.number_or("fps", 24.0, 1e-3, 1e4));
    scene.frame_count = root.has("frames") ? root.get("frames").integer_in(1, 1000000) : 1;
    scene.camera = read_camera(root.get("camera"));

    std::map<std::string, int> material_index;
    if (root.has("materials")) {
        const JsonReader mats = root.get("materials");
        if (!mats.is_object()) mats.fail("expected an object mapping names to materials");
        for (const auto& [name, value] : mats.raw().items()) {
            material_index[name] = int(scene.materials.size());
            scene.materials.push_back(read_material(mats.get(name), name, ctx));
        }
    }

    const JsonReader objects = root.get("objects");
    const size_t nobj = objects.array_size();
    // No objects is a scene too (an environment on its own): every method sees only misses.
    for (size_t i = 0; i < nobj; ++i) {
        const JsonReader o = objects.at(i);
        o.only_keys({"name", "shape", "mesh", "material", "material_map", "transform", "animation",
                     "lightmap"});
        SceneObject obj;
        obj.name = o.has("name") ? o.get("name").string() : "object" + std::to_string(i);
        if (o.has("shape") == o.has("mesh"))
            o.fail(
                "expected exactly one of \"shape\" (a procedural primitive) or \"mesh\" (a file)");
        if (o.has("shape")) {
            obj.mesh = read_shape(o.get("shape"), obj);
        } else {
            obj.mesh = ctx.mesh(o.get("mesh"));
        }
        const JsonReader mat = o.get("material");
        if (mat.is_string()) {
            auto it = material_index.find(mat.string());
            if (it == material_index.end()) {
                std::string names;
                for (const auto& [n, idx] : material_index)
                    names += (names.empty() ? "" : ", ") + n;
                mat.fail("unknown material \"" + mat.string() +
                         "\"; defined materials: " + (names.empty() ? "(none)" : names));
            }
            obj.material = it->second;
        } else {
            obj.material = int(scene.materials.size());
            scene.materials.push_back(read_material(mat, obj.name, ctx));
        }
        if (o.has("transform")) obj.animation.base = read_trs(o.get("transform"));
        if (o.has("lightmap")) obj.lightmap = read_lightmap_options(o.get("lightmap"));
        if (o.has("animation")) {
            const JsonReader a = o.get("animation");
            a.only_keys({"keyframes", "spin_axis", "spin_deg_per_s"});
            if (a.has("keyframes")) {
                const JsonReader keys = a.get("keyframes");
                for (size_t k = 0; k < keys.array_size(); ++k) {
                    const JsonReader key = keys.at(k);
                    TrsKey tk;
                    tk.time = float(key.get("t").number());
                    if (k > 0 && tk.time <= obj.animation.keys.back().time)
                        key.get("t").fail("expected keyframe times in increasing order");
                    // Unset components inherit the static transform.
                    tk.value = obj.animation.base;
                    const Trs t = read_trs(key, {"t"});
                    if (key.has("translate")) tk.value.translate = t.translate;
                    if (key.has("rotate")) tk.value.rotate = t.rotate;
                    if (key.has("scale")) tk.value.scale = t.scale;
                    obj.animation.keys.push_back(tk);
                }
            }
            if (a.has("spin_axis")) obj.animation.spin_axis = a.get("spin_axis").direction();
            if (a.has("spin_deg_per_s"))
                obj.animation.spin_rad_per_s =
                    glm::radians(float(a.get("spin_deg_per_s").number()));
        }
        if (obj.mesh && obj.mesh->degenerate_removed > 0)
            scene.load_notes.push_back(o.path() + " '" + obj.name +
                                       "': " + std::to_string(obj.mesh->degenerate_removed) +
                                       " zero-area or out-of-range triangles dropped");
        scene.objects.push_back(std::move(obj));
    }

    if (root.has("lights")) {
        const JsonReader lights = root.get("lights");
        bool has_env = false;
        for (size_t i = 0; i < lights.array_size(); ++i) {
            Light l = read_light(lights.at(i), ctx);
            const bool env = l.type == LightType::Environment || l.type == LightType::Sky;
            if (env && has_env)
                lights.at(i).fail("only one environment-like light (envmap or sky) per scene");
            has_env = has_env || env;
            if (l.environment && l.environment->negative_texels() > 0) {
                char lowest[32];
                std::snprintf(lowest, sizeof lowest, "%g", double(l.environment->most_negative()));
                scene.load_notes.push_back(
                    lights.at(i).path() + ".file '" + l.environment->source() +
                    "': " + std::to_string(l.environment->negative_texels()) +
                    " texels with negative radiance (down to " + lowest + ") read as 0");
            }
            if (l.environment && l.environment->distribution().tile() > 1) {
                const Distribution2D& d = l.environment->distribution();
                char inflation[32];
                std::snprintf(inflation, sizeof inflation, "%.4f", d.inflation());
                scene.load_notes.push_back(
                    lights.at(i).path() + ": '" + l.environment->source() +
                    "' importance-sampled by tiles of " + std::to_string(d.tile()) + " x " +
                    std::to_string(d.tile()) + " texels (smooth map; second moment x " + inflation +
                    ")");
            }
            scene.lights.push_back(std::move(l));
        }
    }
    if (root.has("media")) {
        scene.media = parse_media(root.get("media"), scene_dir);
    }
    return scene;
}

Scene load_scene(const std::string& path) {
    if (path == "builtin:default") return parse_scene(kBuiltinDefaultScene, path, "");
    if (path.rfind("builtin:", 0) == 0)
        throw Error(path, "", "unknown built-in scene; the built-in scene is builtin:default");
    const std::string text = read_text_file(path);
    return parse_scene(text, path, fs::path(path).parent_path().string());
}

}  // namespace freqlab
