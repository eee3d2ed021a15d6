#include "cache/cache_decision.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace freqlab {

namespace {

std::string format(const char* fmt, double a, double b = 0.0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, fmt, a, b);
    return buf;
}

bool depth_agrees(const CacheTestValues& v) {
    return std::abs(v.depth - v.surface_depth) <= v.depth_slack;
}

double degrees(double rad) {
    return rad * 57.29577951308232;
}

}  // namespace

const char* to_string(CacheDecision d) {
    static const char* names[kCacheDecisionCount] = {
        "reused",          "merged",          "discard_zbuffer",  "discard_frustum",
        "discard_spatial", "discard_angular", "discard_temporal", "discard_occlusion"};
    return names[int(d)];
}

bool is_discard(CacheDecision d) {
    return int(d) >= int(CacheDecision::DiscardZbuffer);
}

vec3 decision_colour(CacheDecision d) {
    switch (d) {
        case CacheDecision::Reused:
            return vec3(0.95f);  // the seed draws them black on white; our viewer is dark
        case CacheDecision::Merged:
            return vec3(0.2f, 0.75f, 0.3f);
        case CacheDecision::DiscardZbuffer:
            return vec3(0.6f);
        case CacheDecision::DiscardFrustum:
            return vec3(0.1f, 0.7f, 0.7f);
        case CacheDecision::DiscardSpatial:
            return vec3(0.15f, 0.35f, 1.0f);
        case CacheDecision::DiscardAngular:
            return vec3(0.95f, 0.1f, 0.1f);
        case CacheDecision::DiscardTemporal:
            return vec3(1.0f, 0.6f, 0.0f);
        case CacheDecision::DiscardOcclusion:
            return vec3(0.6f, 0.2f, 0.8f);
    }
    return vec3(1.0f);
}

double validity_epsilon(double q) {
    return std::acos(1.0 - q);
}

double validity_radius(double q, double bandwidth) {
    if (!(bandwidth > 0.0)) return std::numeric_limits<double>::infinity();
    return 2.0 * M_PI * validity_epsilon(q) / bandwidth;
}

CacheDecision decide_geometric(const CacheTestValues& v, int entry_object, const CacheSettings& s) {
    if (!v.in_frustum) return CacheDecision::DiscardFrustum;
    if (v.surface_object != entry_object || !depth_agrees(v)) return CacheDecision::DiscardZbuffer;
    if (s.test_spatial && v.spatial_distance > v.r_x) return CacheDecision::DiscardSpatial;
    if (s.test_angular && v.angular_distance > v.r_theta) return CacheDecision::DiscardAngular;
    if (s.test_temporal && v.age > v.lifespan) return CacheDecision::DiscardTemporal;
    return CacheDecision::Reused;
}

CacheDecision decide_observed(const CacheTestValues& v, const CacheSettings& s) {
    if (s.test_temporal && v.shading_tested &&
        std::abs(v.shading_now - v.shading_then) > std::log1p(double(s.shading_change)))
        return CacheDecision::DiscardTemporal;
    if (s.test_occlusion && v.occlusion_tested &&
        std::abs(v.occlusion_entry - v.occlusion_pixel) > s.occlusion_threshold)
        return CacheDecision::DiscardOcclusion;
    return CacheDecision::Reused;
}

CacheDecision decide_key_lights(const CacheTestValues& v, const CacheSettings& s) {
    if (s.test_temporal && v.key_lights_tested && v.key_lights_then != v.key_lights_now)
        return CacheDecision::DiscardTemporal;
    return CacheDecision::Reused;
}

std::vector<std::string> explain(const CacheTestValues& v, int entry_object,
                                 const CacheSettings& s) {
    std::vector<std::string> out;
    if (!v.in_frustum) {
        out.push_back("frustum: projects outside the image or behind the camera");
        return out;
    }
    out.push_back("frustum: lands on pixel (" + std::to_string(v.px) + ", " + std::to_string(v.py) +
                  ")");
    if (v.surface_object != entry_object)
        out.push_back(v.surface_object < 0
                          ? "z-buffer: the pixel sees the background"
                          : "z-buffer: the pixel sees object " + std::to_string(v.surface_object) +
                                ", not object " + std::to_string(entry_object));
    else
        out.push_back(format(depth_agrees(v) ? "z-buffer: depth %.4g vs surface %.4g, visible"
                                             : "z-buffer: depth %.4g vs surface %.4g, hidden",
                             v.depth, v.surface_depth));
    auto inside = [](double d, double r) { return d <= r ? "inside" : "outside"; };
    const char* off = " (test off)";
    out.push_back(format("spatial: %.3g from where it was computed, ", v.spatial_distance) +
                  inside(v.spatial_distance, v.r_x) +
                  (std::isinf(v.r_x) ? std::string(" an unbounded patch (B_x = 0)")
                                     : format(" a patch of radius %.3g", v.r_x)) +
                  (s.test_spatial ? "" : off));
    out.push_back(format("angular: view moved %.3g deg, ", degrees(v.angular_distance)) +
                  inside(v.angular_distance, v.r_theta) +
                  (std::isinf(v.r_theta) ? std::string(" an unbounded cone (B_theta = 0)")
                                         : format(" a %.3g deg cone", degrees(v.r_theta))) +
                  (s.test_angular ? "" : off));
    out.push_back(
        format("temporal: age %.4g s, ", v.age) +
        (std::isinf(v.lifespan)
             ? std::string("infinite lifespan (B_t = 0)")
             : format("lifespan %.4g s", v.lifespan) + (v.age > v.lifespan ? ", expired" : "")) +
        (v.shading_tested ? format("; shading around it changed by %.1f %% (limit %.1f %%)",
                                   100.0 * std::expm1(std::abs(v.shading_now - v.shading_then)),
                                   100.0 * s.shading_change)
                          : std::string()) +
        (v.key_lights_tested
             ? (v.key_lights_then != v.key_lights_now
                    ? format("; a shadow came or went between it and a key light (mask %d -> %d)",
                             v.key_lights_then, v.key_lights_now)
                    : format("; key lights seen as when computed (mask %d)", v.key_lights_now))
             : std::string()) +
        (s.test_temporal ? "" : off));
    if (v.occlusion_tested)
        out.push_back(format("occlusion: ratio at the pixel %.3f when computed, %.3f now",
                             v.occlusion_entry, v.occlusion_pixel) +
                      (std::abs(v.occlusion_entry - v.occlusion_pixel) > s.occlusion_threshold
                           ? format(", differs by more than %.3g", s.occlusion_threshold)
                           : format(", within %.3g", s.occlusion_threshold)) +
                      (s.test_occlusion ? "" : off));
    return out;
}

}  // namespace freqlab
