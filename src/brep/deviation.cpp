// Distances between a B-rep and a mesh through a bounding-volume hierarchy of triangles: the
// B-rep is triangulated finely (BRepMesh), each query point descends the tree of the other
// side's triangles, skipping every box farther than the nearest triangle found.
#include "brep/deviation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "detail/huge_pages.h"

namespace ncrev::brep_detail {

// Ericson, Real-Time Collision Detection, 5.1.5.
Vec3 closest_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
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

namespace {

using Triangle = std::array<Vec3, 3>;

/// Triangles per task of the parallel loops over all of a mesh's or a tree's (gathering them,
/// their centres, the tree's reordered copy): each costs a few nanoseconds there, and a task's
/// overhead about a microsecond, so tasks this large keep it under a percent.
constexpr std::uint32_t kGrain = 1u << 14;

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
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& r) {
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
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) sorted[i] = tris_[order_[i]];
        });
        tris_ = std::move(sorted);
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

std::vector<Triangle> mesh_triangles(const Mesh& mesh) {
    std::vector<Triangle> tris;
    detail::resize_huge(tris, mesh.num_faces());
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, mesh.num_faces(), kGrain),
                      [&](const tbb::blocked_range<std::uint32_t>& r) {
                          for (std::uint32_t f = r.begin(); f != r.end(); ++f) {
                              for (int i = 0; i < 3; ++i)
                                  tris[f][i] = mesh.position(mesh.vertex(FaceId(f), i));
                          }
                      });
    return tris;
}

DistanceStats stats_of(const std::vector<Vec3>& points, const TriangleTree& tree) {
    std::vector<double> d(points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              d[i] = tree.distance(points[i]);
                          }
                      });
    DistanceStats s;
    s.points = points.size();
    double sum = 0, sum2 = 0;
    for (double x : d) {
        s.max = std::max(s.max, x);
        sum += x;
        sum2 += x * x;
    }
    if (!d.empty()) {
        s.mean = sum / static_cast<double>(d.size());
        s.rms = std::sqrt(sum2 / static_cast<double>(d.size()));
    }
    return s;
}

}  // namespace

/// BRepMesh's angular deflection for the solid's triangulation, and its own default, which a
/// face it leaves without triangles at the first gets (triangulate()).
constexpr double kMeshAngle = 0.2;
constexpr double kMeshAngleDefault = 0.5;

void triangulate(const TopoDS_Shape& shape, double deflection, bool parallel) {
    BRepMesh_IncrementalMesh(shape, deflection, false, kMeshAngle, parallel);
    for (TopExp_Explorer x(shape, TopAbs_FACE); x.More(); x.Next()) {
        const TopoDS_Face& face = TopoDS::Face(x.Current());
        TopLoc_Location loc;
        if (BRep_Tool::Triangulation(face, loc).IsNull()) {
            BRepMesh_IncrementalMesh(face, deflection, false, kMeshAngleDefault, false);
        }
    }
}

std::vector<std::array<double, 3>> untriangulated_faces(const TopoDS_Shape& shape,
                                                        double deflection) {
    std::vector<std::array<double, 3>> out;
    triangulate(shape, deflection, true);
    for (TopExp_Explorer x(shape, TopAbs_FACE); x.More(); x.Next()) {
        const TopoDS_Face& face = TopoDS::Face(x.Current());
        TopLoc_Location loc;
        if (!BRep_Tool::Triangulation(face, loc).IsNull()) continue;
        GProp_GProps props;
        BRepGProp::SurfaceProperties(face, props);
        gp_Pnt p = props.CentreOfMass();
        // The centre of a curved face is off it, perhaps nearer a neighbour: its foot on the
        // face.
        BRepExtrema_DistShapeShape d(BRepBuilderAPI_MakeVertex(p).Vertex(), face);
        if (d.IsDone() && d.NbSolution() > 0) p = d.PointOnShape2(1);
        out.push_back({p.X(), p.Y(), p.Z()});
    }
    return out;
}

std::vector<double> faces_from_mesh(std::span<const TopoDS_Face> faces, const Mesh& mesh,
                                    double deflection) {
    const TriangleTree tree(mesh_triangles(mesh));
    // Faces share their edges' polygons: those without triangles are meshed one at a time.
    for (const TopoDS_Face& face : faces) {
        TopLoc_Location loc;
        if (BRep_Tool::Triangulation(face, loc).IsNull()) triangulate(face, deflection, false);
    }
    std::vector<double> out(faces.size(), -1.0);
    tbb::parallel_for(std::size_t{0}, faces.size(), [&](std::size_t k) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(faces[k], loc);
        if (tri.IsNull()) return;
        const gp_Trsf tr = loc.Transformation();
        double far = 0;
        for (int i = 1; i <= tri->NbNodes(); ++i) {
            const gp_Pnt p = tri->Node(i).Transformed(tr);
            far = std::max(far, tree.distance(Vec3{p.X(), p.Y(), p.Z()}));
        }
        out[k] = far;
    });
    return out;
}

SolidDeviation measure_deviation(const TopoDS_Shape& shape, const Mesh& mesh, double deflection) {
    SolidDeviation out;
    out.deflection = deflection;
    // In parallel over faces (each face's triangulation does not depend on the others').
    triangulate(shape, deflection, true);
    std::vector<Triangle> solid_tris;
    std::vector<Vec3> solid_nodes;
    for (TopExp_Explorer x(shape, TopAbs_FACE); x.More(); x.Next()) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) tri =
            BRep_Tool::Triangulation(TopoDS::Face(x.Current()), loc);
        if (tri.IsNull()) {
            ++out.faces_without_triangles;
            continue;
        }
        const gp_Trsf tr = loc.Transformation();
        const auto node = [&](int i) {
            const gp_Pnt p = tri->Node(i).Transformed(tr);
            return Vec3{p.X(), p.Y(), p.Z()};
        };
        for (int i = 1; i <= tri->NbNodes(); ++i) solid_nodes.push_back(node(i));
        for (int i = 1; i <= tri->NbTriangles(); ++i) {
            int a = 0, b = 0, c = 0;
            tri->Triangle(i).Get(a, b, c);
            solid_tris.push_back({node(a), node(b), node(c)});
        }
    }
    std::vector<Vec3> mesh_points(mesh.positions().begin(), mesh.positions().end());
    out.mesh_to_solid = stats_of(mesh_points, TriangleTree(std::move(solid_tris)));
    out.solid_to_mesh = stats_of(solid_nodes, TriangleTree(mesh_triangles(mesh)));
    return out;
}

}  // namespace ncrev::brep_detail
