// Method B's table queries (issue "Method B, part 1", acceptance 6: a query <= 200 ns).
//   ./build/tests/freqlab_benchmarks --benchmark_filter=TableQuery
#include <benchmark/benchmark.h>

#include "volume/impulse_tables.h"

using namespace freqlab;

namespace {

const ImpulseTables& tables() {
    static const ImpulseTables t = ImpulseTables::build(30);
    return t;
}

void BM_TableQuery_PointSingle(benchmark::State& state) {
    const ImpulseTables& t = tables();
    HomogeneousMedium m{0.7, 0.05, 0.3};
    double d = 0.01;
    for (auto _ : state) {
        d = d > 5.0 ? 0.01 : d * 1.01;
        benchmark::DoNotOptimize(t.point_single().single(m, d));
    }
}

void BM_TableQuery_PointMultiple10(benchmark::State& state) {
    const ImpulseTables& t = tables();
    HomogeneousMedium m{0.7, 0.05, 0.0};
    double d = 0.01;
    for (auto _ : state) {
        d = d > 5.0 ? 0.01 : d * 1.01;
        benchmark::DoNotOptimize(t.point_multiple().bounces_in(m, d, 2, 10));
    }
}

}  // namespace

BENCHMARK(BM_TableQuery_PointSingle);
BENCHMARK(BM_TableQuery_PointMultiple10);
