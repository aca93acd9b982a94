// Readers and mesh building: throughput (facets/s, bytes/s) and peak heap per facet.
// Peers (OpenMesh, CGAL) are in peer_*_bench.cpp, built when installed.
#include <tbb/global_control.h>

#include <map>

#include "bench_common.h"
#include "ncrev/mesh.h"

namespace ncrev::bench {
namespace {

constexpr std::size_t k100k = 100'000, k1M = 1'000'000, k5M = 5'000'000;
// The three mesh sizes, in milliseconds of wall time (the reads and builds use every core).
#define NCREV_MESH_SIZES \
    ->Arg(k100k)->Arg(k1M)->Arg(k5M)->Unit(benchmark::kMillisecond)->UseRealTime()

std::span<const std::byte> as_bytes(const std::string& s) {
    return {reinterpret_cast<const std::byte*>(s.data()), s.size()};
}

void BM_ReadStlBinary(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto& bytes = stl_binary_bytes(n);
    std::size_t facets = 0;
    for (auto _ : state) {
        auto soup = read_stl(bytes);
        if (!soup) state.SkipWithError("read failed");
        facets = soup->num_facets();
        benchmark::DoNotOptimize(soup->points.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * facets));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes.size()));
    state.counters["facets"] = static_cast<double>(facets);
}
BENCHMARK(BM_ReadStlBinary) NCREV_MESH_SIZES;

// The same with the exact weld done while reading (what `ncrev info` does).
void BM_ReadStlBinaryWelding(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto& bytes = stl_binary_bytes(n);
    ReadOptions options;
    options.weld_exact = true;
    std::size_t facets = 0;
    for (auto _ : state) {
        auto soup = read_stl(bytes, {}, options);
        if (!soup) state.SkipWithError("read failed");
        facets = soup->num_facets();
        benchmark::DoNotOptimize(soup->points.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * facets));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes.size()));
}
BENCHMARK(BM_ReadStlBinaryWelding) NCREV_MESH_SIZES;

void BM_ReadStlAscii(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto& text = stl_ascii_text(n);
    std::size_t facets = 0;
    for (auto _ : state) {
        auto soup = read_stl(as_bytes(text));
        if (!soup) state.SkipWithError("read failed");
        facets = soup->num_facets();
        benchmark::DoNotOptimize(soup->points.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * facets));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_ReadStlAscii)->Arg(k100k)->Arg(k1M)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReadSre(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto& text = sre_text(n);
    std::size_t facets = 0;
    for (auto _ : state) {
        auto soup = read_sre(as_bytes(text));
        if (!soup) state.SkipWithError("read failed");
        facets = soup->num_facets();
        benchmark::DoNotOptimize(soup->points.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * facets));
    state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_ReadSre)->Arg(k100k)->Arg(k1M)->Unit(benchmark::kMillisecond)->UseRealTime();

// Weld + half-edge build + orientation from a soup already in memory (the soup is not
// consumed, so that iterations repeat the same work). Second argument: threads.
void BM_BuildMesh(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                static_cast<std::size_t>(state.range(1)));
    const auto& soup = torus_soup(n);
    for (auto _ : state) {
        auto built = build_mesh(soup);
        if (!built) state.SkipWithError("build failed");
        benchmark::DoNotOptimize(built->mesh.twins().data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * soup.num_facets()));
}
BENCHMARK(BM_BuildMesh)
    ->Args({k100k, 1})
    ->Args({k100k, 2})
    ->Args({k1M, 1})
    ->Args({k1M, 2})
    ->Args({k5M, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same torus with 128 caps stitched in, spread over it: T-junctions closed by zero-area
// facets, as CAD tessellations make them (BRepMesh's meshes of the samples have tens), which
// healing removes by splitting the facet beyond each one's long edge. One thread.
constexpr std::size_t kBenchCaps = 128;

const TriangleSoup& capped_torus_soup(std::size_t facets) {
    static std::map<std::size_t, TriangleSoup> cache;
    auto it = cache.find(facets);
    if (it != cache.end()) return it->second;
    TriangleSoup s = torus_soup(facets);
    const std::size_t n = s.num_facets();
    for (std::size_t i = 0; i < kBenchCaps; ++i) {
        const std::size_t f = (2 * i + 1) * n / (2 * kBenchCaps);
        const auto [a, b, x] = s.triangles[f];
        s.points.push_back(0.5 * (s.points[a] + s.points[b]));
        const auto c = static_cast<std::uint32_t>(s.points.size() - 1);
        s.triangles[f] = {a, c, x};
        s.triangles.push_back({c, b, x});
        s.triangles.push_back({a, b, c});
    }
    return cache.emplace(facets, std::move(s)).first->second;
}

void BM_BuildMeshWithCaps(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 1);
    const auto& soup = capped_torus_soup(n);
    for (auto _ : state) {
        auto built = build_mesh(soup);
        if (!built || built->heal.caps_split != kBenchCaps) {
            state.SkipWithError("the caps were not all split");
            break;
        }
        benchmark::DoNotOptimize(built->mesh.twins().data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * soup.num_facets()));
}
BENCHMARK(BM_BuildMeshWithCaps)->Arg(k100k)->Arg(k1M)->Unit(benchmark::kMillisecond)->UseRealTime();

// What `ncrev info` does: read a binary STL file from the page cache, welding exactly while
// reading, and build the mesh, consuming the soup. Reports the peak heap above the start, per
// facet (the file's mapping is not heap: it is the page cache's).
void BM_ReadAndBuildFile(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto path = stl_binary_file(n);
    std::size_t facets = 0;
    double peak_per_facet = 0;
    for (auto _ : state) {
        const std::size_t base = heap_now();
        heap_reset_peak();
        ReadOptions options;
        options.weld_exact = true;
        auto soup = read_mesh_file(path, options);
        if (!soup) state.SkipWithError("read failed");
        facets = soup->num_facets();
        auto built = build_mesh(std::move(soup).value());
        if (!built) state.SkipWithError("build failed");
        benchmark::DoNotOptimize(built->mesh.twins().data());
        peak_per_facet = static_cast<double>(heap_peak() - base) / static_cast<double>(facets);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * facets));
    state.counters["peak_heap_B_per_facet"] = peak_per_facet;
}
BENCHMARK(BM_ReadAndBuildFile) NCREV_MESH_SIZES;

// The part's size in every pose (part_size(), the segmentation's tolerance), against the
// bounding box's diagonal it replaced, on the torus: no planar face, so its three largest
// facets' directions each give a generic outline to hull.
void BM_PartSize(benchmark::State& state) {
    const Mesh& m = torus_mesh(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(part_size(m));
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * m.num_faces()));
}
BENCHMARK(BM_PartSize) NCREV_MESH_SIZES;

void BM_BoxDiagonal(benchmark::State& state) {
    const Mesh& m = torus_mesh(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) {
        Box3 box;
        for (const Vec3& p : m.positions()) box.add(p);
        benchmark::DoNotOptimize(box.diagonal());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * m.num_faces()));
}
BENCHMARK(BM_BoxDiagonal) NCREV_MESH_SIZES;

}  // namespace
}  // namespace ncrev::bench
