// Which closed components of a triangle mesh lie inside which: a cavity's shell lies inside its
// part, an island inside the cavity inside both. Used by healing (a cavity's shell faces into
// the cavity) and by the B-rep builders (a cavity is a void of its part's solid).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "ncrev/common.h"

namespace ncrev::detail {

/// Ray-triangle tests and box comparisons nest_components() makes at most, a bound on its
/// work: thousands of small loose components in one box would otherwise cost components x
/// facets.
inline constexpr std::uint64_t kNestingWork = 300'000'000;

inline constexpr std::uint32_t kNotNested = 0xffffffffu;

struct Nesting {
    /// Per component: the closed component immediately around it, or kNotNested.
    std::vector<std::uint32_t> parent;
    /// Per component: how many closed components lie around it. Odd: a cavity's shell.
    std::vector<std::uint32_t> depth;
    /// False when the work bound stopped the check: then nothing counts as nested.
    bool complete = true;
};

/// `component[f]`: facet f's component (< `count`); `closed[c]`: component c has no boundary
/// edge (only closed components have an inside); `corners(f)`: facet f's three points. Open
/// components are never nested nor around anything. Component a lies inside b when rays from
/// its extreme vertices (least and greatest x, y, z) cross b's facets an odd number of times,
/// each by the majority of three rays (a ray that grazes an edge may count it twice or not at
/// all), tested only where a's box lies in b's. All six must be inside: two parts that cross
/// (meshes overlapping without a union, which healing does not join) are not nested, and
/// where one pokes through the other an extreme vertex is usually what pokes out.
/// Deterministic; O(facets) when no box lies in another.
template <class Corners>
Nesting nest_components(std::span<const std::uint32_t> component, std::uint32_t count,
                        std::span<const std::uint8_t> closed, const Corners& corners) {
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
    // Directions no mesh of a machined part lines up with.
    const std::array<Vec3, 3> rays{normalized(Vec3{0.5773, 0.4082, 0.7071}),
                                   normalized(Vec3{-0.3162, 0.8944, 0.3169}),
                                   normalized(Vec3{0.6325, -0.2236, -0.7416})};
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
            out.complete = false;
            return out;
        }
    }
    if (std::find(is_outer.begin(), is_outer.end(), 1) == is_outer.end()) return out;
    std::vector<std::vector<std::uint32_t>> facets(count);
    for (std::uint32_t f = 0; f < component.size(); ++f) {
        if (is_outer[component[f]]) facets[component[f]].push_back(f);
    }
    std::vector<std::vector<std::uint32_t>> around(count);
    for (std::uint32_t a = 0; a < count; ++a) {
        for (std::uint32_t b = 0; b < count && closed[a]; ++b) {
            if (!candidate(a, b)) continue;
            bool inside = true;
            for (std::size_t e = 0; e < extreme[a].size() && inside; ++e) {
                const Vec3 o = extreme[a][e];
                int odd = 0;
                for (const Vec3& d : rays) {
                    std::uint64_t hits = 0;
                    for (const std::uint32_t f : facets[b]) {
                        const std::array<Vec3, 3> t = corners(f);
                        const Vec3 e1 = t[1] - t[0];
                        const Vec3 e2 = t[2] - t[0];
                        const Vec3 q = cross(d, e2);
                        const double det = dot(e1, q);
                        if (det == 0) continue;
                        const Vec3 s = o - t[0];
                        const double u = dot(s, q) / det;
                        if (u < 0 || u > 1) continue;
                        const Vec3 r = cross(s, e1);
                        const double v = dot(d, r) / det;
                        if (v < 0 || u + v > 1) continue;
                        if (dot(e2, r) / det > 0) ++hits;
                    }
                    odd += static_cast<int>(hits % 2);
                }
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
