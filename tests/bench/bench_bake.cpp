// Method B's per-path cost by bake method (issue "Method B, part 2", acceptance 3: an impulse
// bake within 1.10x of a surface bake at equal samples). One path per valid texel of the
// scene's lightmaps, single thread, so the numbers are ns per path without a thread pool's
// noise; the per-method ratio to `surface` is the overhead the acceptance line measures.
//   ./build/tests/freqlab_benchmarks --benchmark_filter=BakePath
//   BENCH_BAKE_SCENE=scenes/smoke_room.json ./build/tests/freqlab_benchmarks
//   --benchmark_filter=BakePath
//   BENCH_BAKE_SET="texel_mc_rate=0 single_correction=false" (bake settings by key, as --set)
//   BENCH_BAKE_SET="texel_terms=field": the vertex correction field is built once (its
//   prepass is not timed: BakeFieldPrepass times it) and the texels read it (estimate_texel).
//   Without it impulse's deeper vertices use the tables alone, as before the field.
// These machines are noisy (the same binary's medians move 10-25 % within minutes): compare
// methods within one run, randomly interleaved, and read the medians' ns_per_path:
//   --benchmark_repetitions=12 --benchmark_enable_random_interleaving=true
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>

#include "scene/scene_loader.h"
#include "volume/impulse_irradiance.h"
#include "volume/impulse_tables.h"
#include "volume/lightmap_baker.h"

using namespace freqlab;

namespace {

BakeSettings bench_settings();

struct BakeFixture {
    Scene scene =
        load_scene(std::getenv("BENCH_BAKE_SCENE") ? std::getenv("BENCH_BAKE_SCENE")
                                                   : FREQLAB_SOURCE_DIR "/scenes/cornell_fog.json");
    EmbreeDevice device{1};
    RayScene rays{scene, device};
    Media media{scene.media, scene.source};
    ImpulseTables tables = ImpulseTables::cached(30);  // the CLI's table bounces
    std::vector<ObjectLightmap> maps;
    struct Texel {
        size_t map, index;  // in maps
    };
    std::vector<Texel> texels;  // the valid ones

    BakeFixture() {
        rays.update(0.0f);
        // The atlas at BENCH_BAKE_SET's texel density (quality=low: valley's 4 texels/unit).
        const LightmapBaker atlas(rays, media, nullptr, BakeMethod::Surface, bench_settings());
        maps = atlas.lightmaps();
        for (size_t m = 0; m < maps.size(); ++m)
            for (size_t i = 0; i < maps[m].texels.size(); ++i)
                if (maps[m].texels[i].state == TexelState::Valid) texels.push_back({m, i});
    }
    const LightmapTexel& texel(const Texel& t) const { return maps[t.map].texels[t.index]; }
};

// The estimator's settings: BakeSettings{} with BENCH_BAKE_SET's "key=value" words applied,
// so that one term's cost is the difference of two runs.
BakeSettings bench_settings() {
    BakeSettings settings;
    const char* words = std::getenv("BENCH_BAKE_SET");
    std::istringstream in(words ? words : "");
    for (std::string word; in >> word;) {
        const size_t eq = word.find('=');
        if (eq == std::string::npos) throw std::runtime_error("BENCH_BAKE_SET: expected key=value");
        BakeSettings::schema().set_from_string(&settings, word.substr(0, eq), word.substr(eq + 1),
                                               "BENCH_BAKE_SET");
    }
    return settings;
}

BakeFixture& fixture() {
    static BakeFixture f;
    return f;
}

void BM_BakePath(benchmark::State& state) {
    BakeFixture& f = fixture();
    const BakeMethod method = BakeMethod(state.range(0));
    const BakeSettings settings = bench_settings();
    BakeEstimator estimator(f.rays, f.media, &f.tables, method, settings);
    std::unique_ptr<VertexCorrectionField> field;
    if (settings.texel_terms == TexelTerms::Field &&
        uses_vertex_corrections(method, settings, &f.tables, f.media)) {
        field =
            std::make_unique<VertexCorrectionField>(f.rays, f.media, &f.tables, settings, f.maps);
        estimator.set_vertex_corrections(field.get());
    }
    BakeCounters counters;
    // As the baker: each texel's fixed direct light is computed on its first path only.
    std::vector<BakeEstimator::FixedDirect> fixed(f.texels.size());
    uint64_t sample = 0;
    for (auto _ : state) {
        vec3 sum(0.0f);
        for (size_t i = 0; i < f.texels.size(); ++i) {
            CounterRng rng(0, 0, i, sample);
            sum += estimator
                       .estimate_texel(f.texel(f.texels[i]), f.texels[i].map, f.texels[i].index,
                                       rng, counters, &fixed[i], nullptr, -1.0f, nullptr)
                       .total();
        }
        ++sample;
        benchmark::DoNotOptimize(sum);
    }
    state.SetLabel(std::string(to_string(method)) +
                   (estimator.texel_reads_field() ? " (texels read the field)" : ""));
    state.counters["ns_per_path"] =
        benchmark::Counter(double(f.texels.size()), benchmark::Counter::kIsIterationInvariantRate |
                                                        benchmark::Counter::kInvert);
    state.counters["rays_per_path"] =
        double(counters.rays) / double(f.texels.size() * state.iterations());
    state.counters["queries_per_path"] =
        double(counters.impulse_queries) / double(f.texels.size() * state.iterations());
}

}  // namespace

BENCHMARK(BM_BakePath)
    ->Arg(int(BakeMethod::Surface))
    ->Arg(int(BakeMethod::Extinction))
    ->Arg(int(BakeMethod::Impulse))
    ->Unit(benchmark::kMillisecond);

namespace {

// The vertex correction field's prepass over the scene's lightmaps (once per bake, before its
// first path), one thread: with texel_terms = field it is what the texels' Monte Carlo terms
// cost, shared by the bake's spp paths a texel. ns_per_texel is per valid texel.
void BM_BakeFieldPrepass(benchmark::State& state) {
    BakeFixture& f = fixture();
    const BakeSettings settings = bench_settings();
    // One thread, as BakePath's loop (the prepass's own loops are parallel).
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    long computed = 0, rays = 0;
    int paths = 0;
    for (auto _ : state) {
        const VertexCorrectionField field(f.rays, f.media, &f.tables, settings, f.maps);
        computed = field.computed_texels();
        paths = field.paths_per_texel();
        rays = field.rays();
        benchmark::DoNotOptimize(computed);
    }
    state.counters["ns_per_texel"] =
        benchmark::Counter(double(f.texels.size()), benchmark::Counter::kIsIterationInvariantRate |
                                                        benchmark::Counter::kInvert);
    state.counters["computed_texels"] = double(computed);
    state.counters["paths_per_computed_texel"] = double(paths);
    state.counters["rays_per_computed_texel"] =
        computed > 0 ? double(rays) / double(computed) : 0.0;
}

}  // namespace

BENCHMARK(BM_BakeFieldPrepass)->Unit(benchmark::kMillisecond);

namespace {

// One tabulated double product (impulse_irradiance.h) at pseudo-random distances and cosines:
// the part of an impulse query that is not the segment's tracking.
void BM_ImpulseIrradianceLookup(benchmark::State& state) {
    static const ImpulseTables tables = ImpulseTables::cached(30);
    static const ImpulseIrradiance table(tables, 0.2, 0.35 / 0.4, 30);
    const bool area = state.range(0) != 0;
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    for (auto _ : state) {
        h = h * 6364136223846793005ULL + 1442695040888963407ULL;
        const double D = 0.001 + double(h >> 40) * (3.0 / double(1 << 24));
        const double cos = double((h >> 16) & 0xffffff) * (2.0 / double(1 << 24)) - 1.0;
        const ImpulseIrradiance::At at = ImpulseIrradiance::at(D);
        const ScatteredIrradiance e =
            area ? table.area(at, 0.5 * (cos + 1.0), cos, cos) : table.point(at, cos);
        benchmark::DoNotOptimize(e);
    }
    state.SetLabel(area ? "area" : "point");
}

}  // namespace

BENCHMARK(BM_ImpulseIrradianceLookup)->Arg(0)->Arg(1);

namespace {

// Segment origins uniform in a box, directions uniform-ish (a fixed LCG: the same segments in
// every run and benchmark).
struct RandomSegments {
    vec3 lo, hi;
    uint64_t h = 0x9E3779B97F4A7C15ULL;
    float next() {
        h = h * 6364136223846793005ULL + 1442695040888963407ULL;
        return float(h >> 40) * (1.0f / float(1 << 24));
    }
    void draw(vec3* o, vec3* d) {
        *o = lo + (hi - lo) * vec3(next(), next(), next());
        *d = glm::normalize(vec3(next() - 0.5f, next() - 0.5f, next() - 0.5f));
    }
};

// Media::integrate on segments from random points of the scene's box towards random
// directions (length 2): a segment's tracking, without its ray.
void BM_MediaIntegrate(benchmark::State& state) {
    BakeFixture& f = fixture();
    RandomSegments segments{f.rays.bounds_min(), f.rays.bounds_max()};
    const double length = std::getenv("BENCH_LEN") ? std::atof(std::getenv("BENCH_LEN")) : 2.0;
    for (auto _ : state) {
        vec3 o, d;
        segments.draw(&o, &d);
        benchmark::DoNotOptimize(f.media.integrate(o, d, length));
    }
}

}  // namespace

BENCHMARK(BM_MediaIntegrate);

namespace {

// The scene's first density grid alone on segments from random points of its box: its integral by
// jumps (arg 0, every crossing) and by runs (arg 1, the dominant axis's crossings skipped).
void BM_GridIntegral(benchmark::State& state) {
    BakeFixture& f = fixture();
    const DensityGrid* grid = nullptr;
    for (size_t i = 0; i < f.media.size() && !grid; ++i) grid = f.media.grid(i);
    if (!grid) {
        state.SkipWithError("the scene has no density grid");
        return;
    }
    const bool runs = state.range(0) != 0;
    RandomSegments segments{grid->box_min(), grid->box_max()};
    for (auto _ : state) {
        vec3 o, d;
        segments.draw(&o, &d);
        benchmark::DoNotOptimize(runs ? grid->integral_by_runs(o, d, 0.0, 2.0)
                                      : grid->integral_by_jumps(o, d, 0.0, 2.0));
    }
    state.SetLabel(runs ? "runs" : "jumps");
}

}  // namespace

BENCHMARK(BM_GridIntegral)->Arg(0)->Arg(1);
