// Discrete curvature (../shared/docs/method.md 3.1-3.4): the normal-cycle shape operator of
// D. Cohen-Steiner and J.-M. Morvan, "Restricted Delaunay triangulations and normal cycle"
// (SoCG 2003), over unions of mixed Voronoi cells (M. Meyer, M. Desbrun, P. Schröder,
// A. Barr, "Discrete differential-geometry operators for triangulated 2-manifolds", 2003),
// with the edge weights of S. Anwer et al., "Reverse engineering for NC machining simulation"
// (2010) as an option; shape index and curvedness of J. Koenderink and A. van Doorn, "Surface
// shape and curvature scales" (1992).
//
// Why unions of cells: the boundary of a mixed Voronoi cell crosses every edge of its vertex at
// the edge's midpoint, so |e n B| is half the edge for each cell of B that holds an end of e.
// The tensor of B is then the sum of per-vertex tensors T_v = sum_{e at v} beta(e) |e|/2 e e^T
// and its area the sum of the cell areas: computed once per vertex, summed per neighbourhood.
#include "ncrev/curvature.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <queue>
#include <utility>
#include <vector>

#include "detail/huge_pages.h"
#include "ncrev/io.h"

namespace ncrev {

const char* to_string(CurvatureEstimator estimator) {
    return estimator == CurvatureEstimator::kWeighted ? "weighted" : "plain";
}

const char* to_string(Neighbourhood neighbourhood) {
    switch (neighbourhood) {
        case Neighbourhood::kKernel:
            return "kernel";
        case Neighbourhood::kRings:
            return "rings";
        case Neighbourhood::kGeodesic:
            return "geodesic";
        case Neighbourhood::kSmoothed:
            return "smoothed";
    }
    return "unknown";
}

const char* to_string(ShapeType type) {
    static constexpr const char* kNames[kNumShapeTypes] = {
        "plane",  "cup",          "trough", "rut",  "saddle_rut",
        "saddle", "saddle_ridge", "ridge",  "dome", "cap"};
    const auto i = static_cast<int>(type);
    return i >= 0 && i < kNumShapeTypes ? kNames[i] : "unknown";
}

std::array<std::uint8_t, 3> shape_type_color(ShapeType type) {
    static constexpr std::array<std::uint8_t, 3> kColors[kNumShapeTypes] = {
        {{160, 160, 160}},  // plane: grey
        {{0, 40, 200}},     // cup: deep blue
        {{0, 110, 230}},    // trough
        {{0, 190, 230}},    // rut: cyan
        {{0, 200, 140}},    // saddle rut
        {{40, 180, 40}},    // saddle: green
        {{160, 210, 0}},    // saddle ridge
        {{250, 220, 0}},    // ridge: yellow
        {{250, 140, 0}},    // dome: orange
        {{220, 30, 30}},    // cap: red
    };
    const auto i = static_cast<int>(type);
    return i >= 0 && i < kNumShapeTypes ? kColors[i] : std::array<std::uint8_t, 3>{0, 0, 0};
}

double shape_index(double k1, double k2) {
    if (k1 < k2) std::swap(k1, k2);
    const double sum = k1 + k2, diff = k1 - k2;
    if (diff == 0) return sum > 0 ? 1.0 : (sum < 0 ? -1.0 : 0.0);
    return (2.0 / std::numbers::pi) * std::atan(sum / diff);
}

double curvedness(double k1, double k2) { return std::sqrt(0.5 * (k1 * k1 + k2 * k2)); }

ShapeType classify_shape(double k1, double k2, double planar_curvedness) {
    if (!(curvedness(k1, k2) >= planar_curvedness)) return ShapeType::kPlane;
    const double s = shape_index(k1, k2);
    // Koenderink's classes, symmetric about the saddle (s = 0); a value exactly on a bound
    // goes to the class nearer the saddle.
    const double a = std::fabs(s);
    int step;  // 0 saddle, 1 saddle ridge/rut, 2 ridge/rut, 3 dome/trough, 4 cap/cup
    if (a <= 0.125) {
        step = 0;
    } else if (a <= 0.375) {
        step = 1;
    } else if (a <= 0.625) {
        step = 2;
    } else if (a <= 0.875) {
        step = 3;
    } else {
        step = 4;
    }
    return static_cast<ShapeType>(s >= 0 ? 5 + step : 5 - step);
}

namespace {

/// Curvature radii above this multiple of the model's size (part_size(), the same in every
/// pose) are planar: such a surface deviates from its tangent plane by less than size /
/// 800 across the whole part.
constexpr double kPlanarRadiusFactor = 100.0;
/// Noise floor of the estimator on a plane whose coordinates were rounded to a precision eps:
/// the normals of facets with edges of length l tilt by up to about 2 eps / l, which the
/// estimator divides by another l. Planar points must stay planar with a margin of this factor.
constexpr double kNoiseFloorFactor = 4.0;
/// Largest neighbourhood (vertices) gathered for one vertex: bounds the work on degenerate
/// input (a fan of thousands of slivers) without touching any sensible mesh.
constexpr std::size_t kMaxNeighbourhood = 512;
/// The kernel neighbourhood is bounded by its radius; this only caps the search.
constexpr int kMaxRings = 64;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// At most this many edges are sampled (evenly) for the median edge length.
constexpr std::size_t kMedianSample = 1 << 16;

/// Symmetric 3x3 tensor: xx, xy, xz, yy, yz, zz.
struct Sym3 {
    double v[6] = {0, 0, 0, 0, 0, 0};
    void add_outer(Vec3 e, double w) {
        v[0] += w * e.x * e.x;
        v[1] += w * e.x * e.y;
        v[2] += w * e.x * e.z;
        v[3] += w * e.y * e.y;
        v[4] += w * e.y * e.z;
        v[5] += w * e.z * e.z;
    }
    void add(const Sym3& o, double weight = 1.0) {
        for (int i = 0; i < 6; ++i) v[i] += weight * o.v[i];
    }
    double frobenius() const {
        return std::sqrt(v[0] * v[0] + v[3] * v[3] + v[5] * v[5] +
                         2 * (v[1] * v[1] + v[2] * v[2] + v[4] * v[4]));
    }
    /// Adds R S R^T for the smallest rotation R that turns unit vector `from` into unit
    /// vector `to` (Rodrigues: R = I + [u]x + [u]x^2 / (1 + c), u = from x to, c = from . to).
    void add_rotated(const Sym3& s, Vec3 from, Vec3 to, double weight = 1.0) {
        const Vec3 u = cross(from, to);
        const double c = dot(from, to);
        if (c <= -0.999) return;  // opposite normals: a fold, nothing sensible to transport
        const double k = 1.0 / (1.0 + c);
        const double r[3][3] = {{c + k * u.x * u.x, k * u.x * u.y - u.z, k * u.x * u.z + u.y},
                                {k * u.y * u.x + u.z, c + k * u.y * u.y, k * u.y * u.z - u.x},
                                {k * u.z * u.x - u.y, k * u.z * u.y + u.x, c + k * u.z * u.z}};
        const double m[3][3] = {
            {s.v[0], s.v[1], s.v[2]}, {s.v[1], s.v[3], s.v[4]}, {s.v[2], s.v[4], s.v[5]}};
        double rm[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                rm[i][j] = r[i][0] * m[0][j] + r[i][1] * m[1][j] + r[i][2] * m[2][j];
        auto out = [&](int i, int j) {
            return rm[i][0] * r[j][0] + rm[i][1] * r[j][1] + rm[i][2] * r[j][2];
        };
        v[0] += weight * out(0, 0);
        v[1] += weight * out(0, 1);
        v[2] += weight * out(0, 2);
        v[3] += weight * out(1, 1);
        v[4] += weight * out(1, 2);
        v[5] += weight * out(2, 2);
    }
    /// a^T S b.
    double form(Vec3 a, Vec3 b) const {
        return a.x * (v[0] * b.x + v[1] * b.y + v[2] * b.z) +
               a.y * (v[1] * b.x + v[3] * b.y + v[4] * b.z) +
               a.z * (v[2] * b.x + v[4] * b.y + v[5] * b.z);
    }
};

/// What the first pass knows of a vertex.
struct VertexData {
    Sym3 tensor;           ///< sum over incident edges of beta |e|/2 e e^T
    Vec3 normal;           ///< unit, angle-weighted
    double area = 0;       ///< mixed Voronoi cell area
    double max_turn = 0;   ///< largest |dihedral angle| of an incident edge
    double mean_edge = 0;  ///< mean length of incident edges
    double min_edge = 0;   ///< shortest incident edge
    double max_edge = 0;   ///< longest incident edge
};

/// An orthonormal tangent basis of unit normal n (Duff et al., "Building an orthonormal basis,
/// revisited", 2017): continuous except across n.z = 0, which is fine for a projection.
void tangent_basis(Vec3 n, Vec3& t1, Vec3& t2) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    t1 = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t2 = {b, sign + n.y * n.y * a, -n.y};
}

/// acos to within 2e-8 rad (Abramowitz and Stegun 4.4.46), several times faster than the
/// library's; the angles it gives only weight the vertex normal.
double fast_acos(double x) {
    x = std::clamp(x, -1.0, 1.0);
    const double ax = std::fabs(x);
    const double poly =
        1.5707963050 +
        ax * (-0.2145988016 +
              ax * (0.0889789874 +
                    ax * (-0.0501743046 +
                          ax * (0.0308918810 +
                                ax * (-0.0170881256 + ax * (0.0066700901 - ax * 0.0012624911))))));
    const double r = std::sqrt(1.0 - ax) * poly;
    return x >= 0 ? r : std::numbers::pi - r;
}

/// atan2 to within 2e-8 rad, and with a relative error below 2e-6 x^2 near 0, so that tiny
/// dihedral angles keep their precision (Abramowitz and Stegun 4.4.49 after reduction to
/// |t| <= 1).
double fast_atan2(double y, double x) {
    const double ay = std::fabs(y), ax = std::fabs(x);
    if (ay == 0 && ax == 0) return 0;
    const bool swap = ay > ax;
    const double t = swap ? ax / ay : ay / ax;
    const double t2 = t * t;
    double r =
        t *
        (1.0 + t2 * (-0.3333314528 +
                     t2 * (0.1999355085 +
                           t2 * (-0.1420889944 +
                                 t2 * (0.1065626393 +
                                       t2 * (-0.0752896400 +
                                             t2 * (0.0429096138 +
                                                   t2 * (-0.0161657367 + t2 * 0.0028662257))))))));
    if (swap) r = 0.5 * std::numbers::pi - r;
    if (x < 0) r = std::numbers::pi - r;
    return y < 0 ? -r : r;
}

/// What the face pass knows, indexed by face (normal) or by half-edge h = 3f + i, which is
/// also the corner of face f at the origin of h.
struct FaceData {
    FaceMap<Vec3> normal;              ///< unit facet normals
    std::vector<double> corner_angle;  ///< angle of the corner (vertex normal weight)
    std::vector<double> corner_share;  ///< the corner's mixed Voronoi share of the face
    std::vector<double> dihedral;      ///< signed dihedral angle at the edge of h; 0 on borders
};

FaceData face_pass(const Mesh& m) {
    const std::size_t nf = m.num_faces();
    FaceData fd;
    detail::resize_huge(fd.normal.data(), nf);
    detail::resize_huge(fd.corner_angle, 3 * nf);
    detail::resize_huge(fd.corner_share, 3 * nf);
    detail::resize_huge(fd.dihedral, 3 * nf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf), [&](const auto& r) {
        for (std::size_t f = r.begin(); f != r.end(); ++f) {
            const FaceId ff(static_cast<std::uint32_t>(f));
            const Vec3 p[3] = {m.position(m.vertex(ff, 0)), m.position(m.vertex(ff, 1)),
                               m.position(m.vertex(ff, 2))};
            const Vec3 c = cross(p[1] - p[0], p[2] - p[0]);
            const double area2 = norm(c);
            fd.normal[ff] = area2 > 0 ? c / area2 : Vec3{};
            // Corner i: the dot of its two edges, their squared lengths.
            double d[3], sq[3];  // sq[i]: squared length of the edge opposite corner i
            for (int i = 0; i < 3; ++i) {
                const Vec3 u = p[(i + 1) % 3] - p[i], w = p[(i + 2) % 3] - p[i];
                d[i] = dot(u, w);
                sq[(i + 2) % 3] = dot(u, u);  // edge i -> i+1 is opposite corner i+2
            }
            for (int i = 0; i < 3; ++i) {
                const std::size_t h = 3 * f + static_cast<std::size_t>(i);
                const int j = (i + 1) % 3, k = (i + 2) % 3;
                const double lu2 = sq[k], lw2 = sq[j];  // edges i->j and i->k
                const double denom = std::sqrt(lu2 * lw2);
                fd.corner_angle[h] = denom > 0 ? fast_acos(d[i] / denom) : 0.0;
                double share = 0;
                if (area2 > 0) {
                    if (d[i] < 0) {
                        share = 0.25 * area2;  // obtuse here: half the face
                    } else if (d[j] < 0 || d[k] < 0) {
                        share = 0.125 * area2;  // obtuse elsewhere: a quarter
                    } else {
                        share = (lu2 * d[k] + lw2 * d[j]) / (8.0 * area2);
                    }
                }
                fd.corner_share[h] = share;
            }
        }
    });
    // Dihedral angles once per edge, from the side with the smaller half-edge id.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, 3 * nf), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const HalfedgeId h(static_cast<std::uint32_t>(i));
            const HalfedgeId t = m.twin(h);
            if (!t.is_valid()) {
                fd.dihedral[i] = 0;
                continue;
            }
            if (t.idx() < h.idx()) continue;
            const Vec3 n1 = fd.normal[Mesh::face(h)], n2 = fd.normal[Mesh::face(t)];
            const Vec3 e = m.position(m.target(h)) - m.position(m.origin(h));
            const double len = norm(e);
            const double beta = len > 0 ? fast_atan2(dot(cross(n1, n2), e) / len, dot(n1, n2)) : 0;
            fd.dihedral[i] = beta;
            fd.dihedral[t.idx()] = beta;
        }
    });
    return fd;
}

VertexData vertex_pass(const Mesh& m, const FaceData& fd, VertexId v) {
    VertexData out;
    const Vec3 pv = m.position(v);
    Vec3 normal{};
    double edge_sum = 0;
    int edges = 0;
    HalfedgeId last{};
    m.for_each_outgoing(v, [&](HalfedgeId h) {
        last = h;
        normal += fd.corner_angle[h.idx()] * fd.normal[Mesh::face(h)];
        out.area += fd.corner_share[h.idx()];
        const Vec3 u = m.position(m.target(h)) - pv;
        const double lu = norm(u);
        edge_sum += lu;
        ++edges;
        if (lu > 0 && (out.min_edge == 0 || lu < out.min_edge)) out.min_edge = lu;
        out.max_edge = std::max(out.max_edge, lu);
        const double beta = fd.dihedral[h.idx()];
        if (beta == 0 || lu <= 0) return;
        // beta |e|/2 e e^T with e = u / |u|.
        out.tensor.add_outer(u, 0.5 * beta / lu);
        out.max_turn = std::max(out.max_turn, std::fabs(beta));
    });
    // The last edge of an open fan has no outgoing half-edge from v: count its length too.
    const HalfedgeId h0 = m.outgoing(v);
    if (h0.is_valid() && !m.twin(h0).is_valid()) {
        const double l = norm(m.position(m.origin(Mesh::prev(last))) - pv);
        edge_sum += l;
        out.max_edge = std::max(out.max_edge, l);
        ++edges;
    }
    out.normal = normalized(normal);
    out.mean_edge = edges > 0 ? edge_sum / edges : 0;
    return out;
}

/// Reusable per-thread buffers of the neighbourhood search.
struct Scratch {
    std::vector<std::uint32_t> set;  ///< vertices of the neighbourhood, p first
    std::vector<std::pair<double, std::uint32_t>> heap;
    /// stamp[v] == current: v is in `set` (O(1) membership without clearing per vertex).
    std::vector<std::uint32_t> stamp;
    std::uint32_t current = 0;

    void begin(std::size_t num_vertices) {
        if (stamp.size() != num_vertices) stamp.assign(num_vertices, 0);
        if (++current == 0) {
            std::fill(stamp.begin(), stamp.end(), 0);
            current = 1;
        }
        set.clear();
    }
    bool contains(std::uint32_t v) const { return stamp[v] == current; }
    void insert(std::uint32_t v) {
        stamp[v] = current;
        set.push_back(v);
    }
};

/// The vertices fewer than `rings` edges from p, reached through vertices within `radius` of p
/// that are not on sharp edges. With `local_cells`, also only vertices whose cell lies within the
/// radius (no incident edge longer than it): the cell of a vertex on the border of a CAD face
/// reaches across the long triangles of its neighbour face, whose area must not dilute p's.
void ring_neighbourhood(const Mesh& m, const std::vector<VertexData>& data, double sharp,
                        VertexId p, int rings, double radius, bool local_cells, Scratch& s) {
    s.begin(m.num_vertices());
    s.insert(p.idx());
    const Vec3 pp = m.position(p);
    const double r2 = radius * radius;
    std::size_t level_begin = 0;
    for (int level = 1; level < rings; ++level) {
        const std::size_t level_end = s.set.size();
        for (std::size_t i = level_begin; i < level_end && s.set.size() < kMaxNeighbourhood; ++i) {
            m.for_each_neighbour(VertexId(s.set[i]), [&](VertexId w) {
                const VertexData& dw = data[w.idx()];
                if (s.contains(w.idx()) || dw.max_turn >= sharp) return;
                if (local_cells && dw.max_edge >= radius) return;
                const Vec3 d = m.position(w) - pp;
                if (dot(d, d) >= r2) return;
                s.insert(w.idx());
            });
        }
        if (s.set.size() == level_end) break;
        level_begin = level_end;
    }
}

void geodesic_neighbourhood(const Mesh& m, const std::vector<VertexData>& data, double sharp,
                            VertexId p, double radius, Scratch& s) {
    s.begin(m.num_vertices());
    s.heap.clear();
    // Dijkstra along edges, bounded by the radius; `set` holds the settled vertices.
    auto cmp = [](const auto& a, const auto& b) { return a > b; };
    s.heap.emplace_back(0.0, p.idx());
    while (!s.heap.empty() && s.set.size() < kMaxNeighbourhood) {
        std::pop_heap(s.heap.begin(), s.heap.end(), cmp);
        const double d = s.heap.back().first;
        const std::uint32_t v = s.heap.back().second;
        s.heap.pop_back();
        if (s.contains(v)) continue;
        s.insert(v);
        const Vec3 pq = m.position(VertexId(v));
        m.for_each_neighbour(VertexId(v), [&](VertexId w) {
            if (s.contains(w.idx()) || data[w.idx()].max_turn >= sharp) return;
            const double dw = d + norm(m.position(w) - pq);
            if (dw >= radius) return;
            s.heap.emplace_back(dw, w.idx());
            std::push_heap(s.heap.begin(), s.heap.end(), cmp);
        });
    }
}

/// The weighted tensor of method.md 3.1 over the cells in s.set, relative to p's normal.
Sym3 weighted_tensor(const Mesh& m, const FaceMap<Vec3>& face_normal, Vec3 np, const Scratch& s) {
    Sym3 sum, plain;
    double lambda_sum = 0;
    std::size_t count = 0;
    for (const std::uint32_t qi : s.set) {
        const VertexId q(qi);
        const Vec3 pq = m.position(q);
        m.for_each_outgoing(q, [&](HalfedgeId h) {
            const HalfedgeId t = m.twin(h);
            if (!t.is_valid()) return;
            const Vec3 u = m.position(m.target(h)) - pq;
            const double lu = norm(u);
            if (lu <= 0) return;
            const Vec3 n1 = face_normal[Mesh::face(h)], n2 = face_normal[Mesh::face(t)];
            const Vec3 e = u / lu;
            const double beta =
                std::atan2(dot(cross(n1, n2), e), std::clamp(dot(n1, n2), -1.0, 1.0));
            const double lambda = std::acos(std::clamp(dot(np, normalized(n1 + n2)), -1.0, 1.0));
            sum.add_outer(e, lambda * beta * 0.5 * lu);
            plain.add_outer(e, beta * 0.5 * lu);
            lambda_sum += lambda;
            ++count;
        });
    }
    // Every edge normal parallel to the vertex normal: all weights equal, i.e. 1.
    if (lambda_sum <= 0) return plain;
    // Rescale so that the weights average 1 over the edges (method.md 3.1).
    const double scale = static_cast<double>(count) / lambda_sum;
    for (double& x : sum.v) x *= scale;
    return sum;
}

/// The radius of p's kernel: kernel_edges shortest incident edges, at most kernel_angle times
/// the curvature radius of p's own cell (|W| of the cell, its Frobenius norm).
double reach(const VertexData& d, double kernel_edges, double kernel_angle) {
    double r = kernel_edges * d.min_edge;
    const double kf = d.area > 0 ? d.tensor.frobenius() / d.area : 0;
    if (kf > 0) r = std::min(r, kernel_angle / kf);
    return r;
}

/// The neighbours of every vertex as compressed rows (offsets, then ids in fan order): one
/// linear scan per vertex instead of a walk over half-edges in every smoothing pass.
struct Adjacency {
    std::vector<std::uint32_t> offset, ids;
};

Adjacency adjacency(const Mesh& m) {
    const std::size_t nv = m.num_vertices();
    Adjacency a;
    a.offset.assign(nv + 1, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
            std::uint32_t n = 0;
            m.for_each_neighbour(VertexId(static_cast<std::uint32_t>(v)), [&](VertexId) { ++n; });
            a.offset[v + 1] = n;
        }
    });
    for (std::size_t v = 0; v < nv; ++v) a.offset[v + 1] += a.offset[v];
    a.ids.resize(a.offset[nv]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
            std::uint32_t* out = a.ids.data() + a.offset[v];
            m.for_each_neighbour(VertexId(static_cast<std::uint32_t>(v)),
                                 [&](VertexId w) { *out++ = w.idx(); });
        }
    });
    return a;
}

/// A tensor of a tangent plane in a vertex's frame (t1, t2): mean = (a + c) / 2,
/// diff = (a - c) / 2, off = b for the matrix [[a, b], [b, c]]. Turning the frame by psi turns
/// (diff, off) by 2 psi and leaves the mean alone.
struct Planar {
    double mean = 0, diff = 0, off = 0;
};

/// A 3D tensor restricted to the tangent plane of unit normal n, in the frame of
/// tangent_basis(n) (the frame the eigen-decomposition uses).
Planar in_frame(const Sym3& w, Vec3 n) {
    Vec3 t1, t2;
    tangent_basis(n, t1, t2);
    const double a = w.form(t1, t1), b = w.form(t1, t2), c = w.form(t2, t2);
    return {0.5 * (a + c), 0.5 * (a - c), b};
}

/// Neighbourhood::kSmoothed: `passes` rounds in which every vertex adds its eligible
/// neighbours' tensors (carried to its own tangent plane) and areas to its own, weighted by
/// the kernel (1 - d^2/R^2)^2 of their distance d, R being p's reach. A neighbour is eligible
/// when it is not on a sharp edge and it and its whole cell lie within p's reach.
///
/// Why in 2D: the minimal rotation that takes a neighbour's normal to p's maps the neighbour's
/// tangent frame onto p's turned by an angle psi, fixed per (p, neighbour) pair. Computing
/// cos 2psi and sin 2psi once makes each round a few multiply-adds per neighbour instead of a
/// 3x3 rotation.
void smooth(const Mesh& m, const std::vector<VertexData>& data, const CurvatureOptions& o,
            double sharp, double kernel_edges, double kernel_angle, std::vector<Planar>& cur,
            std::vector<double>& area) {
    const std::size_t nv = m.num_vertices();
    const Adjacency adj = adjacency(m);
    std::vector<Planar> next;
    detail::resize_huge(next, nv);
    // Per (vertex, neighbour) slot: w cos 2psi, w sin 2psi and the kernel weight w, or NaN
    // when not eligible.
    std::vector<std::array<float, 3>> turn;
    detail::resize_huge(turn, adj.ids.size());
    // Compact per-vertex columns for the slot loop: normal, first frame axis, and how far the
    // cell reaches (infinite on a sharp edge: never eligible).
    std::vector<Vec3> normal, axis;
    std::vector<double> extent;
    detail::resize_huge(normal, nv);
    detail::resize_huge(axis, nv);
    detail::resize_huge(extent, nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
            const VertexData& dv = data[v];
            Vec3 t1, t2;
            tangent_basis(dv.normal, t1, t2);
            normal[v] = dv.normal;
            axis[v] = t1;
            extent[v] = dv.max_turn < sharp ? dv.max_edge : kInfinity;
            cur[v] = in_frame(dv.tensor, dv.normal);
            area[v] = dv.area;
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v) {
            const double radius = reach(data[v], kernel_edges, kernel_angle);
            const Vec3 pv = m.position(VertexId(static_cast<std::uint32_t>(v)));
            const Vec3 np = normal[v], t1 = axis[v], t2 = cross(np, t1);
            for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
                const std::uint32_t q = adj.ids[k];
                const Vec3 d = m.position(VertexId(q)) - pv;
                const Vec3 nq = normal[q];
                const double cu = dot(nq, np);
                if (!(extent[q] < radius && dot(d, d) < radius * radius && cu > -0.999)) {
                    turn[k] = {std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f};
                    continue;
                }
                // q's first axis carried by the minimal rotation n_q -> n_p, in p's frame.
                const Vec3 q1 = axis[q];
                const Vec3 u = cross(nq, np);
                const Vec3 moved = cu * q1 + cross(u, q1) + (dot(u, q1) / (1.0 + cu)) * u;
                const double x = dot(moved, t1), y = dot(moved, t2);
                const double len2 = x * x + y * y;
                const double inv = len2 > 0 ? 1.0 / len2 : 0.0;
                const double t = dot(d, d) / (radius * radius);
                const double weight = (1 - t) * (1 - t);
                turn[k] = {static_cast<float>(weight * (len2 > 0 ? (x * x - y * y) * inv : 1.0)),
                           static_cast<float>(weight * 2.0 * x * y * inv),
                           static_cast<float>(weight)};
            }
        }
    });
    std::vector<double> next_area;
    detail::resize_huge(next_area, nv);
    for (int pass = 0; pass < std::max(1, o.passes); ++pass) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
            for (std::size_t v = r.begin(); v != r.end(); ++v) {
                Planar t = cur[v];
                double a = area[v];
                for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
                    const float c2 = turn[k][0];
                    if (std::isnan(c2)) continue;
                    const float s2 = turn[k][1], w = turn[k][2];
                    const std::uint32_t q = adj.ids[k];
                    const Planar& tq = cur[q];
                    t.mean += w * tq.mean;
                    t.diff += tq.diff * c2 - tq.off * s2;
                    t.off += tq.diff * s2 + tq.off * c2;
                    a += w * area[q];
                }
                next[v] = t;
                next_area[v] = a;
            }
        });
        cur.swap(next);
        area.swap(next_area);
    }
}

double median_edge_length(const Mesh& m) {
    const std::size_t nh = m.num_halfedges();
    const std::size_t stride = std::max<std::size_t>(1, nh / kMedianSample);
    std::vector<double> lengths;
    lengths.reserve(nh / stride + 1);
    for (std::size_t i = 0; i < nh; i += stride) {
        const HalfedgeId h(static_cast<std::uint32_t>(i));
        lengths.push_back(norm(m.position(m.target(h)) - m.position(m.origin(h))));
    }
    if (lengths.empty()) return 0;
    auto mid = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
    std::nth_element(lengths.begin(), mid, lengths.end());
    return *mid;
}

std::string format_number(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return buf;
}

}  // namespace

CurvatureResult compute_curvature(const Mesh& m, const CurvatureOptions& options) {
    CurvatureResult result;
    CurvatureThresholds& th = result.thresholds;
    const std::size_t nv = m.num_vertices();
    const int rings = std::max(1, options.rings);
    const double kernel_edges =
        options.kernel_edges > 0 ? options.kernel_edges : kDefaultKernelEdges;
    const double kernel_angle =
        options.kernel_angle > 0 ? options.kernel_angle : kDefaultKernelAngle;
    th.estimator = options.estimator;
    th.sharp_edge_angle =
        options.sharp_edge_angle >= 0 ? options.sharp_edge_angle : kDefaultSharpEdgeAngle;
    switch (options.neighbourhood) {
        case Neighbourhood::kKernel:
            th.neighbourhood = "kernel: radius min(" + format_number(kernel_edges) +
                               " x shortest incident edge, " + format_number(kernel_angle) +
                               " / 1-ring curvature)";
            break;
        case Neighbourhood::kRings:
            th.neighbourhood = std::to_string(rings) + "-ring";
            break;
        case Neighbourhood::kGeodesic:
            th.neighbourhood = "geodesic radius " + format_number(options.radius);
            break;
        case Neighbourhood::kSmoothed:
            th.neighbourhood = std::to_string(std::max(1, options.passes)) +
                               " smoothing passes over neighbours within min(" +
                               format_number(kernel_edges) + " x shortest incident edge, " +
                               format_number(kernel_angle) + " / 1-ring curvature)";
            break;
    }

    // Face normals, then everything a vertex knows of its own fan.
    const FaceData fd = face_pass(m);
    const FaceMap<Vec3>& face_normal = fd.normal;
    std::vector<VertexData> data;
    detail::resize_huge(data, nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t v = r.begin(); v != r.end(); ++v)
            data[v] = vertex_pass(m, fd, VertexId(static_cast<std::uint32_t>(v)));
    });

    const double size = part_size(m);
    th.coordinate_precision = coordinate_rounding(m);
    th.median_edge_length = median_edge_length(m);
    if (options.planar_curvedness >= 0) {
        th.planar_curvedness = options.planar_curvedness;
        th.planar_rule = "given";
    } else {
        const double by_size = size > 0 ? 1.0 / (kPlanarRadiusFactor * size) : 0.0;
        const double l = th.median_edge_length;
        const double by_noise = l > 0 ? kNoiseFloorFactor * th.coordinate_precision / (l * l) : 0;
        th.planar_curvedness = std::max(by_size, by_noise);
        th.planar_rule = by_size >= by_noise
                             ? "1 / (100 x the part's size, the diagonal of its smallest box): "
                               "radii beyond 100 times the part's size are planes"
                             : "4 x coordinate precision / median edge length^2: the noise "
                               "floor of the rounded coordinates";
    }
    th.high_rule =
        "an incident edge turns by at least the sharp-edge angle, or the curvedness exceeds "
        "the sharp-edge angle / the mean length of the incident edges";

    CurvatureField& out = result.field;
    detail::resize_huge(out.k1.data(), nv);
    detail::resize_huge(out.k2.data(), nv);
    detail::resize_huge(out.dir1.data(), nv);
    detail::resize_huge(out.dir2.data(), nv);
    detail::resize_huge(out.normal.data(), nv);
    detail::resize_huge(out.shape_index.data(), nv);
    detail::resize_huge(out.curvedness.data(), nv);
    detail::resize_huge(out.type.data(), nv);
    detail::resize_huge(out.high.data(), nv);

    const double sharp = th.sharp_edge_angle;
    const double planar = th.planar_curvedness;
    // Every vertex's neighbourhood: its tensor in the vertex's tangent frame, and its area.
    std::vector<Planar> tensor;
    std::vector<double> area;
    detail::resize_huge(tensor, nv);
    detail::resize_huge(area, nv);
    if (options.neighbourhood == Neighbourhood::kSmoothed) {
        smooth(m, data, options, sharp, kernel_edges, kernel_angle, tensor, area);
    } else {
        tbb::enumerable_thread_specific<Scratch> scratch;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
            Scratch& s = scratch.local();
            for (std::size_t vi = r.begin(); vi != r.end(); ++vi) {
                const VertexId p(static_cast<std::uint32_t>(vi));
                const VertexData& d = data[vi];
                double kernel_radius = 0;  // 0: every cell of the neighbourhood weighs 1
                switch (options.neighbourhood) {
                    case Neighbourhood::kKernel:
                        kernel_radius = reach(d, kernel_edges, kernel_angle);
                        ring_neighbourhood(m, data, sharp, p, kMaxRings, kernel_radius, true, s);
                        break;
                    case Neighbourhood::kRings:
                        ring_neighbourhood(m, data, sharp, p, rings, kInfinity, false, s);
                        break;
                    case Neighbourhood::kGeodesic:
                        geodesic_neighbourhood(m, data, sharp, p, options.radius, s);
                        break;
                    case Neighbourhood::kSmoothed:
                        break;
                }
                if (options.estimator == CurvatureEstimator::kWeighted) {
                    for (const std::uint32_t q : s.set) area[vi] += data[q].area;
                    tensor[vi] = in_frame(weighted_tensor(m, face_normal, d.normal, s), d.normal);
                    continue;
                }
                const Vec3 pp = m.position(p);
                Sym3 w = d.tensor;
                double a = d.area;
                for (const std::uint32_t q : s.set) {
                    if (q == p.idx()) continue;
                    double kw = 1.0;
                    if (kernel_radius > 0) {
                        const Vec3 dq = m.position(VertexId(q)) - pp;
                        const double t = dot(dq, dq) / (kernel_radius * kernel_radius);
                        kw = (1 - t) * (1 - t);
                    }
                    a += kw * data[q].area;
                    if (options.transport) {
                        w.add_rotated(data[q].tensor, data[q].normal, d.normal, kw);
                    } else {
                        w.add(data[q].tensor, kw);
                    }
                }
                tensor[vi] = in_frame(w, d.normal);
                area[vi] = a;
            }
        });
    }

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const auto& r) {
        for (std::size_t vi = r.begin(); vi != r.end(); ++vi) {
            const VertexId p(static_cast<std::uint32_t>(vi));
            const VertexData& d = data[vi];
            const Vec3 n = d.normal;
            out.normal[p] = n;
            const Planar& w = tensor[vi];
            double k1 = 0, k2 = 0;
            Vec3 t1{}, t2{};
            if (area[vi] > 0 && norm(n) > 0) {
                tangent_basis(n, t1, t2);
                const double inv = 1.0 / area[vi];
                const double a = (w.mean + w.diff) * inv, b = w.off * inv,
                             c = (w.mean - w.diff) * inv;
                const double mean = 0.5 * (a + c), half = 0.5 * (a - c);
                const double radius = std::sqrt(half * half + b * b);
                const double mu1 = mean + radius, mu2 = mean - radius;
                // Eigenvector of mu1: (b, mu1 - a) or (mu1 - c, b), whichever is longer.
                double ex = b, ey = mu1 - a;
                if (half > 0) ex = mu1 - c, ey = b;
                const double el = std::sqrt(ex * ex + ey * ey);
                if (el > 0) {
                    ex /= el;
                    ey /= el;
                } else {
                    ex = 1, ey = 0;  // umbilic: every direction is principal
                }
                const Vec3 e1 = ex * t1 + ey * t2;  // of mu1
                // The eigenvector of an eigenvalue is the direction of the other curvature.
                k1 = mu1;
                k2 = mu2;
                out.dir1[p] = cross(n, e1);
                out.dir2[p] = e1;
            }
            out.k1[p] = k1;
            out.k2[p] = k2;
            const double c = curvedness(k1, k2);
            out.curvedness[p] = c;
            const ShapeType type = classify_shape(k1, k2, planar);
            out.type[p] = type;
            out.shape_index[p] = type == ShapeType::kPlane ? 2.0 : shape_index(k1, k2);
            const bool high = d.max_turn >= sharp || (d.mean_edge > 0 && c * d.mean_edge >= sharp);
            out.high[p] = high ? 1 : 0;
        }
    });
    for (std::size_t v = 0; v < nv; ++v) {
        ++result.count_by_type[static_cast<int>(out.type.data()[v])];
        result.high_points += out.high.data()[v];
    }
    return result;
}

std::vector<std::byte> encode_curvature_ply(const Mesh& m, const CurvatureResult& result) {
    const std::size_t nv = m.num_vertices(), nf = m.num_faces();
    std::vector<std::array<std::uint32_t, 3>> triangles(nf);
    for (std::size_t f = 0; f < nf; ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        triangles[f] = {m.vertex(ff, 0).idx(), m.vertex(ff, 1).idx(), m.vertex(ff, 2).idx()};
    }
    using Type = PlyColumn::Type;
    std::vector<PlyColumn> columns = {
        {"k1", Type::kFloat32, {}},          {"k2", Type::kFloat32, {}},
        {"shape_index", Type::kFloat32, {}}, {"curvedness", Type::kFloat32, {}},
        {"type", Type::kUint8, {}},          {"high", Type::kUint8, {}},
        {"red", Type::kUint8, {}},           {"green", Type::kUint8, {}},
        {"blue", Type::kUint8, {}}};
    for (PlyColumn& c : columns) c.values.resize(nv);
    const CurvatureField& f = result.field;
    for (std::size_t i = 0; i < nv; ++i) {
        const VertexId v(static_cast<std::uint32_t>(i));
        const auto rgb = shape_type_color(f.type[v]);
        columns[0].values[i] = f.k1[v];
        columns[1].values[i] = f.k2[v];
        columns[2].values[i] = f.shape_index[v];
        columns[3].values[i] = f.curvedness[v];
        columns[4].values[i] = static_cast<double>(f.type[v]);
        columns[5].values[i] = f.high[v];
        for (int k = 0; k < 3; ++k) columns[6 + k].values[i] = rgb[k];
    }
    return encode_ply(m.positions(), triangles, columns);
}

}  // namespace ncrev
