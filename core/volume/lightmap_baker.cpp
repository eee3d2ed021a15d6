#include "volume/lightmap_baker.h"

#include <sys/resource.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>

#include "base/error.h"
#include "base/stopwatch.h"
#include "image/layer_codec.h"
#include "volume/texel_filter.h"

namespace freqlab {

nlohmann::json BakeStats::to_json() const {
    return {{"stages",
             {{"atlas_ms", atlas_ms},
              {"tables_ms", tables_ms},
              {"bake_ms", bake_ms},
              {"vertex_corrections_ms", corrections_ms},
              {"vertex_corrections_geometry_ms", correction_geometry_ms}}},
            {"vertex_correction_paths", correction_paths},
            {"vertex_correction_paths_run", correction_paths_run},
            {"vertex_correction_texels", correction_texels},
            {"vertex_correction_straddling_texels", correction_straddling},
            {"texel_terms", texel_terms},
            {"rays", rays},
            {"impulse_queries", impulse_queries},
            {"impulse_mixture_tables", mixture_tables},
            {"nonfinite", guarded},
            {"texels_total", texels_total},
            {"texels_valid", texels_valid},
            {"texels_invalid", texels_invalid},
            {"spp", samples},
            {"storage_mb", storage_mb},
            {"peak_rss_mb", peak_rss_mb},
            {"atlas_notes", atlas_notes}};
}

namespace {

// The process's peak resident memory so far (getrusage; Linux reports kilobytes).
double peak_rss_megabytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) * 1024.0 / 1e6;
}

// Whether a texel's single-scattering corrections are filed apart and filtered as a ratio
// (texel_filter.h, SingleCorrectionSums): impulse's texel Monte Carlo terms draw them, unless
// the texels read the vertex correction field in their place.
bool files_single_corrections(const BakeEstimator& estimator) {
    const BakeSettings& settings = estimator.settings();
    return estimator.method() == BakeMethod::Impulse && settings.single_correction &&
           settings.lit_medium_depth >= 0 && !estimator.texel_reads_field();
}

}  // namespace

std::vector<LayerSet> LightmapBaker::all_layers() const {
    // Reserved: a LayerSet (a deque of layers) is copied, not moved, when a vector grows.
    std::vector<LayerSet> out;
    out.reserve(maps_.size());
    for (size_t i = 0; i < maps_.size(); ++i) out.push_back(layers(i));
    return out;
}

std::string lightmap_name(const Scene& scene, const ObjectLightmap& map) {
    const std::string& n = scene.objects[size_t(map.object)].name;
    const std::string page = map.page > 0 ? "_page" + std::to_string(map.page) : "";
    return (n.empty() ? "object" + std::to_string(map.object) : n) + page;
}

LightmapBaker::LightmapBaker(const RayScene& scene, const Media& media, const ImpulseTables* tables,
                             BakeMethod method, const BakeSettings& settings)
    : scene_(scene),
      media_(media),
      tables_(tables),
      estimator_(scene, media, tables, method, settings),
      method_(method),
      settings_(settings) {
    const auto t0 = Clock::now();
    AtlasSettings atlas;
    atlas.texel_density = settings.texel_density;
    atlas.max_size = settings.max_size;
    atlas.padding = settings.padding;
    atlas.backface_tolerance = settings.backface_tolerance;
    maps_ = build_lightmaps(scene, atlas, &stats_.atlas_notes);
    stats_.atlas_ms = ms_since(t0);
    const vec3 lo = scene.bounds_min(), hi = scene.bounds_max();
    // A scene without geometry has no bounds to lay probes over: it gets none (and says so).
    const bool bounded = glm::all(glm::lessThanEqual(lo, hi)) && std::isfinite(hi.x - lo.x) &&
                         std::isfinite(hi.y - lo.y) && std::isfinite(hi.z - lo.z);
    if (bounded && settings.probes_x > 0 && settings.probes_y > 0 && settings.probes_z > 0) {
        probe_grid_ = ivec3(settings.probes_x, settings.probes_y, settings.probes_z);
        const vec3 centre = 0.5f * (lo + hi), half = 0.45f * (hi - lo);
        const ivec3 n(settings.probes_x, settings.probes_y, settings.probes_z);
        for (int z = 0; z < n.z; ++z)
            for (int y = 0; y < n.y; ++y)
                for (int x = 0; x < n.x; ++x) {
                    const vec3 f = (vec3(x, y, z) + 0.5f) / vec3(n) * 2.0f - 1.0f;
                    probe_positions_.push_back(centre + f * half);
                }
    }
    for (const ObjectLightmap& m : maps_) {
        stats_.texels_total += long(m.texels.size());
        stats_.texels_valid += long(m.count(TexelState::Valid));
        stats_.texels_invalid += long(m.count(TexelState::InsideGeometry));
    }
    reset();
}

void LightmapBaker::reset() {
    sums_.assign(maps_.size(), {});
    for (size_t i = 0; i < maps_.size(); ++i) sums_[i].assign(maps_[i].texels.size(), {});
    // Sized by the first pass, once it knows whether the texels run terms of their own.
    deferred_sums_.assign(maps_.size(), {});
    single_sums_.assign(maps_.size(), {});
    light_squares_.assign(maps_.size(), {});
    for (size_t i = 0; i < maps_.size(); ++i)
        light_squares_[i].assign(maps_[i].texels.size(), 0.0f);
    share_shadows_.assign(maps_.size(), {});
    for (size_t i = 0; i < maps_.size(); ++i) share_shadows_[i].assign(maps_[i].texels.size(), 0);
    fixed_.assign(maps_.size(), {});  // media may have changed: computed afresh
    for (size_t i = 0; i < maps_.size(); ++i) fixed_[i].assign(maps_[i].texels.size(), {});
    probe_sums_.assign(probe_positions_.size(), {});
    estimator_.set_vertex_corrections(nullptr);
    if (corrections_) field_geometry_ = corrections_->geometry();
    corrections_.reset();
    stats_.corrections_ms = stats_.correction_geometry_ms = 0.0;
    stats_.correction_paths = 0;
    stats_.correction_paths_run = 0;
    stats_.correction_texels = 0;
    stats_.correction_straddling = 0;
    samples_ = 0;
    stats_.bake_ms = 0.0;
    stats_.rays = stats_.impulse_queries = stats_.guarded = 0;
    stats_.samples = 0;
}

void LightmapBaker::size_texel_terms() {
    // Texels that read the vertex correction field run no Monte Carlo terms of their own:
    // nothing to sum, filter or raise the rate of (valley low: 84 MB of zeros, and their filter).
    const bool own = !estimator_.texel_reads_field();
    const bool files = files_single_corrections(estimator_);
    for (size_t i = 0; i < maps_.size(); ++i) {
        deferred_sums_[i].assign(own ? maps_[i].texels.size() : 0, {});
        single_sums_[i].assign(files ? maps_[i].texels.size() : 0, {});
    }
    const int radius = texel_filter_radius(estimator_);
    if (mc_rates_.size() == maps_.size() && mc_rates_radius_ == radius) return;
    mc_rates_.clear();
    for (const ObjectLightmap& map : maps_) mc_rates_.push_back(texel_mc_rates(map, estimator_));
    mc_rates_radius_ = radius;
}

void LightmapBaker::run_pass(int samples, Progress* progress) {
    estimator_.check_media();  // the sliders may have moved g since the last pass
    const auto t0 = Clock::now();
    if (samples_ == 0 && !corrections_ &&
        uses_vertex_corrections(method_, settings_, tables_, media_)) {
        // Before the first path: deeper vertices read it (volume/vertex_corrections.h). Its
        // geometry once per atlas (a re-bake after a media change keeps it).
        if (!field_geometry_) {
            field_geometry_ = std::make_shared<const VertexCorrectionField::Geometry>(
                VertexCorrectionField::trace_geometry(scene_, maps_));
            stats_.correction_geometry_ms = ms_since(t0);
        }
        corrections_ = std::make_unique<VertexCorrectionField>(scene_, media_, tables_, settings_,
                                                               maps_, field_geometry_);
        estimator_.set_vertex_corrections(corrections_.get());
        stats_.corrections_ms = ms_since(t0);
        stats_.correction_paths = corrections_->paths_per_texel();
        stats_.correction_paths_run = corrections_->paths_run();
        stats_.correction_texels = corrections_->computed_texels();
        stats_.correction_straddling = corrections_->straddling_texels();
        stats_.rays += corrections_->rays();
    }
    stats_.texel_terms = method_ != BakeMethod::Impulse   ? ""
                         : estimator_.texel_reads_field() ? "field"
                                                          : "own";
    if (samples_ == 0) size_texel_terms();
    // One loop over every map's rows (a loop per map waited at each of valley's 50 maps for
    // its last rows, on every pass); the split into shares numbers the rows the same way.
    std::vector<long> map_row0(maps_.size() + 1, 0);  // global number of each map's row 0
    for (size_t mi = 0; mi < maps_.size(); ++mi) map_row0[mi + 1] = map_row0[mi] + maps_[mi].height;
    const long rows = map_row0.back();
    if (progress) progress->begin_stage("bake " + std::string(to_string(method_)), rows);
    std::atomic<long> rays{0}, queries{0}, guarded{0};
    const int first = samples_;
    tbb::parallel_for(long(0), rows, [&](long row) {
        progress ? progress->checkpoint() : process_checkpoint();
        if (!in_share(row, share_index_)) {
            if (progress) progress->advance();
            return;
        }
        const size_t mi =
            size_t(std::upper_bound(map_row0.begin(), map_row0.end(), row) - map_row0.begin()) - 1;
        const ObjectLightmap& map = maps_[mi];
        const std::vector<float>& rates = mc_rates_[mi];
        const int y = int(row - map_row0[mi]);
        BakeCounters counters;
        for (int x = 0; x < map.width; ++x) {
            const size_t i = size_t(y) * map.width + x;
            const LightmapTexel& t = map.texels[i];
            if (t.state != TexelState::Valid) continue;
            // Summed sample by sample into the running total: the same additions in the
            // same order whatever the split into passes.
            const bool files = !single_sums_[mi].empty();
            IrradianceParts* deferred =
                deferred_sums_[mi].empty() ? nullptr : &deferred_sums_[mi][i];
            for (int s = first; s < first + samples; ++s) {
                CounterRng rng = texel_random(settings_.seed, mi, i, s);
                UnoccludedSingle single;
                add_texel_path(
                    estimator_.estimate_texel(t, mi, i, rng, counters, &fixed_[mi][i], deferred,
                                              rates[i], files ? &single : nullptr),
                    sums_[mi][i], light_squares_[mi][i]);
                if (files) single_sums_[mi][i] += single;
            }
        }
        rays += counters.rays;
        queries += counters.impulse_queries;
        guarded += counters.guarded;
        if (progress) progress->advance();
    });
    // Probes: keyed after the lightmaps (index maps_.size()).
    tbb::parallel_for(size_t(0), probe_positions_.size(), [&](size_t i) {
        if (!in_share(long(i), share_index_)) return;
        BakeCounters counters;
        for (int s = first; s < first + samples; ++s) {
            CounterRng rng = texel_random(settings_.seed, maps_.size(), i, s);
            const BakeEstimator::ProbeParts p =
                estimator_.estimate_probe(probe_positions_[i], rng, counters);
            bool finite = true;
            for (int k = 0; k < 9; ++k)
                finite = finite && std::isfinite(p.surface[size_t(k)].x + p.surface[size_t(k)].y +
                                                 p.surface[size_t(k)].z + p.single[size_t(k)].x +
                                                 p.single[size_t(k)].y + p.single[size_t(k)].z +
                                                 p.multiple[size_t(k)].x + p.multiple[size_t(k)].y +
                                                 p.multiple[size_t(k)].z);
            if (!finite) {
                ++counters.guarded;
                continue;
            }
            for (int k = 0; k < 9; ++k) {
                probe_sums_[i].surface[size_t(k)] += p.surface[size_t(k)];
                probe_sums_[i].single[size_t(k)] += p.single[size_t(k)];
                probe_sums_[i].multiple[size_t(k)] += p.multiple[size_t(k)];
            }
        }
        rays += counters.rays;
        queries += counters.impulse_queries;
        guarded += counters.guarded;
    });
    samples_ += samples;
    stats_.samples = samples_;
    stats_.rays += rays;
    stats_.impulse_queries += queries;
    stats_.guarded += guarded;
    stats_.bake_ms += ms_since(t0);
    stats_.mixture_tables = long(estimator_.mixture_tables());
    // What the bake holds: the atlases' texels and per-texel sums, probes and the correction
    // field's texels (the scene, Embree's BVH and the tables are the process's, in peak_rss_mb).
    size_t bytes = probe_sums_.size() * sizeof(BakeEstimator::ProbeParts);
    for (size_t m = 0; m < maps_.size(); ++m)
        bytes += maps_[m].texels.size() * sizeof(LightmapTexel) +
                 maps_[m].triangle_uv.size() * sizeof(vec2) +
                 (sums_[m].size() + deferred_sums_[m].size()) * sizeof(IrradianceParts) +
                 single_sums_[m].size() * sizeof(SingleCorrectionSums) +
                 light_squares_[m].size() * sizeof(float) +
                 fixed_[m].size() * sizeof(BakeEstimator::FixedDirect);
    stats_.storage_mb = double(bytes) / 1e6;
    stats_.peak_rss_mb = peak_rss_megabytes();
}

void LightmapBaker::set_share(int index, int count) {
    if (count < 1 || index < 0 || index >= count)
        throw Error("bake", "share", "expected 0 <= index < count");
    share_index_ = index;
    share_count_ = count;
}

namespace {
constexpr uint32_t kShareMagic = 0x464c4253;  // "FLBS"
}

template <class RowFn, class ProbeFn>
void LightmapBaker::for_each_in_share(int index, RowFn row_fn, ProbeFn probe_fn) const {
    long row = 0;
    for (size_t mi = 0; mi < maps_.size(); ++mi)
        for (int y = 0; y < maps_[mi].height; ++y, ++row)
            if (in_share(row, index))
                row_fn(mi, size_t(y) * maps_[mi].width, size_t(maps_[mi].width));
    for (size_t i = 0; i < probe_sums_.size(); ++i)
        if (in_share(long(i), index)) probe_fn(i);
}

std::string LightmapBaker::encode_share() const {
    ByteWriter w;
    w.put(kShareMagic);
    w.put<int32_t>(share_index_);
    w.put<int32_t>(samples_);
    w.put<int64_t>(stats_.rays);
    w.put<int64_t>(stats_.impulse_queries);
    w.put<int64_t>(stats_.guarded);
    for_each_in_share(
        share_index_,
        [&](size_t mi, size_t at, size_t n) {
            w.put_bytes(&sums_[mi][at], n * sizeof(IrradianceParts));
            if (!deferred_sums_[mi].empty())
                w.put_bytes(&deferred_sums_[mi][at], n * sizeof(IrradianceParts));
            w.put_bytes(&light_squares_[mi][at], n * sizeof(float));
            if (!single_sums_[mi].empty())
                w.put_bytes(&single_sums_[mi][at], n * sizeof(SingleCorrectionSums));
            std::vector<uint64_t> shadows(n);
            for (size_t x = 0; x < n; ++x) shadows[x] = texel_shadow_bits(fixed_[mi][at + x]);
            w.put_bytes(shadows.data(), n * sizeof(uint64_t));
        },
        [&](size_t i) { w.put_bytes(&probe_sums_[i], sizeof(BakeEstimator::ProbeParts)); });
    return std::move(w.bytes());
}

void LightmapBaker::add_share(const std::string& bytes, int index, const std::string& source) {
    ByteReader r(bytes, source);
    if (r.get<uint32_t>() != kShareMagic || r.get<int32_t>() != index)
        throw Error(source, "share", "expected bake share " + std::to_string(index));
    if (r.get<int32_t>() != samples_)
        throw Error(source, "share", "baked a different number of samples");
    stats_.rays += long(r.get<int64_t>());
    stats_.impulse_queries += long(r.get<int64_t>());
    stats_.guarded += long(r.get<int64_t>());
    for_each_in_share(
        index,
        [&](size_t mi, size_t at, size_t n) {
            r.get_bytes(&sums_[mi][at], n * sizeof(IrradianceParts));
            if (!deferred_sums_[mi].empty())
                r.get_bytes(&deferred_sums_[mi][at], n * sizeof(IrradianceParts));
            r.get_bytes(&light_squares_[mi][at], n * sizeof(float));
            if (!single_sums_[mi].empty())
                r.get_bytes(&single_sums_[mi][at], n * sizeof(SingleCorrectionSums));
            r.get_bytes(&share_shadows_[mi][at], n * sizeof(uint64_t));
        },
        [&](size_t i) { r.get_bytes(&probe_sums_[i], sizeof(BakeEstimator::ProbeParts)); });
    if (r.remaining() != 0) throw Error(source, "share", "bytes past the end");
}

void LightmapBaker::run(Progress* progress) {
    int passes = 0;
    for (int n = 1, done = samples_; done < settings_.spp; n *= 2, ++passes)
        done += std::min(n, settings_.spp - done);
    if (progress) progress->set_stage_count(std::max(1, passes));
    for (int n = 1; samples_ < settings_.spp; n *= 2)
        run_pass(std::min(n, settings_.spp - samples_), progress);
}

std::vector<LightmapBaker::Probe> LightmapBaker::probes() const {
    std::vector<Probe> out(probe_positions_.size());
    const float inv = samples_ > 0 ? 1.0f / float(samples_) : 0.0f;
    for (size_t i = 0; i < out.size(); ++i) {
        out[i].position = probe_positions_[i];
        for (size_t k = 0; k < 9; ++k) {
            out[i].surface[k] = probe_sums_[i].surface[k] * inv;
            out[i].single[k] = probe_sums_[i].single[k] * inv;
            out[i].multiple[k] = probe_sums_[i].multiple[k] * inv;
        }
    }
    return out;
}

nlohmann::json LightmapBaker::probes_json() const {
    auto coefficients = [](const std::array<vec3, 9>& sh) {
        nlohmann::json j = nlohmann::json::array();
        for (const vec3& c : sh) j.push_back({c.x, c.y, c.z});
        return j;
    };
    nlohmann::json list = nlohmann::json::array();
    for (const Probe& p : probes()) {
        std::array<vec3, 9> total;
        for (size_t k = 0; k < 9; ++k) total[k] = p.surface[k] + p.single[k] + p.multiple[k];
        list.push_back({{"position", {p.position.x, p.position.y, p.position.z}},
                        {"sh", coefficients(total)},
                        {"sh_surface", coefficients(p.surface)},
                        {"sh_inscatter_single", coefficients(p.single)},
                        {"sh_inscatter_multiple", coefficients(p.multiple)}});
    }
    return {{"order", 3},
            {"basis", "real SH, y_l^m of core/math/sh.h (index l(l+1)+m), incident radiance"},
            {"grid", {probe_grid_.x, probe_grid_.y, probe_grid_.z}},
            {"spp", samples_},
            {"probes", list}};
}

IrradianceParts texel_estimate(const BakeEstimator& estimator,
                               const std::vector<ObjectLightmap>& maps, size_t lightmap,
                               size_t texel, int seed, int spp, TexelFilterUse* filter) {
    const ObjectLightmap& map = maps.at(lightmap);
    const size_t n = map.texels.size();
    const int radius = texel_filter_radius(estimator);
    // The texel and the window the baker's filter reads, re-run with the bake's keys.
    std::vector<IrradianceParts> sums(n), deferred(n);
    const bool files = files_single_corrections(estimator);
    std::vector<SingleCorrectionSums> single(files ? n : 0);
    TexelFilterGuide guide = TexelFilterGuide::sized(n);
    const int x0 = int(texel % size_t(map.width)), y0 = int(texel / size_t(map.width));
    const std::vector<float> rates = texel_mc_rates(map, estimator);
    BakeCounters counters;
    for (int y = std::max(0, y0 - radius); y <= std::min(map.height - 1, y0 + radius); ++y)
        for (int x = std::max(0, x0 - radius); x <= std::min(map.width - 1, x0 + radius); ++x) {
            const size_t j = size_t(y) * size_t(map.width) + size_t(x);
            const LightmapTexel& t = map.texels.at(j);
            if (t.state != TexelState::Valid && j != texel) continue;
            BakeEstimator::FixedDirect fixed;
            float light_squares = 0.0f;
            const bool record = filter && j == texel;
            for (int s = 0; s < spp; ++s) {
                CounterRng rng = texel_random(seed, lightmap, j, s);
                TexelPathRecord path;
                const PathRecording recording(record ? &path : nullptr);
                const IrradianceParts before = deferred[j];
                UnoccludedSingle unoccluded;  // added sample by sample, as the bake does
                path.path =
                    estimator.estimate_texel(t, lightmap, j, rng, counters, &fixed, &deferred[j],
                                             rates[j], files ? &unoccluded : nullptr);
                add_texel_path(path.path, sums[j], light_squares);
                if (files) single[j] += unoccluded;
                if (!record) continue;
                path.deferred = deferred[j];
                path.deferred.surface -= before.surface;
                path.deferred.single -= before.single;
                path.deferred.multiple -= before.multiple;
                filter->paths.push_back(std::move(path));
            }
            set_texel_filter_guide(guide, j, fixed, sums[j], light_squares, spp);
        }
    IrradianceParts sum = sums[texel];
    const bool filtered = radius > 0 && map.texels[texel].state == TexelState::Valid;
    const std::vector<size_t> near =
        filtered ? texel_filter_neighbours(map, guide, texel, radius) : std::vector<size_t>{texel};
    sum += filtered_texel_terms(deferred, files ? &single : nullptr, texel, near);
    if (filter) {
        filter->mc_rate = rates[texel];
        filter->texels = int(near.size());
        filter->sum = sums[texel];
        filter->deferred = deferred[texel];
        filter->filtered = mean_of_texels(deferred, near);
        if (files) {
            filter->tables_single = single[texel].tables;
            filter->ratio_correction = ratio_correction(single, texel, near);
        }
    }
    const float inv = spp > 0 ? 1.0f / float(spp) : 0.0f;
    sum.surface *= inv;
    sum.single *= inv;
    sum.multiple *= inv;
    return sum;
}

LayerSet LightmapBaker::layers(size_t mi) const {
    const ObjectLightmap& map = maps_.at(mi);
    LayerSet set(map.width, map.height);
    const size_t n = map.texels.size();
    const float inv = samples_ > 0 ? 1.0f / float(samples_) : 0.0f;
    // Outgoing radiance of each part, and irradiance; dilated together.
    std::vector<float> values(n * 15, 0.0f);
    TexelFilterGuide guide = TexelFilterGuide::sized(n);
    for (size_t i = 0; i < n; ++i) {
        set_texel_filter_guide(guide, i, fixed_[mi][i], sums_[mi][i], light_squares_[mi][i],
                               samples_);
        guide.shadows[i] |= share_shadows_[mi][i];
    }
    const int radius = texel_filter_radius(estimator_);
    // None before the first pass, nor where the texels read the vertex correction field.
    std::vector<IrradianceParts> deferred;
    std::vector<int> window(n, 0);
    if (!deferred_sums_[mi].empty())
        deferred =
            filter_texel_sums(map, deferred_sums_[mi], guide, radius,
                              single_sums_[mi].empty() ? nullptr : &single_sums_[mi], &window);
    for (size_t i = 0; i < n; ++i) {
        const LightmapTexel& t = map.texels[i];
        if (t.state != TexelState::Valid) continue;
        IrradianceParts p = sums_[mi][i];
        if (!deferred.empty()) p += deferred[i];
        const vec3 e = p.total() * inv;
        const vec3 k = t.albedo * kInvPi * inv;
        const vec3 out[5] = {k * p.total(), e, p.surface * inv, p.single * inv, p.multiple * inv};
        for (int l = 0; l < 5; ++l)
            for (int c = 0; c < 3; ++c) values[i * 15 + size_t(l) * 3 + c] = out[l][c];
    }
    const std::vector<TexelState> states = dilate(map, values, 15, settings_.dilation);
    const char* names[5] = {"lm_total", "lm_irradiance", "lm_surface", "lm_inscatter_single",
                            "lm_inscatter_multiple"};
    const char* what[5] = {
        "outgoing radiance of the lightmap: albedo / pi x all irradiance",
        "irradiance at the texel (W/m^2), all parts",
        "irradiance from light that reached the texel without scattering in a medium on its "
        "last segment (attenuated unless the method is surface)",
        "irradiance from light scattered once in a medium on its last segment",
        "irradiance from light scattered two or more times on its last segment"};
    for (int l = 0; l < 5; ++l) {
        Layer& layer = set.add(names[l], LayerKind::Color, 3, what[l]);
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c) layer.data[i * 3 + c] = values[i * 15 + size_t(l) * 3 + c];
    }
    Layer& valid = set.add("texel_valid", LayerKind::Categorical, 1,
                           "texel state: empty, valid, inside geometry (flagged), dilated");
    valid.legend = texel_state_legend();
    for (size_t i = 0; i < n; ++i) valid.data[i] = float(int(states[i]));
    if (radius > 0) {
        // Where the Monte Carlo terms rest on few samples: a texel its filter left alone
        // carries them at weight 1 / rate.
        Layer& texels = set.add("texel_mc_window", LayerKind::Continuous, 1,
                                "texels whose Monte Carlo terms the texel's filter averaged "
                                "(bake.texel_mc_radius; 0: not a valid texel)");
        Layer& rates = set.add("texel_mc_rate", LayerKind::Continuous, 1,
                               "the fraction of the texel's paths that ran its Monte Carlo terms "
                               "(bake.texel_mc_rate, raised where its window is small)");
        const std::vector<float>* mc = mi < mc_rates_.size() ? &mc_rates_[mi] : nullptr;
        for (size_t i = 0; i < n; ++i) {
            texels.data[i] = float(window[i]);
            rates.data[i] = mc && states[i] == TexelState::Valid ? (*mc)[i] : 0.0f;
        }
    }
    return set;
}

}  // namespace freqlab
