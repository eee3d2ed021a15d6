// Method B's table queries (issue "Method B, part 1", acceptance 6: a query <= 200 ns).
//   ./build/tests/freqlab_benchmarks --benchmark_filter=TableQuery
#include <benchmark/benchmark.h>

#include "volume/impulse_query.h"
#include "volume/impulse_tables.h"

using namespace freqlab;

namespace {

const ImpulseTables& tables() {
    static const ImpulseTables t = ImpulseTables::build(30);
    return t;
}

// Queries along a slow sweep of distances (0.01 to 5, 1 % steps), as a baker's neighbouring
// texels would make them.
template <class Query>
void sweep_distances(benchmark::State& state, Query query) {
    double d = 0.01;
    for (auto _ : state) {
        d = d > 5.0 ? 0.01 : d * 1.01;
        benchmark::DoNotOptimize(query(d));
    }
}

void BM_TableQuery_PointSingle(benchmark::State& state) {
    const HomogeneousMedium m{0.7, 0.05, 0.3};
    sweep_distances(state, [&](double d) { return tables().point_single().single(m, d); });
}

void BM_TableQuery_PointMultiple10(benchmark::State& state) {
    const HomogeneousMedium m{0.7, 0.05, 0.0};
    sweep_distances(state,
                    [&](double d) { return tables().point_multiple().bounces_in(m, d, 2, 10); });
}

void BM_TableQuery_AreaSingle(benchmark::State& state) {
    const ImpulseTables& t = tables();
    HomogeneousMedium m{0.7, 0.05, 0.3};
    double d = 0.01, shift = 0.0;
    for (auto _ : state) {
        d = d > 5.0 ? 0.01 : d * 1.01;
        shift = shift > 0.99 ? 0.0 : shift + 0.013;
        benchmark::DoNotOptimize(t.area_single().single(m, d, shift));
    }
}

void BM_TableQuery_DirectionalMultiple10(benchmark::State& state) {
    const HomogeneousMedium m{0.7, 0.05, 0.0};
    sweep_distances(
        state, [&](double d) { return tables().directional_multiple().bounces_in(m, d, 2, 10); });
}

// The whole query as the bakers call it: direct + single + bounces 2..30, area emitter.
void BM_TableQuery_AreaAllBounces(benchmark::State& state) {
    const ImpulseTables& t = tables();
    ImpulseQuery q;
    q.emitter = EmitterKind::Area;
    q.medium = {0.7, 0.05, 0.3};
    q.last_bounce = 30;
    double d = 0.01;
    for (auto _ : state) {
        d = d > 5.0 ? 0.01 : d * 1.01;
        q.distance = d;
        q.shift = 0.4;
        benchmark::DoNotOptimize(query_impulse(t, q));
    }
}

}  // namespace

BENCHMARK(BM_TableQuery_AreaSingle);
BENCHMARK(BM_TableQuery_DirectionalMultiple10);
BENCHMARK(BM_TableQuery_AreaAllBounces);
BENCHMARK(BM_TableQuery_PointSingle);
BENCHMARK(BM_TableQuery_PointMultiple10);
