#include "volume/vertex_corrections.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "volume/bake_estimators.h"
#include "volume/lightmap_baker.h"
#include "volume/texel_filter.h"

namespace freqlab {

VertexCorrectionField::VertexCorrectionField(const RayScene& rays, const Media& media,
                                             const ImpulseTables* tables,
                                             const BakeSettings& settings,
                                             const std::vector<ObjectLightmap>& maps)
    : rays_scene_(&rays), maps_(&maps) {
    // The texel's own Monte Carlo terms of its emitters, on every path: no bounces (surface
    // light's scattering is the texel walk's, at the texel only).
    BakeSettings pre = settings;
    pre.texel_mc_rate = 1.0f;
    BakeEstimator estimator(rays, media, tables, BakeMethod::Impulse, pre);
    // A vertex at depth 1 reads the field; the surface its walk reaches is at depth 2 (a
    // vertex deeper still reads light of up to depth - 1 more bounces: stated, small).
    constexpr int kSurfaceLightDepth = 2;
    estimator.set_field_prepass(kSurfaceLightDepth);
    surface_light_ = settings.texel_surface_light == TexelSurfaceLight::Walk &&
                     settings.bounces >= kSurfaceLightDepth;
    paths_ = std::max(1, int(std::ceil(double(settings.spp) * settings.texel_mc_rate - 1e-9)));
    map_of_object_.assign(rays.scene().objects.size(), -1);
    values_.resize(maps.size());
    std::atomic<long> rays_cast{0};
    for (size_t mi = 0; mi < maps.size(); ++mi) {
        const ObjectLightmap& map = maps[mi];
        map_of_object_[size_t(map.object)] = int(mi);
        const size_t n = map.texels.size();
        std::vector<IrradianceParts> sums(n), deferred(n);
        TexelFilterGuide guide{std::vector<uint64_t>(n, 0), std::vector<float>(n, 0.0f)};
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            const LightmapTexel& t = map.texels[i];
            if (t.state != TexelState::Valid) return;
            BakeCounters counters;
            BakeEstimator::FixedDirect fixed;
            // Keyed apart from the bake's lightmaps and probes (maps.size()).
            for (int s = 0; s < paths_; ++s) {
                CounterRng rng = texel_random(settings.seed, maps.size() + 1 + mi, i, s);
                sums[i] += estimator.estimate(t.position, t.normal, t.albedo, rng, counters, &fixed,
                                              &deferred[i]);
            }
            set_texel_filter_guide(guide, i, fixed, sums[i]);
            rays_cast += counters.rays;
        });
        const std::vector<IrradianceParts> filtered =
            filter_texel_sums(map, deferred, guide, texel_filter_radius(estimator));
        std::vector<float>& v = values_[mi];
        v.assign(n * 6, 0.0f);
        for (size_t i = 0; i < n; ++i) {
            const vec3 emitters = (filtered[i].single + filtered[i].multiple) / float(paths_);
            const vec3 surface = filtered[i].surface / float(paths_);
            if (map.texels[i].state != TexelState::Valid ||
                !std::isfinite(emitters.x + emitters.y + emitters.z + surface.x + surface.y +
                               surface.z))
                continue;
            for (int c = 0; c < 3; ++c) {
                v[i * 6 + size_t(c)] = emitters[c];
                v[i * 6 + 3 + size_t(c)] = surface[c];
            }
        }
        // Bilinear lookups at a chart's edge read the ring outside it.
        dilate(map, v, 6, 2);
    }
    rays_ = rays_cast;
}

bool VertexCorrectionField::at(const SurfaceHit& hit, bool with_surface_light, vec3* out) const {
    if (!maps_ || hit.object < 0 || size_t(hit.object) >= map_of_object_.size()) return false;
    const int mi = map_of_object_[size_t(hit.object)];
    if (mi < 0) return false;
    const ObjectLightmap& map = (*maps_)[size_t(mi)];
    vec2 uv;
    if (!lightmap_uv(*rays_scene_, map, hit, &uv)) return false;
    const float* v = values_[size_t(mi)].data();
    *out = sample_bilinear(v, 6, map.width, map.height, uv);
    if (with_surface_light && surface_light_)
        *out += sample_bilinear(v + 3, 6, map.width, map.height, uv);
    return true;
}

}  // namespace freqlab
