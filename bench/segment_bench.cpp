// Segmentation (issue 7): facets per second of the whole stage (segment(): patches, growing
// with fits, merging, refining, the final fit of every region) on generated meshes of 100k, 1M
// and 5M facets: the box grid (a prismatic part: six planes, every facet inside a face) and
// the torus grid (one curved face). The paper method includes its curvature.
#include <map>

#include "bench_common.h"
#include "ncrev/mesh.h"
#include "ncrev/segment.h"

namespace ncrev::bench {
namespace {

constexpr std::size_t k100k = 100'000, k1M = 1'000'000, k5M = 5'000'000;

const Mesh& cached(const TriangleSoup& (*make)(std::size_t), std::size_t facets) {
    static std::map<std::pair<const void*, std::size_t>, Mesh> cache;
    const auto key = std::make_pair(reinterpret_cast<const void*>(make), facets);
    auto it = cache.find(key);
    if (it == cache.end()) it = cache.emplace(key, build_mesh(make(facets)).value().mesh).first;
    return it->second;
}

void run(benchmark::State& state, const Mesh& mesh, SegmentMethod method) {
    SegmentOptions o;
    o.method = method;
    std::size_t regions = 0;
    for (auto _ : state) {
        Result<SegmentResult> r = segment(mesh, o);
        regions = r.value().regions.size();
        benchmark::DoNotOptimize(r.value().region.data().data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * mesh.num_faces()));
    state.counters["facets"] = static_cast<double>(mesh.num_faces());
    state.counters["regions"] = static_cast<double>(regions);
}

void BM_SegmentFacetsBox(benchmark::State& state) {
    run(state, cached(box_grid_soup, static_cast<std::size_t>(state.range(0))),
        SegmentMethod::kFacets);
}
void BM_SegmentFacetsTorus(benchmark::State& state) {
    run(state, cached(torus_soup, static_cast<std::size_t>(state.range(0))),
        SegmentMethod::kFacets);
}
void BM_SegmentPaperBox(benchmark::State& state) {
    run(state, cached(box_grid_soup, static_cast<std::size_t>(state.range(0))),
        SegmentMethod::kPaper);
}
void BM_SegmentPaperTorus(benchmark::State& state) {
    run(state, cached(torus_soup, static_cast<std::size_t>(state.range(0))), SegmentMethod::kPaper);
}

#define NCREV_SEGMENT_SIZES \
    ->Arg(k100k)->Arg(k1M)->Arg(k5M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)
BENCHMARK(BM_SegmentFacetsBox) NCREV_SEGMENT_SIZES;
BENCHMARK(BM_SegmentFacetsTorus) NCREV_SEGMENT_SIZES;
BENCHMARK(BM_SegmentPaperBox) NCREV_SEGMENT_SIZES;
BENCHMARK(BM_SegmentPaperTorus) NCREV_SEGMENT_SIZES;

}  // namespace
}  // namespace ncrev::bench
