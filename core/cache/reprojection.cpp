#include "cache/reprojection.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace freqlab {

namespace {

double angle_between(const vec3& a, const vec3& b) {
    return std::acos(std::clamp(double(glm::dot(a, b)), -1.0, 1.0));
}

vec3 transform_point(const mat4& m, const vec3& p) {
    return vec3(m * vec4(p, 1.0f));
}

}  // namespace

std::vector<CacheRecord> reproject_entries(const RadianceCache& cache, const CacheFrameView& view,
                                           const CacheSettings& settings) {
    std::vector<CacheRecord> records;
    records.reserve(cache.live_count());
    for (size_t o = 0; o < cache.object_count(); ++o) {
        const ObjectCache& c = cache.object(int(o));
        for (size_t s = 0; s < c.capacity(); ++s)
            if (c.live(int(s))) {
                CacheRecord r;
                r.object = int(o);
                r.slot = int(s);
                records.push_back(r);
            }
    }
    std::vector<mat3> to_object(view.to_world.size());
    for (size_t o = 0; o < view.to_world.size(); ++o)
        to_object[o] = glm::inverse(mat3(view.to_world[o]));
    const CameraRayGenerator& cam = *view.camera;
    const int w = view.width, h = view.height;
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, records.size(), 1024),
        [&](const tbb::blocked_range<size_t>& r) {
            for (size_t k = r.begin(); k < r.end(); ++k) {
                CacheRecord& rec = records[k];
                const CacheEntry e = cache.object(rec.object).get(rec.slot);
                CacheTestValues& v = rec.tests;
                const mat4& T = view.to_world[size_t(rec.object)];
                const vec3 p = transform_point(T, e.position);
                rec.world_position = p;
                const vec3 d = p - cam.origin;
                const double z = glm::dot(d, cam.forward);
                v.depth = glm::length(d);
                if (z > 1e-6) {
                    const double x = glm::dot(d, cam.right) / z, y = glm::dot(d, cam.up) / z;
                    const double u = 0.5 * (x / (cam.tan_half_fov * cam.aspect) + 1.0);
                    const double vv = 0.5 * (1.0 - y / cam.tan_half_fov);
                    const double fx = std::floor(u * w), fy = std::floor(vv * h);
                    if (fx >= 0 && fy >= 0 && fx < w && fy < h) {
                        v.in_frustum = true;
                        v.px = int(fx);
                        v.py = int(fy);
                        rec.pixel = v.py * w + v.px;
                    }
                }
                v.r_x = validity_radius(settings.q_eps_x, e.B_x);
                v.r_theta = validity_radius(settings.q_eps_theta, e.B_theta);
                v.lifespan = validity_radius(settings.q_eps_t, e.B_t);
                v.age = double(view.time) - double(e.created);
                v.occlusion_entry = e.occlusion_field;
                v.shading_then = e.shading_field;
                if (v.in_frustum) {
                    const SurfaceHit& hit = (*view.hits)[size_t(rec.pixel)];
                    v.surface_object = hit.valid ? hit.object : -1;
                    v.surface_depth = hit.valid ? hit.distance : 0.0;
                    v.depth_slack = settings.depth_tolerance * v.depth +
                                    (view.footprint ? (*view.footprint)[size_t(rec.pixel)] : 0.0f);
                    if (e.mirror) {
                        const SurfaceHit& refl = (*view.reflected)[size_t(rec.pixel)];
                        v.reflected_object = refl.valid ? refl.object : -1;
                        v.spatial_distance = refl.valid && refl.object == e.reflected_object
                                                 ? glm::length(refl.position - e.created_position)
                                                 : INFINITY;
                    } else {
                        v.spatial_distance = glm::length(p - e.created_position);
                    }
                    const vec3 view_now =
                        glm::normalize(to_object[size_t(rec.object)] * (cam.origin - p));
                    v.angular_distance = angle_between(view_now, e.view);
                }
                rec.decision = decide_geometric(v, rec.object, settings);
            }
        });
    return records;
}

void apply_field_tests(std::vector<CacheRecord>& records, const std::vector<float>& occlusion,
                       const std::vector<float>& shading, const std::vector<char>& known,
                       const CacheSettings& settings) {
    for (CacheRecord& rec : records) {
        if (rec.decision != CacheDecision::Reused || !known[size_t(rec.pixel)]) continue;
        CacheTestValues& v = rec.tests;
        v.occlusion_tested = true;
        v.occlusion_pixel = occlusion[size_t(rec.pixel)];
        v.shading_now = shading[size_t(rec.pixel)];
        v.shading_tested = std::isfinite(v.shading_now) && std::isfinite(v.shading_then);
        rec.decision = decide_observed(v, settings);
    }
}

std::vector<int> resolve_pixels(std::vector<CacheRecord>& records, RadianceCache& cache,
                                const CacheFrameView& view, const CacheSettings& settings) {
    const size_t pixels = size_t(view.width) * view.height;
    std::vector<int> keeper(pixels, -1);
    // The reused records grouped by pixel with a counting sort (stable: record order within a
    // pixel), their entries read in parallel; then each pixel on its own, in parallel (a
    // pixel's records, its keeper's slot and its merged records belong to no other pixel).
    // This was a serial comparison sort and merge loop: ~12 ms of every cache frame.
    std::vector<int> start(pixels + 1, 0);
    for (const CacheRecord& r : records)
        if (r.decision == CacheDecision::Reused) ++start[size_t(r.pixel) + 1];
    for (size_t p = 0; p < pixels; ++p) start[p + 1] += start[p];
    std::vector<int> order(static_cast<size_t>(start[pixels])), position(records.size(), -1);
    {
        std::vector<int> next(start.begin(), start.end() - 1);
        for (size_t k = 0; k < records.size(); ++k)
            if (records[k].decision == CacheDecision::Reused) {
                position[k] = next[size_t(records[k].pixel)]++;
                order[size_t(position[k])] = int(k);
            }
    }
    // entries[m]: that of record order[m], read in record order (the slots' order: the
    // cache's arrays stream through instead of missing once per field).
    std::vector<CacheEntry> entries(order.size());
    tbb::parallel_for(size_t(0), records.size(), [&](size_t k) {
        if (position[k] < 0) return;
        const CacheRecord& r = records[k];
        entries[size_t(position[k])] = cache.object(r.object).get(r.slot);
    });
    tbb::parallel_for(size_t(0), pixels, [&](size_t p) {
        const size_t i = size_t(start[p]), j = size_t(start[p + 1]);
        if (i == j) return;
        // Youngest first, then heaviest, then record order (the lowest (object, slot)):
        // an insertion sort, stable, of the pixel's few records.
        for (size_t a = i + 1; a < j; ++a)
            for (size_t b = a; b > i; --b) {
                const CacheEntry &e = entries[b], &prev = entries[b - 1];
                const bool first =
                    e.created != prev.created ? e.created > prev.created : e.weight > prev.weight;
                if (!first) break;
                std::swap(entries[b], entries[b - 1]);
                std::swap(order[b], order[b - 1]);
            }
        const int k = order[i];
        keeper[p] = k;
        if (!settings.merge) return;
        CacheEntry& ek = entries[i];
        const mat4& T = view.to_world[size_t(records[size_t(k)].object)];
        const vec3 pk = transform_point(T, ek.position);
        const vec3 vk = glm::normalize(mat3(T) * ek.view);
        bool changed = false;
        for (size_t m = i + 1; m < j; ++m) {
            CacheRecord& ro = records[size_t(order[m])];
            const CacheEntry& eo = entries[m];
            if (ro.object != records[size_t(k)].object || eo.mirror || ek.mirror) continue;
            const vec3 po = transform_point(T, eo.position);
            const vec3 vo = glm::normalize(mat3(T) * eo.view);
            const double dx = glm::length(po - pk), dth = angle_between(vo, vk);
            const double rx = std::min(validity_radius(settings.q_eps_x, ek.B_x),
                                       validity_radius(settings.q_eps_x, eo.B_x));
            const double rth = std::min(validity_radius(settings.q_eps_theta, ek.B_theta),
                                        validity_radius(settings.q_eps_theta, eo.B_theta));
            // Values from different times merge only within both lifespans (B_t): averaging a
            // point computed before a moving shadow arrived with one computed after would blur
            // the shadow in time (static scenes: infinite lifespans, always allowed).
            const double dt = std::abs(double(ek.created) - double(eo.created));
            const double rt = std::min(validity_radius(settings.q_eps_t, ek.B_t),
                                       validity_radius(settings.q_eps_t, eo.B_t));
            if (dx > rx || dth > rth || dt > rt) continue;
            const float wsum = ek.weight + eo.weight;
            ek.shading = (ek.weight * ek.shading + eo.weight * eo.shading) / wsum;
            ek.weight = wsum;
            ro.decision = CacheDecision::Merged;
            changed = true;
        }
        if (changed)
            cache.object(records[size_t(k)].object)
                .set_value(records[size_t(k)].slot, ek.shading, ek.weight);
    });
    return keeper;
}

std::vector<long> commit_decisions(const std::vector<CacheRecord>& records, RadianceCache& cache) {
    std::vector<long> counts(kCacheDecisionCount, 0);
    std::vector<std::vector<int>> drop(cache.object_count());
    for (const CacheRecord& r : records) {
        ++counts[size_t(int(r.decision))];
        if (r.decision != CacheDecision::Reused) drop[size_t(r.object)].push_back(r.slot);
    }
    for (size_t o = 0; o < drop.size(); ++o) cache.object(int(o)).remove(drop[o]);
    return counts;
}

}  // namespace freqlab
