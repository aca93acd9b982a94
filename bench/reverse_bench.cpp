// ncrev reverse: facets and planar on 10k, 100k and 1M facets (a torus grid from
// bench_common), per-stage seconds and peak heap per facet as counters.
#include <unistd.h>

#include "bench_common.h"
#include "ncrev/brep.h"
#include "ncrev/mesh.h"

namespace ncrev::bench {
namespace {

void run_reverse(benchmark::State& state, const TriangleSoup& soup) {
    const auto method = state.range(0) == 0 ? ReverseMethod::kFacets : ReverseMethod::kPlanar;
    auto built = build_mesh(soup);
    if (!built) {
        state.SkipWithError("build failed");
        return;
    }
    const auto path = std::filesystem::temp_directory_path() /
                      ("ncrev_bench_reverse_" + std::to_string(::getpid()) + ".step");
    ReverseOptions options;
    options.method = method;
    ReverseReport last;
    double peak_per_facet = 0;
    for (auto _ : state) {
        const std::size_t base = heap_now();
        heap_reset_peak();
        auto rev = reverse_to_step(built->mesh, path, options);
        if (!rev || !rev->written) {
            state.SkipWithError("reverse failed");
            break;
        }
        last = *rev;
        peak_per_facet =
            static_cast<double>(heap_peak() - base) / static_cast<double>(built->mesh.num_faces());
    }
    std::filesystem::remove(path);
    state.SetItemsProcessed(
        static_cast<std::int64_t>(state.iterations() * built->mesh.num_faces()));
    for (const auto& [stage, seconds] : last.stage_seconds) state.counters[stage + "_s"] = seconds;
    state.counters["faces"] = static_cast<double>(last.faces);
    state.counters["step_MB"] = static_cast<double>(last.step_bytes) / 1e6;
    state.counters["peak_heap_B_per_facet"] = peak_per_facet;
    state.SetLabel(to_string(method));
}

// A curved part: a torus grid (planar merges only the planar quads).
void BM_Reverse(benchmark::State& state) {
    run_reverse(state, torus_soup(static_cast<std::size_t>(state.range(1))));
}

// A prismatic part: a box of n x n grids (planar gives its 6 faces).
void BM_ReversePrismatic(benchmark::State& state) {
    run_reverse(state, box_grid_soup(static_cast<std::size_t>(state.range(1))));
    // Written for the FreeCAD comparison (bench/freecad_reverse.py).
    benchmark::DoNotOptimize(box_grid_file(static_cast<std::size_t>(state.range(1))));
}
BENCHMARK(BM_ReversePrismatic)
    ->ArgsProduct({{0, 1}, {10'000, 100'000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_Reverse)
    ->ArgsProduct({{0, 1}, {10'000, 100'000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Reverse)
    ->ArgsProduct({{0, 1}, {1'000'000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace ncrev::bench
BENCHMARK_MAIN();
