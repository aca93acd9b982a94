// Peer: OpenMesh (Debian libopenmesh-dev). Two measures:
//  - its STL reader with its mesh build (IO::read_mesh into a TriMesh), from the same file
//    as BM_ReadAndBuildFile;
//  - its build alone (add_vertex + add_face) from an indexed mesh that is already welded,
//    which favours OpenMesh: ncrev's BM_BuildMesh also welds the bucket of facets.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <map>

#include "bench_common.h"

namespace ncrev::bench {
namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

void BM_Peer_OpenMesh_ReadStlFile(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto path = stl_binary_file(n);
    double peak_per_facet = 0;
    std::size_t facets = 0;
    for (auto _ : state) {
        const std::size_t base = heap_now();
        heap_reset_peak();
        OmMesh mesh;
        if (!OpenMesh::IO::read_mesh(mesh, path.string())) state.SkipWithError("read failed");
        facets = mesh.n_faces();
        peak_per_facet = static_cast<double>(heap_peak() - base) / static_cast<double>(facets);
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * facets));
    state.counters["peak_heap_B_per_facet"] = peak_per_facet;
}
BENCHMARK(BM_Peer_OpenMesh_ReadStlFile)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Peer_OpenMesh_Build(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto& soup = torus_soup(n);
    // Weld outside the timed loop (OpenMesh's build takes indexed input).
    std::vector<Vec3> pts;
    std::vector<std::array<int, 3>> tris;
    {
        std::map<std::tuple<double, double, double>, int> ids;
        for (const auto& t : soup.triangles) {
            std::array<int, 3> tri{};
            for (int k = 0; k < 3; ++k) {
                const Vec3 p = soup.points[t[k]];
                auto [it, fresh] =
                    ids.emplace(std::make_tuple(p.x, p.y, p.z), static_cast<int>(pts.size()));
                if (fresh) pts.push_back(p);
                tri[k] = it->second;
            }
            tris.push_back(tri);
        }
    }
    for (auto _ : state) {
        OmMesh mesh;
        mesh.reserve(pts.size(), pts.size() + tris.size(), tris.size());
        std::vector<OmMesh::VertexHandle> vh;
        vh.reserve(pts.size());
        for (const Vec3& p : pts) {
            vh.push_back(mesh.add_vertex(OmMesh::Point(
                static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z))));
        }
        for (const auto& t : tris) mesh.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
        benchmark::DoNotOptimize(mesh.n_faces());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * tris.size()));
}
BENCHMARK(BM_Peer_OpenMesh_Build)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace ncrev::bench
