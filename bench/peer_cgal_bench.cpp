// Peer: CGAL (Debian libcgal-dev): repair_polygon_soup (merges duplicate points, removes
// degenerate and duplicate polygons) + orient_polygon_soup + polygon_soup_to_polygon_mesh into
// a Surface_mesh, from the same bucket of facets that ncrev's BM_BuildMesh welds.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Surface_mesh.h>

#include "bench_common.h"

namespace ncrev::bench {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
namespace PMP = CGAL::Polygon_mesh_processing;

void BM_Peer_Cgal_SoupToMesh(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const auto& soup = torus_soup(n);
    std::vector<K::Point_3> points0;
    points0.reserve(soup.points.size());
    for (const Vec3& p : soup.points) points0.emplace_back(p.x, p.y, p.z);
    std::vector<std::vector<std::size_t>> polygons0;
    polygons0.reserve(soup.triangles.size());
    for (const auto& t : soup.triangles) polygons0.push_back({t[0], t[1], t[2]});
    for (auto _ : state) {
        state.PauseTiming();
        auto points = points0;
        auto polygons = polygons0;
        state.ResumeTiming();
        PMP::repair_polygon_soup(points, polygons);
        PMP::orient_polygon_soup(points, polygons);
        CGAL::Surface_mesh<K::Point_3> mesh;
        PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
        benchmark::DoNotOptimize(mesh.number_of_faces());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * soup.num_facets()));
}
BENCHMARK(BM_Peer_Cgal_SoupToMesh)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(3);

}  // namespace
}  // namespace ncrev::bench
