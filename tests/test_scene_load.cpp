// Every scene in scenes/ and the built-in scene load, and what they describe is what the
// files say.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "accel/ray_scene.h"
#include "image/image_io.h"
#include "render/frame_renderer.h"
#include "scene/scene_loader.h"
#include "volume/lightmap_baker.h"
#include "volume/media.h"

namespace fs = std::filesystem;
using namespace freqlab;

namespace {

// The unit normal of triangle t, by its winding.
vec3 face_normal(const TriangleMesh& m, const uvec3& t) {
    return glm::normalize(
        glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]));
}

}  // namespace

TEST(SceneLoad, EveryFileInScenesLoads) {
    int count = 0;
    for (const auto& entry :
         fs::recursive_directory_iterator(fs::path(FREQLAB_SOURCE_DIR) / "scenes")) {
        if (entry.path().extension() != ".json") continue;
        SCOPED_TRACE(entry.path().string());
        Scene s;
        ASSERT_NO_THROW(s = load_scene(entry.path().string()));
        EXPECT_GT(s.objects.size(), 0u);
        EXPECT_GE(s.frame_count, 1);
        for (const SceneObject& o : s.objects) {
            ASSERT_LT(o.material, int(s.materials.size()));
            if (o.shape == ShapeKind::Mesh) {
                EXPECT_GT(o.mesh->triangles.size(), 0u);
            }
        }
        ++count;
    }
    EXPECT_GE(count, 1);
}

TEST(SceneLoad, BuiltinDefault) {
    const Scene s = load_scene("builtin:default");
    EXPECT_EQ(s.name, "builtin:default");
    EXPECT_EQ(s.objects.size(), 5u);
    EXPECT_FALSE(s.is_static());  // the torus moves
    ASSERT_EQ(s.lights.size(), 1u);
    EXPECT_EQ(s.lights[0].type, LightType::Sky);
    EXPECT_EQ(s.objects[1].shape, ShapeKind::Sphere);
}

TEST(SceneLoad, KeyframesInterpolateAndClamp) {
    const Scene s = parse_scene(R"({
      "camera": {"position": [0, -5, 1], "look_at": [0, 0, 0]},
      "objects": [{"shape": {"type": "box"}, "material": {"type": "lambert"},
        "animation": {"keyframes": [{"t": 0, "translate": [0, 0, 0]}, {"t": 2, "translate": [4, 0, 0]}]}}]
    })",
                                "inline", "");
    const Animation& a = s.objects[0].animation;
    EXPECT_FLOAT_EQ(a.at(1.0f)[3][0], 2.0f);
    EXPECT_FLOAT_EQ(a.at(-1.0f)[3][0], 0.0f);
    EXPECT_FLOAT_EQ(a.at(5.0f)[3][0], 4.0f);
}

TEST(SceneLoad, SpinTurnsAtItsRate) {
    const Scene s = parse_scene(R"({
      "camera": {"position": [0, -5, 1], "look_at": [0, 0, 0]},
      "objects": [{"shape": {"type": "box"}, "material": {"type": "lambert"},
        "animation": {"spin_axis": [0, 0, 1], "spin_deg_per_s": 90}}]
    })",
                                "inline", "");
    const mat4 m = s.objects[0].animation.at(1.0f);  // 90 degrees: x axis -> y axis
    const vec4 x = m * vec4(1, 0, 0, 0);
    EXPECT_NEAR(x.x, 0.0f, 1e-6f);
    EXPECT_NEAR(x.y, 1.0f, 1e-6f);
}

TEST(SceneLoad, CameraOrbitKeepsDistance) {
    const Scene s = parse_scene(R"({
      "camera": {"position": [3, 0, 1], "look_at": [0, 0, 1], "orbit_deg_per_s": 90},
      "objects": [{"shape": {"type": "box"}, "material": {"type": "lambert"}}]
    })",
                                "inline", "");
    const CameraPose p = s.camera.at(1.0f);
    EXPECT_NEAR(p.position.x, 0.0f, 1e-5f);
    EXPECT_NEAR(p.position.y, 3.0f, 1e-5f);
    EXPECT_NEAR(p.position.z, 1.0f, 1e-6f);
}

TEST(SceneLoad, DegenerateTrianglesAreDroppedAndCounted) {
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
    m.triangles = {
        {0, 1, 2}, {0, 1, 3}, {0, 0, 2}};  // the 2nd is collinear, the 3rd repeats a vertex
    clean_mesh(m, "inline", "mesh");
    EXPECT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.degenerate_removed, 2u);
}

TEST(SceneLoad, SceneWithoutObjectsShowsItsEnvironmentAndBakesNothing) {
    const Scene scene = parse_scene(
        R"({"camera": {"position": [0, -3, 1], "look_at": [0, 0, 1], "fov": 50}, "objects": [],
            "lights": [{"type": "envmap", "radiance": [0.25, 0.5, 0.75]}]})",
        "empty.json", "");
    EmbreeDevice device(1);
    RenderConfig config;
    config.method = RenderMethod::Mis;
    config.frame.width = 4;
    config.frame.height = 3;
    FrameRenderer renderer(scene, config, device);
    Progress progress;
    const FrameResult r = renderer.render(0, progress);
    const Layer& color = r.layers.get("color");
    for (size_t i = 0; i < color.data.size(); ++i)
        EXPECT_FLOAT_EQ(color.data[i], 0.25f * float(1 + i % 3)) << "value " << i;
    EXPECT_EQ(count_nonfinite(r.layers), 0);
    RayScene rays(scene, device);
    rays.update(0.0f);
    const Media media;
    LightmapBaker baker(rays, media, nullptr, BakeMethod::Surface, BakeSettings{});
    baker.run();
    EXPECT_TRUE(baker.lightmaps().empty());
    // No geometry, no bounds to lay probes over: none, and the grid says so.
    EXPECT_TRUE(baker.probes().empty());
    EXPECT_EQ(baker.probes_json()["grid"], nlohmann::json({0, 0, 0}));
}

TEST(SceneLoad, LoadNotesNameWhatTheLoaderChanged) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_load_notes";
    fs::create_directories(dir);
    std::ofstream(dir / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n";
    LayerSet env(4, 2);
    Layer& c = env.add("color", LayerKind::Color, 3);
    std::fill(c.data.begin(), c.data.end(), 1.0f);
    c.data[3 * 5 + 1] = -0.25f;  // pixel (1, 1), green
    write_exr(dir / "env.exr", env);
    const Scene scene = parse_scene(
        R"({"camera": {"position": [0, -3, 1], "look_at": [0, 0, 1], "fov": 50},
            "objects": [{"name": "tri", "mesh": "tri.obj", "material": {"type": "lambert"}}],
            "lights": [{"type": "envmap", "file": "env.exr"}]})",
        "notes.json", dir.string());
    ASSERT_EQ(scene.load_notes.size(), 2u);
    EXPECT_EQ(scene.load_notes[0],
              "objects[0] 'tri': 1 zero-area or out-of-range triangles dropped");
    EXPECT_EQ(
        scene.load_notes[1],
        "lights[0].file 'env.exr': 1 texels with negative radiance (down to -0.25) read as 0");
    const EnvironmentMap& map = *scene.environment();
    EXPECT_EQ(map.negative_texels(), 1);
    // The texel is read as 0 in that channel, its others kept.
    const vec3 d = map.uv_to_direction(vec2(1.5f / 4, 1.5f / 2));
    EXPECT_EQ(map.eval(d), vec3(1.0f, 0.0f, 1.0f));
}

// Terrain (scene/mesh.h): heights within +-height, and the analytic vertex normals agree with
// the faces they border: on a grid of ~24 cells per wavelength of the finest octave the face
// normals turn by < 3.6 degrees within a cell (the error shrinks with the cell: 9.6 degrees at a
// quarter of this resolution).
TEST(SceneLoad, TerrainNormalsAreThoseOfItsSurface) {
    TerrainShape t;
    t.size = vec2(40.0f, 30.0f);
    t.cells = ivec2(640, 480);
    t.height = 3.0f;
    t.frequency = 0.08;
    const TriangleMesh m = make_terrain(t);
    ASSERT_EQ(m.triangles.size(), size_t(2 * 640 * 480));
    ASSERT_EQ(m.normals.size(), m.positions.size());
    float lo = 1e9f, hi = -1e9f;
    for (const vec3& p : m.positions) {
        lo = std::min(lo, p.z);
        hi = std::max(hi, p.z);
    }
    EXPECT_GE(lo, -3.0f);
    EXPECT_LE(hi, 3.0f);
    EXPECT_GT(hi - lo, 1.0f);  // not flat
    double worst = 1.0;
    for (const uvec3& tri : m.triangles) {
        const vec3 n = face_normal(m, tri);
        for (int k = 0; k < 3; ++k) worst = std::min(worst, double(glm::dot(n, m.normals[tri[k]])));
    }
    EXPECT_GT(worst, 0.998);
}

// A terrain's skirt (TerrainShape::skirt) closes the space under it at its edges: from below
// the lowest possible height every ray that does not point down meets the terrain or a skirt
// from behind (valley's low sun lit buried house slabs through the open sides); without a
// skirt the horizontal ones escape.
TEST(SceneLoad, TerrainSkirtClosesTheSpaceUnderIt) {
    for (const float skirt : {0.0f, 2.0f}) {
        const Scene s = parse_scene(
            R"({"frames": 1, "camera": {"position": [0, -50, 10], "look_at": [0, 0, 0]},
                "materials": {"m": {"type": "lambert"}},
                "objects": [{"name": "ground", "material": "m", "shape": {"type": "terrain",
                  "size": [40, 30], "cells": [40, 30], "height": 1.5, "frequency": 0.05,
                  "skirt": )" +
                std::to_string(skirt) + "}}]}",
            "s.json", "");
        const TriangleMesh& m = *s.objects[0].mesh;
        EXPECT_EQ(m.triangles.size(), size_t(2 * 40 * 30 + (skirt > 0 ? 4 * (40 + 30) : 0)));
        EmbreeDevice device(1);
        RayScene rays(s, device);
        rays.update(0.0f);
        int escaped = 0, from_behind = 0, cast = 0;
        for (int k = 0; k < 72; ++k)
            for (const float elevation : {0.0f, 0.05f, 0.3f}) {
                const float a = glm::radians(5.0f * float(k));
                const vec3 d = glm::normalize(vec3(std::cos(a), std::sin(a), elevation));
                const vec3 o(3.0f, -2.0f, -1.5f - 0.5f * std::max(skirt, 1.0f));
                const SurfaceHit h = rays.intersect(Ray{o, d, 0.0f, 1e9f});
                ++cast;
                if (!h.valid)
                    ++escaped;
                else if (h.back_face)
                    ++from_behind;
            }
        if (skirt > 0) {
            EXPECT_EQ(escaped, 0);
            EXPECT_EQ(from_behind, cast);  // the skirts face out
        } else {
            EXPECT_GT(escaped, 0);
        }
    }
}

// Normals a mesh file lacks (load_mesh_file, kGeneratedNormalMaxAngle): a cube's faces meet at
// 90 degrees and keep their own normals (assimp's default averaged its corners to the diagonal,
// as on every box of valley's IFC houses); a roof whose two faces meet at 20 degrees is smoothed
// along its ridge.
TEST(SceneLoad, GeneratedNormalsKeepSharpEdges) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_generated_normals";
    fs::create_directories(dir);
    std::ofstream(dir / "cube.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                       "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                       "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\n"
                                       "f 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    const float rise = std::tan(glm::radians(10.0f));  // each face 10 degrees off horizontal
    std::ofstream(dir / "roof.obj") << "v 0 0 0\nv 0 1 0\nv 1 0 " << rise << "\nv 1 1 " << rise
                                    << "\nv 2 0 0\nv 2 1 0\nf 1 3 4 2\nf 3 5 6 4\n";
    const TriangleMesh cube = load_mesh_file(dir / "cube.obj", "cube.obj", "mesh");
    ASSERT_EQ(cube.triangles.size(), 12u);
    for (const uvec3& t : cube.triangles)
        for (int k = 0; k < 3; ++k)
            EXPECT_GT(glm::dot(face_normal(cube, t), glm::normalize(cube.normals[t[k]])), 0.9999f);
    const TriangleMesh roof = load_mesh_file(dir / "roof.obj", "roof.obj", "mesh");
    ASSERT_EQ(roof.triangles.size(), 4u);
    int on_ridge = 0;
    for (size_t v = 0; v < roof.positions.size(); ++v) {
        if (std::abs(roof.positions[v].x - 1.0f) > 1e-6f) continue;
        ++on_ridge;
        EXPECT_GT(glm::normalize(roof.normals[v]).z, 0.9999f);  // the mean of the two faces
    }
    EXPECT_GT(on_ridge, 0);
    fs::remove_all(dir);
}

// Objects naming one mesh file share it (and the ray scene's BVH): a level instancing a house
// reads it once.
TEST(SceneLoad, ObjectsNamingOneFileShareItsMesh) {
    const Scene s =
        parse_scene(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert"}},
      "objects": [{"name": "a", "mesh": "PLY/Wuson.ply", "material": "m"},
                  {"name": "b", "mesh": "PLY/Wuson.ply", "material": "m",
                   "transform": {"translate": [3, 0, 0]}}]})",
                    "s.json", "");
    ASSERT_EQ(s.objects.size(), 2u);
    EXPECT_EQ(s.objects[0].mesh.get(), s.objects[1].mesh.get());
    EmbreeDevice device(1);
    RayScene rays(s, device);
    rays.update(0.0f);
    // Both instances are hit where they stand.
    for (int i = 0; i < 2; ++i) {
        const float x = 3.0f * float(i);
        const SurfaceHit h = rays.intersect(Ray{vec3(x, -10.0f, 0.0f), vec3(0, 1, 0), 0, 1e9f});
        ASSERT_TRUE(h.valid) << i;
        EXPECT_EQ(h.object, i);
    }
}
