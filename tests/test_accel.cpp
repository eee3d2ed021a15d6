// Embree scene: exact sphere distances, world-space normals through instances, and objects
// that move with update(time) without rebuilding their own BVH.
#include <gtest/gtest.h>

#include "accel/ray_scene.h"
#include "scene/scene_loader.h"

using namespace freqlab;

namespace {

Scene test_scene() {
    return parse_scene(R"({
      "camera": {"position": [0, -5, 1], "look_at": [0, 0, 0]},
      "objects": [
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.5}, "material": {"type": "lambert"},
         "transform": {"translate": [0, 0, 2], "scale": 2}},
        {"name": "slider", "shape": {"type": "box", "size": [1, 1, 1]}, "material": {"type": "lambert"},
         "animation": {"keyframes": [{"t": 0, "translate": [5, 0, 0]}, {"t": 1, "translate": [10, 0, 0]}]}},
        {"name": "tilted", "shape": {"type": "plane", "size": [2, 2]}, "material": {"type": "lambert"},
         "transform": {"translate": [0, 0, -3], "rotate": {"axis": [1, 0, 0], "deg": 45}, "scale": [1, 3, 1]}}
      ]
    })",
                       "inline", "");
}

}  // namespace

TEST(Accel, SphereDistanceIsExact) {
    const Scene scene = test_scene();
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    // Scaled sphere: radius 0.5 * 2 = 1 centred at (0, 0, 2). From (0, -5, 2) along +y.
    const SurfaceHit h = rs.intersect(Ray{vec3(0, -5, 2), vec3(0, 1, 0)});
    ASSERT_TRUE(h.valid);
    EXPECT_EQ(h.object, 0);
    EXPECT_NEAR(h.distance, 4.0f, 1e-5f);
    EXPECT_NEAR(h.geometric_normal.y, -1.0f, 1e-5f);
    // Oblique: ray at height z = 2.6 hits where y = -sqrt(1 - 0.36) = -0.8.
    const SurfaceHit o = rs.intersect(Ray{vec3(0, -5, 2.6f), vec3(0, 1, 0)});
    ASSERT_TRUE(o.valid);
    EXPECT_NEAR(o.distance, 5.0f - 0.8f, 1e-5f);
    EXPECT_NEAR(glm::dot(o.geometric_normal, glm::normalize(vec3(0, -0.8f, 0.6f))), 1.0f, 1e-5f);
}

TEST(Accel, NormalsUseTheInverseTransposeUnderNonUniformScale) {
    const Scene scene = test_scene();
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    // Plane rotated 45 deg about x: its normal is (0, -sin45, cos45) whatever the y scale.
    const SurfaceHit h = rs.intersect(Ray{vec3(0, 0, 0), vec3(0, 0, -1)});
    ASSERT_TRUE(h.valid);
    EXPECT_EQ(h.object, 2);
    EXPECT_NEAR(std::fabs(h.geometric_normal.y), std::sqrt(0.5f), 1e-5f);
    EXPECT_NEAR(std::fabs(h.geometric_normal.z), std::sqrt(0.5f), 1e-5f);
    EXPECT_GT(h.geometric_normal.z, 0.0f);  // faces the ray that came from above
}

// Both normals face the ray; back_face says when that flipped the winding's (the sphere's
// inside, the plane's underside: its normal is +z before the rotation).
TEST(Accel, BackFaceHitsAreFlagged) {
    const Scene scene = test_scene();
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    const SurfaceHit outside = rs.intersect(Ray{vec3(0, -5, 2), vec3(0, 1, 0)});
    const SurfaceHit inside = rs.intersect(Ray{vec3(0, 0, 2), vec3(0, 1, 0)});
    ASSERT_TRUE(outside.valid && inside.valid);
    EXPECT_FALSE(outside.back_face);
    EXPECT_TRUE(inside.back_face);
    EXPECT_LT(glm::dot(inside.geometric_normal, vec3(0, 1, 0)), 0.0f);
    const SurfaceHit above = rs.intersect(Ray{vec3(0, 0, 0), vec3(0, 0, -1)});
    const SurfaceHit below = rs.intersect(Ray{vec3(0, 0, -6), vec3(0, 0, 1)});
    ASSERT_TRUE(above.valid && below.valid);
    EXPECT_EQ(below.object, 2);
    EXPECT_FALSE(above.back_face);
    EXPECT_TRUE(below.back_face);
    EXPECT_LT(below.geometric_normal.z, 0.0f);
}

TEST(Accel, UpdateMovesAnimatedObjects) {
    const Scene scene = test_scene();
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    const Ray probe{vec3(7.5f, -5, 0), vec3(0, 1, 0)};
    EXPECT_FALSE(rs.intersect(probe).valid);  // t = 0: box spans x in [4.5, 5.5]
    rs.update(0.5f);                          // box at x = 7.5
    const SurfaceHit h = rs.intersect(probe);
    ASSERT_TRUE(h.valid);
    EXPECT_EQ(h.object, 1);
    EXPECT_NEAR(h.distance, 4.5f, 1e-5f);
    EXPECT_TRUE(rs.occluded(Ray{vec3(7.5f, -5, 0), vec3(0, 1, 0), 0.0f, 10.0f}));
    EXPECT_FALSE(rs.occluded(Ray{vec3(7.5f, -5, 0), vec3(0, 1, 0), 0.0f, 4.0f}));
}

TEST(Accel, PacketsAgreeWithSingleRays) {
    const Scene scene = load_scene("builtin:default");
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    rs.update(0.3f);
    Ray rays[8];
    bool active[8];
    SurfaceHit hits[8];
    const CameraRayGenerator cam(scene.camera.at(0.3f), 64, 64);
    for (int i = 0; i < 8; ++i) {
        rays[i] = Ray{cam.origin, cam.direction(0.1f + 0.1f * i, 0.3f + 0.05f * i)};
        active[i] = i != 3;
    }
    rs.intersect8(rays, active, hits);
    for (int i = 0; i < 8; ++i) {
        const SurfaceHit s = rs.intersect(rays[i]);
        if (!active[i]) {
            EXPECT_FALSE(hits[i].valid);
            continue;
        }
        EXPECT_EQ(hits[i].valid, s.valid);
        EXPECT_EQ(hits[i].object, s.object);
        EXPECT_FLOAT_EQ(hits[i].distance, s.distance);
    }
}
