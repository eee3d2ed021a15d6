#include "accel/ray_scene.h"

#include <map>

#include <algorithm>
#include <cmath>
#include <string>

#include "base/error.h"

namespace freqlab {

namespace {

// Embree may call this from its worker threads, so it only records the message; check()
// turns it into an Error on the calling thread after each build.
thread_local std::string g_last_embree_message;
void embree_error(void*, RTCError code, const char* message) {
    if (code != RTC_ERROR_NONE) g_last_embree_message = message ? message : "unknown error";
}

void check(RTCDevice device, const char* what) {
    const RTCError code = rtcGetDeviceError(device);
    if (code != RTC_ERROR_NONE)
        throw Error("embree", what,
                    "error " + std::to_string(int(code)) + " " + g_last_embree_message);
}

RTCRay to_rtc_ray(const Ray& ray, unsigned id) {
    RTCRay r;
    r.org_x = ray.origin.x, r.org_y = ray.origin.y, r.org_z = ray.origin.z;
    r.dir_x = ray.direction.x, r.dir_y = ray.direction.y, r.dir_z = ray.direction.z;
    r.tnear = ray.tnear;
    r.tfar = ray.tfar;
    r.time = 0.0f;
    r.mask = ~0u;
    r.id = id;
    r.flags = 0;
    return r;
}

}  // namespace

EmbreeDevice::EmbreeDevice(int threads) {
    const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : "";
    device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!device_) throw Error("embree", "device", "rtcNewDevice failed");
    rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
}

EmbreeDevice::~EmbreeDevice() {
    rtcReleaseDevice(device_);
}

RTCScene RayScene::build_object_scene(const SceneObject& obj) const {
    RTCScene s = rtcNewScene(device_);
    RTCGeometry g;
    if (obj.shape == ShapeKind::Sphere) {
        g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        float* p = static_cast<float*>(rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
        p[0] = p[1] = p[2] = 0.0f;
        p[3] = obj.sphere_radius;
    } else {
        const TriangleMesh& m = *obj.mesh;
        g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               m.positions.size()));
        for (size_t k = 0; k < m.positions.size(); ++k)
            for (int c = 0; c < 3; ++c) v[3 * k + c] = m.positions[k][c];
        unsigned* idx = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(unsigned), m.triangles.size()));
        for (size_t k = 0; k < m.triangles.size(); ++k)
            for (int c = 0; c < 3; ++c) idx[3 * k + c] = m.triangles[k][c];
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(s, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(s);
    check(device_, ("building object " + obj.name).c_str());
    return s;
}

RayScene::RayScene(const Scene& scene, const EmbreeDevice& device)
    : scene_(scene), device_(device.handle()) {
    top_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(top_, RTC_BUILD_QUALITY_LOW);  // rebuilt when instances move
    const size_t n = scene.objects.size();
    to_world_.resize(n);
    normal_to_world_.resize(n);
    to_object_.resize(n);
    // Objects sharing one mesh (the loader reads a file once) share its BVH: instances.
    std::map<const TriangleMesh*, RTCScene> built;
    for (size_t i = 0; i < n; ++i) {
        const SceneObject& obj = scene.objects[i];
        const bool shareable = obj.shape != ShapeKind::Sphere;
        auto it = shareable ? built.find(obj.mesh.get()) : built.end();
        RTCScene s;
        if (it != built.end()) {
            s = it->second;
            rtcRetainScene(s);
        } else {
            s = build_object_scene(obj);
            if (shareable) built[obj.mesh.get()] = s;
        }
        object_scenes_.push_back(s);
        RTCGeometry inst = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(inst, s);
        rtcAttachGeometryByID(top_, inst, unsigned(i));
        instances_.push_back(inst);
    }
    update(0.0f);
}

RayScene::~RayScene() {
    for (RTCGeometry g : instances_) rtcReleaseGeometry(g);
    for (RTCScene s : object_scenes_) rtcReleaseScene(s);
    rtcReleaseScene(top_);
}

void RayScene::place(int i, float time) {
    const mat4 m = scene_.objects[i].animation.at(time);
    to_world_[i] = m;
    to_object_[i] = glm::inverse(m);
    normal_to_world_[i] = glm::transpose(to_object_[i]);
    rtcSetGeometryTransform(instances_[i], 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &m[0][0]);
    rtcCommitGeometry(instances_[i]);
}

void RayScene::update(float time) {
    if (committed_ && time == time_) return;
    const EnvironmentMap* env = scene_.environment();
    environment_now_ = env && env->spin_deg_per_s() != 0.0f ? env->at_time(time) : nullptr;
    bool moved = !committed_;
    for (size_t i = 0; i < instances_.size(); ++i) {
        if (committed_ && scene_.objects[i].animation.is_static()) continue;
        place(int(i), time);
        moved = true;
    }
    time_ = time;
    if (!moved) return;
    rtcCommitScene(top_);
    check(device_, "committing the top-level scene");
    committed_ = true;
    RTCBounds b;
    rtcGetSceneBounds(top_, &b);
    bounds_min_ = vec3(b.lower_x, b.lower_y, b.lower_z);
    bounds_max_ = vec3(b.upper_x, b.upper_y, b.upper_z);
}

vec3 RayScene::background(const vec3& direction) const {
    const EnvironmentMap* env = environment();
    return env ? env->eval_smooth(direction) : vec3(0.0f);
}

SurfaceHit RayScene::make_hit(const Ray& ray, float t, unsigned inst, unsigned prim, vec3 ng_object,
                              float u, float v) const {
    SurfaceHit h;
    h.valid = true;
    h.distance = t;
    h.object = int(inst);
    h.primitive = int(prim);
    h.position = ray.origin + t * ray.direction;
    const SceneObject& obj = scene_.objects[inst];
    h.material = obj.material;
    if (!obj.group_material.empty() && !obj.mesh->triangle_group.empty())
        h.material = obj.group_material[obj.mesh->triangle_group[prim]];
    const mat3 nm(normal_to_world_[inst]);
    vec3 ng = glm::normalize(nm * ng_object);
    vec3 ns = ng;
    if (obj.shape == ShapeKind::Sphere) {
        const vec3 local = glm::normalize(vec3(to_object_[inst] * vec4(h.position, 1.0f)));
        h.uv = vec2(0.5f + std::atan2(local.y, local.x) / kTwoPi,
                    std::acos(std::clamp(local.z, -1.0f, 1.0f)) / kPi);
    } else {
        const TriangleMesh& m = *obj.mesh;
        const uvec3 tri = m.triangles[prim];
        const float w = 1.0f - u - v;
        if (!m.normals.empty()) {
            const vec3 n = w * m.normals[tri.x] + u * m.normals[tri.y] + v * m.normals[tri.z];
            if (glm::length(n) > 1e-8f) ns = glm::normalize(nm * n);
        }
        if (!m.uvs.empty()) h.uv = w * m.uvs[tri.x] + u * m.uvs[tri.y] + v * m.uvs[tri.z];
    }
    // Both normals face the viewer: freqlab's surfaces are two-sided.
    h.back_face = glm::dot(ng, ray.direction) > 0.0f;
    if (h.back_face) ng = -ng;
    if (glm::dot(ns, ng) < 0.0f) ns = -ns;
    h.geometric_normal = ng;
    h.shading_normal = ns;
    return h;
}

SurfaceHit RayScene::intersect(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = ray.origin.x, rh.ray.org_y = ray.origin.y, rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x, rh.ray.dir_y = ray.direction.y, rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = ray.tnear;
    rh.ray.tfar = ray.tfar;
    rh.ray.time = 0.0f;
    rh.ray.mask = ~0u;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(top_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return SurfaceHit{};
    return make_hit(ray, rh.ray.tfar, rh.hit.instID[0], rh.hit.primID,
                    vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z), rh.hit.u, rh.hit.v);
}

void RayScene::intersect8(const Ray* rays, const bool* active, SurfaceHit* hits) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(32) int valid[8];
    alignas(32) RTCRayHit8 rh;
    for (int i = 0; i < 8; ++i) {
        valid[i] = active[i] ? -1 : 0;
        const Ray& r = rays[i];
        rh.ray.org_x[i] = r.origin.x, rh.ray.org_y[i] = r.origin.y, rh.ray.org_z[i] = r.origin.z;
        rh.ray.dir_x[i] = r.direction.x, rh.ray.dir_y[i] = r.direction.y,
        rh.ray.dir_z[i] = r.direction.z;
        rh.ray.tnear[i] = r.tnear;
        rh.ray.tfar[i] = r.tfar;
        rh.ray.time[i] = 0.0f;
        rh.ray.mask[i] = ~0u;
        rh.ray.id[i] = unsigned(i);
        rh.ray.flags[i] = 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, top_, &ctx, &rh);
    for (int i = 0; i < 8; ++i) {
        hits[i] = SurfaceHit{};
        if (!active[i] || rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
        hits[i] = make_hit(rays[i], rh.ray.tfar[i], rh.hit.instID[0][i], rh.hit.primID[i],
                           vec3(rh.hit.Ng_x[i], rh.hit.Ng_y[i], rh.hit.Ng_z[i]), rh.hit.u[i],
                           rh.hit.v[i]);
    }
}

bool RayScene::occluded(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r = to_rtc_ray(ray, 0);
    rtcOccluded1(top_, &ctx, &r);
    return r.tfar < 0.0f;
}

void RayScene::occluded_stream(const Ray* rays, int count, bool* occluded) const {
    constexpr int kChunk = 64;
    RTCRay batch[kChunk];
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int start = 0; start < count; start += kChunk) {
        const int n = std::min(kChunk, count - start);
        for (int i = 0; i < n; ++i) batch[i] = to_rtc_ray(rays[start + i], unsigned(i));
        rtcOccluded1M(top_, &ctx, batch, unsigned(n), sizeof(RTCRay));
        for (int i = 0; i < n; ++i) occluded[start + i] = batch[i].tfar < 0.0f;
    }
}

}  // namespace freqlab
