// Curvature (issue 5): vertices per second of compute_curvature() on the torus grid of 100k,
// 1M and 5M facets, for the default (smoothed) neighbourhood, the exact kernel, and the 1-ring
// and 2-ring ones.
#include <tbb/global_control.h>

#include "bench_common.h"
#include "ncrev/curvature.h"
#include "ncrev/mesh.h"

namespace ncrev::bench {
namespace {

constexpr std::size_t k100k = 100'000, k1M = 1'000'000, k5M = 5'000'000;

void run(benchmark::State& state, const CurvatureOptions& options) {
    const Mesh& mesh = torus_mesh(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) {
        const CurvatureResult r = compute_curvature(mesh, options);
        benchmark::DoNotOptimize(r.field.k1.data().data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * mesh.num_vertices()));
    state.counters["vertices"] = static_cast<double>(mesh.num_vertices());
}

void BM_CurvatureDefault(benchmark::State& state) { run(state, {}); }
void BM_CurvatureKernel(benchmark::State& state) {
    CurvatureOptions o;
    o.neighbourhood = Neighbourhood::kKernel;
    run(state, o);
}
void BM_CurvatureOneRing(benchmark::State& state) {
    CurvatureOptions o;
    o.neighbourhood = Neighbourhood::kRings;
    o.rings = 1;
    run(state, o);
}
void BM_CurvatureTwoRing(benchmark::State& state) {
    CurvatureOptions o;
    o.neighbourhood = Neighbourhood::kRings;
    o.rings = 2;
    run(state, o);
}
// The default on one core, for the parallel speed-up.
void BM_CurvatureDefaultOneThread(benchmark::State& state) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    run(state, {});
}

#define NCREV_CURVATURE_SIZES \
    ->Arg(k100k)->Arg(k1M)->Arg(k5M)->Unit(benchmark::kMillisecond)->UseRealTime()
BENCHMARK(BM_CurvatureDefault) NCREV_CURVATURE_SIZES;
BENCHMARK(BM_CurvatureKernel) NCREV_CURVATURE_SIZES;
BENCHMARK(BM_CurvatureOneRing) NCREV_CURVATURE_SIZES;
BENCHMARK(BM_CurvatureTwoRing) NCREV_CURVATURE_SIZES;
BENCHMARK(BM_CurvatureDefaultOneThread)->Arg(k1M)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace ncrev::bench
