// Fuzz target: mesh building and healing on arbitrary facet soups (coordinates from a small
// lattice so that welds, duplicates, non-manifold edges and vertices are frequent). The mesh
// must always satisfy its invariants, and the components' nesting and crossing pairs stay within
// its components; the facets found crossing each other are as many on one thread as on all.
#include <tbb/global_control.h>

#include <cstdlib>
#include <cstring>

#include "ncrev/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ncrev::TriangleSoup soup;
    // Each byte triple is one point on a 4x4x4 lattice plus a tiny jitter (cracks).
    for (std::size_t i = 0; i + 2 < size; i += 3) {
        const auto c = [&](std::size_t k) {
            const std::uint8_t b = data[i + k];
            return static_cast<double>(b & 3) + ((b >> 2) & 1 ? 1e-9 : 0.0);
        };
        soup.points.push_back({c(0), c(1), c(2)});
    }
    // Triangles: consecutive points, three at a time (as STL), plus some reuse of earlier ones.
    for (std::size_t i = 0; i + 2 < soup.points.size(); i += 3) {
        const auto a = static_cast<std::uint32_t>(i);
        soup.triangles.push_back({a, a + 1, a + 2});
    }
    auto r = ncrev::build_mesh(soup);
    if (!r.ok()) std::abort();
    if (!r->mesh.validate().empty()) std::abort();
    const auto stats = ncrev::compute_stats(r->mesh);
    if (stats.faces != r->mesh.num_faces()) std::abort();
    // Which closed component lies inside which (healing used the same to orient cavities).
    const auto nesting = ncrev::component_nesting(r->mesh);
    if (nesting.parent.size() != stats.components || nesting.depth.size() != stats.components)
        std::abort();
    for (std::size_t c = 0; c < nesting.parent.size(); ++c) {
        const std::uint32_t p = nesting.parent[c];
        if (p != ncrev::ComponentNesting::kNone && (p >= stats.components || p == c)) std::abort();
        if ((p == ncrev::ComponentNesting::kNone) != (nesting.depth[c] == 0)) std::abort();
    }
    // Crossing pairs: sorted, of two distinct closed components, never one inside the other.
    for (std::size_t i = 0; i < nesting.crossing.size(); ++i) {
        const auto [a, b] = nesting.crossing[i];
        if (!(a < b) || b >= stats.components || !nesting.components.closed[a] ||
            !nesting.components.closed[b])
            std::abort();
        if (i > 0 && !(nesting.crossing[i - 1] < nesting.crossing[i])) std::abort();
        if (nesting.parent[a] == b || nesting.parent[b] == a) std::abort();
    }
    if (r->heal.crossing_components > stats.components) std::abort();
    // Facets through each other: at most every pair of the input's, checked (a few facets),
    // where the first crosses within the mesh's box, and the same on one thread.
    const ncrev::HealReport& h = r->heal;
    const std::uint64_t n = soup.triangles.size();
    if (h.self_intersection_unchecked || h.self_intersections > n * (n + 1) / 2) std::abort();
    if (h.self_intersections > 0) {
        const ncrev::Box3 box = stats.bbox;
        const ncrev::Vec3 at = h.self_intersection_at;
        for (int k = 0; k < 3; ++k) {
            if (!(at[k] >= box.min[k] - 1e-9 && at[k] <= box.max[k] + 1e-9)) std::abort();
        }
    }
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        auto again = ncrev::build_mesh(soup);
        if (!again.ok() || again->heal.self_intersections != h.self_intersections ||
            !(again->heal.self_intersection_at == h.self_intersection_at))
            std::abort();
    }
    return 0;
}
