// The stability sweep's configurations (issue "Reliability", acceptance 3; the ranges are the
// settings' declared ones in core/settings/*, the scene's in scene/scene_loader.cpp).
//
// | group       | varied                                                   | methods          |
// |-------------|----------------------------------------------------------|------------------|
// | setting     | each field: min, max, middle (full: quartiles too)        | those reading it |
// | medium      | sigma_s, sigma_a in [0, 1e6], g in (-1, 1), grid density  | bakes (impulse   |
// |             |                                                          | refuses |g|>0.95)|
// | material    | Phong exponent (0, 1e6], GGX/Beckmann roughness (0, 1]    | renders, bakes   |
// | camera      | grazing, in a surface, fov near 0 and 180, far away       | renders          |
// | geometry    | zero-area / collinear / sliver triangles, 1e-5 and 1e5    | renders, bakes   |
// | environment | NaN / Inf / negative texels (refused), black, one 1e19    | renders, bakes   |
// | scene       | no objects, no lights, lights on and parallel to surfaces | renders, bakes   |
#include "stability_cases.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "base/error.h"
#include "image/image_io.h"
#include "render/frame_renderer.h"
#include "render/method.h"
#include "settings/bake_settings.h"
#include "settings/settings_group.h"
#include "volume/bake_estimators.h"
#include "volume/impulse_response.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::vector<std::string> all_render_methods() {
    return render_method_names();
}

std::vector<std::string> all_bake_methods() {
    std::vector<std::string> names;
    for (const auto& n : kBakeMethodNames) names.push_back(n.name);
    return names;
}

std::string number_text(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

// The values a field is swept over: its minimum, maximum and points between (geometric
// when the range spans decades and starts above 0).
std::vector<double> sweep_values(const SettingField& f, bool full) {
    if (f.type == SettingType::Bool || f.type == SettingType::Choice) {
        std::vector<double> v;
        for (double x = f.min; x <= f.max; x += 1) v.push_back(x);
        return v;
    }
    const bool geometric = f.min > 0 && f.max / f.min >= 100;
    std::vector<double> fractions =
        full ? std::vector<double>{0, 0.25, 0.5, 0.75, 1} : std::vector<double>{0, 0.5, 1};
    std::vector<double> v;
    for (double q : fractions) {
        double x = geometric ? f.min * std::pow(f.max / f.min, q) : f.min + q * (f.max - f.min);
        if (f.type == SettingType::Int) x = std::round(x);
        if (v.empty() || x != v.back()) v.push_back(x);
    }
    return v;
}

std::string value_text(const SettingField& f, double v) {
    if (f.type == SettingType::Choice) return f.choices.at(size_t(v));
    if (f.type == SettingType::Bool) return v != 0 ? "true" : "false";
    if (f.type == SettingType::Int) return std::to_string((long long)v);
    return number_text(v);
}

// Sample counts this large are affordable only at one pixel / the smallest atlas.
bool is_large_sample_count(const SettingField& f, double v) {
    return f.unit.find("samples") != std::string::npos && v > 4096;
}

void add_setting_cases(std::vector<StabilityCase>& out, bool full) {
    RenderConfig config;
    const SettingsGroup render_group = config.settings_group();
    for (const SettingsGroup::Binding& b : render_group.bindings()) {
        std::vector<std::string> methods;
        for (const std::string& name : render_method_names()) {
            const auto& groups = render_method_info(parse_render_method(name)).setting_groups;
            if (std::find(groups.begin(), groups.end(), b.schema->prefix()) != groups.end())
                methods.push_back(name);
        }
        for (const SettingField& f : b.schema->fields()) {
            for (double v : sweep_values(f, full)) {
                StabilityCase c;
                c.group = "setting";
                c.name = b.schema->prefix() + "." + f.key + "=" + value_text(f, v);
                c.scene = stability_base_scene();
                c.render_methods = methods;
                if (is_large_sample_count(f, v)) {
                    if (!full && v > (1 << 16)) continue;
                    c.sets = {"frame.width=1", "frame.height=1"};
                }
                // A wide or tall frame keeps the other side at one pixel.
                if (f.key == "width" && v > 64) c.sets.push_back("frame.height=1");
                if (f.key == "height" && v > 64) c.sets.push_back("frame.width=1");
                c.sets.push_back(c.name);
                out.push_back(std::move(c));
            }
        }
    }
    const SettingsSchema& bake = BakeSettings::schema();
    for (const SettingField& f : bake.fields()) {
        for (double v : sweep_values(f, full)) {
            StabilityCase c;
            c.group = "setting";
            c.name = bake.prefix() + "." + f.key + "=" + value_text(f, v);
            c.scene = stability_base_scene();
            c.bake_methods = all_bake_methods();
            if (is_large_sample_count(f, v)) {
                if (!full && v > (1 << 12)) continue;
                // One small quad: a handful of texels, no probes.
                c.scene["objects"] = json::array({c.scene["objects"][0]});
                c.scene["objects"][0]["shape"]["size"] = {0.25, 0.25};
                c.sets = {"bake.probes_x=0"};
            }
            c.sets.push_back(c.name);
            out.push_back(std::move(c));
        }
    }
}

StabilityCase scene_case(const std::string& group, const std::string& name, json scene,
                         bool renders, bool bakes) {
    StabilityCase c;
    c.group = group;
    c.name = name;
    c.scene = std::move(scene);
    if (renders) c.render_methods = all_render_methods();
    if (bakes) c.bake_methods = all_bake_methods();
    return c;
}

void add_medium_cases(std::vector<StabilityCase>& out, bool full) {
    const std::vector<double> sigmas = {0, 1e-6, 1e-2, 1, 1e2, 1e4, 1e6};
    const std::vector<double> absorptions =
        full ? std::vector<double>{0, 1e-6, 1, 1e4, 1e6} : std::vector<double>{0.1};
    const std::vector<double> gs = {-0.999, -0.99, -0.5, 0, 0.5, 0.99, 0.999};
    auto with_medium = [](double ss, double sa, double g, bool grid) {
        json s = stability_base_scene();
        json& m = s["media"][grid ? 1 : 0];
        m["sigma_s"] = ss;
        m["sigma_a"] = sa;
        m["g"] = g;
        return s;
    };
    for (bool grid : {false, true})
        for (double ss : sigmas)
            for (double sa : absorptions)
                for (double g : gs) {
                    if (!full && grid && g != gs.front() && g != gs.back() && g != 0) continue;
                    StabilityCase c = scene_case(
                        "medium",
                        std::string(grid ? "grid" : "homogeneous") + " sigma_s=" + number_text(ss) +
                            " sigma_a=" + number_text(sa) + " g=" + number_text(g),
                        with_medium(ss, sa, g, grid), false, true);
                    // Method B's tables stop at |g| = kGRange (volume/impulse_response.h); the
                    // other bakers take any g the scene format allows.
                    if (std::abs(g) > kGRange)
                        c.method_refusals["impulse"] =
                            "media[" + std::to_string(grid ? 1 : 0) + "].g";
                    out.push_back(std::move(c));
                }
    for (double sa : {0.0, 1e-6, 1.0, 1e4, 1e6})
        if (!full)
            out.push_back(scene_case("medium",
                                     "homogeneous sigma_s=1 g=0 sigma_a=" + number_text(sa),
                                     with_medium(1, sa, 0, false), false, true));
    for (double scale : {0.0, 1e-3, 1e3}) {
        json s = stability_base_scene();
        s["media"][1]["density_scale"] = scale;
        out.push_back(
            scene_case("medium", "grid density_scale=" + number_text(scale), s, false, true));
    }
    json sparse_grid = stability_base_scene();
    sparse_grid["media"][1]["density"]["threshold"] = 0.99;  // nearly every voxel 0
    out.push_back(scene_case("medium", "grid at threshold 0.99", sparse_grid, false, true));
    json thin = stability_base_scene();  // a medium box of zero thickness
    thin["media"][0]["bounds"]["box"] = {{"min", {-1, -1, 0.5}}, {"max", {1, 1, 0.5}}};
    StabilityCase flat =
        scene_case("medium", "homogeneous box of zero thickness", thin, false, true);
    flat.expect_refusal = true;
    flat.refusal_contains = "max > min";
    out.push_back(std::move(flat));
    json slab = stability_base_scene();  // a medium box 1e-6 thick
    slab["media"][0]["bounds"]["box"] = {{"min", {-1, -1, 0.5}}, {"max", {1, 1, 0.500001}}};
    out.push_back(scene_case("medium", "homogeneous box 1e-6 thick", slab, false, true));
}

void add_material_cases(std::vector<StabilityCase>& out) {
    for (double e : {1e-6, 1.0, 10.0, 1e3, 1e5, 1e6}) {
        json s = stability_base_scene();
        s["materials"]["shiny"]["exponent"] = e;
        s["materials"]["white"] = s["materials"]["shiny"];
        out.push_back(scene_case("material", "phong exponent=" + number_text(e), s, true, true));
    }
    for (const char* type : {"ggx", "beckmann"})
        for (double r : {1e-6, 1e-3, 0.5, 1.0}) {
            json s = stability_base_scene();
            s["materials"]["white"] = {{"type", type}, {"roughness", r}, {"albedo", 0.8}};
            out.push_back(scene_case("material", std::string(type) + " roughness=" + number_text(r),
                                     s, true, true));
        }
    for (double a : {0.0, 1.0}) {
        json s = stability_base_scene();
        for (auto& [name, m] : s["materials"].items()) m["albedo"] = a;
        out.push_back(scene_case("material", "every albedo=" + number_text(a), s, true, true));
    }
}

void add_camera_cases(std::vector<StabilityCase>& out) {
    auto with_camera = [](json camera) {
        json s = stability_base_scene();
        s["camera"] = std::move(camera);
        return s;
    };
    const std::vector<std::pair<std::string, json>> cameras = {
        {"grazing at 1e-3 above the floor",
         {{"position", {0, -3, 1e-3}}, {"look_at", {0, 0, 1e-3}}, {"fov", 50}}},
        {"in the floor's plane", {{"position", {0, -3, 0}}, {"look_at", {0, 0, 0}}, {"fov", 50}}},
        {"at 89.9 deg to the floor",
         {{"position", {0, -3, 0.005}}, {"look_at", {0, 0, 0}}, {"fov", 10}}},
        {"1e-4 above the floor looking down",
         {{"position", {0.1, 0.1, 1e-4}},
          {"look_at", {0.1, 0.1, -1}},
          {"up", {0, 1, 0}},
          {"fov", 50}}},
        {"fov 1e-3", {{"position", {0, -3, 1}}, {"look_at", {0, 0, 0.3}}, {"fov", 1e-3}}},
        {"fov 179.9", {{"position", {0, -3, 1}}, {"look_at", {0, 0, 0.3}}, {"fov", 179.9}}},
        {"inside the box", {{"position", {0.6, 0.3, 0.3}}, {"look_at", {0, 0, 0.3}}, {"fov", 50}}},
        {"1e6 away", {{"position", {0, -1e6, 1e5}}, {"look_at", {0, 0, 0}}, {"fov", 1e-2}}},
    };
    for (const auto& [name, camera] : cameras)
        out.push_back(scene_case("camera", name, with_camera(camera), true, false));
}

void write_obj(const fs::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

void add_geometry_cases(std::vector<StabilityCase>& out, const fs::path& dir) {
    // Zero-area (repeated vertex, collinear) triangles beside a sliver 1e-6 of the extent wide
    // and a needle: the loader drops the first two, the renderers must survive the others.
    write_obj(dir / "degenerate.obj",
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 0.5 1e-6 0\nv 0 0 1\nv 0 1e-7 1\n"
              "v 1e-7 0 2\nf 1 2 3\nf 1 1 2\nf 1 2 4\nf 1 4 5\nf 1 6 7\nf 6 7 8\n");
    auto with_object = [](json object) {
        json s = stability_base_scene();
        s["objects"].push_back(std::move(object));
        return s;
    };
    StabilityCase degenerate =
        scene_case("geometry", "zero-area, collinear, sliver and needle triangles",
                   with_object({{"name", "degenerate"},
                                {"mesh", "degenerate.obj"},
                                {"material", "white"},
                                {"transform", {{"translate", {-0.5, -0.5, 0.01}}}}}),
                   true, true);
    degenerate.note_contains = "'degenerate': 2 zero-area or out-of-range triangles dropped";
    out.push_back(std::move(degenerate));
    out.push_back(
        scene_case("geometry", "a box 1e-5 wide",
                   with_object({{"name", "speck"},
                                {"shape", {{"type", "box"}, {"size", {1e-5, 1e-5, 1e-5}}}},
                                {"material", "white"},
                                {"transform", {{"translate", {0, -1, 0.5}}}}}),
                   true, true));
    json huge = stability_base_scene();
    huge["objects"][0]["shape"]["size"] = {1e5, 1e5};
    out.push_back(scene_case("geometry", "a floor 1e5 wide", huge, true, true));
    out.push_back(scene_case("geometry", "a second floor coincident with the first",
                             with_object({{"name", "floor2"},
                                          {"shape", {{"type", "plane"}, {"size", {4, 4}}}},
                                          {"material", "shiny"}}),
                             true, true));
}

void write_env(const fs::path& path, int w, int h, float fill, int texel, float value) {
    LayerSet set(w, h);
    Layer& c = set.add("color", LayerKind::Color, 3);
    std::fill(c.data.begin(), c.data.end(), fill);
    for (int ch = 0; ch < 3; ++ch) c.data[size_t(texel) * 3 + ch] = value;
    write_exr(path, set);
}

void add_environment_cases(std::vector<StabilityCase>& out, const fs::path& dir) {
    auto with_env = [](json env) {
        json s = stability_base_scene();
        s["lights"][0] = std::move(env);
        return s;
    };
    const int w = 16, h = 8, texel = 3 * 16 + 5;
    struct Damaged {
        const char* file;
        float value;
        const char* says;
    };
    for (const Damaged& d :
         {Damaged{"env_nan.exr", NAN, "non-finite"}, Damaged{"env_inf.exr", INFINITY, "non-finite"},
          Damaged{"env_neginf.exr", -INFINITY, "non-finite"}}) {
        write_env(dir / d.file, w, h, 0.5f, texel, d.value);
        StabilityCase c = scene_case("environment", std::string("texel ") + d.file,
                                     with_env({{"type", "envmap"}, {"file", d.file}}), true, true);
        c.expect_refusal = true;
        c.refusal_contains = d.says;
        out.push_back(std::move(c));
    }
    // Negative texels (real maps have them: Blender's city.exr) are read as 0 and reported.
    write_env(dir / "env_negative.exr", w, h, 0.5f, texel, -0.5f);
    StabilityCase negative =
        scene_case("environment", "texel env_negative.exr",
                   with_env({{"type", "envmap"}, {"file", "env_negative.exr"}}), true, true);
    negative.note_contains = "1 texels with negative radiance (down to -0.5) read as 0";
    out.push_back(std::move(negative));
    write_env(dir / "env_black.exr", w, h, 0.0f, 0, 0.0f);
    write_env(dir / "env_spike.exr", w, h, 0.0f, texel, 1e19f);
    write_env(dir / "env_dim.exr", w, h, 1e-30f, texel, 1e10f);
    write_env(dir / "env_2x1.exr", 2, 1, 0.7f, 0, 0.7f);
    for (const char* file : {"env_black.exr", "env_spike.exr", "env_dim.exr", "env_2x1.exr"})
        out.push_back(scene_case("environment", file,
                                 with_env({{"type", "envmap"}, {"file", file}}), true, true));
    out.push_back(scene_case("environment", "scale 0",
                             with_env({{"type", "envmap"}, {"radiance", 1.0}, {"scale", 0.0}}),
                             true, true));
    out.push_back(scene_case("environment", "spinning 1e6 deg/s",
                             with_env({{"type", "envmap"},
                                       {"radiance", {0.3, 0.5, 0.9}},
                                       {"rotation_deg", 1e6},
                                       {"rotation_deg_per_s", 1e6}}),
                             true, true));
    out.push_back(scene_case("environment", "sky, sun at the horizon",
                             with_env({{"type", "sky"},
                                       {"sun_direction", {1, 0, 0}},
                                       {"sun_radius_deg", 0.01},
                                       {"resolution", 8}}),
                             true, true));
}

void add_scene_cases(std::vector<StabilityCase>& out) {
    json empty = stability_base_scene();
    empty["objects"] = json::array();
    out.push_back(scene_case("scene", "no objects", empty, true, true));
    json dark = stability_base_scene();
    dark["lights"] = json::array();
    out.push_back(scene_case("scene", "no lights", dark, true, true));
    json nothing = empty;
    nothing["lights"] = json::array();
    nothing["media"] = json::array();
    out.push_back(scene_case("scene", "no objects, lights or media", nothing, true, true));
    auto with_light = [](json light) {
        json s = stability_base_scene();
        s["lights"] = json::array({std::move(light)});
        return s;
    };
    out.push_back(
        scene_case("scene", "point light on the floor",
                   with_light({{"type", "point"}, {"position", {0.3, -0.2, 0}}, {"intensity", 3}}),
                   false, true));
    out.push_back(scene_case(
        "scene", "point light inside the grid medium",
        with_light({{"type", "point"}, {"position", {-0.5, 0.5, 0.6}}, {"intensity", 3}}), false,
        true));
    out.push_back(
        scene_case("scene", "point light of intensity 1e15",
                   with_light({{"type", "point"}, {"position", {0, 0, 1.5}}, {"intensity", 1e15}}),
                   false, true));
    out.push_back(scene_case(
        "scene", "sun parallel to the floor",
        with_light({{"type", "directional"}, {"direction", {1, 0, 0}}, {"irradiance", 2}}), false,
        true));
    out.push_back(scene_case("scene", "quad light 1e-5 wide on the ceiling of the medium",
                             with_light({{"type", "quad"},
                                         {"corner", {0, 0, 1.2}},
                                         {"edge_u", {1e-5, 0, 0}},
                                         {"edge_v", {0, 1e-5, 0}},
                                         {"radiance", 1e6}}),
                             false, true));
}

}  // namespace

json stability_base_scene() {
    return json::parse(R"({
  "name": "stability", "fps": 24, "frames": 2,
  "camera": {"position": [0.4, -3.2, 1.4], "look_at": [0, 0, 0.4], "fov": 50},
  "materials": {
    "white": {"type": "lambert", "albedo": 0.7},
    "shiny": {"type": "phong", "exponent": 60, "albedo": [0.6, 0.5, 0.3]},
    "chrome": {"type": "mirror", "albedo": 0.9}
  },
  "objects": [
    {"name": "floor", "shape": {"type": "plane", "size": [4, 4]}, "material": "white"},
    {"name": "box", "shape": {"type": "box", "size": [0.6, 0.6, 0.6]}, "material": "shiny",
     "transform": {"translate": [0.5, 0.2, 0.3]},
     "animation": {"spin_axis": [0, 0, 1], "spin_deg_per_s": 90}},
    {"name": "ball", "shape": {"type": "sphere", "radius": 0.3}, "material": "chrome",
     "transform": {"translate": [-0.6, -0.2, 0.3]}}
  ],
  "lights": [
    {"type": "envmap", "radiance": [0.3, 0.4, 0.6]},
    {"type": "point", "position": [0.3, -0.6, 1.6], "intensity": 3},
    {"type": "directional", "direction": [-0.3, 0.4, -1], "irradiance": 1.5},
    {"type": "quad", "corner": [-0.3, -0.3, 1.9], "edge_u": [0.6, 0, 0], "edge_v": [0, 0.6, 0],
     "radiance": 4}
  ],
  "media": [
    {"name": "haze", "sigma_s": 0.3, "sigma_a": 0.05, "g": 0.3,
     "bounds": {"box": {"min": [-2, -2, 0], "max": [2, 2, 2]}}},
    {"name": "smoke", "sigma_s": 3.0, "sigma_a": 0.3, "g": -0.2,
     "bounds": {"box": {"min": [-0.9, 0.0, 0.0], "max": [-0.1, 0.8, 0.9]}},
     "density": {"source": "noise", "resolution": [8, 8, 8], "frequency": 1.6, "octaves": 2,
                 "threshold": 0.4, "seed": 3}}
  ]
})");
}

std::vector<std::string> stability_base_render_sets() {
    return {"frame.width=8",
            "frame.height=6",
            "mis.spp=4",
            "reference.spp=8",
            "reference.use_cache=false",
            "points.max_samples=64"};
}

std::vector<std::string> stability_base_bake_sets() {
    return {"bake.spp=2",      "bake.texel_density=2", "bake.max_size=64",
            "bake.probes_x=2", "bake.probes_y=2",      "bake.probes_z=2"};
}

std::vector<StabilityCase> stability_cases(const fs::path& asset_dir, bool full) {
    std::vector<StabilityCase> out;
    add_setting_cases(out, full);
    add_medium_cases(out, full);
    add_material_cases(out);
    add_camera_cases(out);
    add_geometry_cases(out, asset_dir);
    add_environment_cases(out, asset_dir);
    add_scene_cases(out);
    return out;
}

}  // namespace freqlab
