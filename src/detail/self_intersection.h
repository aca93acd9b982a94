// Where a triangle mesh passes through itself: two facets of one component that cross (a
// vertex pushed through the opposite wall, a surface folded back over its neighbour). A solid
// built from such a mesh intersects itself too, which OpenCASCADE's check does not see (it
// checks each face's wires, not faces against each other). Used by healing, which reports
// them and mends none.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "detail/nesting.h"
#include "detail/triangle_tree.h"
#include "ncrev/common.h"

namespace ncrev::detail {

/// Facet pairs the tree hands out at most, summed over all facets, before the check gives up:
/// a bound of a few seconds. A mesh of a machined part gets a few dozen per facet (its leaves
/// hold kLeafTriangles each, and a facet's box meets those of its fan and the next ring): a
/// ball of 2M facets 38M (docs/benchmarks.md). A pile of facets over one another in one place
/// would otherwise cost facets squared.
inline constexpr std::uint64_t kSelfIntersectionWork = 400'000'000;

/// Pairs a task counts before it adds them to the shared count (and learns whether to stop).
inline constexpr std::uint64_t kWorkFlush = 1u << 16;

inline constexpr std::uint32_t kNoFacet = 0xffffffffu;

struct SelfIntersections {
    /// Facet pairs of one component that cross each other (see self_intersections()).
    std::uint64_t pairs = 0;
    /// False when the work bound (kSelfIntersectionWork) stopped the check: then no pair is
    /// counted.
    bool complete = true;
    /// The crossing pair (first < second) of least indices, kNoFacet for none, and a point where
    /// they meet.
    std::uint32_t first = kNoFacet, second = kNoFacet;
    Vec3 at{};
};

/// The point where segment pq meets the plane of triangle t (pq not parallel to it).
inline Vec3 plane_crossing(Vec3 p, Vec3 q, const Triangle& t) {
    const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
    const double dp = dot(p - t[0], n), dq = dot(q - t[0], n);
    return p + (dp / (dp - dq)) * (q - p);
}

/// Whether two facets of one component cross, and where: `u`, `t` their corners, `iu`, `it`
/// their vertex ids. Sharing no vertex: an edge of one passes through the other more than
/// `tol` inside it (pierces(), kThrough). An edge through a border between facets (kBorder)
/// does not count: it may only graze a convex edge, and telling needs the facets around it.
/// Where a part crosses itself, most of its crossing edges pass through facets; only a crossing
/// whose every edge meets borders (a cube's corner pushed straight through the diagonal of the
/// opposite wall) is missed. Sharing one vertex: the edge of one opposite that vertex
/// passes through the other (where two facets of a fan overlap, the line they share through
/// the vertex leaves the nearer one through that edge). Sharing an edge: folded onto each
/// other, the third corner of one in the other's plane within `tol` and on the same side of
/// the edge by more than `tol`. Facets that only touch (a wall within `tol` of another, an
/// edge along a facet) do not cross.
inline bool facets_cross(const Triangle& u, const std::array<std::uint32_t, 3>& iu,
                         const Triangle& t, const std::array<std::uint32_t, 3>& it, double tol,
                         Vec3& at) {
    int shared = 0;
    std::array<bool, 3> u_shared{}, t_shared{};
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
            if (iu[i] != it[k]) continue;
            u_shared[i] = t_shared[k] = true;
            ++shared;
        }
    }
    // Edge k of a triangle runs from corner k to corner k + 1.
    const auto through = [&](const Triangle& a, std::size_t k, const Triangle& b) {
        const Vec3 p = a[k], q = a[(k + 1) % 3];
        if (pierces(p, q, b, tol) != Pierce::kThrough) return false;
        at = plane_crossing(p, q, b);
        return true;
    };
    if (shared == 0) {
        // Most pairs the tree hands out: one wholly on one side of the other's plane.
        if (apart(u, t, tol) || apart(t, u, tol)) return false;
        for (std::size_t k = 0; k < 3; ++k)
            if (through(u, k, t) || through(t, k, u)) return true;
        return false;
    }
    if (shared == 1) {
        // The edge opposite the shared corner: the one whose ends are both unshared.
        const auto opposite = [](const std::array<bool, 3>& s) {
            for (std::size_t k = 0; k < 3; ++k)
                if (!s[k] && !s[(k + 1) % 3]) return k;
            return std::size_t{0};
        };
        return through(u, opposite(u_shared), t) || through(t, opposite(t_shared), u);
    }
    if (shared == 2) {
        std::size_t ku = 0, kt = 0;  // the unshared corners
        while (u_shared[ku]) ++ku;
        while (t_shared[kt]) ++kt;
        const Vec3 p = u[(ku + 1) % 3], q = u[(ku + 2) % 3];
        Vec3 n = cross(u[1] - u[0], u[2] - u[0]);
        const double len = norm(n), edge = norm(q - p);
        if (!(len > 0) || !(edge > 0)) return false;
        n = (1 / len) * n;
        if (std::fabs(dot(t[kt] - p, n)) > tol) return false;
        // Sides of the edge within u's plane: u's own corner, t's.
        const double side_u = dot(cross(q - p, u[ku] - p), n) / edge;
        const double side_t = dot(cross(q - p, t[kt] - p), n) / edge;
        if (!((side_u > 0) == (side_t > 0) && std::fabs(side_t) > tol)) return false;
        at = (1.0 / 3) * (t[0] + t[1] + t[2]);
        return true;
    }
    return false;  // the same three vertices: a duplicate, which healing removes
}

/// The facet pairs of one component (`component[f]`) that cross (facets_cross()), counted
/// each once: `corners(f)` facet f's three points, `ids(f)` their vertex ids, `tol` the distance
/// within which points touch (at least kTouchShare of the mesh's size). Facets of different
/// components are not compared: closed ones that cross are crossing_components()'s. A tree of
/// all facets hands each facet those whose boxes may meet its own; past kSelfIntersectionWork
/// of them the check stops, incomplete. Deterministic on any thread count.
template <class Corners, class Ids>
SelfIntersections self_intersections(std::span<const std::uint32_t> component, double tol,
                                     const Corners& corners, const Ids& ids) {
    SelfIntersections out;
    const std::size_t nf = component.size();
    if (nf < 2) return out;
    std::vector<Triangle> tris(nf);
    Box3 all;
    for (std::size_t f = 0; f < nf; ++f) {
        tris[f] = corners(static_cast<std::uint32_t>(f));
        for (const Vec3& p : tris[f]) all.add(p);
    }
    tol = std::max(tol, kTouchShare * all.diagonal());
    const TriangleTree tree(std::move(tris));
    // The facets' components and vertex ids in the tree's order, where the pairs come from:
    // read one after another rather than all over the mesh.
    std::vector<std::uint32_t> comp_at(nf);
    std::vector<std::array<std::uint32_t, 3>> ids_at(nf);
    tbb::parallel_for(
        tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(nf), 1u << 14),
        [&](const auto& r) {
            for (std::uint32_t pos = r.begin(); pos != r.end(); ++pos) {
                comp_at[pos] = component[tree.index(pos)];
                ids_at[pos] = ids(tree.index(pos));
            }
        });
    // Per thread: pairs handed out (told the others every kWorkFlush and at the end), pairs
    // that cross, and the least of those.
    struct Tally {
        std::uint64_t work = 0, found = 0;
        std::uint32_t first = kNoFacet, second = kNoFacet;
        Vec3 at{};
    };
    tbb::enumerable_thread_specific<Tally> tallies;
    std::atomic<std::uint64_t> work{0};
    std::atomic<bool> stopped{false};
    tree.for_each_pair(tol, [&](std::uint32_t a, std::uint32_t b) {
        Tally& mine = tallies.local();
        if (++mine.work >= kWorkFlush) {
            if (work.fetch_add(mine.work) + mine.work > kSelfIntersectionWork) stopped = true;
            mine.work = 0;
        }
        if (stopped) return false;
        if (comp_at[a] != comp_at[b]) return true;
        // Always the lower index first: the same answer whichever way the tree pairs them.
        if (tree.index(b) < tree.index(a)) std::swap(a, b);
        const std::uint32_t f = tree.index(a), g = tree.index(b);
        Vec3 at;
        if (!facets_cross(tree.triangle(a), ids_at[a], tree.triangle(b), ids_at[b], tol, at))
            return true;
        ++mine.found;
        if (mine.first == kNoFacet || f < mine.first || (f == mine.first && g < mine.second)) {
            mine.first = f;
            mine.second = g;
            mine.at = at;
        }
        return true;
    });
    std::uint64_t pairs = 0;
    for (const Tally& t : tallies) {
        if (work.fetch_add(t.work) + t.work > kSelfIntersectionWork) stopped = true;
        pairs += t.found;
        if (t.first == kNoFacet) continue;
        if (out.first == kNoFacet || t.first < out.first ||
            (t.first == out.first && t.second < out.second)) {
            out.first = t.first;
            out.second = t.second;
            out.at = t.at;
        }
    }
    if (stopped) return SelfIntersections{0, false, kNoFacet, kNoFacet, {}};
    out.pairs = pairs;
    return out;
}

}  // namespace ncrev::detail
