// Shadow-ray throughput of the direct-lighting integrator on rotor.json against a bare Embree
// occlusion loop over exactly the rays it casts (issue "Reference direct-lighting integrator",
// acceptance 5: the integrator should reach >= 70 % of the bare loop).
//
//   ./build/tests/freqlab_benchmarks --benchmark_filter=ShadowRays
//       --benchmark_repetitions=9 --benchmark_enable_random_interleaving=true
// (the argument is the spp; BENCH_SCENE=path.json runs another scene).
#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>

#include "render/direct_lighting.h"
#include "render/gbuffer.h"
#include "scene/scene_loader.h"

using namespace freqlab;

namespace {

// Every spp shades the same number of samples: 320x180 pixels at 16 spp, 80x45 at 256.
struct Fixture {
    Scene scene = load_scene(std::getenv("BENCH_SCENE") ? std::getenv("BENCH_SCENE")
                                                        : FREQLAB_SOURCE_DIR "/scenes/rotor.json");
    EmbreeDevice device{0};
    RayScene rays{scene, device};
    int spp, width, height;
    GBuffer gbuffer;
    std::vector<Ray> recorded;  // the integrator's shadow rays, in the order it cast them
    std::vector<size_t> calls;  // where each of its occluded_stream calls (one a pixel) begins
    std::vector<int> call_row;  // the image row of each call

    explicit Fixture(int spp_)
        : spp(spp_),
          width(int(320 / std::sqrt(spp_ / 16.0))),
          height(int(180 / std::sqrt(spp_ / 16.0))) {
        FrameSettings fs;
        fs.width = width;
        fs.height = height;
        GBufferSettings gs;
        gs.aa_samples = 1;
        Progress p;
        gbuffer = render_gbuffer(rays, 0, fs, gs, p).gbuffer;
        DirectLighting lighting(rays, ShadingSettings{});
        lighting.record_rays(&recorded);
        for (size_t i = 0; i < gbuffer.hits.size(); ++i) {
            CounterRng rng(0, 0, i, 0);
            const size_t before = recorded.size();
            if (gbuffer.hits[i].valid)
                lighting.shade_hit(gbuffer.hits[i], -gbuffer.view_dirs[i], spp, rng);
            if (recorded.size() > before) {
                calls.push_back(before);
                call_row.push_back(int(i) / width);
            }
        }
        calls.push_back(recorded.size());
    }
};

Fixture& fixture(int spp) {
    static std::map<int, std::unique_ptr<Fixture>> fixtures;
    std::unique_ptr<Fixture>& f = fixtures[spp];
    if (!f) f = std::make_unique<Fixture>(spp);
    return *f;
}

void BM_ShadowRays_Integrator(benchmark::State& state) {
    Fixture& f = fixture(int(state.range(0)));
    const DirectLighting lighting(f.rays, ShadingSettings{});
    long rays = 0;
    for (auto _ : state) {
        std::atomic<long> count{0};
        tbb::parallel_for(0, f.height, [&](int y) {
            long local = 0;
            for (int x = 0; x < f.width; ++x) {
                const size_t p = size_t(y) * f.width + x;
                CounterRng rng(0, 0, p, 0);
                if (f.gbuffer.hits[p].valid)
                    local +=
                        lighting.shade_hit(f.gbuffer.hits[p], -f.gbuffer.view_dirs[p], f.spp, rng)
                            .rays;
            }
            count += local;
        });
        rays += count.load();
    }
    state.counters["Mrays/s"] =
        benchmark::Counter(double(rays) * 1e-6, benchmark::Counter::kIsRate);
}

void BM_ShadowRays_BareEmbree(benchmark::State& state) {
    Fixture& f = fixture(int(state.range(0)));
    // The same rays, pre-converted; the loop is nothing but rtcOccluded1M in chunks of 64.
    std::vector<RTCRay> rtc(f.recorded.size());
    for (size_t i = 0; i < f.recorded.size(); ++i) {
        const Ray& r = f.recorded[i];
        rtc[i] =
            RTCRay{r.origin.x,    r.origin.y, r.origin.z, r.tnear, r.direction.x, r.direction.y,
                   r.direction.z, 0.0f,       r.tfar,     ~0u,     unsigned(i),   0};
    }
    std::vector<RTCRay> work(rtc.size());
    const int chunks = int((rtc.size() + 63) / 64);
    long rays = 0;
    for (auto _ : state) {
        state.PauseTiming();
        work = rtc;  // occlusion overwrites tfar
        state.ResumeTiming();
        tbb::parallel_for(0, chunks, [&](int c) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            const size_t begin = size_t(c) * 64, n = std::min<size_t>(64, work.size() - begin);
            rtcOccluded1M(f.rays.top_scene(), &ctx, &work[begin], unsigned(n), sizeof(RTCRay));
        });
        rays += long(rtc.size());
    }
    state.counters["Mrays/s"] =
        benchmark::Counter(double(rays) * 1e-6, benchmark::Counter::kIsRate);
}

// The integrator's casting alone: the same rays through the same RayScene::occluded_stream
// calls (one a pixel, rows in parallel as above), without the shading around them. Integrator
// minus this is its shading time.
void BM_ShadowRays_IntegratorCasts(benchmark::State& state) {
    Fixture& f = fixture(int(state.range(0)));
    std::vector<std::pair<size_t, size_t>> rows(size_t(f.height), {0, 0});  // call range a row
    for (size_t c = 0; c + 1 < f.calls.size(); ++c) {
        auto& r = rows[size_t(f.call_row[c])];
        if (r.first == r.second) r.first = c;
        r.second = c + 1;
    }
    long rays = 0;
    for (auto _ : state) {
        tbb::parallel_for(0, f.height, [&](int y) {
            static thread_local std::unique_ptr<bool[]> occluded;
            static thread_local size_t capacity = 0;
            for (size_t c = rows[size_t(y)].first; c < rows[size_t(y)].second; ++c) {
                const size_t begin = f.calls[c], n = f.calls[c + 1] - begin;
                if (capacity < n) occluded.reset(new bool[capacity = n]);
                f.rays.occluded_stream(&f.recorded[begin], int(n), occluded.get());
            }
        });
        rays += long(f.recorded.size());
    }
    state.counters["Mrays/s"] =
        benchmark::Counter(double(rays) * 1e-6, benchmark::Counter::kIsRate);
}

// The same rays as 8-wide packets in cast order (consecutive rays mostly share a shading
// point, so a packet is coherent at its origin): what a packet-casting integrator could reach.
void BM_ShadowRays_BareEmbreePackets8(benchmark::State& state) {
    Fixture& f = fixture(int(state.range(0)));
    const int packets = int((f.recorded.size() + 7) / 8);
    std::vector<RTCRay8> rtc{size_t(packets)};
    std::vector<std::array<int, 8>> valid{size_t(packets)};
    for (size_t i = 0; i < f.recorded.size(); ++i) {
        const Ray& r = f.recorded[i];
        RTCRay8& p = rtc[i / 8];
        const size_t l = i % 8;
        p.org_x[l] = r.origin.x, p.org_y[l] = r.origin.y, p.org_z[l] = r.origin.z;
        p.dir_x[l] = r.direction.x, p.dir_y[l] = r.direction.y, p.dir_z[l] = r.direction.z;
        p.tnear[l] = r.tnear, p.tfar[l] = r.tfar, p.time[l] = 0.0f;
        p.mask[l] = ~0u, p.id[l] = unsigned(i), p.flags[l] = 0;
        valid[i / 8][l] = -1;
    }
    std::vector<RTCRay8> work(rtc.size());
    long rays = 0;
    for (auto _ : state) {
        state.PauseTiming();
        work = rtc;
        state.ResumeTiming();
        tbb::parallel_for(0, packets, [&](int c) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            rtcOccluded8(valid[size_t(c)].data(), f.rays.top_scene(), &ctx, &work[size_t(c)]);
        });
        rays += long(f.recorded.size());
    }
    state.counters["Mrays/s"] =
        benchmark::Counter(double(rays) * 1e-6, benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_ShadowRays_Integrator)
    ->Arg(16)
    ->Arg(256)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ShadowRays_IntegratorCasts)
    ->Arg(16)
    ->Arg(256)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ShadowRays_BareEmbree)
    ->Arg(16)
    ->Arg(256)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ShadowRays_BareEmbreePackets8)
    ->Arg(16)
    ->Arg(256)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_MAIN();
