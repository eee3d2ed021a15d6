// The environment bandwidth hierarchy's build (issue "Method A, part 1", acceptance 6: a
// 1024 x 512 map in <= 2 s on 2 cores). rotor.json's map, resampled to 1024 x 512 if needed.
//   ./build/tests/freqlab_benchmarks --benchmark_filter=EnvBandwidth
#include <benchmark/benchmark.h>

#include <memory>

#include "freq/env_bandwidth.h"
#include "scene/scene_loader.h"

using namespace freqlab;

namespace {

void BM_EnvBandwidthBuild_1024x512(benchmark::State& state) {
    const Scene scene = load_scene(FREQLAB_SOURCE_DIR "/scenes/rotor.json");
    const EnvironmentMap& source = *scene.environment();
    auto image = std::make_shared<RgbImage>();
    image->width = 1024;
    image->height = 512;
    image->pixels.resize(size_t(1024) * 512);
    for (int y = 0; y < 512; ++y)
        for (int x = 0; x < 1024; ++x)
            image->pixels[size_t(y) * 1024 + size_t(x)] = source.eval_smooth(
                source.uv_to_direction(vec2((x + 0.5f) / 1024, (y + 0.5f) / 512)));
    const EnvironmentMap env("rotor-1024", image, 0.0f, 1.0f);
    for (auto _ : state) benchmark::DoNotOptimize(EnvBandwidthHierarchy::build(env));
}

}  // namespace

BENCHMARK(BM_EnvBandwidthBuild_1024x512)->Unit(benchmark::kMillisecond)->Iterations(3);
