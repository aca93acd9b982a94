// A bounding-volume hierarchy of triangles, for nearest-triangle distances (the deviation
// between a B-rep and a mesh), and for the triangles near a box and the ray crossings that tell
// inside from outside (which closed components of a mesh cross each other).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "detail/huge_pages.h"
#include "ncrev/common.h"

namespace ncrev::detail {

using Triangle = std::array<Vec3, 3>;

// Ericson, Real-Time Collision Detection, 5.1.5.
inline Vec3 closest_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    }
    const double denom = 1.0 / (va + vb + vc);
    return a + (vb * denom) * ab + (vc * denom) * ac;
}

/// Whether the ray from o along d crosses triangle t beyond o (Moller-Trumbore; a ray in t's
/// plane does not).
inline bool ray_crosses(Vec3 o, Vec3 d, const Triangle& t) {
    const Vec3 e1 = t[1] - t[0];
    const Vec3 e2 = t[2] - t[0];
    const Vec3 q = cross(d, e2);
    const double det = dot(e1, q);
    if (det == 0) return false;
    const Vec3 s = o - t[0];
    const double u = dot(s, q) / det;
    if (u < 0 || u > 1) return false;
    const Vec3 r = cross(s, e1);
    const double v = dot(d, r) / det;
    if (v < 0 || u + v > 1) return false;
    return dot(e2, r) / det > 0;
}

/// Triangle t's bounding box.
inline Box3 box_of(const Triangle& t) {
    Box3 b;
    for (int k = 0; k < 3; ++k) {
        b.min[k] = std::min({t[0][k], t[1][k], t[2][k]});
        b.max[k] = std::max({t[0][k], t[1][k], t[2][k]});
    }
    return b;
}

/// Box b grown by d on every side.
inline Box3 grown(Box3 b, double d) {
    for (int k = 0; k < 3; ++k) b.min[k] -= d, b.max[k] += d;
    return b;
}

/// Whether boxes a and b share a point.
inline bool boxes_meet(const Box3& a, const Box3& b) {
    for (int k = 0; k < 3; ++k) {
        if (a.max[k] < b.min[k] || b.max[k] < a.min[k]) return false;
    }
    return true;
}

/// Triangles per task of the parallel loops over all of a tree's (their centres, the tree's
/// reordered copy): each costs a few nanoseconds there, and a task's overhead about a
/// microsecond, so tasks this large keep it under a percent.
inline constexpr std::uint32_t kTreeGrain = 1u << 14;

// A bounding-volume hierarchy of triangles: boxes split at the median of their triangles'
// centres along their longest side, down to kLeafTriangles. A nearest-triangle query descends
// nearer child first and skips every box farther than the best distance found. Unlike a
// uniform grid it needs no cell size: a B-rep's triangulation mixes triangles a hundred times
// larger (planes) than others (fillets), and a tessellated part's long strips (extrusions)
// would fill a grid's cells by the thousand.
class TriangleTree {
   public:
    explicit TriangleTree(std::vector<Triangle> tris) : tris_(std::move(tris)) {
        if (tris_.empty()) return;
        // Fresh memory of some 200 bytes a triangle (5M-facet meshes are measured): on huge
        // pages, as the mesh build's arrays (src/detail/huge_pages.h).
        const std::size_t n = tris_.size();
        std::vector<Vec3> centre;
        detail::resize_huge(centre, n);
        detail::resize_huge(order_, n);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kTreeGrain), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                centre[i] = (1.0 / 3) * (tris_[i][0] + tris_[i][1] + tris_[i][2]);
                order_[i] = static_cast<std::uint32_t>(i);
            }
        });
        // Every node's place is known before it is built (nodes_below()): the two halves of a
        // large range are built at once, into the layout one depth-first pass gives.
        const auto count = static_cast<std::uint32_t>(n);
        Memo below;
        memoize_below(count, below);
        detail::resize_huge(nodes_, 1 + nodes_below(count, below));
        build(0, 1, 0, count, centre, below);
        // Leaves hold their triangles in tree order: a query reads them one after another.
        std::vector<Triangle> sorted;
        detail::resize_huge(sorted, n);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kTreeGrain), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) sorted[i] = tris_[order_[i]];
        });
        tris_ = std::move(sorted);
    }

    /// Calls fn(t) for the triangles t of every leaf whose box meets `box` (a few triangles
    /// each: those near it, and perhaps some not), in the tree's order: the same on every run.
    template <class Fn>
    void for_each_near(const Box3& box, Fn&& fn) const {
        if (tris_.empty()) return;
        std::array<std::uint32_t, 64> stack{};
        std::size_t top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& n = nodes_[stack[--top]];
            if (!boxes_meet(n.box, box)) continue;
            if (n.count == 0) {
                stack[top++] = n.first + 1;
                stack[top++] = n.first;
                continue;
            }
            for (std::uint32_t i = n.first; i < n.first + n.count; ++i) fn(tris_[i]);
        }
    }

    /// Distance from p to the nearest triangle.
    double distance(Vec3 p) const {
        if (tris_.empty()) return 0;
        double best2 = std::numeric_limits<double>::infinity();
        // Each level leaves at most one node on the stack (two pushed, one taken): 64 covers
        // any depth a 32-bit triangle count gives.
        std::array<std::uint32_t, 64> stack{};
        std::size_t top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& n = nodes_[stack[--top]];
            if (box_distance2(n.box, p) >= best2) continue;
            if (n.count > 0) {
                for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
                    const Triangle& t = tris_[i];
                    const Vec3 q = closest_on_triangle(p, t[0], t[1], t[2]);
                    best2 = std::min(best2, dot(p - q, p - q));
                }
                continue;
            }
            // The nearer child on top of the stack, searched first.
            const std::uint32_t a = n.first, b = n.first + 1;
            const bool a_first = box_distance2(nodes_[a].box, p) <= box_distance2(nodes_[b].box, p);
            stack[top++] = a_first ? b : a;
            stack[top++] = a_first ? a : b;
        }
        return std::sqrt(best2);
    }

    /// How many triangles the ray from o along d crosses (ray_crosses()).
    std::uint64_t ray_hits(Vec3 o, Vec3 d) const {
        std::uint64_t hits = 0;
        if (tris_.empty()) return hits;
        std::array<std::uint32_t, 64> stack{};
        std::size_t top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& n = nodes_[stack[--top]];
            if (!ray_meets_box(o, d, n.box)) continue;
            if (n.count == 0) {
                stack[top++] = n.first + 1;
                stack[top++] = n.first;
                continue;
            }
            for (std::uint32_t i = n.first; i < n.first + n.count; ++i)
                hits += ray_crosses(o, d, tris_[i]);
        }
        return hits;
    }

   private:
    // Triangles per leaf: a few closest-point tests cost less than another level of boxes.
    static constexpr std::uint32_t kLeafTriangles = 4;
    // Ranges of at least this many triangles build their halves at once (below it a task
    // costs more than it saves); the tree is the same on any thread count.
    static constexpr std::uint32_t kParallelBuild = 1u << 14;
    struct Node {
        Box3 box;
        std::uint32_t first = 0;  // leaf: first triangle; inner node: first of two children
        std::uint32_t count = 0;  // triangles of a leaf, 0 for an inner node
    };

    /// Whether the ray from o along d meets box b (slabs).
    static bool ray_meets_box(Vec3 o, Vec3 d, const Box3& b) {
        double lo = 0, hi = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
            if (d[k] == 0) {
                if (o[k] < b.min[k] || o[k] > b.max[k]) return false;
                continue;
            }
            double t0 = (b.min[k] - o[k]) / d[k], t1 = (b.max[k] - o[k]) / d[k];
            if (t0 > t1) std::swap(t0, t1);
            lo = std::max(lo, t0);
            hi = std::min(hi, t1);
            if (lo > hi) return false;
        }
        return true;
    }

    static double box_distance2(const Box3& b, Vec3 p) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k) {
            const double d = std::max({b.min[k] - p[k], 0.0, p[k] - b.max[k]});
            d2 += d * d;
        }
        return d2;
    }

    /// The nodes below the node of a range of `count` triangles (its children, theirs...):
    /// the median split makes it a function of the count, with at most two counts a level
    /// (the floor and the ceiling of a half). `memo` holds them sorted by count once
    /// memoize_below() has filled it; the parallel build only reads it.
    using Memo = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
    static std::uint32_t nodes_below(std::uint32_t count, const Memo& memo) {
        if (count <= kLeafTriangles) return 0;
        const auto it = std::lower_bound(memo.begin(), memo.end(),
                                         std::pair<std::uint32_t, std::uint32_t>(count, 0));
        if (it != memo.end() && it->first == count) return it->second;
        const std::uint32_t half = count / 2;
        return 2 + nodes_below(half, memo) + nodes_below(count - half, memo);
    }
    static void memoize_below(std::uint32_t count, Memo& memo) {
        if (count <= kLeafTriangles) return;
        for (const auto& [c, k] : memo)
            if (c == count) return;
        const std::uint32_t half = count / 2;
        memoize_below(half, memo);
        memoize_below(count - half, memo);
        memo.emplace_back(count, 2 + nodes_below(half, memo) + nodes_below(count - half, memo));
        std::sort(memo.begin(), memo.end());
    }

    // Node `slot` over order_[begin, end), its two children next to each other at `free`,
    // their subtrees after them, the first's then the second's (as a depth-first pass that
    // appends them lays them out); its box the union of theirs. Depth is about
    // log2(n / kLeafTriangles): the median split halves every range.
    void build(std::uint32_t slot, std::uint32_t free, std::uint32_t begin, std::uint32_t end,
               const std::vector<Vec3>& centre, const Memo& below) {
        if (end - begin <= kLeafTriangles) {
            Box3 box;
            for (std::uint32_t i = begin; i < end; ++i) {
                for (const Vec3& v : tris_[order_[i]]) box.add(v);
            }
            nodes_[slot].box = box;
            nodes_[slot].first = begin;
            nodes_[slot].count = end - begin;
            return;
        }
        Vec3 lo = centre[order_[begin]], hi = lo;
        for (std::uint32_t i = begin + 1; i < end; ++i) {
            const Vec3 c = centre[order_[i]];
            lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
            hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
        }
        const Vec3 ext = hi - lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
        const std::uint32_t mid = begin + (end - begin) / 2;
        // Ties broken by index: the same tree whatever the standard library's partitioning.
        std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                         [&](std::uint32_t a, std::uint32_t b) {
                             const double ca = centre[a][axis], cb = centre[b][axis];
                             return ca < cb || (ca == cb && a < b);
                         });
        const std::uint32_t left = free;
        nodes_[slot].first = left;
        const std::uint32_t left_free = left + 2;
        const std::uint32_t right_free = left_free + nodes_below(mid - begin, below);
        const auto build_left = [&] { build(left, left_free, begin, mid, centre, below); };
        const auto build_right = [&] { build(left + 1, right_free, mid, end, centre, below); };
        if (end - begin >= kParallelBuild) {
            tbb::parallel_invoke(build_left, build_right);
        } else {
            build_left();
            build_right();
        }
        Box3 box = nodes_[left].box;
        box.add(nodes_[left + 1].box);
        nodes_[slot].box = box;
    }

    std::vector<Triangle> tris_;
    std::vector<std::uint32_t> order_;
    std::vector<Node> nodes_;
};

}  // namespace ncrev::detail
