// Peer for segmentation (issue 7): CGAL's Efficient RANSAC shape detection with all five
// primitive kinds (plane, sphere, cylinder, cone, torus), what a CGAL user would run to split a
// scanned part into primitives, on the vertices (with their normals) of the same generated
// meshes as segment_bench.cpp. Its epsilon is ncrev's derived tolerance (1e-4 x the diagonal),
// cluster epsilon three times the mean edge length, at least 0.5 % of the points per shape.
// It labels points, not facets, and leaves unassigned points; ncrev labels every facet.
#include <map>
#include <utility>
#include <vector>

#include "bench_common.h"
#include "ncrev/mesh.h"
#include "ncrev/segment.h"
#include "peer_cgal_ransac.h"

namespace ncrev::bench {
namespace {

using namespace cgal_ransac;

struct Input {
    Pwns points;
    double tolerance = 0, mean_edge = 0;
};

const Input& input(const TriangleSoup& (*make)(std::size_t), std::size_t facets) {
    static std::map<std::pair<const void*, std::size_t>, Input> cache;
    const auto key = std::make_pair(reinterpret_cast<const void*>(make), facets);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    const Mesh mesh = build_mesh(make(facets)).value().mesh;
    Input in;
    const VertexMap<Vec3> n = vertex_normals(mesh);
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        const VertexId id(static_cast<std::uint32_t>(v));
        const Vec3 p = mesh.position(id);
        in.points.emplace_back(K::Point_3(p.x, p.y, p.z), K::Vector_3(n[id].x, n[id].y, n[id].z));
    }
    in.tolerance = default_segment_tolerance(mesh);
    double sum = 0;
    for (std::uint32_t h = 0; h < mesh.num_halfedges(); ++h)
        sum += norm(mesh.position(mesh.target(HalfedgeId(h))) -
                    mesh.position(mesh.origin(HalfedgeId(h))));
    in.mean_edge = sum / static_cast<double>(mesh.num_halfedges());
    return cache.emplace(key, std::move(in)).first->second;
}

void run(benchmark::State& state, const Input& in) {
    Ransac::Parameters p;
    p.probability = 0.01;
    p.min_points = std::max<std::size_t>(10, in.points.size() / 200);
    p.epsilon = in.tolerance;
    p.cluster_epsilon = 3 * in.mean_edge;
    p.normal_threshold = 0.9;
    std::size_t shapes = 0, unassigned = 0;
    for (auto _ : state) {
        Pwns points = in.points;  // detect() reorders its input
        Ransac ransac;
        ransac.set_input(points);
        ransac.add_shape_factory<CGAL::Shape_detection::Plane<Traits>>();
        ransac.add_shape_factory<CGAL::Shape_detection::Sphere<Traits>>();
        ransac.add_shape_factory<CGAL::Shape_detection::Cylinder<Traits>>();
        ransac.add_shape_factory<CGAL::Shape_detection::Cone<Traits>>();
        ransac.add_shape_factory<CGAL::Shape_detection::Torus<Traits>>();
        ransac.detect(p);
        shapes = ransac.shapes().size();
        unassigned = ransac.number_of_unassigned_points();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * in.points.size()));
    state.counters["points"] = static_cast<double>(in.points.size());
    state.counters["shapes"] = static_cast<double>(shapes);
    state.counters["unassigned"] = static_cast<double>(unassigned);
}

void BM_Peer_Cgal_RansacSegmentBox(benchmark::State& state) {
    run(state, input(box_grid_soup, static_cast<std::size_t>(state.range(0))));
}
void BM_Peer_Cgal_RansacSegmentTorus(benchmark::State& state) {
    run(state, input(torus_soup, static_cast<std::size_t>(state.range(0))));
}
BENCHMARK(BM_Peer_Cgal_RansacSegmentBox)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_Peer_Cgal_RansacSegmentTorus)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace ncrev::bench
