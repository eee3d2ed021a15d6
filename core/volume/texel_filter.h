// The filter of a lightmap's deferred Monte Carlo terms (issue "Method B, part 3"): impulse's
// corrections through the real media at a texel (single scattering the tables' model misses,
// the lit medium below the horizon, hidden surfaces' light, the multiple-scattering walk) are
// smooth over the surface, but at bake.texel_mc_rate of the paths their per-texel estimate is
// noisy. Each texel takes the mean of the texels within `radius` of it in the atlas that lie
// on its own surface (valid, normals within ~25 degrees, covered alike (lightmap_atlas.h: the
// ground under a floor apart from the open ground beside it, as in the vertex field's neighbour
// means), world distance within the window's, so that a neighbouring chart across a gutter
// never mixes in) and on the same side of every point or directional light's shadow: those
// terms jump there (the lit medium of an occluded connection stands in for the tables'
// response plus a correction), their sum with the unfiltered tables' part does not. Last, the
// texels' unfiltered light (direct and tables, summed at every path) must agree within
// kTexelFilterLightRatio: a texel in a crack under a box sees little of the medium that lights its
// open neighbours. Those sums are estimates: their difference may also be within
// kTexelFilterLightSigmas standard deviations of it (each sum's variance from its paths' squared
// light; a sum of one path has none) when their scattered light (the tables' part, how much lit
// medium they see) agrees within the ratio. The first version compared the sums alone, and at dark
// texels one path of 16 catching a lit wall split them: valley's terrain texels in the gaps under
// houses were filtered over 1-3 texels, where their walks' rare escapes through the gap weighed 1 /
// texel_mc_rate alone (1.4 and 2.7 where VPT reads 0.004 and 0.0025). Comparing their scattered
// light instead (the tables' part, not noisy there) joined them, but also joined the closed
// cavities of layered walls (no light at all) with the rooms beside them (houses' relMSE x3); the
// noise alone joined dark texels under houses with noisy neighbours that see the lit medium
// (house10 texels at 0.26 where VPT reads 0). radius 0 keeps every texel's own estimate (unbiased
// per texel); a radius trades that for (2 radius + 1)^2 times the samples, with the bias of a box
// blur of a smooth field.
//
// | parameter | meaning                                                    |
// |-----------|------------------------------------------------------------|
// | radius    | half-width of the window, texels (bake.texel_mc_radius)    |
#pragma once

#include <vector>

#include "volume/bake_estimators.h"
#include "volume/lightmap_atlas.h"

namespace freqlab {

constexpr float kTexelFilterLightRatio = 1.5f;
constexpr float kTexelFilterLightSigmas = 2.0f;

// What the filter compares texels by, one entry per texel.
struct TexelFilterGuide {
    std::vector<uint64_t> shadows;  // a bit per point / directional light the texel sees occluded
    std::vector<float> light;       // luminance of the texel's unfiltered sum
    std::vector<float> variance;    // that sum's estimated variance (empty: none known)
    std::vector<float> scattered;   // luminance of its tables' single and multiple scattering
    static TexelFilterGuide sized(size_t n) {
        return {std::vector<uint64_t>(n, 0), std::vector<float>(n, 0.0f),
                std::vector<float>(n, 0.0f), std::vector<float>(n, 0.0f)};
    }
};
// The bits of the point and directional lights a texel's fixed direct light found occluded.
uint64_t texel_shadow_bits(const BakeEstimator::FixedDirect& fixed);
// Texel i's entry: its occluded fixed lights, the luminance of its unfiltered sum of `paths`
// paths and, from `light_squares` (the sum of their luminances squared), that sum's variance.
void set_texel_filter_guide(TexelFilterGuide& guide, size_t i,
                            const BakeEstimator::FixedDirect& fixed, const IrradianceParts& sum,
                            float light_squares = 0.0f, int paths = 1);
// One path's estimate added to a texel's sum and to the sum of its paths' squared luminance
// (what set_texel_filter_guide reads the sum's variance from).
inline void add_texel_path(const IrradianceParts& path, IrradianceParts& sum,
                           float& light_squares) {
    sum += path;
    const float light = luminance(path.total());
    light_squares += light * light;
}
// Whether texels i and j's unfiltered light agrees (the filter's last test).
bool texel_lights_agree(const TexelFilterGuide& guide, size_t i, size_t j);
// The radius the baker filters `estimator`'s deferred terms with (0 unless impulse).
int texel_filter_radius(const BakeEstimator& estimator);
struct SingleCorrectionSums;
// The filtered sums, one per texel (invalid texels: zero). sums.size() == map.texels.size().
// With `single`, each texel's single scattering also gets its ratio_correction over the same
// window (radius 0: the texel alone). With `window`, how many texels each one averaged (0 for
// invalid texels).
std::vector<IrradianceParts> filter_texel_sums(
    const ObjectLightmap& map, const std::vector<IrradianceParts>& sums,
    const TexelFilterGuide& guide, int radius,
    const std::vector<SingleCorrectionSums>* single = nullptr, std::vector<int>* window = nullptr);
// The mean of sums over the texels `near` (zero when none).
IrradianceParts mean_of_texels(const std::vector<IrradianceParts>& sums,
                               const std::vector<size_t>& near);
// How many texels texel i's window can average at most: the valid ones within `radius` on its
// surface (before the bake's shadow and light-level tests). `stride` > 1: for the vertex
// correction field's prepass filter (vertex_corrections.cpp), which averages only the texels
// the prepass ran: those of the lattice of every stride-th texel in x and y, and texel i.
int texel_filter_capacity(const ObjectLightmap& map, size_t i, int radius, int stride = 1);
// The rate at which each texel runs its Monte Carlo terms: bake.texel_mc_rate x (2r + 1)^2 /
// its capacity (at most kMaxMcRateBoost times the rate, at most 1), so that a texel's filtered
// terms rest on about as many samples as a texel's amid a wide flat chart. At the plain rate
// valley's statues (small charts, curved at 1 texel/unit: windows of 1-5 like texels) took one
// lit-medium sample of the sky at weight 50 alone: 80 against VPT's 0.70, relMSE 9.9 on
// statue03 at 16 spp. valley at 1 texel/unit, 16 spp, boost at most 1 / 4 / 8 / 49: bake 6.0 /
// 7.1 / 7.3 / 9.5 s, lm_irradiance relMSE 1.16 / 0.82 / 0.74 / 0.67 (statues' rel. L2 0.63 /
// 0.36 / 0.29 / 0.19): 8 has the least error x time.
constexpr float kMaxMcRateBoost = 8.0f;
std::vector<float> texel_mc_rates(const ObjectLightmap& map, const BakeEstimator& estimator);
// A texel's single-scattering corrections of its unoccluded connections (impulse), summed
// apart from its other Monte Carlo terms: the tables' single scattering of those connections on
// every path, and the real single scattering drawn for some of them (at the texel's Monte Carlo
// rate, by emitter roulette) beside the tables' value of those same connections, weighted alike
// (UnoccludedSingle). The filter applies the ratio of the real parts to their tables, summed
// over the texel's window, to the texel's own tables: a texel in a gap under a house (its rare
// unoccluded environment samples see dark media) reads about 0, not the tables of every path
// plus one correction at weight 1 / rate (-1.5 where VPT reads 0 on valley at 4 texels/unit).
struct SingleCorrectionSums {
    vec3 tables{0.0f}, paired_tables{0.0f}, real{0.0f};
    SingleCorrectionSums& operator+=(const UnoccludedSingle& u) {
        tables += u.tables;
        paired_tables += u.paired_tables;
        real += u.real;
        return *this;
    }
};
// Where a window's paired tables fall below this share of its real single scattering, the
// tables no longer explain it (a wall whose connections graze a smoke volume it faces: paired
// tables 0.0025 against real parts 5e6 times larger on smoke_room), and the texel leans to the
// window's mean real part instead of scaling its own tables by an exploding ratio.
constexpr float kTablesExplainShare = 0.05f;
// Single scattering from one's own tables T from real parts R drawn beside tables P over n
// texels or paths: R (T + e R / n) / (P + e R) = scale T + added, e = kTablesExplainShare:
// T R / P where P >> e R, the mean R / n where P << e R; >= 0. T itself (scale 1, added 0)
// where P + e R is not positive: nothing was drawn. The texel filter's and the vertex
// correction field's one formula.
struct ExplainedSingle {
    float scale = 1.0f, added = 0.0f;
};
ExplainedSingle explained_single(float real, float paired, float count);
// Texel i's correction of its tables T, per channel, from the real parts and paired tables
// summed over `near` (n = its size): explained_single's value minus T.
vec3 ratio_correction(const std::vector<SingleCorrectionSums>& sums, size_t i,
                      const std::vector<size_t>& near);
// Texel i's filtered terms over `near`: the mean of its sums, plus with `single` its
// ratio_correction (what filter_texel_sums stores, and --debug-texel prints).
IrradianceParts filtered_texel_terms(const std::vector<IrradianceParts>& sums,
                                     const std::vector<SingleCorrectionSums>* single, size_t i,
                                     const std::vector<size_t>& near);
// The texels filter_texel_sums averages for texel i (i itself among them); with `among`, only
// the texels it flags (the vertex correction field's computed texels).
std::vector<size_t> texel_filter_neighbours(const ObjectLightmap& map,
                                            const TexelFilterGuide& guide, size_t i, int radius,
                                            const std::vector<char>* among = nullptr);

}  // namespace freqlab
