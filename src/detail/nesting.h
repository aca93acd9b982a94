// Which closed components of a triangle mesh lie inside which: a cavity's shell lies inside its
// part, an island inside the cavity inside both; and which cross each other (parts overlapping
// without their union). Used by healing (a cavity's shell faces into the cavity; crossing parts
// are reported) and by the B-rep builders (a cavity is a void of its part's solid).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <utility>
#include <vector>

#include "detail/box_pairs.h"
#include "detail/triangle_tree.h"
#include "ncrev/common.h"

namespace ncrev::detail {

/// Ray-triangle tests and box comparisons nest_components() makes at most, a bound on its
/// work: thousands of small loose components in one box would otherwise cost components x
/// facets.
inline constexpr std::uint64_t kNestingWork = 300'000'000;

inline constexpr std::uint32_t kNotNested = 0xffffffffu;

/// The crossing check's work at most, in facets scanned and facet pairs tested, summed over
/// the pairs of components whose boxes meet, counted before each pair is compared: a bound of a
/// few seconds. A ball of 2M facets with a cavity just under its surface counts 2M + 8 x 2M
/// (0.9 s, docs/benchmarks.md). A thousand closed cubes over one another in their faces' planes
/// (scripts/crossing_meshes_stl.py cubes 2000), half a million pairs of 12 x 12 facets whose
/// edges meet the others' borders (each asking which side its ends are on), reach it after 3.9 s
/// and are left unchecked (8.3 s to check them all).
inline constexpr std::uint64_t kCrossingWork = 30'000'000;
/// Facet pairs a search hands out per facet, about, when both sides are large: a facet's box
/// meets those of a few facets of the other side, where the two lie close.
inline constexpr std::uint64_t kCandidatesPerFacet = 8;
/// Facet pairs of two parts' near sides compared one by one, without a search, at most: a few
/// microseconds of box tests, less than setting up the search (its sort and passes).
inline constexpr std::uint64_t kEveryPair = 4096;

/// Points nearer each other than this share of the closed components' size count as touching
/// when no tolerance larger is given: about eight float32 rounding steps at the model's size, as
/// the weld's default tolerance (a vertex of one part lying on a face of another, written in
/// float32, is off that face by rounding).
inline constexpr double kTouchShare = 1e-6;

/// Three directions no mesh of a machined part lines up with, for parity tests.
inline std::array<Vec3, 3> parity_rays() {
    return {normalized(Vec3{0.5773, 0.4082, 0.7071}), normalized(Vec3{-0.3162, 0.8944, 0.3169}),
            normalized(Vec3{0.6325, -0.2236, -0.7416})};
}

enum class Pierce { kNo, kThrough, kBorder };

/// Whether segment pq passes through triangle t: p and q more than `tol` on either side of its
/// plane, the point where it meets the plane more than `tol` inside t (kThrough) or within `tol`
/// of its border (kBorder: through the edge between two facets, or past a convex edge of the
/// surface without entering it; where two parts cross symmetrically, their edges meet the
/// other's facets on their diagonals). A segment that only touches t (an end on it, along its
/// plane) does not.
inline Pierce pierces(Vec3 p, Vec3 q, const Triangle& t, double tol) {
    Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
    // Most segments asked end on one side of the plane: told without a square root, the
    // distances scaled by |n| (a distance d is more than tol off when d |n| is more than tol |n|).
    const double len2 = dot(n, n);
    if (!(len2 > 0)) return Pierce::kNo;
    const double sp = dot(p - t[0], n), sq = dot(q - t[0], n), lim2 = tol * tol * len2;
    const bool p_off = sp * sp > lim2, q_off = sq * sq > lim2;
    if (!(p_off && q_off && (sp > 0) != (sq > 0))) return Pierce::kNo;
    const double len = std::sqrt(len2);
    n = (1 / len) * n;
    const double dp = sp / len, dq = sq / len;
    const Vec3 x = p + (dp / (dp - dq)) * (q - p);
    Pierce out = Pierce::kThrough;
    for (std::size_t i = 0; i < 3; ++i) {
        const Vec3 e = t[(i + 1) % 3] - t[i];
        const double le = norm(e);
        if (!(le > 0)) return Pierce::kNo;
        const double inside = dot(cross(e, x - t[i]), n) / le;
        if (inside < -tol) return Pierce::kNo;
        if (inside <= tol) out = Pierce::kBorder;
    }
    return out;
}

/// Whether triangle u lies wholly on one side of t's plane, each corner more than `tol` off it:
/// then no edge of either passes through the other (most pairs a tree hands out).
inline bool apart(const Triangle& u, const Triangle& t, double tol) {
    const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
    // Distances scaled by |n|, compared squared: no square root, no division.
    const double len2 = dot(n, n);
    if (!(len2 > 0)) return true;
    const double lim2 = tol * tol * len2;
    int above = 0, below = 0;
    for (const Vec3& v : u) {
        const double d = dot(v - t[0], n);
        const bool off = d * d > lim2;
        above += off && d > 0;
        below += off && d < 0;
    }
    return above == 3 || below == 3;
}

struct Nesting {
    /// Per component: the closed component immediately around it, or kNotNested.
    std::vector<std::uint32_t> parent;
    /// Per component: how many closed components lie around it. Odd: a cavity's shell.
    std::vector<std::uint32_t> depth;
    /// False when the work bound stopped the check: then nothing counts as nested.
    bool complete = true;
    /// Pairs (a < b) of closed components whose surfaces cross (meshes of parts overlapping
    /// without their union), sorted. Neither lies inside the other.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> crossing;
    /// False when the work bound (kCrossingWork) stopped the crossing check: then no pair is
    /// listed.
    bool crossing_complete = true;
};

/// The pairs (a < b) of closed components whose surfaces cross, sorted: an edge of a facet of
/// one passes through a facet of the other (pierces(), within `tol`), or through its border
/// from outside the other component to inside it (each end off its surface by more than `tol`;
/// inside by the parity of rays, as nesting tests). Parts that only touch (a face on a face, an
/// edge along a face or across an edge) do not cross. `pairs`: the pairs whose boxes meet; of
/// each, only the facets within both boxes are compared (those whose boxes meet, found by
/// BoxPairs), stopping at the first crossing. `facets[c]`: component c's facets (for every c of
/// a pair). The work is counted before each pair is compared (kCrossingWork): past it,
/// `complete` is false and no pair is listed.
template <class Corners>
std::vector<std::pair<std::uint32_t, std::uint32_t>> crossing_components(
    std::span<const std::vector<std::uint32_t>> facets,
    std::span<const std::pair<std::uint32_t, std::uint32_t>> pairs, std::span<const Box3> box,
    double tol, const Corners& corners, bool& complete) {
    using Pair = std::pair<std::uint32_t, std::uint32_t>;
    std::vector<Pair> out;
    const std::size_t count = facets.size();
    // A whole component's tree, made when a segment through a facet's border asks whether its
    // ends are in that component (rare: symmetric parts).
    std::vector<std::unique_ptr<TriangleTree>> whole(count);
    std::vector<std::once_flag> made(count);
    const std::array<Vec3, 3> rays = parity_rays();
    const auto in = [&](Vec3 p, std::uint32_t c, bool& off) {
        // Made in isolation: a thread waiting for the tree's parallel parts takes no other
        // facet's test, which could wait for this same tree (a deadlock).
        std::call_once(made[c], [&] {
            tbb::this_task_arena::isolate([&] {
                std::vector<Triangle> tris(facets[c].size());
                for (std::size_t i = 0; i < tris.size(); ++i) tris[i] = corners(facets[c][i]);
                whole[c] = std::make_unique<TriangleTree>(std::move(tris));
            });
        });
        off = whole[c]->distance(p) > tol;
        if (!off) return false;
        int odd = 0;
        for (const Vec3& d : rays) odd += static_cast<int>(whole[c]->ray_hits(p, d) % 2);
        return 2 * odd > static_cast<int>(rays.size());
    };
    // Whether segment pq of one component passes into or out of component c through t, one of
    // c's facets: through t, or through its border with one end in c and the other out.
    const auto passes = [&](Vec3 p, Vec3 q, const Triangle& t, std::uint32_t c) {
        const Pierce how = pierces(p, q, t, tol);
        if (how != Pierce::kBorder) return how == Pierce::kThrough;
        bool p_off = false, q_off = false;
        const bool p_in = in(p, c, p_off);
        if (!p_off) return false;
        const bool q_in = in(q, c, q_off);
        return q_off && p_in != q_in;
    };
    std::uint64_t work = 0;
    for (const auto& [a, b] : pairs) {
        // Where the two boxes overlap.
        Box3 both;
        for (int k = 0; k < 3; ++k) {
            both.min[k] = std::max(box[a].min[k], box[b].min[k]);
            both.max[k] = std::min(box[a].max[k], box[b].max[k]);
        }
        both = grown(both, tol);
        // The facets of each side within both boxes.
        std::array<std::vector<std::uint32_t>, 2> near;
        for (std::size_t side = 0; side < 2; ++side) {
            for (const std::uint32_t f : facets[side == 0 ? a : b])
                if (boxes_meet(box_of(corners(f)), both)) near[side].push_back(f);
        }
        // The scan, and the facet pairs the search may hand out: every pair when the sides are
        // small (two cubes over each other), a few per facet when they are large.
        const std::uint64_t na = near[0].size(), nb = near[1].size();
        work += facets[a].size() + facets[b].size() +
                std::min(na * nb, kCandidatesPerFacet * (na + nb));
        if (work > kCrossingWork) {
            complete = false;
            return {};
        }
        if (near[0].empty() || near[1].empty()) continue;
        // Whether facet f of side a and facet g of side b cross; with `through_only`, only
        // through a facet's inside (a pierce through a border asks which side of a whole
        // component each end lies, through a tree of it: noted in `border`, left to a second
        // pass, which two parts crossing through each other's insides never need).
        const std::uint32_t ca = a, cb = b;
        std::atomic<bool> border{false};
        const auto cross = [&](std::uint32_t f, std::uint32_t g, bool through_only) {
            const Triangle u = corners(f), t = corners(g);
            if (apart(u, t, tol) || apart(t, u, tol)) return false;
            for (std::size_t k = 0; k < 3; ++k) {
                if (through_only) {
                    const Pierce x = pierces(u[k], u[(k + 1) % 3], t, tol);
                    const Pierce y = pierces(t[k], t[(k + 1) % 3], u, tol);
                    if (x == Pierce::kThrough || y == Pierce::kThrough) return true;
                    if (x == Pierce::kBorder || y == Pierce::kBorder) border = true;
                } else if (passes(u[k], u[(k + 1) % 3], t, cb) ||
                           passes(t[k], t[(k + 1) % 3], u, ca)) {
                    return true;
                }
            }
            return false;
        };
        std::atomic<bool> found{false};
        if (na * nb <= kEveryPair) {
            // Two small parts (cubes over each other): every pair, no search to set up.
            for (std::size_t i = 0; i < na && !found; ++i) {
                const Box3 bi = grown(box_of(corners(near[0][i])), tol);
                for (std::size_t j = 0; j < nb && !found; ++j) {
                    if (boxes_meet(bi, box_of(corners(near[1][j]))) &&
                        cross(near[0][i], near[1][j], false))
                        found = true;
                }
            }
        } else {
            // The facets of both sides in one search for boxes that meet (BoxPairs); of each
            // pair found, those from both sides compared.
            const auto n = static_cast<std::uint32_t>(na + nb);
            const auto facet = [&](std::uint32_t i) {
                return i < na ? near[0][i] : near[1][i - na];
            };
            const BoxPairs search(
                n, [&](std::uint32_t i) { return box_of(corners(facet(i))); }, 0.5 * tol);
            for (const bool through_only : {true, false}) {
                if (!through_only && !border) break;
                search.for_each_pair(
                    [&](std::span<const BoxPairs::Pair> batch) {
                        for (auto [i, j] : batch) {
                            if ((i < na) == (j < na)) continue;
                            if (j < na) std::swap(i, j);
                            if (found) return;
                            if (cross(facet(i), facet(j), through_only)) found = true;
                        }
                    },
                    found);
                if (found) break;
            }
        }
        if (found) out.emplace_back(a, b);
    }
    return out;
}

/// `component[f]`: facet f's component (< `count`); `closed[c]`: component c has no boundary
/// edge (only closed components have an inside); `corners(f)`: facet f's three points. Open
/// components are never nested nor around anything. Component a lies inside b when rays from
/// its extreme vertices (least and greatest x, y, z) cross b's facets an odd number of times,
/// each by the majority of three rays (a ray that grazes an edge may count it twice or not at
/// all), tested only where a's box lies in b's. All six must be inside: two parts that cross
/// (meshes overlapping without a union, which healing does not join) are not nested, and
/// where one pokes through the other an extreme vertex is usually what pokes out.
/// Components whose surfaces cross (crossing_components(), `tol` the distance within which
/// points touch, at least kTouchShare of the components' size) are listed, and never nested.
/// Deterministic; O(facets) when no box meets another.
template <class Corners>
Nesting nest_components(std::span<const std::uint32_t> component, std::uint32_t count,
                        std::span<const std::uint8_t> closed, double tol, const Corners& corners) {
    Nesting out;
    out.parent.assign(count, kNotNested);
    out.depth.assign(count, 0);
    std::uint32_t num_closed = 0;
    for (std::uint32_t c = 0; c < count; ++c) num_closed += closed[c] != 0;
    if (num_closed < 2) return out;
    std::vector<Box3> box(count);
    // Per component, its vertices of least and greatest x, y and z (the first met).
    std::vector<std::array<Vec3, 6>> extreme(count);
    std::vector<std::uint64_t> size(count, 0);
    for (std::uint32_t f = 0; f < component.size(); ++f) {
        const std::uint32_t c = component[f];
        if (!closed[c]) continue;
        ++size[c];
        for (const Vec3& p : corners(f)) {
            const bool fresh = box[c].empty();
            for (int axis = 0; axis < 3; ++axis) {
                if (fresh || p[axis] < box[c].min[axis]) extreme[c][2 * axis] = p;
                if (fresh || p[axis] > box[c].max[axis]) extreme[c][2 * axis + 1] = p;
            }
            box[c].add(p);
        }
    }
    const auto inside_box = [](const Box3& a, const Box3& b) {
        return a.min.x >= b.min.x && a.min.y >= b.min.y && a.min.z >= b.min.z &&
               a.max.x <= b.max.x && a.max.y <= b.max.y && a.max.z <= b.max.z;
    };
    const auto candidate = [&](std::uint32_t a, std::uint32_t b) {
        return a != b && closed[a] && closed[b] && inside_box(box[a], box[b]);
    };
    const std::array<Vec3, 3> rays = parity_rays();
    // The pairs are found twice (here, then tested below) rather than stored: concentric
    // shells by the thousand would make millions of them. Their whole work is counted before
    // any ray is cast, so that a check too large to finish costs no more than this count.
    std::uint64_t work = 0;
    std::vector<std::uint8_t> is_outer(count, 0);
    for (std::uint32_t a = 0; a < count; ++a) {
        if (!closed[a]) continue;
        work += count;
        for (std::uint32_t b = 0; b < count && work <= kNestingWork; ++b) {
            if (!candidate(a, b)) continue;
            is_outer[b] = 1;
            work += extreme[a].size() * rays.size() * size[b];
        }
        if (work > kNestingWork) {
            out.complete = out.crossing_complete = false;
            return out;
        }
    }
    // Components whose boxes meet (within the touching distance) may cross.
    Box3 all;
    for (std::uint32_t c = 0; c < count; ++c)
        if (closed[c]) all.add(box[c]);
    const double touch = std::max(tol, kTouchShare * all.diagonal());
    // The pairs' facets, summed, bound the pairs kept (their scan alone would pass the bound).
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    std::uint64_t facets_compared = 0;
    for (std::uint32_t a = 0; a < count && out.crossing_complete; ++a) {
        for (std::uint32_t b = a + 1; b < count && closed[a]; ++b) {
            if (!closed[b] || !boxes_meet(grown(box[a], touch), box[b])) continue;
            facets_compared += size[a] + size[b];
            if (facets_compared > kCrossingWork) {
                out.crossing_complete = false;
                pairs = {};
                break;
            }
            pairs.emplace_back(a, b);
        }
    }
    // The facets of the components either check looks at, listed once.
    std::vector<std::uint8_t> listed = is_outer;
    for (const auto& [a, b] : pairs) listed[a] = listed[b] = 1;
    if (std::find(listed.begin(), listed.end(), 1) == listed.end()) return out;
    std::vector<std::vector<std::uint32_t>> facets(count);
    for (std::uint32_t f = 0; f < component.size(); ++f) {
        if (listed[component[f]]) facets[component[f]].push_back(f);
    }
    if (!pairs.empty()) {
        out.crossing =
            crossing_components<Corners>(facets, pairs, box, touch, corners, out.crossing_complete);
    }
    const auto crossed = [&](std::uint32_t a, std::uint32_t b) {
        return std::binary_search(out.crossing.begin(), out.crossing.end(),
                                  std::pair{std::min(a, b), std::max(a, b)});
    };
    if (std::find(is_outer.begin(), is_outer.end(), 1) == is_outer.end()) return out;
    std::vector<std::vector<std::uint32_t>> around(count);
    for (std::uint32_t a = 0; a < count; ++a) {
        for (std::uint32_t b = 0; b < count && closed[a]; ++b) {
            if (!candidate(a, b) || crossed(a, b)) continue;
            bool inside = true;
            for (std::size_t e = 0; e < extreme[a].size() && inside; ++e) {
                const Vec3 o = extreme[a][e];
                // The three rays' crossings at once, on all cores (a sum: the same on any).
                using Hits = std::array<std::uint64_t, 3>;
                const std::vector<std::uint32_t>& fb = facets[b];
                const Hits hits = tbb::parallel_reduce(
                    tbb::blocked_range<std::size_t>(0, fb.size(), kTreeGrain), Hits{},
                    [&](const auto& r, Hits h) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            const Triangle t = corners(fb[i]);
                            for (std::size_t k = 0; k < rays.size(); ++k)
                                h[k] += ray_crosses(o, rays[k], t);
                        }
                        return h;
                    },
                    [](Hits x, const Hits& y) {
                        for (std::size_t k = 0; k < x.size(); ++k) x[k] += y[k];
                        return x;
                    });
                int odd = 0;
                for (const std::uint64_t h : hits) odd += static_cast<int>(h % 2);
                inside = 2 * odd > static_cast<int>(rays.size());
            }
            if (inside) around[a].push_back(b);
        }
    }
    // The innermost of the components around a is the one with most around it.
    for (std::uint32_t a = 0; a < count; ++a) {
        out.depth[a] = static_cast<std::uint32_t>(around[a].size());
    }
    for (std::uint32_t a = 0; a < count; ++a) {
        for (const std::uint32_t b : around[a]) {
            if (out.parent[a] == kNotNested || out.depth[b] > out.depth[out.parent[a]])
                out.parent[a] = b;
        }
    }
    return out;
}

}  // namespace ncrev::detail
