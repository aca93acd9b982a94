// Differential-geometry building blocks on the mesh: dihedral angles, mixed Voronoi areas
// (Meyer, Desbrun, Schröder and Barr, "Discrete Differential-Geometry Operators for
// Triangulated 2-Manifolds", 2003), angle-weighted vertex normals; the part's size in every
// pose (its smallest box, by convex hull and rotating calipers).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include "ncrev/mesh.h"

namespace ncrev {

namespace {

// part_size(): the facets whose normals give the box's first axis, largest first. A machined
// part's planar faces are its largest facets (a CAD tessellation spans a plane with few
// triangles); a thousand reach its main faces on every corpus part.
constexpr std::size_t kPartSizeFacets = 1024;
// Normals within this angle (rad) are one direction: a plane's facets agree to float rounding
// (about 1e-7 rad), turned out of its axes or not.
constexpr double kSameDirection = 1e-5;
// The directions of most area tried as the box's first axis: a block's three.
constexpr std::size_t kPartSizeAxes = 3;
// Points per task in the passes over them.
constexpr std::size_t kPointGrain = 1 << 16;

// box_diagonal2_along(): the share of the squared radius of the circle its fence's edges clear
// within which a point needs no edge test (a tenth of a percent short of the radius: rounding
// keeps no point that near an edge).
constexpr double kClearShare = 0.998;

// convex_hull(): corners nearer than this share of the hull's extent to the one before, or
// turning by less than this angle (rad), are not corners: rounding, not shape.
constexpr double kHullSlack = 1e-9;

struct P2 {
    double x, y;
};

double cross2(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/// The convex hull of `p`, counter-clockwise, without points along its edges (Andrew's
/// monotone chain).
std::vector<P2> convex_hull(std::vector<P2> p) {
    std::sort(p.begin(), p.end(), [](P2 a, P2 b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    p.erase(std::unique(p.begin(), p.end(), [](P2 a, P2 b) { return a.x == b.x && a.y == b.y; }),
            p.end());
    if (p.size() < 3) return p;
    std::vector<P2> h(2 * p.size());
    std::size_t k = 0;
    for (const P2 q : p) {
        while (k >= 2 && cross2(h[k - 2], h[k - 1], q) <= 0) --k;
        h[k++] = q;
    }
    for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
        h[k++] = p[i];
    }
    h.resize(k - 1);
    // Points a rounding apart (a prism's two rims seen along its axis, turned out of the
    // coordinate axes) leave edges of any direction, which the calipers below cannot follow:
    // drop the corners whose edge in is shorter than kHullSlack x the hull's extent or where
    // the outline turns by less than kHullSlack rad, until every corner turns.
    double extent = 0;
    for (const P2 q : h)
        extent = std::max({extent, std::fabs(q.x - h[0].x), std::fabs(q.y - h[0].y)});
    for (bool dropped = true; dropped && h.size() >= 3;) {
        dropped = false;
        std::vector<P2> kept;
        for (std::size_t i = 0; i < h.size(); ++i) {
            const P2 prev = kept.empty() ? h[(i + h.size() - 1) % h.size()] : kept.back();
            const P2 cur = h[i], next = h[(i + 1) % h.size()];
            const double in = std::hypot(cur.x - prev.x, cur.y - prev.y);
            const double out = std::hypot(next.x - cur.x, next.y - cur.y);
            const double turn =
                (cur.x - prev.x) * (next.y - cur.y) - (cur.y - prev.y) * (next.x - cur.x);
            const double ahead =
                (cur.x - prev.x) * (next.x - cur.x) + (cur.y - prev.y) * (next.y - cur.y);
            // Straight on to rounding: the sine small and the outline going on, not back (the
            // tip of a needle turns by nearly pi, its sine as small).
            if (in <= kHullSlack * extent || (turn <= kHullSlack * in * out && ahead > 0)) {
                dropped = true;
                continue;
            }
            kept.push_back(cur);
        }
        h = std::move(kept);
    }
    return h;
}

/// The squared diagonal of the smallest rectangle round the convex polygon `h` (counter-
/// clockwise) with a side along one of its edges, by rotating calipers: as the edges turn, the
/// vertices farthest along the edge, against it and away from it move forward only.
double smallest_rectangle_diagonal2(const std::vector<P2>& h) {
    const std::size_t n = h.size();
    if (n < 2) return 0;
    if (n == 2)
        return (h[1].x - h[0].x) * (h[1].x - h[0].x) + (h[1].y - h[0].y) * (h[1].y - h[0].y);
    const auto along = [&](std::size_t i, P2 d) { return h[i % n].x * d.x + h[i % n].y * d.y; };
    double best = std::numeric_limits<double>::infinity();
    std::size_t ahead = 0, behind = 0, away = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const P2 a = h[i], b = h[(i + 1) % n];
        const double len = std::hypot(b.x - a.x, b.y - a.y);
        const P2 d{(b.x - a.x) / len, (b.y - a.y) / len};
        const P2 in{-d.y, d.x};  // into the polygon
        const P2 back{-d.x, -d.y};
        if (i == 0) {
            for (std::size_t j = 1; j < n; ++j) {
                if (along(j, d) > along(ahead, d)) ahead = j;
                if (along(j, back) > along(behind, back)) behind = j;
                if (along(j, in) > along(away, in)) away = j;
            }
        } else {
            // Each extreme moves forward while the next vertex lies further (at most once
            // round the polygon in all).
            while (along(ahead + 1, d) > along(ahead, d)) ahead = (ahead + 1) % n;
            while (along(behind + 1, back) > along(behind, back)) behind = (behind + 1) % n;
            while (along(away + 1, in) > along(away, in)) away = (away + 1) % n;
        }
        const double w = along(ahead, d) + along(behind, back);
        const double t = along(away, in) - (a.x * in.x + a.y * in.y);
        best = std::min(best, w * w + t * t);
    }
    return best;
}

/// The squared diagonal of the smallest box round `points` with `axis` (unit) for an axis and
/// the other two along an edge of their outline seen along it (smallest_rectangle_diagonal2()).
double box_diagonal2_along(std::span<const Vec3> points, Vec3 axis) {
    // Any two directions square to the axis and each other: the rectangle does not depend on
    // them.
    const Vec3 other =
        std::fabs(axis.x) <= std::fabs(axis.y) && std::fabs(axis.x) <= std::fabs(axis.z)
            ? Vec3{1, 0, 0}
        : std::fabs(axis.y) <= std::fabs(axis.z) ? Vec3{0, 1, 0}
                                                 : Vec3{0, 0, 1};
    const Vec3 u = normalized(cross(axis, other)), v = cross(axis, u);
    // The points extreme along sixteen directions bound a polygon whose inside holds no point
    // of the outline (Akl and Toussaint): only the points outside it are sorted for the hull.
    constexpr std::size_t kFilter = 16;
    std::array<P2, kFilter> kDirs{};
    for (std::size_t k = 0; k < kFilter; ++k) {
        const double a = 2 * std::numbers::pi * static_cast<double>(k) / kFilter;
        kDirs[k] = {std::cos(a), std::sin(a)};
    }
    // Extreme along each direction: the farthest, the first in the points' order of those as
    // far (the same whatever the threads).
    struct Extremes {
        std::array<double, kFilter> reach{};
        std::array<P2, kFilter> at{};
        std::array<std::size_t, kFilter> index{};
        double lo = std::numeric_limits<double>::infinity();
        double hi = -std::numeric_limits<double>::infinity();
        Extremes() { reach.fill(-std::numeric_limits<double>::infinity()); }
    };
    const Extremes ext = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, points.size(), kPointGrain), Extremes{},
        [&](const tbb::blocked_range<std::size_t>& range, Extremes e) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                const Vec3 p = points[i];
                const P2 q{dot(p, u), dot(p, v)};
                const double t = dot(p, axis);
                e.lo = std::min(e.lo, t), e.hi = std::max(e.hi, t);
                for (std::size_t k = 0; k < kFilter; ++k) {
                    const double r = q.x * kDirs[k].x + q.y * kDirs[k].y;
                    if (r > e.reach[k]) e.reach[k] = r, e.at[k] = q, e.index[k] = i;
                }
            }
            return e;
        },
        [](Extremes a, const Extremes& b) {
            a.lo = std::min(a.lo, b.lo), a.hi = std::max(a.hi, b.hi);
            for (std::size_t k = 0; k < kFilter; ++k) {
                if (b.reach[k] > a.reach[k] ||
                    (b.reach[k] == a.reach[k] && b.index[k] < a.index[k]))
                    a.reach[k] = b.reach[k], a.at[k] = b.at[k], a.index[k] = b.index[k];
            }
            return a;
        });
    if (points.empty()) return 0;
    const std::array<P2, kFilter>& extreme = ext.at;
    const double lo = ext.lo, hi = ext.hi;
    std::vector<P2> fence;
    for (const P2 q : extreme)
        if (fence.empty() || q.x != fence.back().x || q.y != fence.back().y) fence.push_back(q);
    while (fence.size() > 1 && fence.back().x == fence.front().x &&
           fence.back().y == fence.front().y)
        fence.pop_back();
    // Most points lie well inside: those within the circle the fence's edges clear round
    // the mean of its corners (kClearShare of it) need no edge test.
    P2 mid{0, 0};
    double clear2 = 0;
    if (fence.size() >= 3) {
        for (const P2 q : fence) mid.x += q.x, mid.y += q.y;
        mid.x /= static_cast<double>(fence.size()), mid.y /= static_cast<double>(fence.size());
        clear2 = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < fence.size(); ++k) {
            const P2 a = fence[k], b = fence[(k + 1) % fence.size()];
            const double len2 = (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y);
            const double c = cross2(a, b, mid);  // positive: mid is inside
            clear2 = std::min(clear2, c > 0 ? c * c / len2 : 0.0);
        }
        clear2 *= kClearShare;
    }
    // Per fence edge, kHullSlack x its length x the fence's extent: the cross product of a point
    // on the edge's line to rounding.
    double reach = 0;
    for (const P2 q : fence)
        reach = std::max({reach, std::fabs(q.x - mid.x), std::fabs(q.y - mid.y)});
    std::vector<double> slack(fence.size());
    for (std::size_t k = 0; k < fence.size(); ++k) {
        const P2 a = fence[k], b = fence[(k + 1) % fence.size()];
        slack[k] = kHullSlack * std::hypot(b.x - a.x, b.y - a.y) * reach;
    }
    // Chunk by chunk on all cores; the hull does not depend on the points' order.
    const std::size_t chunks = (points.size() + kPointGrain - 1) / kPointGrain;
    std::vector<std::vector<P2>> out(chunks);
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
        const std::size_t end = std::min(points.size(), (c + 1) * kPointGrain);
        for (std::size_t i = c * kPointGrain; i < end; ++i) {
            const P2 q{dot(points[i], u), dot(points[i], v)};
            if ((q.x - mid.x) * (q.x - mid.x) + (q.y - mid.y) * (q.y - mid.y) < clear2) continue;
            // On a fence's edge or within rounding of it is inside too: no corner of the hull
            // but the fence's own (added below), which a part's straight outline (a torus seen
            // from its side: its tube's top and bottom circles) would fill with points.
            bool inside = fence.size() >= 3;
            for (std::size_t k = 0; inside && k < fence.size(); ++k)
                inside = cross2(fence[k], fence[(k + 1) % fence.size()], q) > -slack[k];
            if (!inside) out[c].push_back(q);
        }
    });
    std::vector<P2> outside = fence;
    for (const std::vector<P2>& o : out) outside.insert(outside.end(), o.begin(), o.end());
    const double w = hi - lo;
    return w * w + smallest_rectangle_diagonal2(convex_hull(std::move(outside)));
}

}  // namespace

double part_size(const Mesh& m) {
    const std::size_t nf = m.num_faces();
    // The facets of most area (twice the area; ties by index), then their normals' directions,
    // either sense, with the area of each. Per task, a heap of its largest so far, smallest on top
    // (most facets are refused by one comparison, and nothing the size of the mesh is allocated);
    // then the tasks' best in one order: area, then index (the same whatever the threads).
    using Scored = std::pair<double, std::uint32_t>;
    const auto larger = [](const Scored& a, const Scored& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
    };
    const std::size_t chunks = (nf + kPointGrain - 1) / kPointGrain;
    std::vector<std::vector<Scored>> best_of(chunks);
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
        std::vector<Scored>& heap = best_of[c];
        const std::size_t end = std::min(nf, (c + 1) * kPointGrain);
        for (std::size_t f = c * kPointGrain; f < end; ++f) {
            const auto id = static_cast<std::uint32_t>(f);
            const Scored a{norm(m.face_normal_area2(FaceId(id))), id};
            if (heap.size() == kPartSizeFacets && !larger(a, heap.front())) continue;
            heap.push_back(a);
            std::push_heap(heap.begin(), heap.end(), larger);
            if (heap.size() > kPartSizeFacets) {
                std::pop_heap(heap.begin(), heap.end(), larger);
                heap.pop_back();
            }
        }
    });
    std::vector<Scored> facets;
    for (const std::vector<Scored>& h : best_of) facets.insert(facets.end(), h.begin(), h.end());
    std::sort(facets.begin(), facets.end(), larger);
    if (facets.size() > kPartSizeFacets) facets.resize(kPartSizeFacets);
    const std::size_t top = facets.size();
    struct Direction {
        Vec3 n;
        double area = 0;
    };
    std::vector<Direction> dirs;
    const double same = std::cos(kSameDirection);
    for (std::size_t i = 0; i < top && facets[i].first > 0; ++i) {
        const Vec3 n = m.face_normal_area2(FaceId(facets[i].second)) / facets[i].first;
        const auto d = std::find_if(dirs.begin(), dirs.end(), [&](const Direction& o) {
            return std::fabs(dot(n, o.n)) >= same;
        });
        if (d != dirs.end())
            d->area += facets[i].first;
        else
            dirs.push_back({n, facets[i].first});
    }
    std::stable_sort(dirs.begin(), dirs.end(),
                     [](const Direction& a, const Direction& b) { return a.area > b.area; });
    if (dirs.size() > kPartSizeAxes) dirs.resize(kPartSizeAxes);
    if (dirs.empty()) {
        Box3 box;
        for (const Vec3& p : m.positions()) box.add(p);
        return box.diagonal();
    }
    double best = std::numeric_limits<double>::infinity();
    for (const Direction& d : dirs) best = std::min(best, box_diagonal2_along(m.positions(), d.n));
    return std::sqrt(best);
}

double coordinate_rounding(const Mesh& m) {
    // max and "and" are exact: the parallel reduction is deterministic.
    struct Extent {
        double max_abs = 0;
        bool all_float = true;
    };
    const std::span<const Vec3> points = m.positions();
    const Extent e = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, points.size(), kPointGrain), Extent{},
        [&](const tbb::blocked_range<std::size_t>& range, Extent acc) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                for (int k = 0; k < 3; ++k) {
                    const double x = points[i][k];
                    acc.max_abs = std::max(acc.max_abs, std::fabs(x));
                    acc.all_float =
                        acc.all_float && static_cast<double>(static_cast<float>(x)) == x;
                }
            }
            return acc;
        },
        [](Extent a, const Extent& b) {
            a.max_abs = std::max(a.max_abs, b.max_abs);
            a.all_float = a.all_float && b.all_float;
            return a;
        });
    return e.max_abs * (e.all_float ? 0x1.0p-24 : 0x1.0p-53);
}

double dihedral_angle(const Mesh& m, HalfedgeId h) {
    const HalfedgeId t = m.twin(h);
    if (!t.is_valid()) return 0.0;
    const Vec3 n1 = m.face_normal(Mesh::face(h)), n2 = m.face_normal(Mesh::face(t));
    const Vec3 a = m.position(m.origin(h)), b = m.position(m.target(h));
    const Vec3 e = normalized(b - a);
    // The angle from n1 to n2 about the edge direction of h (h runs a -> b in facet 1): for a
    // convex edge, n2 is n1 turned positively about e.
    const double sin_angle = dot(cross(n1, n2), e);
    const double cos_angle = std::clamp(dot(n1, n2), -1.0, 1.0);
    return std::atan2(sin_angle, cos_angle);
}

VertexMap<double> mixed_voronoi_areas(const Mesh& m) {
    VertexMap<double> area(m.num_vertices(), 0.0);
    for (std::size_t f = 0; f < m.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const VertexId v[3] = {m.vertex(ff, 0), m.vertex(ff, 1), m.vertex(ff, 2)};
        const Vec3 p[3] = {m.position(v[0]), m.position(v[1]), m.position(v[2])};
        const double face_area = 0.5 * norm(cross(p[1] - p[0], p[2] - p[0]));
        if (face_area <= 0) continue;
        // cot of the angle at corner i, and whether it is obtuse.
        double cot[3];
        int obtuse = -1;
        for (int i = 0; i < 3; ++i) {
            const Vec3 u = p[(i + 1) % 3] - p[i], w = p[(i + 2) % 3] - p[i];
            const double d = dot(u, w);
            cot[i] = d / norm(cross(u, w));
            if (d < 0) obtuse = i;
        }
        if (obtuse < 0) {
            // Voronoi share of vertex i: (|e_ij|^2 cot(k) + |e_ik|^2 cot(j)) / 8.
            for (int i = 0; i < 3; ++i) {
                const int j = (i + 1) % 3, k = (i + 2) % 3;
                const Vec3 eij = p[j] - p[i], eik = p[k] - p[i];
                area[v[i]] += (dot(eij, eij) * cot[k] + dot(eik, eik) * cot[j]) / 8.0;
            }
        } else {
            for (int i = 0; i < 3; ++i) area[v[i]] += face_area * (i == obtuse ? 0.5 : 0.25);
        }
    }
    return area;
}

VertexMap<Vec3> vertex_normals(const Mesh& m) {
    VertexMap<Vec3> normal(m.num_vertices(), Vec3{});
    for (std::size_t f = 0; f < m.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const Vec3 n = m.face_normal(ff);
        for (int i = 0; i < 3; ++i) {
            const Vec3 p = m.position(m.vertex(ff, i));
            const Vec3 u = normalized(m.position(m.vertex(ff, (i + 1) % 3)) - p);
            const Vec3 w = normalized(m.position(m.vertex(ff, (i + 2) % 3)) - p);
            const double angle = std::acos(std::clamp(dot(u, w), -1.0, 1.0));
            normal[m.vertex(ff, i)] += angle * n;
        }
    }
    for (Vec3& n : normal.data()) n = normalized(n);
    return normal;
}

}  // namespace ncrev
