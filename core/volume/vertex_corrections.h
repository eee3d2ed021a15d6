// Deeper path vertices' share of the texels' Monte Carlo terms (issue "Method B, part 3").
// At the texel, impulse corrects its tables through the real media and geometry (single
// scattering the infinite medium misses near walls, the lit medium of occluded connections,
// the multiple-scattering walk: volume/bake_estimators.h); a vertex one bounce deeper used the
// tables alone, whose infinite medium puts 1.2-1.4x the single and 2-2.8x the multiple
// scattering of cornell_fog's walls and floor on them. That light reaches every texel that
// sees those surfaces (cornell's short box read +4.7 % of VPT's unscattered light).
//
// Before the first pass the baker estimates every valid texel's Monte Carlo terms of its
// emitters (a prepass: bounces 0, every path runs them, ceil(spp x texel_mc_rate) paths,
// the number the texel itself gets) and filters them as the texel's own (texel_filter.h).
// A vertex deeper than bake.lit_medium_depth that lands on a lightmapped surface then adds the
// field's value there (bilinear in the atlas) to its irradiance, and leaves its emitters'
// multiple scattering to it when the texel's walk supplies it (texel_multiple = walk). One
// lookup a vertex; the prepass costs ~2 % of a 1024-spp bake. Objects without a lightmap
// keep the tables. The field is a fixed function during the bake, so the bake stays
// deterministic and --debug-texel re-runs it exactly.
//
// | parameter          | meaning                                                           |
// |--------------------|-------------------------------------------------------------------|
// | vertex_corrections | bake.vertex_corrections: 1 builds and reads the field (impulse)    |
// | paths per texel    | ceil(spp x texel_mc_rate) (1024 spp at 0.02: 21)                  |
// | filter radius      | bake.texel_mc_radius                                              |
#pragma once

#include <vector>

#include "accel/ray_scene.h"
#include "volume/lightmap_atlas.h"

namespace freqlab {

class ImpulseTables;
class Media;
struct BakeSettings;

class VertexCorrectionField {
  public:
    VertexCorrectionField() = default;
    // Estimates the field over `maps` (kept by reference: the baker's atlases).
    VertexCorrectionField(const RayScene& rays, const Media& media, const ImpulseTables* tables,
                          const BakeSettings& settings, const std::vector<ObjectLightmap>& maps);
    // The correction irradiance at a surface hit, with its surface light's scattering when
    // the vertex there continues the path (with_surface_light); false (and nothing) when its
    // object has no lightmap.
    bool at(const SurfaceHit& hit, bool with_surface_light, vec3* out) const;
    // Whether the field holds surface light (texel_surface_light = walk, bounces >= 2).
    bool has_surface_light() const { return surface_light_; }
    bool empty() const { return maps_ == nullptr; }
    // The field's value per texel of lightmap `map` (dilated over empty texels): RGB of the
    // emitters' terms, then RGB of the surface light's.
    const std::vector<float>& values(size_t map) const { return values_.at(map); }
    int paths_per_texel() const { return paths_; }
    long rays() const { return rays_; }

  private:
    const RayScene* rays_scene_ = nullptr;
    const std::vector<ObjectLightmap>* maps_ = nullptr;
    std::vector<int> map_of_object_;
    std::vector<std::vector<float>> values_;
    int paths_ = 0;
    long rays_ = 0;
    bool surface_light_ = false;
};

}  // namespace freqlab
