#include "render/cache_pass.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "scene/scene.h"

namespace freqlab {

bool scene_has_motion(const Scene& scene) {
    if (const EnvironmentMap* env = scene.environment(); env && env->spin_deg_per_s() != 0.0f)
        return true;
    for (const SceneObject& o : scene.objects)
        if (!o.animation.is_static()) return true;
    return false;
}

std::vector<int> first_survivors(const std::vector<CacheRecord>& records, int pixel_count,
                                 const RadianceCache& cache) {
    std::vector<int> best(size_t(pixel_count), -1);
    std::vector<float> created(size_t(pixel_count), -INFINITY);
    for (size_t k = 0; k < records.size(); ++k) {
        const CacheRecord& r = records[k];
        if (r.decision != CacheDecision::Reused) continue;
        const float c = cache.object(r.object).created_times()[size_t(r.slot)];
        if (c > created[size_t(r.pixel)]) {
            created[size_t(r.pixel)] = c;
            best[size_t(r.pixel)] = int(k);
        }
    }
    return best;
}

std::vector<float> splat_coverage(int w, int h, const std::vector<int>& reused,
                                  const std::vector<float>& density,
                                  const std::vector<PixelFeature>& features) {
    std::vector<float> coverage(size_t(w) * h, 0.0f);
    for (int j : reused) {
        const float d = std::max(density[size_t(j)], 1e-6f);
        const float r = std::max(0.5f, std::sqrt(1.0f / (float(M_PI) * d)));
        const int jx = j % w, jy = j / w, ri = int(std::ceil(r));
        const int object = features[size_t(j)].object;
        for (int y = std::max(jy - ri, 0); y <= std::min(jy + ri, h - 1); ++y)
            for (int x = std::max(jx - ri, 0); x <= std::min(jx + ri, w - 1); ++x) {
                const float dx = float(x - jx), dy = float(y - jy);
                const size_t i = size_t(y) * w + x;
                if (dx * dx + dy * dy > r * r || features[i].object != object) continue;
                coverage[i] += d;
            }
    }
    return coverage;
}

CacheEntry make_cache_entry(const SurfaceHit& hit, const vec3& view_dir, const mat4& to_world,
                            const RadiancePoint& point, const vec3& shading, float occlusion_field,
                            float shading_field, bool mirror, const SurfaceHit& reflected,
                            const mat4* reflected_to_world, bool moving, float time) {
    CacheEntry e;
    const mat3 linear(to_world);
    e.position = vec3(glm::inverse(to_world) * vec4(hit.position, 1.0f));
    e.created_position = hit.position;
    e.view = glm::normalize(glm::inverse(linear) * -view_dir);
    e.normal = glm::normalize(glm::transpose(linear) * hit.shading_normal);
    e.shading = shading;
    e.weight = float(std::max(point.N_omega, 1.0));
    e.created = time;
    e.B_x = float(point.B_x);
    e.B_theta = float(point.B_theta);
    e.B_t = float(point.B_t);
    e.occlusion_ratio = float(point.occlusion_ratio);
    e.occlusion_field = occlusion_field;
    e.shading_field = shading_field;
    e.sigma_v = float(point.sigma_V);
    e.t_min = float(point.t_min);
    e.occluded = point.pilot_occluded > 0;
    e.moving = moving;
    e.mirror = mirror;
    if (mirror && reflected.valid && reflected_to_world) {
        e.reflected_object = reflected.object;
        e.reflected_position =
            vec3(glm::inverse(*reflected_to_world) * vec4(reflected.position, 1.0f));
        e.reflected_normal =
            glm::normalize(glm::transpose(mat3(*reflected_to_world)) * reflected.shading_normal);
        e.created_position = reflected.position;  // the spatial test follows the reflection
    }
    return e;
}

void add_cache_layers(LayerSet& layers, const std::vector<PixelDecision>& decision,
                      const std::vector<float>& age, const std::vector<CacheRecord>& records) {
    Layer& d = layers.add("decision", LayerKind::Categorical, 1,
                          "where each pixel's radiance point came from");
    d.legend = {"none", "reused", "new initial", "new adaptive", "new fallback"};
    d.palette = {vec3(0.0f), vec3(0.55f), vec3(0.2f, 0.45f, 1.0f), vec3(0.95f, 0.25f, 0.15f),
                 vec3(1.0f, 0.85f, 0.1f)};
    Layer& a = layers.add("age", LayerKind::Continuous, 1,
                          "age (s) of the reused cache entry (0 where new)");
    Layer& c = layers.add("cache_decisions", LayerKind::Categorical, 1,
                          "the previous frame's entries where they land, by decision");
    c.sparse = true;
    c.legend.push_back("none");
    c.palette.push_back(vec3(0.12f));
    for (int k = 0; k < kCacheDecisionCount; ++k) {
        c.legend.push_back(to_string(CacheDecision(k)));
        c.palette.push_back(decision_colour(CacheDecision(k)));
    }
    for (size_t i = 0; i < decision.size(); ++i) {
        d.data[i] = float(int(decision[i]));
        a.data[i] = age[i];
    }
    // A discard outranks a kept entry on the same pixel (the layer shows why points go).
    for (const CacheRecord& r : records) {
        if (r.pixel < 0) continue;
        float& v = c.data[size_t(r.pixel)];
        v = std::max(v, float(int(r.decision) + 1));
    }
}

std::vector<std::string> cache_entries_near(const std::vector<CacheRecord>& records,
                                            const RadianceCache* snapshot, int x, int y, int radius,
                                            int width, const CacheSettings& settings,
                                            size_t max_entries) {
    std::vector<std::string> out;
    std::vector<const CacheRecord*> near;
    for (const CacheRecord& r : records) {
        if (r.pixel < 0) continue;
        const int px = r.pixel % width, py = r.pixel / width;
        if (std::abs(px - x) <= radius && std::abs(py - y) <= radius) near.push_back(&r);
    }
    char buf[256];
    std::snprintf(buf, sizeof buf, "cache: %zu entries land within %d px of (%d, %d)", near.size(),
                  radius, x, y);
    out.push_back(buf);
    for (size_t k = 0; k < near.size() && k < max_entries; ++k) {
        const CacheRecord& r = *near[k];
        std::snprintf(buf, sizeof buf, "entry object %d slot %d at (%d, %d): %s", r.object, r.slot,
                      r.tests.px, r.tests.py, to_string(r.decision));
        out.push_back(buf);
        if (snapshot && r.object < int(snapshot->object_count()) &&
            size_t(r.slot) < snapshot->object(r.object).capacity()) {
            const CacheEntry e = snapshot->object(r.object).get(r.slot);
            std::snprintf(buf, sizeof buf,
                          "  x_obj (%.4g, %.4g, %.4g) n (%.3f, %.3f, %.3f) L (%.4g, %.4g, %.4g) "
                          "w %.0f created %.4g s%s%s",
                          e.position.x, e.position.y, e.position.z, e.normal.x, e.normal.y,
                          e.normal.z, e.shading.x, e.shading.y, e.shading.z, e.weight, e.created,
                          e.moving ? " moving" : "", e.mirror ? " mirror" : "");
            out.push_back(buf);
            std::snprintf(buf, sizeof buf,
                          "  B_x %.4g  B_theta %.4g  B_t %.4g  occlusion %.3f  sigma_V %.4g", e.B_x,
                          e.B_theta, e.B_t, e.occlusion_ratio, e.sigma_v);
            out.push_back(buf);
            if (e.mirror) {
                std::snprintf(buf, sizeof buf, "  reflects object %d at (%.4g, %.4g, %.4g)",
                              e.reflected_object, e.reflected_position.x, e.reflected_position.y,
                              e.reflected_position.z);
                out.push_back(buf);
            }
        }
        for (const std::string& s : explain(r.tests, r.object, settings)) out.push_back("  " + s);
    }
    return out;
}

nlohmann::json cache_stats(const std::vector<long>& counts, const RadianceCache& cache) {
    nlohmann::json discards = nlohmann::json::object();
    for (int k = int(CacheDecision::DiscardZbuffer); k < kCacheDecisionCount; ++k) {
        const std::string name = to_string(CacheDecision(k));
        discards[name.substr(8)] = counts[size_t(k)];  // "discard_" dropped
    }
    return {{"merged", counts[size_t(CacheDecision::Merged)]},
            {"entries_kept", counts[size_t(CacheDecision::Reused)]},
            {"discards", discards},
            {"cache_points", long(cache.live_count())},
            {"cache_bytes", long(cache.bytes())},
            {"cache_bytes_per_point",
             cache.live_count() ? double(cache.bytes()) / double(cache.live_count()) : 0.0}};
}

}  // namespace freqlab
