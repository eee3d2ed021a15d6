// Method A's cache stages of one sparse frame (sparse_frame.h; seed, Premier article §5,
// Algorithm 1): reprojection and tests of every entry, the occlusion and key-light tests with
// one entry kept per pixel, then the batch discard and the insertion of the new points.
#include <tbb/parallel_for.h>

#include "base/stopwatch.h"
#include "render/sparse_frame.h"

namespace freqlab {

void SparseFrame::cache_reproject() {
    // 0. The cache: move, project and test every entry (all but the occlusion test).
    const auto t0 = Clock::now();
    std::vector<CacheRecord>& records = result.cache_records;
    {
        reflected.resize(n);
        footprint.resize(n);
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            footprint[i] = features[i].footprint;
            if (mirror[i])
                reflected[i] = integrator.follow_mirrors(gb.hits[i], -gb.view_dirs[i]).hit;
        });
        view.width = w;
        view.height = h;
        view.camera = &camera;
        view.hits = &gb.hits;
        view.footprint = &footprint;
        view.reflected = &reflected;
        view.time = rs.time();
        for (size_t o = 0; o < scene.objects.size(); ++o)
            view.to_world.push_back(rs.object_to_world(int(o)));
        records = reproject_entries(cache->state.cache, view, cache->settings);
        if (!moves) standin = first_survivors(records, int(n), cache->state.cache);
        result.stats["stages"]["reproject"] = ms_since(t0);
    }
}

void SparseFrame::cache_resolve() {
    // 2b. The cache: the occlusion test against this frame's statistics, then one entry per
    // pixel (merging the others where the rule allows).
    std::vector<CacheRecord>& records = result.cache_records;
    {
        const auto t0 = Clock::now();
        for (size_t i = 0; i < n; ++i) {
            field[i] = found[i] ? stats[i][2] : mu_v[i];
            // Only when something moves can the shading change in time (the view's own changes
            // are the angular test's): a camera moving through a still scene expires nothing.
            shading_field[i] = found[i] && moves ? stats[i][4] : NAN;
        }
        apply_field_tests(records, field, shading_field, found, cache->settings);
        if (moves && cache->settings.test_temporal && !keys.empty()) {
            // The key-light half of the temporal test (render/key_lights.h).
            tbb::parallel_for(size_t(0), records.size(), [&](size_t k) {
                CacheRecord& r = records[k];
                if (r.decision != CacheDecision::Reused) return;
                const ObjectCache& oc = cache->state.cache.object(r.object);
                if (!oc.key_light_known(r.slot)) return;
                r.tests.key_lights_tested = true;
                r.tests.key_lights_then = oc.key_light_mask(r.slot);
                r.tests.key_lights_now = key_light_mask(rs, keys, r.world_position,
                                                        gb.hits[size_t(r.pixel)].geometric_normal);
                r.decision = decide_key_lights(r.tests, cache->settings);
            });
        }
        keeper = resolve_pixels(records, cache->state.cache, view, cache->settings);
        // Per pixel in parallel (each writes only its own pixel), then the list in pixel order.
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            if (keeper[i] < 0 || fresh[i]) return;
            const CacheRecord& r = records[size_t(keeper[i])];
            const CacheEntry e = cache->state.cache.object(r.object).get(r.slot);
            value[i] = e.shading;
            if (!found[i] && !own[i]) {  // as for new points: upsampled where known, else own
                mu_v[i] = e.occlusion_ratio;
                sigma_v[i] = e.sigma_v;
            }
            age[i] = float(r.tests.age);
            sampled[i] = 1;
        });
        for (size_t i = 0; i < n; ++i)
            if (keeper[i] >= 0 && !fresh[i]) reused.push_back(int(i));
        reused_fields.assign(reused.size(), {});
        reused_field_slot.assign(n, -1);
        for (size_t k = 0; k < reused.size(); ++k) {
            const CacheRecord& r = records[size_t(keeper[size_t(reused[k])])];
            const CacheEntry e = cache->state.cache.object(r.object).get(r.slot);
            // B_L, sigma_rho, B_S are not kept in an entry, and its weight is N_omega only until
            // it merges: no data (0) there.
            reused_fields[k] = {0.0f,    0.0f, 0.0f,  e.sigma_v, e.occlusion_ratio,
                                e.t_min, 0.0f, e.B_x, e.B_theta, e.B_t};
            reused_field_slot[size_t(reused[k])] = int(k);
        }
        result.stats["stages"]["reproject"] =
            result.stats["stages"]["reproject"].get<double>() + ms_since(t0);
    }
}

void SparseFrame::cache_insert() {
    // 6. The cache: batch discard, then every new point becomes an entry.
    std::vector<CacheRecord>& records = result.cache_records;
    {
        const auto t0 = Clock::now();
        RadianceCache& rc = cache->state.cache;
        const std::vector<long> counts = commit_decisions(records, rc);
        std::vector<std::vector<size_t>> by_object(scene.objects.size());
        for (size_t i = 0; i < n; ++i)
            if (fresh[i]) by_object[size_t(gb.hits[i].object)].push_back(i);
        // What each new entry sees of the key lights (only when something moves).
        std::vector<uint8_t> key_mask(moves && !keys.empty() ? n : 0, 0);
        if (!key_mask.empty())
            tbb::parallel_for(size_t(0), n, [&](size_t i) {
                if (fresh[i])
                    key_mask[i] =
                        key_light_mask(rs, keys, gb.hits[i].position, gb.hits[i].geometric_normal);
            });
        std::vector<CacheEntry> entries;
        for (size_t o = 0; o < by_object.size(); ++o) {
            ObjectCache& oc = rc.object(int(o));
            oc.reserve_for(by_object[o].size());
            const bool moving = !scene.objects[o].animation.is_static();
            // The entries in parallel, their insertion (slot allocation) in pixel order.
            const std::vector<size_t>& pixels = by_object[o];
            entries.resize(pixels.size());
            tbb::parallel_for(size_t(0), pixels.size(), [&](size_t m) {
                const size_t i = pixels[m];
                const SurfaceHit& refl = reflected[i];
                CacheEntry& entry = entries[m];
                entry = make_cache_entry(gb.hits[i], gb.view_dirs[i], view.to_world[o], point_at(i),
                                         value[i], field[i], shading_field[i], mirror[i], refl,
                                         refl.valid ? &view.to_world[size_t(refl.object)] : nullptr,
                                         moving, rs.time());
                if (!key_mask.empty()) {
                    entry.key_light_mask = key_mask[i];
                    entry.key_light_known = true;
                }
            });
            for (size_t m = 0; m < pixels.size(); ++m) oc.insert(entries[m]);
        }
        const long evicted = rc.evict_oldest(size_t(double(cache->settings.max_megabytes) * 1e6));
        result.stats["stages"]["insert"] = ms_since(t0);
        nlohmann::json cs = cache_stats(counts, rc);
        for (const auto& [key, v] : cs.items()) result.stats[key] = v;
        result.stats["evicted"] = evicted;
        result.stats["pixels_reused"] = long(reused.size());
        result.stats["pixels_standin"] = long(initial.size() - initial_shaded.size());
        std::vector<PixelDecision> decision(n, PixelDecision::None);
        for (size_t i = 0; i < n; ++i) {
            if (kind[i] != SampleKind::None)
                decision[i] = kind[i] == SampleKind::Initial    ? PixelDecision::NewInitial
                              : kind[i] == SampleKind::Adaptive ? PixelDecision::NewAdaptive
                                                                : PixelDecision::NewFallback;
            else if (sampled[i])
                decision[i] = PixelDecision::Reused;
        }
        add_cache_layers(layers, decision, age, records);
    }
}

}  // namespace freqlab
