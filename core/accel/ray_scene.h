// Embree for freqlab: one device per process (thread count capped there), one instance per
// scene object in a top-level scene. update(time) moves the instances of animated objects and
// recommits only the top level; object BVHs are built once.
//
// Hit data comes back in world space: Embree reports Ng in the instanced object's space, so
// normals are carried through the inverse transpose of the instance transform here, once.
#pragma once

#include <embree3/rtcore.h>

#include <cmath>
#include <memory>
#include <vector>

#include "math/types.h"
#include "scene/scene.h"

namespace freqlab {

class EmbreeDevice {
  public:
    explicit EmbreeDevice(int threads = 0);  // 0: Embree's default (all cores)
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;
    RTCDevice handle() const { return device_; }

  private:
    RTCDevice device_;
};

struct SurfaceHit {
    bool valid = false;
    float distance = 0.0f;
    int object = -1;  // index into Scene::objects
    int primitive = -1;
    int material = -1;  // index into Scene::materials (sub-mesh materials resolved)
    vec3 position{0.0f};
    vec3 geometric_normal{0.0f};  // world, unit, facing the incoming ray
    vec3 shading_normal{0.0f};    // world, unit, same hemisphere as geometric_normal
    vec2 uv{0.0f};
    // The ray met the triangle's back (its winding's normal faced away; both normals above
    // were flipped): the side a lightmap texel does not describe (lightmap_atlas.h).
    bool back_face = false;
};

struct Ray {
    vec3 origin;
    vec3 direction;  // unit
    float tnear = 0.0f;
    float tfar = INFINITY;
};

// The one ray-offset rule (method A, the bakers, VPT, the key-light and shadow masks): a ray
// leaving the surface point p (normal n, on the side the ray leaves) starts at p moved off the
// surface by epsilon x max(1, |p|_inf), relative so that float rounding of the hit position
// (~1e-7 |p|) never puts it back behind the surface. Method A reads epsilon from
// shading.ray_epsilon (default kRayEpsilon); everything else uses kRayEpsilon.
constexpr float kRayEpsilon = 1e-4f;
inline vec3 spawn_point(const vec3& p, const vec3& n, float epsilon = kRayEpsilon) {
    const float scale =
        std::max(1.0f, std::max(std::abs(p.x), std::max(std::abs(p.y), std::abs(p.z))));
    return p + n * (epsilon * scale);
}
// A shadow ray from `origin` along unit `direction` to a point `distance` away, stopping
// kShadowRayShortening of the way short so the light's own surface (a quad, a surface vertex)
// does not occlude it; an infinite distance (a distant light) is unbounded.
constexpr float kShadowRayShortening = 1e-4f;
inline Ray shadow_ray(const vec3& origin, const vec3& direction, double distance) {
    return Ray{
        origin, direction, 0.0f,
        std::isfinite(distance) ? float(distance) * (1.0f - kShadowRayShortening) : INFINITY};
}

class RayScene {
  public:
    RayScene(const Scene& scene, const EmbreeDevice& device);
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    // Places every object at `time` (seconds). Static objects are placed once; the top level
    // is recommitted only when something moved.
    void update(float time);
    float time() const { return time_; }

    SurfaceHit intersect(const Ray& ray) const;
    // Eight rays at once (an RTCRayHit8 packet); `active[i]` false skips lane i.
    void intersect8(const Ray* rays, const bool* active, SurfaceHit* hits) const;
    bool occluded(const Ray& ray) const;
    // Many incoherent shadow rays in one rtcOccluded1M stream (~2x single rays, PLATFORM.md).
    void occluded_stream(const Ray* rays, int count, bool* occluded) const;

    const mat4& object_to_world(int object) const { return to_world_[object]; }
    // The scene's environment as it stands at time() (turned when it spins); null without one.
    const EnvironmentMap* environment() const {
        return environment_now_ ? environment_now_.get() : scene_.environment();
    }
    // Radiance seen along `direction` when nothing is hit (the environment at time()).
    vec3 background(const vec3& direction) const;
    vec3 bounds_min() const { return bounds_min_; }
    vec3 bounds_max() const { return bounds_max_; }
    const Scene& scene() const { return scene_; }
    RTCScene top_scene() const { return top_; }  // for benchmarks against bare Embree

  private:
    SurfaceHit make_hit(const Ray& ray, float t, unsigned inst, unsigned prim, vec3 ng_object,
                        float u, float v) const;
    void place(int object, float time);

    const Scene& scene_;
    RTCDevice device_;
    RTCScene top_ = nullptr;
    // One object's geometry in a committed scene of its own (instanced in top_).
    RTCScene build_object_scene(const SceneObject& obj) const;
    std::vector<RTCScene> object_scenes_;
    std::vector<RTCGeometry> instances_;
    std::vector<mat4> to_world_, normal_to_world_, to_object_;
    float time_ = -1.0f;
    bool committed_ = false;
    vec3 bounds_min_{0.0f}, bounds_max_{0.0f};
    std::shared_ptr<const EnvironmentMap> environment_now_;  // set when the environment spins
};

}  // namespace freqlab
