// Distances between a B-rep and a mesh through a uniform grid of triangles: the B-rep is
// triangulated finely (BRepMesh), each query point searches the grid's cells ring by ring
// outward until no nearer triangle can exist.
#include "brep/deviation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

class TriangleGrid {
   public:
    explicit TriangleGrid(std::vector<Triangle> tris) : tris_(std::move(tris)) {
        for (const Triangle& t : tris_) {
            for (const Vec3& p : t) box_.add(p);
        }
        // Cells about twice the mean triangle size: a few triangles each.
        double edge = 0;
        for (const Triangle& t : tris_) edge += norm(t[1] - t[0]) + norm(t[2] - t[1]);
        edge = tris_.empty() ? 1 : edge / (2.0 * static_cast<double>(tris_.size()));
        const Vec3 ext = box_.max - box_.min;
        cell_ = std::max({2 * edge, 1e-9 * (ext.x + ext.y + ext.z), 1e-12});
        for (int k = 0; k < 3; ++k) {
            const double e = k == 0 ? ext.x : k == 1 ? ext.y : ext.z;
            n_[k] = std::clamp(static_cast<int>(e / cell_) + 1, 1, 1024);
        }
        // Grow the cell when the grid would be too large.
        while (static_cast<double>(n_[0]) * n_[1] * n_[2] > 8.0 * tris_.size() + 64) {
            cell_ *= 1.5;
            for (int k = 0; k < 3; ++k) {
                const double e = k == 0 ? ext.x : k == 1 ? ext.y : ext.z;
                n_[k] = std::clamp(static_cast<int>(e / cell_) + 1, 1, 1024);
            }
        }
        start_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
        const auto each_cell = [&](const Triangle& t, auto&& f) {
            std::array<int, 3> lo{}, hi{};
            for (int k = 0; k < 3; ++k) {
                const double mn = std::min({coord(t[0], k), coord(t[1], k), coord(t[2], k)});
                const double mx = std::max({coord(t[0], k), coord(t[1], k), coord(t[2], k)});
                lo[k] = index(mn, k);
                hi[k] = index(mx, k);
            }
            for (int z = lo[2]; z <= hi[2]; ++z)
                for (int y = lo[1]; y <= hi[1]; ++y)
                    for (int x = lo[0]; x <= hi[0]; ++x) f(cell_id(x, y, z));
        };
        for (const Triangle& t : tris_) each_cell(t, [&](std::size_t c) { ++start_[c + 1]; });
        for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
        items_.resize(start_.back());
        std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
        for (std::uint32_t i = 0; i < tris_.size(); ++i) {
            each_cell(tris_[i], [&](std::size_t c) { items_[fill[c]++] = i; });
        }
    }

    /// Distance from p to the nearest triangle.
    double distance(Vec3 p) const {
        if (tris_.empty()) return 0;
        std::array<int, 3> c{};
        for (int k = 0; k < 3; ++k) c[k] = index(coord(p, k), k);
        double best2 = 1e300;
        const int max_ring = std::max({n_[0], n_[1], n_[2]});
        for (int ring = 0; ring <= max_ring; ++ring) {
            for (int z = c[2] - ring; z <= c[2] + ring; ++z) {
                if (z < 0 || z >= n_[2]) continue;
                for (int y = c[1] - ring; y <= c[1] + ring; ++y) {
                    if (y < 0 || y >= n_[1]) continue;
                    for (int x = c[0] - ring; x <= c[0] + ring; ++x) {
                        if (x < 0 || x >= n_[0]) continue;
                        if (std::max({std::abs(x - c[0]), std::abs(y - c[1]),
                                      std::abs(z - c[2])}) != ring) {
                            continue;
                        }
                        const std::size_t id = cell_id(x, y, z);
                        for (std::uint32_t i = start_[id]; i < start_[id + 1]; ++i) {
                            const Triangle& t = tris_[items_[i]];
                            const Vec3 q = closest_on_triangle(p, t[0], t[1], t[2]);
                            best2 = std::min(best2, dot(p - q, p - q));
                        }
                    }
                }
            }
            // Every triangle not yet seen is in a cell outside the block searched: at least
            // `ring` cells away (the point is inside its clamped cell, or outside the grid,
            // which only makes them farther), and at least as far as the block's nearest side
            // that has cells beyond it — most points lie on the other mesh, and stop at ring 0
            // instead of searching the 26 cells around theirs.
            double reach = ring * cell_;
            double side = 1e300;
            for (int k = 0; k < 3; ++k) {
                const double lo = coord(box_.min, k), v = coord(p, k);
                if (c[k] - ring > 0) side = std::min(side, v - (lo + (c[k] - ring) * cell_));
                if (c[k] + ring < n_[k] - 1) {
                    side = std::min(side, lo + (c[k] + ring + 1) * cell_ - v);
                }
            }
            reach = std::max(reach, side);
            if (best2 < 1e300 && best2 <= reach * reach) break;
        }
        return std::sqrt(best2);
    }

   private:
    static double coord(Vec3 p, int k) { return k == 0 ? p.x : k == 1 ? p.y : p.z; }
    int index(double v, int k) const {
        const double lo = coord(box_.min, k);
        return std::clamp(static_cast<int>(std::floor((v - lo) / cell_)), 0, n_[k] - 1);
    }
    std::size_t cell_id(int x, int y, int z) const {
        return static_cast<std::size_t>(x) +
               static_cast<std::size_t>(n_[0]) *
                   (static_cast<std::size_t>(y) + static_cast<std::size_t>(n_[1]) * z);
    }
    std::vector<Triangle> tris_;
    Box3 box_;
    double cell_ = 1;
    std::array<int, 3> n_{1, 1, 1};
    std::vector<std::uint32_t> start_, items_;
};

DistanceStats stats_of(const std::vector<Vec3>& points, const TriangleGrid& grid) {
    std::vector<double> d(points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              d[i] = grid.distance(points[i]);
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

std::vector<std::array<double, 3>> untriangulated_faces(const TopoDS_Shape& shape,
                                                        double deflection) {
    std::vector<std::array<double, 3>> out;
    BRepMesh_IncrementalMesh(shape, deflection, false, 0.2, true);
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

SolidDeviation measure_deviation(const TopoDS_Shape& shape, const Mesh& mesh, double deflection) {
    SolidDeviation out;
    out.deflection = deflection;
    // In parallel over faces (each face's triangulation does not depend on the others').
    BRepMesh_IncrementalMesh(shape, deflection, false, 0.2, true);
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
    std::vector<Triangle> mesh_tris(mesh.num_faces());
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        for (int i = 0; i < 3; ++i) mesh_tris[f][i] = mesh.position(mesh.vertex(FaceId(f), i));
    }
    std::vector<Vec3> mesh_points(mesh.positions().begin(), mesh.positions().end());
    out.mesh_to_solid = stats_of(mesh_points, TriangleGrid(std::move(solid_tris)));
    out.solid_to_mesh = stats_of(solid_nodes, TriangleGrid(std::move(mesh_tris)));
    return out;
}

}  // namespace ncrev::brep_detail
