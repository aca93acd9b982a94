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
#include "detail/triangle_tree.h"

namespace ncrev::brep_detail {

namespace {

using detail::Triangle;
using detail::TriangleTree;

/// Triangles per task of the loops over all of a mesh's (gathering them): as the tree's.
constexpr std::uint32_t kGrain = detail::kTreeGrain;

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
