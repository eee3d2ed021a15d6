#include "volume/vertex_corrections.h"

#include <tbb/parallel_for.h>

#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "volume/bake_estimators.h"
#include "volume/lightmap_baker.h"
#include "volume/texel_filter.h"

namespace freqlab {

namespace {
// Three half floats from `h` on.
vec3 unpack_rgb(const uint16_t* h) {
    return vec3(glm::unpackHalf1x16(h[0]), glm::unpackHalf1x16(h[1]), glm::unpackHalf1x16(h[2]));
}

// The prepass runs every kFieldStride-th texel in x and y (the others take their mean), with
// kFieldPathFraction of the Monte Carlo samples a texel gets in the bake (texel_mc_rate x
// spp): an eighth of the texels' own Monte Carlo work. Measured on cornell_fog at 1024 spp
// (impulse vs VPT, 4096 spp for bias): stride 1 / fraction 1 and stride 2 / fraction 0.5 give
// the same bias (short box 0.0008 / 0.0011) and variance within the seeds' spread; the
// prepass cost sun_haze 18 % of a surface bake at stride 1, 6 % at 2 / 0.5.
constexpr int kFieldStride = 2;
constexpr double kFieldPathFraction = 0.5;
// With bake.texel_terms = field the prepass's paths are the texels' only Monte Carlo samples:
// ceil(spp x texel_mc_rate x 2.5), about the texels' own budget (spp x rate at every texel; the
// prepass runs ~40 % of them). At 0.5 the field kept 1 path up to 100 spp: valley at 1
// texel/unit, 64 spp, against VPT at 128: lm_irradiance relMSE 0.414 (own terms 0.181, 22.0 s);
// at 2.5 (4 paths) 0.291, 16.3 s against 15.9. 16 spp (the low preset): 1 path either way.
constexpr double kFieldPathFractionForTexels = 2.5;
// When the texels read the field, a computed texel's mean spans up to kFullLattice computed
// texels (the lattice within kFieldStride of a lattice texel on a flat chart); where its surface
// holds fewer (valley's statues, curved at 1 texel/unit; thin strips; the texels that run
// themselves) it runs up to kFieldMaxBoost times the paths, as the texels' own terms raise
// their rate where the bake's filter has few texels (texel_filter.h). With its 2 paths alone a
// statue05 texel at 1 texel/unit, 32 spp, held 3.2 where its converged terms are 0.18 (its
// walk's multiple scattering 3.0 against 0.064), and every path of the texel read it:
// lm_irradiance 4.19 where VPT reads 0.81. Valley, impulse against VPT (seed 0), boost at most
// 1 / 3 / 8: at 1 texel/unit, 64 spp, lit texels' relMSE 0.031 / 0.021 / 0.018, prepass 2.9 /
// 6.4 / 15.7 s of a 20-34 s bake; the low preset (4 texels/unit, 16 spp) 0.037 / 0.031 / 0.029,
// prepass 3.9 / 5.5 / 8.5 s; all texels' relMSE (their darkest, a few fireflies) 0.317 / 0.314 /
// 0.313. Without texels reading it (deeper vertices land anywhere on a surface) no boost.
constexpr int kFullLattice = 9;  // 3 x 3: the mean's radius is kFieldStride, the lattice's step
static_assert(kFieldStride == 2, "kFullLattice counts a stride-2 lattice within 2 texels");
constexpr float kFieldMaxBoost = 3.0f;

// Each computed texel's terms become the mean of the computed texels within kFieldStride of
// it that the bake's texel filter would average with it (texel_filter.h: its surface, its side
// of every fixed light's shadow, its light level) and that it sees where geometry crosses
// either footprint: up to 9 prepass paths instead of one. One path at a texel read by all the
// deeper vertices landing there passed its noise to all of them alike: valley's terrain under
// a house's floor read -0.40 (an environment sample through the 0.03-unit gap, unoccluded, its
// control variate minus the tables' single scattering), and the texels above it -0.08 to
// -0.31 where VPT reads 0 (relMSE of the houses 20-30). Also the smoothing the emitters' multiple
// scattering needs near point lights (one prepass path of a cornell_fog floor texel by the
// short box brought 41.9 against ~0.1).
template <typename SameSurface>
void filter_computed(const ObjectLightmap& map, const std::vector<char>& done,
                     const std::vector<uint32_t>& row, const std::vector<uint32_t>& computed,
                     const TexelFilterGuide& guide, const SameSurface& same_surface,
                     std::vector<IrradianceParts>& deferred,
                     std::vector<UnoccludedSingle>& unoccluded) {
    std::vector<IrradianceParts> filtered(computed.size());
    std::vector<UnoccludedSingle> filtered_unoccluded(computed.size());
    tbb::parallel_for(size_t(0), computed.size(), [&](size_t k) {
        const size_t i = computed[k];
        std::vector<size_t> near = texel_filter_neighbours(map, guide, i, kFieldStride, &done);
        near.erase(std::remove_if(near.begin(), near.end(),
                                  [&](size_t j) { return j != i && !same_surface(i, j); }),
                   near.end());
        if (near.empty()) near.push_back(i);
        for (size_t& j : near) j = row[j];
        filtered[k] = mean_of_texels(deferred, near);
        // Sums, not means: the field carries their ratio.
        for (size_t q : near) filtered_unoccluded[k] += unoccluded[q];
    });
    for (size_t k = 0; k < computed.size(); ++k) {
        deferred[row[computed[k]]] = filtered[k];
        unoccluded[row[computed[k]]] = filtered_unoccluded[k];
    }
}

// Straddle rays run this fraction of a texel above the surface: a wall standing on it blocks
// them at any height, the surface's own curvature within a texel (terrain) does not. Not a
// round fraction: at 0.1 texel (0.025 at 4 texels/unit) the lifted points of valley's IFC walls
// fell on the planes of their 0.025-wide layers.
constexpr float kStraddleLift = 0.13f;
// A straddling texel is read from a hit whose ray to its lifted centre stays clear this
// fraction of the lift past the centre: a centre on a wall is read from neither side.
constexpr float kStraddleOvershoot = 0.5f;

// How far above texel i its straddle and visibility rays run.
float straddle_lift(const ObjectLightmap& map, size_t i) {
    return kStraddleLift / map.density_at(i);
}

// Texel i's centre, as high above its surface (where its straddle rays start).
vec3 lifted_centre(const ObjectLightmap& map, size_t i) {
    return map.texels[i].position + map.texels[i].normal * straddle_lift(map, i);
}

// Whether geometry crosses texel i's footprint (a wall standing on a roof's underside: the
// eave outside, the attic inside, one texel at low density). Four rays along the surface from
// the texel's centre, lifted, to its footprint's corners.
bool straddles_geometry(const RayScene& rays, const ObjectLightmap& map, size_t i) {
    const LightmapTexel& t = map.texels[i];
    const Frame frame(t.normal);
    const float reach = 0.7072f / map.density_at(i);
    const vec3 from = spawn_point(t.position + t.normal * straddle_lift(map, i), t.normal);
    for (const vec3& d :
         {frame.t + frame.b, frame.t - frame.b, -frame.t + frame.b, -frame.t - frame.b})
        if (rays.occluded(shadow_ray(from, glm::normalize(d), reach))) return true;
    return false;
}

// Whether texel i's footprint corners differ in cover from its centre (lightmap_atlas.h: the
// inner layer of a wall ends inside it); such a texel straddles too.
bool cover_mixed(const RayScene& rays, const ObjectLightmap& map, size_t i) {
    const LightmapTexel& t = map.texels[i];
    const Frame frame(t.normal);
    const float reach = kTexelCoverReach / map.density_at(i), half = 0.45f / map.density_at(i);
    for (const vec3& d :
         {frame.t + frame.b, frame.t - frame.b, -frame.t + frame.b, -frame.t - frame.b})
        if (covered_along(rays, t.position + d * half, t.normal, reach) != t.covered) return true;
    return false;
}

// The map's valid texels in texel order: the field's rows (MapTerms, Geometry).
std::vector<uint32_t> valid_texels(const ObjectLightmap& map) {
    std::vector<uint32_t> out;
    for (size_t i = 0; i < map.texels.size(); ++i)
        if (map.texels[i].state == TexelState::Valid) out.push_back(uint32_t(i));
    return out;
}

// Whether the segment between two points is clear.
bool sees(const RayScene& rays, const vec3& from, const vec3& to) {
    const vec3 d = to - from;
    const float length = glm::length(d);
    return !(length > 0.0f) || !rays.occluded(shadow_ray(from, d / length, length));
}

// Whether the segment from `from` to `to`, continued `beyond` past `to`, is clear. The IFC
// houses' walls stand on texel centres at round coordinates: a wall through a straddling
// texel's centre ends the plain segment on its plane, unseen, and a pocket of a layered wall
// read the lit room's value through it (valley, house10:98,270: 0.20 where VPT reads 0).
bool sees_past(const RayScene& rays, const vec3& from, const vec3& to, float beyond) {
    const vec3 d = to - from;
    const float length = glm::length(d);
    return !(length > 0.0f) || !rays.occluded(Ray{from, d / length, 0.0f, length + beyond});
}

}  // namespace

bool uses_vertex_corrections(BakeMethod method, const BakeSettings& settings,
                             const ImpulseTables* tables, const Media& media) {
    return method == BakeMethod::Impulse && settings.vertex_corrections &&
           settings.lit_medium_depth >= 0 && tables && !media.empty();
}

bool texels_read_field(const BakeSettings& settings) {
    return settings.texel_terms == TexelTerms::Field &&
           settings.texel_surface_light == TexelSurfaceLight::Walk;
}

// One map's prepass: the computed texels' Monte Carlo terms, filtered, and the others' from
// their sources, with what the packing needs of the texels' geometry. Per valid texel (a
// row: valley's atlases are 80 % gutters and empty texels; per texel these arrays and the
// filter's copies were 1.3 GB of zeroed pages at low quality; peak RSS 2159 -> 2033 MB, the
// prepass's time unchanged), except the filter's guide, which its neighbour tests read by texel.
constexpr uint32_t kNoRow = ~uint32_t(0);
struct VertexCorrectionField::MapTerms {
    std::vector<uint32_t> row;    // per texel: its row, kNoRow where not valid
    std::vector<uint32_t> texel;  // per row
    std::vector<IrradianceParts> deferred;
    std::vector<UnoccludedSingle> unoccluded;
    std::vector<char> gated, straddles, cover_mixed;
    TexelFilterGuide guide;  // per texel
};

VertexCorrectionField::Geometry VertexCorrectionField::trace_geometry(
    const RayScene& rays, const std::vector<ObjectLightmap>& maps) {
    Geometry g;
    g.triangles.resize(maps.size());
    g.straddles.resize(maps.size());
    g.cover_mixed.resize(maps.size());
    tbb::parallel_for(size_t(0), maps.size(), [&](size_t mi) {
        const ObjectLightmap& map = maps[mi];
        g.triangles[mi].resize(map.triangle_uv.size() / 3);
        tbb::parallel_for(size_t(0), g.triangles[mi].size(),
                          [&](size_t t) { g.triangles[mi][t] = triangle_to_texels(rays, map, t); });
        const std::vector<uint32_t> valid = valid_texels(map);  // estimate_map's rows
        std::vector<char>&straddles = g.straddles[mi], &mixed = g.cover_mixed[mi];
        straddles.assign(valid.size(), 0);
        mixed.assign(valid.size(), 0);
        tbb::parallel_for(size_t(0), valid.size(), [&](size_t r) {
            mixed[r] = cover_mixed(rays, map, valid[r]);
            straddles[r] = mixed[r] || straddles_geometry(rays, map, valid[r]);
        });
    });
    return g;
}

VertexCorrectionField::MapTerms VertexCorrectionField::estimate_map(
    const RayScene& rays, const BakeEstimator& estimator, const ObjectLightmap& map, size_t mi,
    uint64_t key, int seed, PrepassCounts& counts) const {
    const size_t n = map.texels.size();
    MapTerms m;
    m.texel = valid_texels(map);
    m.row.assign(n, kNoRow);
    for (size_t r = 0; r < m.texel.size(); ++r) m.row[m.texel[r]] = uint32_t(r);
    const size_t rows = m.texel.size();
    m.deferred.resize(rows);
    m.unoccluded.resize(rows);
    m.gated.assign(rows, 0);
    m.straddles = geometry_->straddles[mi];
    m.cover_mixed = geometry_->cover_mixed[mi];
    m.guide = TexelFilterGuide::sized(n);
    std::vector<char> done(n, 0);  // by texel: the filter's `among`
    auto run = [&](size_t r) {
        const size_t i = m.texel[r];
        const LightmapTexel& t = map.texels[i];
        const int capacity = texel_filter_capacity(map, i, kFieldStride, kFieldStride);
        const float boost =
            std::min(max_boost_, float(kFullLattice) / float(std::max(1, capacity)));
        const int paths = std::max(paths_, int(std::lround(float(paths_) * boost)));
        BakeCounters counters;
        BakeEstimator::FixedDirect fixed;
        IrradianceParts sum;
        float light_squares = 0.0f;
        for (int s = 0; s < paths; ++s) {
            CounterRng rng = texel_random(seed, key, i, s);
            add_texel_path(estimator.estimate(t.position, t.normal, t.albedo, rng, counters, &fixed,
                                              &m.deferred[r], -1.0f, &m.unoccluded[r]),
                           sum, light_squares);
        }
        // As a sum of paths_ paths (what the means and the packing divide by); the unoccluded
        // sums count their own paths.
        if (paths != paths_) {
            const float scale = float(paths_) / float(paths);
            m.deferred[r].surface *= scale;
            m.deferred[r].single *= scale;
            m.deferred[r].multiple *= scale;
        }
        set_texel_filter_guide(m.guide, i, fixed, sum, light_squares, paths);
        m.gated[r] = fixed.known;  // its lights' shadows known (exact tracking)
        done[i] = 1;
        counts.rays += counters.rays;
        counts.paths += paths;
        ++counts.texels;
    };
    const int w = map.width, stride = kFieldStride;
    // Neighbours in the atlas stand for a texel when they face its way, are covered as it is
    // and, where geometry crosses either footprint, see it (not the eave's light for the attic
    // behind the wall). Cover: at 1 texel/unit valley's terrain texels in the 0.09-unit gap
    // under a house's floor took the mean of the open ground beside it in the house's shadow
    // (0.21 of lit medium where their own terms read 0.001), and every bounce from the floor's
    // underside read that (house03:224,47: 0.055 where VPT reads 0.0003).
    auto same_surface = [&](size_t i, size_t j) {
        const LightmapTexel &a = map.texels[i], &b = map.texels[j];
        return glm::dot(a.normal, b.normal) > 0.9f && a.covered == b.covered &&
               (!(m.straddles[m.row[i]] || m.straddles[m.row[j]]) ||
                sees(rays, lifted_centre(map, i), lifted_centre(map, j)));
    };
    // Every stride-th texel in x and y; the others take the mean of those around them on
    // their own surface, or run themselves where none is (a chart's thin strip).
    auto on_stride = [&](size_t i) {
        return int(i % size_t(w)) % stride == 0 && int(i / size_t(w)) % stride == 0;
    };
    tbb::parallel_for(size_t(0), rows, [&](size_t r) {
        if (on_stride(m.texel[r])) run(r);
    });
    std::vector<std::vector<size_t>> sources(rows);  // rows
    tbb::parallel_for(size_t(0), rows, [&](size_t r) {
        const size_t i = m.texel[r];
        if (done[i]) return;
        const int x0 = int(i % size_t(w)), y0 = int(i / size_t(w));
        for (int y = std::max(0, y0 - stride + 1); y <= std::min(map.height - 1, y0 + stride - 1);
             ++y)
            for (int x = std::max(0, x0 - stride + 1); x <= std::min(w - 1, x0 + stride - 1); ++x) {
                const size_t j = size_t(y) * size_t(w) + size_t(x);
                if (done[j] && same_surface(i, j)) sources[r].push_back(m.row[j]);
            }
        // Sources on both sides of a light's shadow (the texels along shadow edges): the
        // texel's own side from its shadow rays to its point and directional lights, and the
        // sources on that side; it runs itself where none is. (Every such texel ran itself:
        // 65 k of valley low's 426 k computed texels, each a whole prepass path.)
        const size_t first = m.texel[sources[r].empty() ? r : sources[r].front()];
        const bool mixed = std::any_of(sources[r].begin(), sources[r].end(), [&](size_t q) {
            return m.guide.shadows[m.texel[q]] != m.guide.shadows[first] ||
                   m.gated[q] != m.gated[m.row[first]];
        });
        if (mixed) {
            BakeCounters counters;
            const LightmapTexel& t = map.texels[i];
            const uint64_t shadows = estimator.fixed_light_shadows(t.position, t.normal, counters);
            counts.rays += counters.rays;
            // Sources whose shadows are known (gated) and the texel's.
            sources[r].erase(std::remove_if(sources[r].begin(), sources[r].end(),
                                            [&](size_t q) {
                                                return !m.gated[q] ||
                                                       m.guide.shadows[m.texel[q]] != shadows;
                                            }),
                             sources[r].end());
        }
    });
    std::vector<uint32_t> missing;
    for (size_t r = 0; r < rows; ++r)
        if (!done[m.texel[r]] && sources[r].empty()) missing.push_back(uint32_t(r));
    tbb::parallel_for(size_t(0), missing.size(), [&](size_t k) { run(missing[k]); });
    std::vector<uint32_t> computed_texels;
    for (size_t r = 0; r < rows; ++r)
        if (done[m.texel[r]]) computed_texels.push_back(m.texel[r]);
    filter_computed(map, done, m.row, computed_texels, m.guide, same_surface, m.deferred,
                    m.unoccluded);
    for (size_t r = 0; r < rows; ++r) {
        if (sources[r].empty()) continue;
        // The sources, all shadowed alike: the texel's value and shadows.
        m.deferred[r] = mean_of_texels(m.deferred, sources[r]);
        for (size_t q : sources[r]) m.unoccluded[r] += m.unoccluded[q];
        const size_t first = sources[r].front();
        m.guide.shadows[m.texel[r]] = m.guide.shadows[m.texel[first]];
        m.gated[r] = m.gated[first];
    }
    return m;
}

long VertexCorrectionField::pack_map(const ObjectLightmap& map, const MapTerms& m, int paths,
                                     bool corrections_drawn, PackedMap& packed) {
    const size_t n = map.texels.size(), rows = m.texel.size();
    // Per valid texel: the emitters' RGB, the surface light's RGB, the corrections' ratio to
    // the tables' single scattering of the unoccluded connections. Only valid texels are read:
    // a hit whose nearest texel is the ring outside a chart, or inside geometry, keeps its
    // tables as an object without a lightmap does. (The ring dilated from its neighbours held
    // for any hit: valley's hits in the closed cavities of layered IFC walls read lit walls'
    // values there, 10 % of the bake's lm_irradiance relMSE.)
    constexpr size_t kChannels = 9;
    std::vector<float> v(rows * kChannels, 0.0f);
    std::vector<float> multiple(rows * kMultipleHalves, 0.0f);
    std::vector<char> readable(rows, 0);
    for (size_t r = 0; r < rows; ++r) {
        vec3 emitters = (m.deferred[r].single + m.deferred[r].multiple) / float(paths);
        const vec3 surface = m.deferred[r].surface / float(paths);
        // A vertex's single scattering of its unoccluded connections from its own tables T_v,
        // by the prepass's real parts and tables over its paths (explained_single): stored as
        // a ratio relative to T_v (the vertex keeps T_v) and a part added to the value. A bare
        // ratio of real parts to tables read 5.8e4 on smoke_room's floor where the prepass's
        // connections grazed the smoke (tables ~0) and its real parts did not: every bounce
        // landing there brought ~2000.
        // Without bake.single_correction the prepass draws no real parts: no ratio (one of 0
        // real parts over the tables, -1, took the tables' single scattering from every vertex
        // reading the field: haze_occluder's lit floor read 0.37 of VPT's in-scattered light
        // when the texels read it too).
        const UnoccludedSingle& u = m.unoccluded[r];
        vec3 ratio(0.0f);
        for (int c = 0; c < 3 && corrections_drawn; ++c) {
            if (!(u.tables[c] > 0.0f)) continue;
            const ExplainedSingle x = explained_single(u.real[c], u.tables[c], u.paths);
            ratio[c] = x.scale - 1.0f;
            emitters[c] += x.added;
        }
        if (!std::isfinite(emitters.x + emitters.y + emitters.z + surface.x + surface.y +
                           surface.z + ratio.x + ratio.y + ratio.z))
            continue;
        // Sums over the texels the filter averaged, as the ratio's (u.paths paths).
        const vec3 emitters_multiple = m.deferred[r].multiple / float(paths);
        const vec3 surface_multiple =
            u.paths > 0.0f ? u.surface_light_multiple / u.paths : vec3(0.0f);
        if (!all_finite(emitters_multiple + surface_multiple)) continue;
        readable[r] = 1;
        for (int c = 0; c < 3; ++c) {
            v[r * kChannels + size_t(c)] = emitters[c];
            v[r * kChannels + 3 + size_t(c)] = surface[c];
            v[r * kChannels + 6 + size_t(c)] = ratio[c];
            multiple[r * kMultipleHalves + size_t(c)] = emitters_multiple[c];
            multiple[r * kMultipleHalves + 3 + size_t(c)] = surface_multiple[c];
        }
    }
    packed.width = map.width;
    packed.height = map.height;
    for (size_t r = 0; r < rows; ++r) {
        for (size_t c = 0; c < 6; ++c)
            packed.scale = std::max(packed.scale, std::abs(v[r * kChannels + c]));
        for (size_t c = 6; c < 9; ++c)
            packed.ratio_scale = std::max(packed.ratio_scale, std::abs(v[r * kChannels + c]));
    }
    const float inv = packed.scale > 0.0f ? 1.0f / packed.scale : 0.0f;
    const float inv_ratio = packed.ratio_scale > 0.0f ? 1.0f / packed.ratio_scale : 0.0f;
    packed.halves.clear();
    packed.halves.reserve(rows * kHalvesPerTexel);
    packed.multiple_halves.clear();
    packed.multiple_halves.reserve(rows * kMultipleHalves);
    packed.straddles.assign((n + 63) / 64, {});
    long straddling = 0;
    for (size_t r = 0; r < rows; ++r) {
        if (!readable[r]) continue;
        const size_t i = m.texel[r];
        packed.straddles[i / 64].readable |= uint64_t(1) << (i % 64);
        // No channel of the tables: no ratio (it was left 0 above).
        if (!glm::any(glm::greaterThan(m.unoccluded[r].tables, vec3(0.0f))))
            packed.straddles[i / 64].no_ratio |= uint64_t(1) << (i % 64);
        uint16_t h[kHalvesPerTexel];
        for (size_t c = 0; c < kChannels; ++c)
            h[c] = glm::packHalf1x16(v[r * kChannels + c] * (c < 6 ? inv : inv_ratio));
        // The shadows of the texel's point and directional lights, where known (exact
        // tracking).
        for (int w16 = 0; w16 < 4; ++w16)
            h[9 + w16] = m.gated[r] ? uint16_t(m.guide.shadows[i] >> (16 * w16)) : 0;
        h[13] = m.gated[r] ? 1 : 0;
        packed.halves.insert(packed.halves.end(), h, h + kHalvesPerTexel);
        for (size_t c = 0; c < kMultipleHalves; ++c)
            packed.multiple_halves.push_back(
                glm::packHalf1x16(multiple[r * kMultipleHalves + c] * inv));
        if (m.straddles[r]) {
            packed.straddles[i / 64].bits |= uint64_t(1) << (i % 64);
            const bool mixed = m.cover_mixed[r];
            packed.centres.push_back({uint32_t(i), lifted_centre(map, i), straddle_lift(map, i),
                                      mixed, mixed && map.texels[i].covered});
            ++straddling;
        }
    }
    uint32_t before = 0, readable_before = 0;
    for (PackedMap::StraddleWord& w : packed.straddles) {
        w.before = before;
        w.readable_before = readable_before;
        before += uint32_t(__builtin_popcountll(w.bits));
        readable_before += uint32_t(__builtin_popcountll(w.readable));
    }
    return straddling;
}

VertexCorrectionField::VertexCorrectionField(const RayScene& rays, const Media& media,
                                             const ImpulseTables* tables,
                                             const BakeSettings& settings,
                                             const std::vector<ObjectLightmap>& maps,
                                             std::shared_ptr<const Geometry> geometry)
    : maps_(&maps),
      geometry_(geometry ? std::move(geometry)
                         : std::make_shared<const Geometry>(trace_geometry(rays, maps))) {
    // The texels' own Monte Carlo terms, on every path (set_field_prepass: no indirect segment
    // at the texel; the walk's surface light filed apart).
    BakeSettings pre = settings;
    pre.texel_mc_rate = 1.0f;
    BakeEstimator estimator(rays, media, tables, BakeMethod::Impulse, pre);
    // A vertex at depth 1 reads the field; the surface its walk reaches is at depth 2 (a
    // vertex deeper still reads light of up to depth - 1 more bounces: stated, small).
    constexpr int kSurfaceLightDepth = 2;
    estimator.set_field_prepass(kSurfaceLightDepth);
    surface_light_ = settings.texel_surface_light == TexelSurfaceLight::Walk &&
                     settings.bounces >= kSurfaceLightDepth;
    max_boost_ = texels_read_field(settings) ? kFieldMaxBoost : 1.0f;
    paths_ =
        std::max(1, int(std::ceil(double(settings.spp) * settings.texel_mc_rate *
                                      (texels_read_field(settings) ? kFieldPathFractionForTexels
                                                                   : kFieldPathFraction) -
                                  1e-9)));
    map_of_object_.assign(rays.scene().objects.size(), -1);
    lookup_ = LightmapLookup(maps, rays.scene().objects.size());
    packed_.resize(maps.size());
    PrepassCounts counts;
    std::atomic<long> straddling{0};
    scene_ = &rays;
    for (size_t mi = 0; mi < maps.size(); ++mi) {
        int& of_object = map_of_object_[size_t(maps[mi].object)];
        of_object = of_object == -1 ? int(mi) : kSeveralPages;
    }
    // The maps side by side, each with its own parallel loops: a map's serial steps (its
    // packing, the means of the texels that do not run) overlap other maps' work (valley: 50
    // maps, most of them small). Every texel's random numbers are keyed by map and texel, so
    // the field does not depend on the order.
    tbb::parallel_for(size_t(0), maps.size(), [&](size_t mi) {
        const ObjectLightmap& map = maps[mi];
        // Keyed apart from the bake's lightmaps and probes (maps.size()).
        const MapTerms terms =
            estimate_map(rays, estimator, map, mi, maps.size() + 1 + mi, settings.seed, counts);
        straddling += pack_map(map, terms, paths_, settings.single_correction, packed_[mi]);
    });
    rays_ = counts.rays;
    computed_ = counts.texels;
    paths_run_ = counts.paths;
    straddling_ = straddling;
}

VertexCorrectionField::Texel VertexCorrectionField::locate(const SurfaceHit& hit,
                                                           long* rays) const {
    Texel texel;
    // A texel holds its front's terms (the side its winding faces, lightmap_atlas.h): a hit on
    // the back of a one-sided wall read the lit outside's through the wall.
    if (!maps_ || hit.back_face || hit.object < 0 || size_t(hit.object) >= map_of_object_.size())
        return texel;
    int mi = map_of_object_[size_t(hit.object)];
    if (mi == kSeveralPages) mi = lookup_.find(hit.object, hit.primitive);
    if (mi < 0) return texel;
    const std::vector<TriangleToTexels>& tris = geometry_->triangles[size_t(mi)];
    if (hit.primitive < 0 || size_t(hit.primitive) >= tris.size()) return texel;
    const vec2 uv = tris[size_t(hit.primitive)].uv(hit.position);
    // The nearest texel (a valid one, or no field): one cache line, where a bilinear
    // read of four cost 5 % of a smoke_room bake; the field is a noisy, unfiltered estimate
    // that deeper vertices integrate over what they see, so its interpolation buys nothing.
    const PackedMap& map = packed_[size_t(mi)];
    const int x = std::clamp(int(uv.x), 0, map.width - 1);
    const int y = std::clamp(int(uv.y), 0, map.height - 1);
    const size_t k = size_t(y) * size_t(map.width) + size_t(x);
    // Geometry crosses this texel: its value holds for the side its centre is on (one ray, two
    // where a cover close above is checked; valley at low quality: 10.3 M of 12.8 M lookups).
    const PackedMap::StraddleWord& word = map.straddles[k / 64];
    if (!(word.readable >> (k % 64) & 1)) return texel;
    if (word.bits >> (k % 64) & 1) {
        const StraddlingTexel* it = &map.centres[PackedMap::rank(word.bits, word.before, k)];
        long cast = 1;
        bool read = sees_past(*scene_, spawn_point(hit.position, hit.geometric_normal),
                              it->lifted_centre, it->lift * kStraddleOvershoot);
        if (read && it->check_cover) {
            ++cast;
            read = covered_along(*scene_, hit.position, hit.geometric_normal,
                                 it->lift * (kTexelCoverReach / kStraddleLift)) == it->covered;
        }
        if (rays) *rays += cast;
        if (!read) return texel;
    }
    texel = readable_texel(map, word, k);
    __builtin_prefetch(texel.halves_);
    return texel;
}

VertexCorrectionField::Texel VertexCorrectionField::readable_texel(
    const PackedMap& map, const PackedMap::StraddleWord& word, size_t k) const {
    Texel t;
    t.halves_ = map.halves.data() +
                PackedMap::rank(word.readable, word.readable_before, k) * kHalvesPerTexel;
    t.scale_ = map.scale;
    t.ratio_scale_ = map.ratio_scale;
    t.surface_light_ = surface_light_;
    t.ratio_known_ = !(word.no_ratio >> (k % 64) & 1);
    return t;
}

VertexCorrectionField::Texel VertexCorrectionField::at_texel(size_t map, size_t texel) const {
    Texel t;
    // Not read by any hit (not valid, or not finite): what a hit there adds, nothing.
    static const uint16_t kNothing[kHalvesPerTexel] = {};
    t.halves_ = kNothing;
    if (map >= packed_.size() || texel >= size_t(packed_[map].width) * packed_[map].height)
        return t;
    const PackedMap& packed = packed_[map];
    const PackedMap::StraddleWord& word = packed.straddles[texel / 64];
    if (!(word.readable >> (texel % 64) & 1)) return t;
    t = readable_texel(packed, word, texel);
    t.multiple_halves_ =
        packed.multiple_halves.data() +
        PackedMap::rank(word.readable, word.readable_before, texel) * kMultipleHalves;
    return t;
}

vec3 VertexCorrectionField::Texel::multiple(bool with_surface_light) const {
    if (!multiple_halves_) return vec3(0.0f);
    vec3 v = unpack_rgb(multiple_halves_);
    if (with_surface_light && surface_light_) v += unpack_rgb(multiple_halves_ + 3);
    return v * scale_;
}

vec3 VertexCorrectionField::Texel::value(bool with_surface_light) const {
    vec3 v = unpack_rgb(halves_);
    if (with_surface_light && surface_light_) v += unpack_rgb(halves_ + 3);
    return v * scale_;
}

bool VertexCorrectionField::Texel::holds_for(uint64_t shadows) const {
    if (halves_[13] == 0) return true;
    uint64_t own = 0;
    for (int w16 = 0; w16 < 4; ++w16) own |= uint64_t(halves_[9 + w16]) << (16 * w16);
    return own == shadows;
}

vec3 VertexCorrectionField::Texel::single_ratio() const {
    return unpack_rgb(halves_ + 6) * ratio_scale_;
}

}  // namespace freqlab
