// Deeper path vertices' share of the texels' Monte Carlo terms (issue "Method B, part 3").
// At the texel, impulse corrects its tables through the real media and geometry (single
// scattering the infinite medium misses near walls, the lit medium of occluded connections,
// the multiple-scattering walk: volume/bake_estimators.h); a vertex one bounce deeper used the
// tables alone, whose infinite medium puts 1.2-1.4x the single and 2-2.8x the multiple
// scattering of cornell_fog's walls and floor on them. That light reaches every texel that
// sees those surfaces (cornell's short box read +4.7 % of VPT's unscattered light).
//
// Before the first pass the baker estimates the texels' Monte Carlo terms (a prepass: every
// path runs them, no indirect segment; every second texel in x and y, the others the mean of
// those around them on their surface and their side of the shadows, or themselves where none
// is; ceil(spp x texel_mc_rate / 2) paths a texel, x 2.5 and up to x 3 more where few texels
// share a mean when the texels read it too, see the table): the
// emitters' (lit medium, the walk's multiple) and, apart, the walk's light of other surfaces;
// the single-scattering corrections of unoccluded connections as their ratio to the tables'
// single scattering of those connections, which a deeper vertex multiplies by its own tables'
// value (added, they reached vertices whose own connections were occluded: valley's terrain
// under a house's floor read -0.40, one environment sample through a 0.03-unit gap). Each
// computed texel takes the mean of the computed texels within 2 that the bake's texel filter
// would average with it (its surface, its side of every fixed light's shadow, its light
// level): one path a texel, read alike by every vertex landing there, passed its noise to all
// of them (valley's houses' relMSE 20-30). The texel filter's 7x7 window blurred a correction
// that changes within a texel near a seam (cornell's short box's bottom row read +18 %
// unscattered light); this one spans 5x5 and stops at the shadows. Each texel also keeps
// which point and directional lights it sees occluded: a vertex shadowed otherwise (a pocket
// of a layered IFC wall whose texel's centre sees a lamp: +0.14 where VPT reads 0) does not
// read it and keeps its tables' multiple scattering.
// With bake.texel_terms = field the texels themselves read it too (at_texel, not locate: their
// own texel, no straddle rays), in place of their own Monte Carlo terms; for them the field
// also keeps the multiple-scattering part of its value apart (kMultipleHalves, read in texel
// order), so that lm_inscatter_single / multiple split as the texel's own terms would.
// Without bake.single_correction the prepass draws no real parts and the field lends no ratio
// (a ratio of 0 real parts to the tables, -1, took every reader's single scattering away).
// A vertex deeper than bake.lit_medium_depth that lands on a lightmapped surface adds the
// field's value at the nearest texel to its irradiance: the emitters' part, and the surface
// light's where the vertex continues the path (its indirect segment then carries only
// unscattered light); it leaves its emitters' multiple scattering to the field when the
// texel's walk supplies it (texel_multiple = walk). One lookup a vertex, a cache miss (reading
// a fixed texel instead made a smoke_room bake 7 % faster): stored as half floats and
// prefetched where the vertex is found, read after its path; the prepass ~6 % of a surface
// bake on sun_haze. Where geometry crosses a texel's footprint (a wall standing on a roof's
// underside: at 1 texel/unit one texel holds the eave outside and the attic inside) the
// texel's value holds for its centre's side only: such texels are flagged (four rays from the
// centre to its corners, 0.1 texel above the surface so that the surface's own curvature does
// not count), a hit landing in one reads it only when a ray as high above reaches the centre,
// and the prepass's neighbour means and filter only take neighbours that see each other across
// them. On valley at 1 texel/unit (impulse vs VPT 128 spp, seed 0) the houses' median
// lm_irradiance relMSE went 146 -> 1.6 (field off: 0.49), the terrain's 1.09 -> 0.63; 87 % of
// the IFC houses' texels straddle (layered walls, frames), 0.6 % of the terrain's. Objects
// without a lightmap keep the tables, and so does a hit whose nearest texel is not valid (the
// ring outside a chart, texels inside geometry): that ring, dilated from the chart's texels,
// held for any hit, and valley's hits in the closed cavities of layered IFC walls read lit
// walls' values there (relMSE 2.11 -> 1.90, seed 0). The field is fixed during the bake, so
// the bake stays deterministic and --debug-texel re-runs it exactly. A re-bake after a media
// change (LightmapBaker::reset) keeps its Geometry (straddle and cover rays, the triangles'
// texel mapping) and re-runs its prepass.
//
// | parameter           | meaning                                                          |
// |---------------------|------------------------------------------------------------------|
// | vertex_corrections  | bake.vertex_corrections: 1 builds and reads the field (impulse)   |
// | kFieldStride        | 2: the prepass runs every second texel in x and y                |
// | kFieldMaxBoost      | 3: with texels reading it, x up to 3 paths where few computed    |
// |                     | texels share a texel's mean (9 / their count; statues, strips)   |
// | kFieldPathFraction  | 0.5: ceil(spp x texel_mc_rate x 0.5) paths (1024 spp: 11); 2.5   |
// |                     | when the texels read it too (texel_terms = field: 64 spp, 4)     |
// | straddle rays       | 4 a texel, 0.71 / density long: geometry crossing the footprint   |
// | surface light depth | 2: the surface a depth-1 vertex's walk reaches (deeper vertices   |
// |                     | read light of up to depth - 1 more bounces than bake.bounces)    |
#pragma once

#include <atomic>
#include <memory>
#include <vector>

#include "accel/ray_scene.h"
#include "volume/lightmap_atlas.h"

namespace freqlab {

class BakeEstimator;
class ImpulseTables;
class Media;
struct BakeSettings;
enum class BakeMethod;

// Whether a bake of `method` with these settings builds and reads the field.
bool uses_vertex_corrections(BakeMethod method, const BakeSettings& settings,
                             const ImpulseTables* tables, const Media& media);
// Whether the texels of such a bake read the field at themselves (bake.texel_terms = field; the
// field holds the walk's surface light only with texel_surface_light = walk): the field then
// runs the texels' Monte Carlo budget, and BakeEstimator::estimate_texel reads it.
bool texels_read_field(const BakeSettings& settings);

class VertexCorrectionField {
  public:
    // What the field takes from the atlases' geometry alone (no media, no light): per map, its
    // mesh triangles' texel mapping, and per valid texel whether geometry crosses its footprint
    // or its cover is mixed (rays). A re-bake after a media change (the sliders) keeps it: on
    // cornell_fog at 64 texels/unit its rays were a fifth of the prepass that the re-bake's
    // first pass waits for.
    struct Geometry {
        std::vector<std::vector<TriangleToTexels>> triangles;   // per map, per mesh triangle
        std::vector<std::vector<char>> straddles, cover_mixed;  // per map, per valid texel
    };
    static Geometry trace_geometry(const RayScene& rays, const std::vector<ObjectLightmap>& maps);
    VertexCorrectionField() = default;
    // Estimates the field over `maps` (kept by reference: the baker's atlases). `geometry`:
    // a field's over the same maps and scene (geometry()), or null to trace it.
    VertexCorrectionField(const RayScene& rays, const Media& media, const ImpulseTables* tables,
                          const BakeSettings& settings, const std::vector<ObjectLightmap>& maps,
                          std::shared_ptr<const Geometry> geometry = nullptr);
    const std::shared_ptr<const Geometry>& geometry() const { return geometry_; }
    // Where the field holds a surface hit's value: found() is false when its object has no
    // lightmap. Locating prefetches the texel; value() reads it, best after other work (the
    // read is a cache miss, ~40 ns, that the vertex's own path hides).
    class Texel {
      public:
        bool found() const { return halves_ != nullptr; }
        // The correction irradiance, with its surface light's scattering when the vertex
        // continues the path (with_surface_light).
        vec3 value(bool with_surface_light) const;
        // The multiple-scattering part of value(): reported where the texel was found by
        // at_texel (a texel reading the field at itself), 0 by locate (a deeper vertex).
        vec3 multiple(bool with_surface_light) const;
        // The real single scattering of the unoccluded connections over the tables' (regularised
        // as pack_map says), minus 1: the vertex adds this times its own tables' value.
        vec3 single_ratio() const;
        // Whether the texel's prepass met an unoccluded connection, so that it has a ratio to
        // lend (read with the texel's location: known before the vertex's path runs).
        bool single_ratio_known() const { return ratio_known_; }
        // Whether the value holds for a point that sees the point and directional lights of
        // `shadows` occluded (a bit each): the texel's own (any where they are not known:
        // ratio tracking).
        bool holds_for(uint64_t shadows) const;

      private:
        friend class VertexCorrectionField;
        const uint16_t* halves_ = nullptr;
        const uint16_t* multiple_halves_ = nullptr;  // kMultipleHalves of them, or none
        float scale_ = 0.0f, ratio_scale_ = 0.0f;
        bool surface_light_ = false, ratio_known_ = true;
    };
    // `rays`: where given, counts the visibility rays the lookup casts (a straddling texel's).
    Texel locate(const SurfaceHit& hit, long* rays = nullptr) const;
    // The field's value at texel `texel` of lightmap `map` (the trace prints it).
    Texel at_texel(size_t map, size_t texel) const;
    // Whether the field holds surface light (texel_surface_light = walk, bounces >= 2).
    bool has_surface_light() const { return surface_light_; }
    bool empty() const { return maps_ == nullptr; }
    int paths_per_texel() const { return paths_; }
    long rays() const { return rays_; }
    // Texels whose prepass ran (the others took their neighbours' mean).
    long computed_texels() const { return computed_; }
    // Their paths: paths_per_texel() each, more where few computed texels share their surface.
    long paths_run() const { return paths_run_; }
    // Valid texels whose footprint geometry crosses: a lookup there casts a ray to the texel's
    // centre and ignores the field when something is in between.
    long straddling_texels() const { return straddling_; }

  private:
    const std::vector<ObjectLightmap>* maps_ = nullptr;
    // Its triangles' texel mapping precomputed: a lookup is ~30 flops.
    std::shared_ptr<const Geometry> geometry_;
    // Per object: its map, -1 none, kSeveralPages: ask lookup_ (pages, volume/lightmap_atlas.h),
    // so that an object of one map costs the hot path no more than before pages.
    static constexpr int kSeveralPages = -2;
    std::vector<int> map_of_object_;
    LightmapLookup lookup_;
    // Per map, per readable texel (valid, its terms finite; PackedMap::rank finds its entry): RGB
    // of the emitters' terms, then RGB of the surface light's, as half floats of value / scale
    // (scale: the map's largest |value|, so nothing overflows; relative precision 2^-11). A lookup
    // is one random read, a cache miss at 24 bytes a texel: 8 % of a smoke_room impulse bake,
    // against ~2 % at 12 (28 now: the ratio and the shadows joined in session 28). A texel crossed
    // by geometry: its centre lifted off the surface by `lift` (the visibility ray from a hit runs
    // from the hit to it and half a lift on).
    struct StraddlingTexel {
        uint32_t texel;
        vec3 lifted_centre;
        float lift;
        // Geometry close above covers part of the footprint: a hit reads the texel only when
        // covered as its centre is (a ray along the hit's normal, kTexelCoverReach of a texel).
        bool check_cover = false, covered = false;
    };
    // Emitters, surface light, ratio (RGB each), the shadows' 64 bits, whether they are known.
    static constexpr size_t kHalvesPerTexel = 14;
    // The multiple parts of the emitters' terms and of the surface light (RGB each), apart:
    // only a texel reading itself asks (in texel order), so the hot entry keeps its 28 bytes.
    static constexpr size_t kMultipleHalves = 6;
    struct PackedMap {
        int width = 0, height = 0;
        float scale = 0.0f, ratio_scale = 0.0f;
        std::vector<uint16_t> halves;           // readable texels only, in texel order
        std::vector<uint16_t> multiple_halves;  // the same texels, kMultipleHalves each
        // Texels crossed by geometry: a bit each, 64 to a word, beside the number of straddling
        // texels in the words before it (the rank of a texel's entry in `centres`, which are
        // in texel order). One cache line answers both: a binary search over the centres was
        // 19 dependent misses on valley's houses (0.9 s of a 50 s bake). `readable`: the
        // texels a hit reads (valid, with a finite value).
        // `readable_before`: the readable texels in the words before it, the rank of a
        // readable texel's entry in `halves` (which holds readable texels only). `no_ratio`:
        // readable texels without a single-scattering ratio (in the same line as the others:
        // a vertex must know it before its path runs, and the texel's halves are a miss).
        struct StraddleWord {
            uint64_t bits = 0, readable = 0, no_ratio = 0;
            uint32_t before = 0, readable_before = 0;
        };
        std::vector<StraddleWord> straddles;
        std::vector<StraddlingTexel> centres;
        // Texel k's entry among those flagged in `bits` (its word's; `before` flagged in the
        // words before it): in `centres` by bits / before, in `halves` by readable /
        // readable_before.
        static size_t rank(uint64_t bits, uint32_t before, size_t k) {
            return before + size_t(__builtin_popcountll(bits & ((uint64_t(1) << (k % 64)) - 1)));
        }
    };
    std::vector<PackedMap> packed_;
    // Readable texel k of `map` (its word `word`): its entry, scales and flags.
    Texel readable_texel(const PackedMap& map, const PackedMap::StraddleWord& word, size_t k) const;
    // The prepass of one map (its texels' terms) and their packing (returns the valid
    // straddling texels).
    struct MapTerms;
    struct PrepassCounts {
        std::atomic<long> rays{0}, texels{0}, paths{0};
    };
    MapTerms estimate_map(const RayScene& rays, const BakeEstimator& estimator,
                          const ObjectLightmap& map, size_t mi, uint64_t key, int seed,
                          PrepassCounts& counts) const;
    static long pack_map(const ObjectLightmap& map, const MapTerms& terms, int paths,
                         bool corrections_drawn, PackedMap& packed);
    int paths_ = 0;
    long rays_ = 0;
    long computed_ = 0, paths_run_ = 0;
    float max_boost_ = 1.0f;  // the most paths_ is raised by where few texels share a mean
    long straddling_ = 0;
    const RayScene* scene_ = nullptr;
    bool surface_light_ = false;
};

}  // namespace freqlab
