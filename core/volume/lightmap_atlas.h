// Lightmap bake targets (issue "Method B, part 2"; seed, Deuxième article §5, §6): one atlas
// per static mesh object, its texels placed on the surface and flagged valid or not.
//
// Charts are automatic: triangles grouped by the dominant axis of their world normal (six
// classes) and by shared vertices, each group projected onto its axis plane at
// `texel_density` texels per scene unit and shelf-packed (tallest first) with a gutter of
// `padding` texels, each chart centred on the nearest whole number of texels (every texel
// centre at least a quarter texel inside a rectangular chart's edges, never on a seam). A texel
// whose centre falls inside a triangle is placed at that point; a valid texel whose hemisphere sees
// more back faces than `backface_tolerance` (a fraction of `validity_rays` rays over its
// hemisphere) lies inside geometry and is flagged, one with geometry right above it is marked
// covered (kTexelCoverReach; the texel filters keep it apart from open neighbours); after a
// bake, empty and invalid texels next to valid ones take their neighbours' mean (dilation), so
// bilinear lookups do not bleed black.
// Spheres (exact primitives, no mesh), moving objects, perfect mirrors (a mirror's appearance is
// not view-independent) and objects whose scene entry says "lightmap": false get no lightmap.
//
// An object's requested density is texel_density x its own lightmap.density_scale, its side
// limit its lightmap.max_size (else max_size). What cannot be honoured is lowered where it
// fails, and said (AtlasReduction, naming object, requested and granted density): a chart
// wider than the side gets its own density (a 2000-unit ground plane does not shrink the
// object's other charts); when the charts' total area overflows the atlas, every chart of
// that object is scaled by the largest common factor that packs (bisection on it).
//
// | parameter          | default | meaning                                             |
// |--------------------|---------|-----------------------------------------------------|
// | texel_density      | 16      | texels per scene unit                               |
// | max_size           | 1024    | an atlas side never exceeds it (density drops)      |
// | padding            | 2       | gutter texels around each chart                     |
// | backface_tolerance | 0.3     | fraction of back-face hits that flags a texel       |
#pragma once

#include <string>
#include <vector>

#include "accel/ray_scene.h"

namespace freqlab {

enum class TexelState : uint8_t { Empty = 0, Valid = 1, InsideGeometry = 2, Dilated = 3 };

struct LightmapTexel {
    TexelState state = TexelState::Empty;
    // Geometry lies within kTexelCoverReach of a texel above its centre, along its normal (a
    // floor over the ground, the inner layer of a wall): its light differs from an open
    // neighbour's, so the texel filters do not mix the two (set for valid texels).
    bool covered = false;
    int triangle = -1;
    vec3 position{0.0f};  // world
    vec3 normal{0.0f};    // world shading normal, unit
    vec3 albedo{0.0f};    // the material's albedo texture at the point
};

// How far above a surface point geometry covers it, in texels of its chart: valley's IFC walls
// stand in layers 0.025 apart (the straddle rays of vertex_corrections.cpp, 0.13 texel high, run
// past the inner layer), its floors 0.03-0.09 above the terrain.
constexpr float kTexelCoverReach = 0.25f;
// Whether geometry lies within `reach` of p along n.
bool covered_along(const RayScene& rays, const vec3& p, const vec3& n, float reach);

// A density the atlas could not honour: `charts` charts of the object got `granted` texels per
// unit instead of `requested`, because of `reason`.
struct AtlasReduction {
    int charts = 0;
    float requested = 0.0f, granted = 0.0f;
    std::string reason;
};

struct ObjectLightmap {
    int object = -1;
    int page = 0;  // > 0: a chart wider than the atlas side, on a page of its own
    int width = 0, height = 0;
    int charts = 0;
    float requested_density = 0.0f;          // bake texel_density x the object's density_scale
    float texel_density = 0.0f;              // the lowest density granted to any of its charts
    std::vector<AtlasReduction> reductions;  // empty: every chart at requested_density
    std::vector<float> chart_density;        // per chart
    std::vector<int> triangle_chart;         // per triangle of the mesh; -1: on another page
    std::vector<LightmapTexel> texels;       // row-major from the top row
    // Lightmap coordinates (texels, continuous: texel i spans [i, i+1)) of each triangle's
    // three corners, 3 per triangle of the object's mesh: what lookups at a surface point use.
    std::vector<vec2> triangle_uv;
    size_t count(TexelState s) const;
    // Texels per scene unit at a placed texel (its chart's density).
    float density_at(size_t texel) const;
    bool holds(int triangle) const {
        return triangle >= 0 && size_t(triangle) < triangle_chart.size() &&
               triangle_chart[size_t(triangle)] >= 0;
    }
};

// Which lightmap (index into build_lightmaps' result) holds a triangle of an object.
class LightmapLookup {
  public:
    LightmapLookup() = default;  // finds nothing
    LightmapLookup(const std::vector<ObjectLightmap>& maps, size_t object_count);
    int find(int object, int triangle) const;  // -1: none

  private:
    const std::vector<ObjectLightmap>* maps_ = nullptr;
    std::vector<std::vector<int>> maps_of_object_;
};

struct AtlasSettings {
    float texel_density = 16.0f;
    int max_size = 1024;
    int padding = 2;
    float backface_tolerance = 0.3f;
    int validity_rays = 32;
};

// Objects are placed at time 0. Throws nothing; objects without a lightmap are skipped. Every
// reduction and every object that gets no atlas although it asked for one is said in `notes`
// ("objects[3] 'ground': ...") when given.
std::vector<ObjectLightmap> build_lightmaps(const RayScene& scene, const AtlasSettings& settings,
                                            std::vector<std::string>* notes = nullptr);
// The note of one reduction, as build_lightmaps says it.
std::string reduction_note(const Scene& scene, const ObjectLightmap& map, const AtlasReduction& r);

// A triangle's world -> lightmap affine map (the instance at time 0): uv = t0 + ((p - a) . gb) du
// + ((p - a) . gc) dv, barycentrics by scalar triple products. Degenerate triangles map every
// point to their first corner.
struct TriangleToTexels {
    vec3 a{0.0f}, gb{0.0f}, gc{0.0f};
    vec2 t0{0.0f}, du{0.0f}, dv{0.0f};
    vec2 uv(const vec3& p) const {
        const vec3 q = p - a;
        return t0 + glm::dot(q, gb) * du + glm::dot(q, gc) * dv;
    }
};
// Triangle `t` of `map`'s object (t < map.triangle_uv.size() / 3).
TriangleToTexels triangle_to_texels(const RayScene& rays, const ObjectLightmap& map, size_t t);
// A surface point's lightmap coordinates (texels) in `map`; false when the hit is not on one
// of the map's triangles (another object's, or on another page).
bool lightmap_uv(const RayScene& rays, const ObjectLightmap& map, const SurfaceHit& hit, vec2* uv);
// Bilinear between texel centres of `channels` floats per texel (RGB read); uv in texels.
vec3 sample_bilinear(const float* values, int channels, int width, int height, vec2 uv);

// Fills Empty / InsideGeometry texels that touch a Valid (or already dilated) one with the mean
// of those neighbours, `rings` times; `values` has `channels` floats per texel. Returns the
// texel states after dilation (filled texels become Dilated).
std::vector<TexelState> dilate(const ObjectLightmap& map, std::vector<float>& values, int channels,
                               int rings);

// The legend of the `texel_valid` layer, in TexelState order.
std::vector<std::string> texel_state_legend();

}  // namespace freqlab
