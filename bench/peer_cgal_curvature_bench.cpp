// Peer: CGAL's jet fitting (Cazals and Pouget, "Estimating differential quantities using
// polynomial fitting of osculating jets", 2005; Debian libcgal-dev), the curvature estimator a
// user of CGAL would pick: a degree-2 jet fitted to each vertex's 2-ring (about 19 points), run
// in parallel over the vertices like ncrev. The 2-rings are gathered before the clock starts.
#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <map>
#include <vector>

#include "bench_common.h"
#include "ncrev/mesh.h"

namespace ncrev::bench {
namespace {

using K = CGAL::Simple_cartesian<double>;
using Fitting = CGAL::Monge_via_jet_fitting<K>;

/// Every vertex's 2-ring (itself first), as CSR.
struct Rings {
    std::vector<std::uint32_t> offset, ids;
};

Rings two_rings(const Mesh& m) {
    Rings r;
    r.offset.push_back(0);
    std::vector<std::uint32_t> ring;
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        ring.assign(1, static_cast<std::uint32_t>(v));
        auto add = [&](std::uint32_t w) {
            if (std::find(ring.begin(), ring.end(), w) == ring.end()) ring.push_back(w);
        };
        m.for_each_neighbour(VertexId(static_cast<std::uint32_t>(v)),
                             [&](VertexId w) { add(w.idx()); });
        const std::size_t first = ring.size();
        for (std::size_t i = 1; i < first; ++i)
            m.for_each_neighbour(VertexId(ring[i]), [&](VertexId w) { add(w.idx()); });
        r.ids.insert(r.ids.end(), ring.begin(), ring.end());
        r.offset.push_back(static_cast<std::uint32_t>(r.ids.size()));
    }
    return r;
}

void BM_Peer_Cgal_JetCurvature(benchmark::State& state) {
    const Mesh mesh = build_mesh(torus_soup(static_cast<std::size_t>(state.range(0)))).value().mesh;
    const Rings rings = two_rings(mesh);
    const std::size_t nv = mesh.num_vertices();
    std::vector<double> k1(nv), k2(nv);
    for (auto _ : state) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
            std::vector<K::Point_3> pts;
            for (std::size_t v = r.begin(); v != r.end(); ++v) {
                pts.clear();
                for (std::uint32_t k = rings.offset[v]; k < rings.offset[v + 1]; ++k) {
                    const Vec3 p = mesh.position(VertexId(rings.ids[k]));
                    pts.emplace_back(p.x, p.y, p.z);
                }
                Fitting fit;
                const Fitting::Monge_form form = fit(pts.begin(), pts.end(), 2, 2);
                k1[v] = form.principal_curvatures(0);
                k2[v] = form.principal_curvatures(1);
            }
        });
        benchmark::DoNotOptimize(k1.data());
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * nv));
    state.counters["vertices"] = static_cast<double>(nv);
}
BENCHMARK(BM_Peer_Cgal_JetCurvature)
    ->Arg(100'000)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace ncrev::bench
