// Every scene in scenes/ and the built-in scene load, and what they describe is what the
// files say.
#include <gtest/gtest.h>

#include <filesystem>

#include "scene/scene_loader.h"

namespace fs = std::filesystem;
using namespace freqlab;

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
