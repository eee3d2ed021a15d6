// Method B's lightmap bake as a progressive, deterministic, cancellable job (issue "Method B,
// part 2"; DESIGN.md "Method B: one bake"). Texels are laid out once (volume/lightmap_atlas.h);
// each pass adds paths per texel to running sums, so a preview appears after the first pass and
// refines. Random numbers are keyed by (seed, lightmap, texel, sample): a bake is identical for
// any thread count and any split into passes.
//
// Layers per lightmap (atlas resolution): lm_total (the lightmap: outgoing radiance,
// albedo / pi x E), lm_irradiance (E), and E split by what carried it: lm_surface,
// lm_inscatter_single, lm_inscatter_multiple (irradiance, so that a black receiver still shows
// them; they sum to lm_irradiance), texel_valid (categorical).
#pragma once

#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/job.h"
#include "image/layers.h"
#include "image/metrics.h"
#include "volume/bake_estimators.h"
#include "volume/lightmap_atlas.h"
#include "volume/lightmap_error.h"
#include "volume/texel_filter.h"
#include "volume/vertex_corrections.h"

namespace freqlab {

struct BakeStats {
    double atlas_ms = 0.0, tables_ms = 0.0, bake_ms = 0.0;
    double corrections_ms = 0.0;  // the vertex correction field's prepass (in bake_ms too)
    // Of which tracing its geometry (straddle and cover rays; 0 where a re-bake kept it).
    double correction_geometry_ms = 0.0;
    int correction_paths = 0;        // its paths per texel (0: no field)
    long correction_texels = 0;      // texels whose prepass ran
    long correction_paths_run = 0;   // their paths (more where few share their surface)
    long correction_straddling = 0;  // field texels crossed by geometry (lookups test them)
    // Impulse: where the texels' Monte Carlo terms came from (bake.texel_terms as it ran:
    // "own", or "field" where the field was built and may lend them); "" other methods.
    std::string texel_terms;
    long rays = 0, impulse_queries = 0, guarded = 0;
    // Impulse: node tables built for segments through several media (this process's,
    // ImpulseIrradianceCache::blend; not summed across a cluster's ranks).
    long mixture_tables = 0;
    long texels_valid = 0, texels_invalid = 0, texels_total = 0;
    int samples = 0;
    double storage_mb = 0.0;   // the bake's own arrays (atlases, sums, probes)
    double peak_rss_mb = 0.0;  // the process's peak resident memory at the last pass's end
    // Densities the atlases could not honour and objects left without one (build_lightmaps).
    std::vector<std::string> atlas_notes;
    nlohmann::json to_json() const;
};

class LightmapBaker {
  public:
    // Builds the atlases now; `tables` is needed for BakeMethod::Impulse when media exist.
    LightmapBaker(const RayScene& scene, const Media& media, const ImpulseTables* tables,
                  BakeMethod method, const BakeSettings& settings);

    // Adds `samples` paths to every valid texel (progress: one unit per row of texels).
    void run_pass(int samples, Progress* progress = nullptr);
    // Passes until settings.spp samples (first pass: 1 sample, then doubling).
    void run(Progress* progress = nullptr);
    // Forget the sums (after a media change); the atlas stays.
    void reset();

    // A bake split across processes (app/cluster.h): share `index` of `count` computes the texel
    // rows r (numbered over the lightmaps in order) and probes i with r, i = index (mod count);
    // their sums are what one process computes there, bit for bit. encode_share() is this
    // process's rows and probes as bytes (with its counters); add_share() stores another
    // share's into this baker, after which layers() and probes() are the whole bake's. The
    // vertex correction field is built whole by every share (deeper vertices read any texel).
    void set_share(int index, int count);
    std::string encode_share() const;
    void add_share(const std::string& bytes, int index, const std::string& source);

    int samples() const { return samples_; }
    // Light probes: positions and their mean order-3 SH of incident radiance per part.
    struct Probe {
        vec3 position{0.0f};
        std::array<vec3, 9> surface{}, single{}, multiple{};
    };
    std::vector<Probe> probes() const;
    nlohmann::json probes_json() const;  // grid, order, and per probe position + SH
    const std::vector<ObjectLightmap>& lightmaps() const { return maps_; }
    LayerSet layers(size_t lightmap) const;
    // Every lightmap's layers, in lightmaps() order.
    std::vector<LayerSet> all_layers() const;
    const BakeStats& stats() const { return stats_; }
    BakeMethod method() const { return method_; }
    const BakeEstimator& estimator() const { return estimator_; }
    // The field deeper vertices read (built by the first pass; empty before, or when unused).
    const VertexCorrectionField* vertex_corrections() const { return corrections_.get(); }

  private:
    const RayScene& scene_;
    const Media& media_;
    const ImpulseTables* tables_;
    BakeEstimator estimator_;
    BakeMethod method_;
    BakeSettings settings_;
    std::vector<ObjectLightmap> maps_;
    // Per lightmap, per texel: surface, single, multiple (RGB each) summed over samples.
    std::vector<std::vector<IrradianceParts>> sums_;
    // The same for the texels' deferred Monte Carlo terms (impulse), filtered over
    // neighbouring texels when the layers are made (volume/texel_filter.h); empty before the
    // first pass and where the texels read the vertex correction field.
    std::vector<std::vector<IrradianceParts>> deferred_sums_;
    // And their single-scattering corrections, filtered as a ratio (texel_filter.h); empty
    // unless files_single_corrections().
    std::vector<std::vector<SingleCorrectionSums>> single_sums_;
    // Per lightmap, per texel: its paths' total luminance squared, summed (the filter's guide
    // reads the variance of the texel's light from it: texel_filter.h).
    std::vector<std::vector<float>> light_squares_;
    // Per lightmap, per texel: the rate of its Monte Carlo terms (texel_filter.h), made by the
    // first pass for the filter's radius then (mc_rates_radius_).
    std::vector<std::vector<float>> mc_rates_;
    int mc_rates_radius_ = -1;
    // Sizes deferred_sums_ / single_sums_ and makes mc_rates_: the first pass's, once the
    // estimator knows whether its texels read the vertex correction field.
    void size_texel_terms();
    // Per lightmap, per texel: its paths' shared direct light (BakeEstimator::FixedDirect).
    std::vector<std::vector<BakeEstimator::FixedDirect>> fixed_;
    std::unique_ptr<VertexCorrectionField> corrections_;
    // The field's geometry, kept by reset(): a media change re-runs its prepass, not its rays.
    std::shared_ptr<const VertexCorrectionField::Geometry> field_geometry_;
    std::vector<vec3> probe_positions_;
    ivec3 probe_grid_{0};  // the probes laid out (0: none, e.g. a scene without geometry)
    std::vector<BakeEstimator::ProbeParts> probe_sums_;
    int samples_ = 0;
    BakeStats stats_;
    int share_index_ = 0, share_count_ = 1;
    // Other shares' texels: which lights' connections are occluded (the filter's guide, which
    // a share's own texels read from fixed_).
    std::vector<std::vector<uint64_t>> share_shadows_;
    // Whether global texel row `row` / probe `probe` belongs to share `index`.
    bool in_share(long row, int index) const { return row % share_count_ == index; }
    // row_fn(lightmap, first texel, texels) for each texel row of share `index`, then
    // probe_fn(probe) for each of its probes: what a share's bytes hold, in their order.
    template <class RowFn, class ProbeFn>
    void for_each_in_share(int index, RowFn row_fn, ProbeFn probe_fn) const;
};

// The random numbers of sample `sample` of texel `texel` of lightmap `lightmap` (probes: lightmap
// index = the number of lightmaps): the one key the bake, --debug-texel and the workbench's
// texel trace share, so that a trace re-runs the bake's own paths.
inline CounterRng texel_random(int seed, size_t lightmap, size_t texel, int sample) {
    return CounterRng(uint64_t(seed), lightmap, texel, uint64_t(sample));
}

// The mean of paths 0 .. spp-1 of `estimator` at texel `texel` of lightmap `lightmap` (of `maps`)
// under the bake's keys: what a bake with that estimator and seed stores there (up to the order
// of the additions), impulse's deferred terms filtered over the same neighbours (re-run here).
// --debug-texel prints it for every method, with `filter` when given: the texel's Monte Carlo
// rate (texel_mc_rates) and how many texels its filter averaged (itself included).
struct TexelFilterUse {
    float mc_rate = 0.0f;
    int texels = 0;
    // The texel's own paths as the bake ran them (what each one's Monte Carlo terms brought),
    // its sums, and what the filter made of its deferred terms (its window's mean, with the
    // single-scattering corrections' ratio over the window times the texel's own tables).
    std::vector<TexelPathRecord> paths;
    IrradianceParts sum, deferred, filtered;
    vec3 tables_single{0.0f}, ratio_correction{0.0f};
};
IrradianceParts texel_estimate(const BakeEstimator& estimator,
                               const std::vector<ObjectLightmap>& maps, size_t lightmap,
                               size_t texel, int seed, int spp, TexelFilterUse* filter = nullptr);

// The scene's lightmap name for file output: "<object name>" or "object<i>".
std::string lightmap_name(const Scene& scene, const ObjectLightmap& map);

}  // namespace freqlab
