// The per-point estimators of method B's bakers (seed, Deuxième article §5, §5.1, §5.2; issue
// "Method B, part 2"): irradiance at a surface point, split by what carried it.
//
// | method     | each path segment x -> y (y an emitter or a surface vertex)                |
// |------------|-----------------------------------------------------------------------------|
// | surface    | L(y) as if the media were not there (the baseline)                          |
// | extinction | L(y) x transmittance of the segment (seed Fig. 30 a/c)                      |
// | impulse    | extinction, plus L(y)'s scattered ZH response queried with the segment's     |
// |            | effective sigma_s, sigma_a, g (§4.4) and the emitter kind of y: point and    |
// |            | directional tables for those lights, the differential-area table for quad  |
// |            | lights and for surface vertices (§5); only on unoccluded segments (§5.2);  |
// |            | ZH -> irradiance by the O(N) double product with the clamped cosine (App. 8) |
// | vpt        | volumetric path tracing of the same quantity: exact free flights and exact  |
// |            | transmittance through the piecewise-constant media, NEE at every vertex,   |
// |            | point lights in media by equiangular sampling along every segment, HG phase |
// |            | sampling, Russian roulette after 4 scattering events                        |
//
// Impulse at the texel (issue "Method B, part 3"): the tables give what they describe well on
// every path; the Monte Carlo terms through the real media (single-scattering corrections, the
// lit medium of occluded connections, hidden surfaces' light, the multiple-scattering walk) run
// on bake.texel_mc_rate of the paths, weighted up, and are returned apart (`deferred`) for the
// baker to filter over neighbouring texels (texel_filter.h). With bake.texel_terms = field
// (the quality presets') the texel runs none: it reads the vertex correction field at itself
// as a deeper vertex does (estimate_texel; volume/vertex_corrections.h), whose prepass already
// ran those terms at every second texel. Valley at low quality (4 texels/unit, seed 0): the
// bake 29.5 -> 22.1 s (surface 17.2 s), lm_irradiance relMSE against VPT 0.396 -> 0.317, its
// lit texels' 0.036 -> 0.037; haze_occluder's floor against VPT (1024 spp): umbra 1.013 ->
// 0.935, the far field's in-scattered light 0.991 of VPT's.
//
// Parts: `surface` is light that reached x along a final segment without scattering in it;
// `single` / `multiple` had one / several scattering events between x and the previous surface
// vertex (or emitter). Environment and sky light is reached by NEE only (escaping rays add
// nothing), so no light is counted twice. Surfaces are seen as diffuse with their albedo
// texture (a lightmap stores view-independent light); mirrors reflect nothing here.
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "accel/ray_scene.h"
#include "base/enum_names.h"
#include "math/rng.h"
#include "settings/bake_settings.h"
#include "volume/emitter_roulette.h"
#include "volume/impulse_irradiance.h"
#include "volume/impulse_query.h"
#include "volume/media.h"
#include "volume/near_light_directions.h"
#include "volume/single_scatter_lobe.h"
#include "volume/vertex_corrections.h"

namespace freqlab {

enum class BakeMethod { Surface, Extinction, Impulse, Vpt };
inline constexpr EnumName<BakeMethod> kBakeMethodNames[] = {{BakeMethod::Surface, "surface"},
                                                            {BakeMethod::Extinction, "extinction"},
                                                            {BakeMethod::Impulse, "impulse"},
                                                            {BakeMethod::Vpt, "vpt"}};
inline const char* to_string(BakeMethod m) {
    return enum_name(kBakeMethodNames, m);
}
BakeMethod parse_bake_method(const std::string& text);  // throws Error naming --method
// Every bake method in enum order, and them joined by `separator` (help texts, menus).
const std::vector<BakeMethod>& bake_methods();
std::string bake_method_list(const std::string& separator = "|");
bool is_bake_method(const std::string& name);

// A surface vertex as an emitter of the tables (a differential area): the infinite medium's
// isotropic multiple lobe about it (power-equivalent point, impulse_query.h) sends half its
// light into the half-space behind the surface, where the medium is not, so its multiple
// response counts at half weight. Measured: haze_occluder's open floor, surface-reflected
// multiple scattering over VPT's 1.37 at full weight, 0.59 without, 0.98 at half; cornell_fog's
// lightmaps, multiple over VPT's 1.15-1.33 at full weight, 0.84-1.00 at half (smoke_room
// 0.91-0.99 -> 0.80-0.89, sun_haze 1.04-1.17 -> 0.94-1.02).
constexpr float kSurfaceEmitterMultipleWeight = 0.5f;

struct IrradianceParts {
    vec3 surface{0.0f}, single{0.0f}, multiple{0.0f};
    vec3 total() const { return surface + single + multiple; }
    IrradianceParts& operator+=(const IrradianceParts& o) {
        surface += o.surface;
        single += o.single;
        multiple += o.multiple;
        return *this;
    }
};

// What one path's Monte Carlo terms at the receiver brought, as the bake ran them
// (--debug-texel): surface_path records them at depth 0 while a PathRecording of the thread
// is open. Values are before the path's weight 1 / rate and after each emitter's roulette.
struct TexelPathRecord {
    bool mc_ran = false;
    float mc_weight = 0.0f;  // 1 / the rate the path ran them at
    struct Term {
        int light = -1;
        bool occluded = false;  // the lit medium; else the single-scattering correction
        float roulette = 1.0f;  // the emitter roulette's weight (included in `value`)
        IrradianceParts value;
    };
    std::vector<Term> terms;
    IrradianceParts walk;      // the texel walk: emitters' multiple scattering and surface light
    IrradianceParts hidden;    // hidden surfaces' light
    IrradianceParts path;      // the path's estimate at the texel (without the deferred terms)
    IrradianceParts deferred;  // what it added to the texel's deferred sum
    // The texel's indirect segment: where it landed and the irradiance that vertex gathered
    // (its own path, with the vertex correction field's value where it read one).
    struct Bounce {
        bool hit = false;
        int object = -1;
        vec3 position{0.0f};
        float distance = 0.0f;
        IrradianceParts vertex;
        bool field_read = false;        // the field held for the vertex (found, same shadows)
        bool drew_corrections = false;  // the field had no ratio: the vertex drew its own
        vec3 field{0.0f};               // what it added (its value and ratio x the vertex's tables)
    } bounce;
    bool in_bounce = false;  // the texel's indirect segment is running (its vertex records)
    // bake.texel_terms = field: what the texel read of the field at itself (no terms ran).
    struct TexelField {
        bool read = false, holds = false, drew_corrections = false;
        vec3 added{0.0f};
    } texel_field;
};
// Records the receiver's terms of the paths estimated on this thread while it lives.
// (Inline: surface_path asks at every texel path.)
class PathRecording {
  public:
    explicit PathRecording(TexelPathRecord* record) : previous_(active_) { active_ = record; }
    ~PathRecording() { active_ = previous_; }
    PathRecording(const PathRecording&) = delete;
    PathRecording& operator=(const PathRecording&) = delete;
    static TexelPathRecord* current() { return active_; }

  private:
    static inline thread_local TexelPathRecord* active_ = nullptr;
    TexelPathRecord* previous_;
};

struct BakeCounters {
    long rays = 0;             // intersection + occlusion rays
    long impulse_queries = 0;  // table lookups
    long guarded = 0;          // non-finite estimates dropped
};

// The bit of point / directional light `light` in a shadows word (UnoccludedSingle::shadows,
// the texel filter's guide): lights past 64 share bits, which only merges shadow classes.
inline uint64_t shadow_bit(int light) {
    return uint64_t(1) << (unsigned(light) % 64u);
}

// A vertex's tables' single scattering of its unoccluded connections (`tables`) and, where its
// Monte Carlo terms ran, the real single scattering of those connections drawn by
// single_correction / local_single_correction (`real`), over `paths` paths. At a texel of the
// vertex correction field's prepass (drawn on every path) the field carries their ratio,
// which a deeper vertex applies to its own tables' value (vertex_corrections.h).
// A deeper vertex also learns from it which point and directional lights it sees occluded (a
// bit each, as the texel filter's guide) and the tables' multiple scattering it left to the
// field: the field's value holds only for points shadowed as its texel is.
// At a texel of the bake (the baker passes one), `paired_tables` holds the tables' single
// scattering of the very connections whose real parts were drawn, weighted alike: the filter
// applies their ratio to the texel's own tables (texel_filter.h, ratio_correction).
struct UnoccludedSingle {
    vec3 tables{0.0f}, real{0.0f};
    float paths = 0.0f;
    uint64_t shadows = 0;
    vec3 left_multiple{0.0f};
    vec3 paired_tables{0.0f};
    // Set by a deeper vertex whose field texel has no ratio (its prepass met no unoccluded
    // connection): the vertex draws its unoccluded connections' corrections itself.
    bool draw_corrections = false;
    // The field's prepass: the multiple part of the walk's surface light, which it files
    // under the deferred terms' `surface` (the field reports the split to texels reading it).
    vec3 surface_light_multiple{0.0f};
    UnoccludedSingle& operator+=(const UnoccludedSingle& o) {
        tables += o.tables;
        real += o.real;
        paths += o.paths;
        paired_tables += o.paired_tables;
        surface_light_multiple += o.surface_light_multiple;
        return *this;
    }
};

// One medium point's estimates of a connection's single scattering (BakeEstimator::
// single_correction): through the real media and geometry, and by the tables' model.
struct SingleCorrection {
    vec3 real{0.0f}, model{0.0f};
    vec3 difference() const { return real - model; }
};

class BakeEstimator {
  public:
    // `tables` is needed by Impulse only (may be null otherwise).
    BakeEstimator(const RayScene& scene, const Media& media, const ImpulseTables* tables,
                  BakeMethod method, const BakeSettings& settings);
    // Impulse: every medium's g within the tables' |g| <= kGRange, or an Error naming
    // media[i].g (run by the constructor and by every bake pass: sliders change media).
    void check_media() const;
    // Impulse: path vertices deeper than bake.lit_medium_depth read the texels' Monte Carlo
    // terms from `field` (volume/vertex_corrections.h; null: the tables alone). Not owned.
    // Sets whether the texels read it too (bake.texel_terms = field, texel_surface_light = walk;
    // not the prepass's own estimator).
    void set_vertex_corrections(const VertexCorrectionField* field);
    // Whether a texel's Monte Carlo terms come from the field (estimate_texel).
    bool texel_reads_field() const { return texel_reads_field_; }
    const VertexCorrectionField* vertex_corrections() const { return corrections_; }
    // The field's prepass (vertex_corrections.cpp): at the texel no indirect segment runs, and
    // the walk's surface light, the surface it reaches evaluated at `surface_light_depth`, is
    // filed under the deferred terms' `surface`, apart from the emitters' terms.
    void set_field_prepass(int surface_light_depth) {
        prepass_surface_depth_ = surface_light_depth;
    }
    // An emitter connection that brings no direct light (occluded, or below the horizon).
    struct OccludedConnection {
        bool occluded = false;
        vec3 multiple{0.0f};  // the unoccluded response's orders 3 and up (for add_lit_medium)
    };
    // The part of a texel's paths that is the same for every one of them: the direct light of
    // point and directional lights at the texel itself (no random number decides it), computed
    // on the first path and added to the others (not with ratio tracking, which draws).
    struct FixedDirect {
        bool known = false;
        IrradianceParts parts;
        // Impulse: the point and directional lights whose connection is occluded, and how;
        // their Monte Carlo terms draw random numbers, so they run on every path.
        std::vector<std::pair<int, OccludedConnection>> occluded;
        uint64_t shadows = 0;  // shadow_bit of every point and directional light not seen
    };
    // Irradiance at p (normal n, albedo of the receiver for back-scatter): one path. `fixed`,
    // when given, is this point's FixedDirect, filled by the first call. `deferred`, when
    // given, receives the texel's Monte Carlo terms through the real media instead of the
    // result (the baker filters them over neighbouring texels; without it they are added).
    // mc_rate > 0: the rate of the receiver's Monte Carlo terms instead of
    // bake.texel_mc_rate (texel_filter.h's texel_mc_rates). `unoccluded`, when given, receives
    // the receiver's UnoccludedSingle (the field's prepass, the baker's texels) and its
    // single-scattering corrections, which are then not in the result.
    IrradianceParts estimate(const vec3& p, const vec3& n, const vec3& albedo, CounterRng& rng,
                             BakeCounters& counters, FixedDirect* fixed = nullptr,
                             IrradianceParts* deferred = nullptr, float mc_rate = -1.0f,
                             UnoccludedSingle* unoccluded = nullptr) const;

    // One path of texel `texel` of lightmap `map` (its LightmapTexel t), as the baker runs it
    // and texel_estimate re-runs it: estimate(), or where the texel reads the field
    // (texel_reads_field) its value there added to a path without Monte Carlo terms, as a
    // deeper vertex does (deferred and unoccluded then receive nothing).
    IrradianceParts estimate_texel(const LightmapTexel& t, size_t map, size_t texel,
                                   CounterRng& rng, BakeCounters& counters, FixedDirect* fixed,
                                   IrradianceParts* deferred, float mc_rate,
                                   UnoccludedSingle* unoccluded) const;

    BakeMethod method() const { return method_; }
    const BakeSettings& settings() const { return settings_; }
    // The shadow_bit of every point and directional light (p, n) does not see: what a first
    // path learns in FixedDirect::shadows, for the shadow rays alone.
    uint64_t fixed_light_shadows(const vec3& p, const vec3& n, BakeCounters& counters) const;

    // Incident radiance at a probe p as order-3 SH (9 RGB coefficients per part): one path.
    struct ProbeParts {
        std::array<vec3, 9> surface{}, single{}, multiple{};
    };
    ProbeParts estimate_probe(const vec3& p, CounterRng& rng, BakeCounters& counters) const;

    // One texel's record as text: every emitter sample with its segment (length, optical
    // thicknesses, transmittance, effective medium) and, for impulse, the ZH components of
    // its response (order 11, about the axis to the emitter) and the irradiance they give.
    std::vector<std::string> trace_texel(const vec3& p, const vec3& n, const vec3& albedo,
                                         CounterRng& rng) const;

    // Node tables built so far for segments through several media (impulse_irradiance.h).
    size_t mixture_tables() const { return irradiance_ ? irradiance_->blend_nodes() : 0; }

  private:
    struct EmitterSample {
        EmitterKind kind = EmitterKind::Point;
        vec3 dir{0.0f};  // from the receiver towards the emitter, unit
        double distance = std::numeric_limits<double>::infinity();  // infinity: distant
        vec3 irradiance{0.0f};      // at normal incidence, before transmittance and visibility
        vec3 intensity{0.0f};       // the tables' emitter strength (I, E0 or L x area)
        vec3 emitter_normal{0.0f};  // area emitters
        double shift = 0.0;         // area emitters: sin(angle of the emitter normal to -dir)
        bool fixed = false;         // a point or directional light: the same for every path
        bool behind = false;        // impulse: p behind the quad light (lit medium only)
        int light = -1;             // index in the scene's lights
    };
    // A point x = o + t w of the media in front of the receiver: w cosine-sampled about n, t by
    // a free flight at the ray's mean extinction or, given an emitter point, equiangular about
    // it; pdf is t's. check_path: geometry may lie between o and x.
    struct MediumPoint {
        bool valid = false;
        vec3 o{0.0f}, w{0.0f}, x{0.0f};
        double t = 0.0, pdf = 0.0;
        bool check_path = true;
        double t_end = 0.0;  // the drawn part of the ray: to the media's exit or first surface
        HomogeneousMedium here{0.0, 0.0, 0.0};
        double direction_weight = 3.14159265358979323846;  // cos / pdf of w (pi: the cosine)
    };
    // Light of one emitter sample scattered into (p, n) by the lit medium around p, for a
    // connection the tables cannot take (occluded, or below the horizon): one point x_t drawn
    // along a cosine-sampled direction w (a forced collision of the real media for distant
    // emitters, equiangular about the emitter point otherwise), a shadow ray from x_t to the
    // emitter and one from p to x_t when geometry may lie between them; the single-scattered
    // irradiance pi T(p, x_t) sigma_s(x_t) f_HG E(x_t) T(x_t, emitter) V / pdf(t), unbiased for
    // single scattering through the real (heterogeneous, bounded) media and geometry.
    struct LitMediumSample {
        bool in_medium = false;  // a point was drawn inside the media
        bool seen = false;       // it sees the receiver
        bool lit = false;        // it sees the emitter and the receiver
        vec3 single{0.0f};       // the irradiance estimate
        vec3 multiple{0.0f};     // order 2 through it (second_scatter)
    };
    // An emitter sample seen from a point x (emitter: its point, unused for distant ones).
    struct EmitterSeen {
        bool valid = false;
        vec3 l{0.0f};                                               // towards the emitter
        double distance = std::numeric_limits<double>::infinity();  // shadow ray length
        double to_emitter = 0.0;  // the transmittance's length (media exit for distant)
        vec3 strength{0.0f};      // what reaches x before the medium (E0, or I / d^2 x emission)
    };
    EmitterSeen emitter_seen(const EmitterSample& s, const vec3& emitter, const vec3& x) const;
    // Light scattered twice, the second time at x, towards the receiver (along -w): one more
    // point x2 by HG sampling about w and a free flight through the real media and geometry,
    // NEE from x2 to the emitter. radiance x sigma_s(x) is unbiased for order 2 through x.
    struct SecondScatter {
        vec3 radiance{0.0f};
    };
    // Order 2 through the medium point m (seen by the receiver) into r.multiple; to_receiver:
    // T(p, m.x) when known.
    void add_second_scatter(const EmitterSample& s, const vec3& emitter, const MediumPoint& m,
                            CounterRng& rng, BakeCounters& counters, LitMediumSample& r,
                            double to_receiver = -1.0) const;
    SecondScatter second_scatter(const EmitterSample& s, const vec3& emitter, const vec3& x,
                                 const vec3& w, const HomogeneousMedium& here, CounterRng& rng,
                                 BakeCounters& counters) const;
    // A distant emitter's unoccluded connection: the lit medium's single scattering through
    // the real media and geometry (`real`, unbiased and >= 0) and the tables' model of it
    // (`model`) on the same draw. Their difference is a control variate: the tables' value
    // plus it is unbiased for single scattering, up to the tables' ZH error.
    SingleCorrection single_correction(const EmitterSample& s, const vec3& p, const vec3& n,
                                       CounterRng& rng, BakeCounters& counters) const;
    // The same for a point or area emitter sample (the tables' infinite-medium model).
    SingleCorrection local_single_correction(const EmitterSample& s, const vec3& p, const vec3& n,
                                             CounterRng& rng, BakeCounters& counters) const;
    // Whichever of the two the sample's distance calls for.
    SingleCorrection connection_single_correction(const EmitterSample& s, const vec3& p,
                                                  const vec3& n, CounterRng& rng,
                                                  BakeCounters& counters) const {
        return std::isfinite(s.distance) ? local_single_correction(s, p, n, rng, counters)
                                         : single_correction(s, p, n, rng, counters);
    }
    // whole_ray (with an emitter): t equiangular over [0, infinity); valid only before t_end.
    // w by the cosine, or by `directions` (receiver_directions.h).
    MediumPoint draw_medium_point(const vec3& p, const vec3& n, const vec3* emitter,
                                  CounterRng& rng, BakeCounters& counters, bool whole_ray = false,
                                  const ReceiverDirections* directions = nullptr) const;
    bool sees_receiver(const MediumPoint& m, BakeCounters& counters) const;
    // Light reflected by surfaces the receiver cannot see, scattered once in the medium in
    // front of it towards it: x by draw_medium_point, HG sampling at x to a surface y, y's
    // radiance from its own direct light and the media's response (the last vertex of a
    // surface path); order 2 of y's light through the in-medium area response at x.
    struct ScatteredSurfaceLight {
        vec3 single{0.0f}, multiple{0.0f};
    };
    ScatteredSurfaceLight surface_light_scattered(const vec3& p, const vec3& n, CounterRng& rng,
                                                  BakeCounters& counters) const;
    // sigma_s-less radiance scattered at a medium point towards -w of the in-medium single
    // response there to a differential-area emitter seen along l at `distance`: the phase
    // (anisotropy g_here) convolved with the response (Funk-Hecke).
    vec3 area_response_rescattered(const vec3& intensity, const vec3& l, double distance,
                                   const vec3& emitter_normal, const SegmentOptics& optics,
                                   double g_here, const vec3& w, BakeCounters& counters) const;
    LitMediumSample lit_medium_single(const EmitterSample& s, const vec3& p, const vec3& n,
                                      CounterRng& rng, BakeCounters& counters) const;
    // The tables' scattered response for the connection as if it were unoccluded, at a
    // receiver of normal n: its single
    // and multiple irradiance (the ratio scales the lit-medium estimate into multiple
    // scattering: the lit medium's visibility, single's estimate over the tables' single,
    // applied to the broad multiple-scattering lobe).
    IrradianceParts unoccluded_scatter(const EmitterSample& s, const vec3& p, const vec3& n,
                                       float albedo_lum, CounterRng& rng,
                                       BakeCounters& counters) const;
    // The tables' scattering orders 3 and up for the connection as if it were unoccluded (order
    // 2 of an occluded connection is second_scatter's).
    vec3 unoccluded_higher_orders(const EmitterSample& s, const vec3& p, const vec3& n,
                                  float albedo_lum, CounterRng& rng, BakeCounters& counters) const;
    void sample_emitters(const vec3& p, CounterRng& rng, std::vector<EmitterSample>& out) const;
    // corrected: the caller adds the vertex correction field's value at p (which holds the
    // walk's multiple scattering of the emitters, so the tables' is left out).
    IrradianceParts surface_path(const vec3& p, const vec3& n, const vec3& albedo, int depth,
                                 CounterRng& rng, BakeCounters& counters,
                                 FixedDirect* fixed = nullptr, IrradianceParts* deferred = nullptr,
                                 bool corrected = false, float mc_rate = -1.0f,
                                 UnoccludedSingle* unoccluded = nullptr) const;
    // A surface vertex at depth `depth` reached by a ray (hit): its surface_path plus, when the
    // vertex correction field covers it, the field's value (added to the single part: it is
    // in-scattered light). What indirect segments and walks take as the vertex's irradiance.
    IrradianceParts vertex_irradiance(const SurfaceHit& hit, const vec3& albedo, int depth,
                                      CounterRng& rng, BakeCounters& counters,
                                      IrradianceParts* deferred = nullptr) const;
    // A vertex (or texel) that reads the field at `field`: its surface_path without the
    // Monte Carlo terms the field holds, plus the field's value where it holds for the
    // vertex's shadows (else the tables' multiple scattering kept aside). The one copy of
    // vertex_irradiance's and estimate_texel's reading; *read gets what it added.
    struct FieldRead {
        bool holds = false;
        bool drew_corrections = false;  // no ratio there: the vertex drew its own corrections
        vec3 added{0.0f};
    };
    IrradianceParts field_corrected_path(const VertexCorrectionField::Texel& field, const vec3& p,
                                         const vec3& n, const vec3& albedo, int depth,
                                         CounterRng& rng, BakeCounters& counters,
                                         FixedDirect* fixed, IrradianceParts* deferred,
                                         FieldRead& read) const;
    // The path's segment from (p, n) to the next surface vertex and that vertex's light, into
    // parts; correction (when given) gets the segment's single-scattering correction; the
    // next vertex's deferred terms, carried to p, go to *deferred (when given); scatter: the
    // vertex's light scattered on the segment (tables), else only its transmitted light.
    void indirect_segment(const vec3& p, const vec3& n, float albedo_lum, int depth,
                          CounterRng& rng, BakeCounters& counters, IrradianceParts& parts,
                          vec3* correction, IrradianceParts* deferred, bool scatter = true) const;
    // Direct light of one emitter sample at (p, n): visibility, transmittance and, for impulse,
    // its scattered response, added to parts.
    // Returns false when the connection is occluded or below the horizon; then, for impulse,
    // *occluded (when given) is marked, with the unoccluded response's orders 3 and up.
    bool direct_light(const EmitterSample& s, const vec3& p, const vec3& n, float albedo_lum,
                      CounterRng& rng, BakeCounters& counters, IrradianceParts& parts,
                      OccludedConnection* occluded = nullptr, bool no_multiple = false) const;
    // The lit-medium estimate of an occluded connection, added to parts: its single
    // scattering and order 2 (lit_medium_single), and the unoccluded orders 3 and up.
    void add_lit_medium(const EmitterSample& s, const vec3& p, const vec3& n,
                        const vec3& higher_orders, CounterRng& rng, BakeCounters& counters,
                        IrradianceParts& parts, bool no_multiple = false) const;
    // The Monte Carlo terms' roulette (volume/emitter_roulette.h): an emitter sample's strength
    // at the receiver (I / d^2, or E when distant), whether a connection has a term (an
    // occluded one's lit medium, a visible one's single-scattering correction), and each
    // emitter's keep probability at a vertex (1 for a vertex with one term).
    static float emitter_strength(const EmitterSample& s);
    bool has_mc_term(const EmitterSample& s, const OccludedConnection& c, const vec3& n) const;
    // Each emitter's keep probability over those has(i) picks (the rest keep 1).
    template <class Has>
    void emitter_keep(const std::vector<EmitterSample>& emitters, Has has,
                      std::vector<float>& keep) const;
    // Each point light's keep probability from strength_of(light), in scene order, against the
    // distant lights' strength `competing` (emitter_roulette.h); empty (every light kept, no
    // number drawn) with fewer than two of them or budget 0.
    template <class Strength>
    void point_light_keep(Strength strength_of, float competing, std::vector<float>& keep) const {
        keep.clear();
        const bool distant = competing > 0.0f && std::isfinite(competing);
        if (point_lights_ + (distant ? 1 : 0) < 2 || !(settings_.mc_emitter_budget > 0.0f)) return;
        thread_local std::vector<float> strength;
        strength.clear();
        for (const Light& light : scene_.scene().lights)
            if (light.type == LightType::Point) strength.push_back(strength_of(light));
        if (distant) strength.push_back(competing);
        emitter_keep_probabilities(strength, settings_.mc_emitter_budget, keep);
        keep.resize(size_t(point_lights_));
    }
    std::vector<float> mc_keep(const std::vector<EmitterSample>& emitters,
                               const std::vector<OccludedConnection>& occluded,
                               const vec3& n) const;
    // trace_texel's lines for an occluded connection.
    template <class Line>
    void trace_occluded(const EmitterSample& s, const vec3& p, const vec3& n, const vec3& albedo,
                        CounterRng& rng, Line& line) const;
    IrradianceParts volume_path(const vec3& p, const vec3& n, CounterRng& rng,
                                BakeCounters& counters) const;
    // What a texel's walk gathers (walk's media_only mode): it ends at the first surface.
    struct TexelWalk {
        // Emitters' light scattered twice or more (NEE from the second scattering event on).
        bool emitters_multiple = true;
        // >= 0: where the walk reaches a surface after scattering, that surface's light (its
        // surface_path at this depth: direct light, tables, bounces), into *surface_light
        // (single: scattered once; multiple: more). -1: none.
        int surface_light_depth = -1;
        IrradianceParts* surface_light = nullptr;
    };
    // VPT's random walk from pos along dir: free flights, scattering in media (NEE, HG),
    // diffuse bounces on surfaces; what arrives back at pos, times `throughput`.
    // texel (when given): only what the media scatter between pos and the first surface
    // (TexelWalk; no emitter's single scattering is gathered).
    IrradianceParts walk(vec3 pos, vec3 dir, vec3 throughput, CounterRng& rng,
                         BakeCounters& counters, const TexelWalk* texel = nullptr) const;
    // The walk's last scattering event (bake_surface_light.cpp).
    struct WalkScatter {
        vec3 x{0.0f}, dir_in{0.0f};  // where, and the walk's direction of travel arriving there
        double g = 0.0;
        float survive = 1.0f;  // the roulette's chance that the walk's next segment is traced
        bool aimed = false;    // its next direction was drawn with NearLightDirections
    };
    // walk's TexelWalk surface light at the surface it ends on, coming from the scattering
    // event `from`; with bake.surface_light_mis, less the share of point-lit light that
    // point_lit_surface_light takes.
    void add_walk_surface_light(const SurfaceHit& hit, int chain, const vec3& throughput,
                                const TexelWalk& texel, const WalkScatter& from, CounterRng& rng,
                                BakeCounters& counters) const;
    // bake.surface_light_mis: the light of surfaces lit by point lights scattered at `at`
    // towards the walk's origin, by light tracing (one ray from each point light), weighted
    // against the walk's own landing on the same point (power heuristic).
    vec3 point_lit_surface_light(const WalkScatter& at, CounterRng& rng,
                                 BakeCounters& counters) const;
    // The point light's irradiance at y (shading normal ns) and the densities of y under
    // light tracing from it and under the walk from `from` (area measure); false when the
    // light does not reach y's side.
    struct PointLitPoint {
        vec3 irradiance{0.0f};
        double light_pdf = 0.0, walk_pdf = 0.0;  // densities of y (area measure)
        // The path's factor from x to y: phase x transmittance x cos_y / r^2 (walk_pdf without
        // the roulette, when the walk's direction is the phase function's alone).
        double walk_f = 0.0;
        vec3 to_y{0.0f};  // unit, from the scattering event to y
        float distance = 0.0f;
    };
    bool point_lit_point(const Light& light, const SurfaceHit& y, const WalkScatter& from,
                         bool check_visibility, BakeCounters& counters, PointLitPoint* out) const;
    bool surface_light_mis() const;
    // Light of the scene's point lights scattered once anywhere on the segment o + t d,
    // t < t_max, towards o: equiangular sampling, since collision-point NEE to a point light
    // has infinite variance in a medium (1/r^2 near the light).
    vec3 point_lights_along(const vec3& o, const vec3& d, double t_max, CounterRng& rng,
                            BakeCounters& counters) const;
    // Scattered irradiance at (p, n) from an emitter of strength `intensity` seen along `dir`
    // at `distance` (the table's normalisation), through the segment's effective medium.
    void add_scattered(EmitterKind kind, const vec3& intensity, const vec3& dir, double distance,
                       double shift, const vec3& emitter_normal, const SegmentOptics& optics,
                       const vec3& n, float albedo_lum, IrradianceParts& out,
                       BakeCounters& counters, int last_bounce_cap = 0) const;
    // An area emitter's single-scattered lobe axis: l tilted by `tilt` towards the part of the
    // emitter's normal across l (area_tables.h).
    static glm::dvec3 tilted_axis(const glm::dvec3& l, const vec3& emitter_normal, double tilt);
    // A path segment's optics, exact or by ratio tracking (BakeSettings::tracking).
    SegmentOptics segment_optics(const vec3& p, const vec3& dir, double length,
                                 CounterRng& rng) const;
    // The tabulated double products for a segment's effective medium (null: query directly).
    const ImpulseIrradiance* irradiance_table(double g, double albedo, int last_bounce) const;
    // One table's scattered irradiance per unit strength (add_scattered's lookup).
    static ScatteredIrradiance tabulated_scattered(const ImpulseIrradiance& table,
                                                   const ImpulseIrradiance::At& D, EmitterKind kind,
                                                   const vec3& dir, double shift,
                                                   const vec3& emitter_normal, const vec3& n,
                                                   float cos_light);
    bool visible(const vec3& from, const vec3& n, const vec3& dir, double distance,
                 BakeCounters& counters) const;
    // Whether (p, n) sees emitter sample s: above its horizon, in front of it, unoccluded.
    bool seen(const EmitterSample& s, const vec3& p, const vec3& n, BakeCounters& counters) const;
    vec3 origin(const vec3& p, const vec3& n) const;
    // Walks aim some directions past point lights (volume/near_light_directions.h).
    bool aims_at_point_lights() const;
    // A walk's next direction from x: the cosine about the surface normal `axis` (g null) or
    // HG(*g) about the direction of travel `axis`, mixed with NearLightDirections when `aim`.
    // `weight`: the walk's throughput factor (f / pdf; pi for the cosine: irradiance). False:
    // no direction (the walk ends).
    bool sample_walk_direction(const vec3& x, const vec3& axis, const double* g, bool aim,
                               CounterRng& rng, vec3* dir, float* weight) const;
    // The texel walk from p (the bake's and trace_texel's one copy): a cosine-sampled first
    // direction, then walk() in TexelWalk mode.
    IrradianceParts texel_walk_from(const vec3& p, const vec3& n, CounterRng& rng,
                                    BakeCounters& counters, const TexelWalk& texel) const;
    // Impulse's texel vertices take their multiple scattering from a walk (BakeSettings).
    bool texel_walk() const;
    // ... and the in-scattered light of other surfaces (BakeSettings::texel_surface_light).
    bool surface_light_walk() const;

    const RayScene& scene_;
    const Media& media_;
    const ImpulseTables* tables_;
    BakeMethod method_;
    BakeSettings settings_;
    NearLightDirections near_lights_;
    int table_bounces_ = 1;
    // What the method does with media on a segment (fixed at construction: which media exist
    // never changes, only their coefficients): attenuate it (extinction, impulse, and vpt's
    // probes' direct light) and add its scattered response (impulse).
    bool attenuates_ = false, scatters_ = false;
    const VertexCorrectionField* corrections_ = nullptr;
    bool texel_reads_field_ = false;
    int prepass_surface_depth_ = -1;
    std::unique_ptr<ImpulseIrradianceCache> irradiance_;  // impulse: tabulated double products
    int point_lights_ = 0;           // the scene's (their roulette needs two or more)
    float distant_strength_ = 0.0f;  // D of emitter_roulette.h, when the estimator is built
    // Scenes with one medium: its table and the Media::version() it was resolved at.
    mutable std::atomic<const ImpulseIrradiance*> single_table_{nullptr};
    mutable std::atomic<uint64_t> single_version_{~uint64_t(0)};
    double cosine_zh_[kImpulseOrder];
};

// Used by the texel terms (bake_lit_medium.cpp) and the walks (bake_walk.cpp).
template <class Has>
void BakeEstimator::emitter_keep(const std::vector<EmitterSample>& emitters, Has has,
                                 std::vector<float>& keep) const {
    thread_local std::vector<float> strength;
    strength.assign(emitters.size(), 0.0f);
    size_t count = 0;
    for (size_t i = 0; i < emitters.size(); ++i)
        if (has(i)) {
            strength[i] = emitter_strength(emitters[i]);
            ++count;
        }
    // One emitter with a term is kept for sure, whatever the others (which have none).
    emitter_keep_probabilities(strength, count > 1 ? settings_.mc_emitter_budget : 0.0f, keep);
}

}  // namespace freqlab
