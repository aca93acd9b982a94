// Where a triangle mesh passes through itself: two facets of one component that cross (a
// vertex pushed through the opposite wall, a surface folded back over its neighbour). A solid
// built from such a mesh intersects itself too, which OpenCASCADE's check does not see (it
// checks each face's wires, not faces against each other). Used by healing, which reports
// them and mends none.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "detail/box_pairs.h"
#include "detail/nesting.h"
#include "detail/triangle_tree.h"
#include "ncrev/common.h"
#include "ncrev/mesh.h"

namespace ncrev::detail {

/// Facet pairs whose boxes meet, as the search hands them out, at most, before the check
/// gives up: a bound of some fifteen seconds. A mesh of a machined part has about a dozen per
/// facet (a facet's box meets those of its fans and a few more): 24M on a ball of 2M facets,
/// searched and compared in about 1 s (docs/benchmarks.md). A pile of facets over one another
/// in one place would otherwise cost facets squared.
inline constexpr std::uint64_t kSelfIntersectionWork = 400'000'000;

/// Pairs a task counts before it adds them to the shared count (and learns whether to stop).
inline constexpr std::uint64_t kWorkFlush = 1u << 16;

inline constexpr std::uint32_t kNoFacet = 0xffffffffu;

/// The point where segment pq meets the plane of triangle t (pq not parallel to it).
inline Vec3 plane_crossing(Vec3 p, Vec3 q, const Triangle& t) {
    const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
    const double dp = dot(p - t[0], n), dq = dot(q - t[0], n);
    return p + (dp / (dp - dq)) * (q - p);
}

/// Whether segment pq, which passes within `tol` of the border of facet b (index bi), crosses
/// the surface there (`at`: where). Only through an edge, within `tol` of one of b's edges and
/// clear of the others (through a corner it is not counted), and one with a facet across it
/// (`across(bi, k, ci, c, ids)`: the facet ci across b's edge k, from corner k to k + 1, its
/// corners c and vertex ids, both facets turned as the mesh's orientation has them). The two
/// facets make a wedge, open (convex: c's middle below b's plane) or closed; pq crosses when
/// one end lies outside the wedge and the other inside, each by more than `tol`: an edge that
/// only grazes a convex edge has both ends outside. Counted on the facet of lower index of the
/// two, or on b when pq's facet (vertex ids `ids_pq`) shares a corner with c (its pair with c
/// is tested otherwise).
template <class Across>
bool crosses_border(Vec3 p, Vec3 q, const Triangle& b, std::uint32_t bi,
                    const std::array<std::uint32_t, 3>& ids_pq, const Across& across, double tol,
                    Vec3& at) {
    Vec3 n1 = cross(b[1] - b[0], b[2] - b[0]);
    const double len = norm(n1);
    if (!(len > 0)) return false;
    n1 = (1 / len) * n1;
    const Vec3 x = plane_crossing(p, q, b);
    int edge = -1;
    for (std::size_t k = 0; k < 3; ++k) {
        const Vec3 e = b[(k + 1) % 3] - b[k];
        const double le = norm(e);
        if (!(le > 0)) return false;
        if (dot(cross(e, x - b[k]), n1) / le > tol) continue;
        if (edge >= 0) return false;  // near a corner
        edge = static_cast<int>(k);
    }
    std::uint32_t ci = kNoFacet;
    Triangle c;
    std::array<std::uint32_t, 3> ids_c{};
    if (edge < 0 || !across(bi, edge, ci, c, ids_c)) return false;
    bool shares = false;
    for (const std::uint32_t v : ids_pq)
        shares = shares || std::find(ids_c.begin(), ids_c.end(), v) != ids_c.end();
    if (!(bi < ci) && !shares) return false;
    Vec3 n2 = cross(c[1] - c[0], c[2] - c[0]);
    const double len2 = norm(n2);
    if (!(len2 > 0)) return false;
    n2 = (1 / len2) * n2;
    const Vec3 a = b[static_cast<std::size_t>(edge)];
    const bool convex = dot((1.0 / 3) * (c[0] + c[1] + c[2]) - a, n1) < 0;
    // How far outside the wedge (negative: inside).
    const auto outside = [&](Vec3 v) {
        const double s1 = dot(v - a, n1), s2 = dot(v - a, n2);
        return convex ? std::max(s1, s2) : std::min(s1, s2);
    };
    const double op = outside(p), oq = outside(q);
    if (!((op > tol && oq < -tol) || (op < -tol && oq > tol))) return false;
    at = x;
    return true;
}

/// Whether two facets of one component cross, and where: `u`, `t` their corners, `iu`, `it`
/// their vertex ids, `ui`, `ti` their indices. Sharing no vertex: an edge of one passes through
/// the other, more than `tol` inside it (pierces(), kThrough), or through its border where the
/// surface is crossed there (crosses_border(), with `across`: a part's corner pushed straight
/// through the diagonal of the opposite wall). Sharing one vertex: the edge of one opposite
/// that vertex passes through the other likewise (where two facets of a fan overlap, the line
/// they share through the vertex leaves the nearer one through that edge). Sharing an edge:
/// folded onto each other, the third corner of one in the other's plane within `tol` and on
/// the same side of the edge by more than `tol`. Facets that only touch (a wall within `tol` of
/// another, an edge along a facet, across an edge) do not cross.
template <class Across>
bool facets_cross(const Triangle& u, const std::array<std::uint32_t, 3>& iu, std::uint32_t ui,
                  const Triangle& t, const std::array<std::uint32_t, 3>& it, std::uint32_t ti,
                  const Across& across, double tol, Vec3& at) {
    int shared = 0;
    std::array<bool, 3> u_shared{}, t_shared{};
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
            if (iu[i] != it[k]) continue;
            u_shared[i] = t_shared[k] = true;
            ++shared;
        }
    }
    // Whether edge k of u (from_u) or of t, from corner k to corner k + 1, passes through the
    // other.
    const auto through = [&](bool from_u, std::size_t k) {
        const Triangle& a = from_u ? u : t;
        const Triangle& b = from_u ? t : u;
        const Vec3 p = a[k], q = a[(k + 1) % 3];
        const Pierce how = pierces(p, q, b, tol);
        if (how == Pierce::kBorder)
            return crosses_border(p, q, b, from_u ? ti : ui, from_u ? iu : it, across, tol, at);
        if (how != Pierce::kThrough) return false;
        at = plane_crossing(p, q, b);
        return true;
    };
    if (shared == 0) {
        // Most pairs the tree hands out: one wholly on one side of the other's plane.
        if (apart(u, t, tol) || apart(t, u, tol)) return false;
        for (std::size_t k = 0; k < 3; ++k)
            if (through(true, k) || through(false, k)) return true;
        return false;
    }
    if (shared == 1) {
        // The edge opposite the shared corner: the one whose ends are both unshared.
        const auto opposite = [](const std::array<bool, 3>& s) {
            for (std::size_t k = 0; k < 3; ++k)
                if (!s[k] && !s[(k + 1) % 3]) return k;
            return std::size_t{0};
        };
        return through(true, opposite(u_shared)) || through(false, opposite(t_shared));
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
/// each once: `corners(f)` facet f's three points, `ids(f)` their vertex ids (both in the
/// order the mesh's orientation gives), `across` as crosses_border() asks it, `tol` the distance
/// within which points touch (at least kTouchShare of the mesh's size). Facets of different
/// components are not compared: closed ones that cross are crossing_components()'s. The facets
/// whose boxes, grown by `tol`, meet are found by BoxPairs; past kSelfIntersectionWork of them
/// the check stops, incomplete. Deterministic on any thread count.
template <class Corners, class Ids, class Across>
SelfIntersectionReport self_intersections(std::span<const std::uint32_t> component, double tol,
                                          const Corners& corners, const Ids& ids,
                                          const Across& across) {
    SelfIntersectionReport out;
    const auto nf = static_cast<std::uint32_t>(component.size());
    if (nf < 2) return out;
    const auto box = [&](std::uint32_t f) { return box_of(corners(f)); };
    const Box3 all = tbb::parallel_reduce(
        tbb::blocked_range<std::uint32_t>(0, nf, kTreeGrain), Box3{},
        [&](const auto& r, Box3 acc) {
            for (std::uint32_t f = r.begin(); f != r.end(); ++f) acc.add(box(f));
            return acc;
        },
        [](Box3 a, const Box3& b) {
            a.add(b);
            return a;
        });
    tol = std::max(tol, kTouchShare * all.diagonal());
    // Each box grown by half the distance: two meet when one grown by all of it meets the other.
    const BoxPairs pairs(nf, box, 0.5 * tol);
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
    pairs.for_each_pair(
        [&](std::span<const BoxPairs::Pair> batch) {
            Tally& mine = tallies.local();
            mine.work += batch.size();
            if (mine.work >= kWorkFlush) {
                if (work.fetch_add(mine.work) + mine.work > kSelfIntersectionWork) stopped = true;
                mine.work = 0;
            }
            if (stopped) return;
            for (auto [f, g] : batch) {
                if (component[f] != component[g]) continue;
                // Always the lower index first: the same answer whichever way they are paired.
                if (g < f) std::swap(f, g);
                Vec3 at;
                if (!facets_cross(corners(f), ids(f), f, corners(g), ids(g), g, across, tol, at))
                    continue;
                ++mine.found;
                if (mine.first == kNoFacet || f < mine.first ||
                    (f == mine.first && g < mine.second)) {
                    mine.first = f;
                    mine.second = g;
                    mine.at = at;
                }
            }
        },
        stopped);
    Tally least;  // the crossing pair of least indices, of all threads'
    for (const Tally& t : tallies) {
        if (work.fetch_add(t.work) + t.work > kSelfIntersectionWork) stopped = true;
        out.pairs += t.found;
        if (t.first != kNoFacet && (least.first == kNoFacet || t.first < least.first ||
                                    (t.first == least.first && t.second < least.second))) {
            least = t;
        }
    }
    if (stopped) return SelfIntersectionReport{0, {}, false};
    out.at = least.at;
    return out;
}

}  // namespace ncrev::detail
