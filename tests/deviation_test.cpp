// The deviation measure's tree search against brute force (an internal module: src/brep).
#include "brep/deviation.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_Transform.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRep_Tool.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Trsf.hxx>
#include <numbers>
#include <vector>

#include "analytic_shapes.h"
#include "detail/triangle_tree.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"

namespace ncrev {
namespace {

// A cylinder turned about a skew axis: BRepMesh gives its side long thin triangles along the
// axis, none parallel to the coordinate axes, their boxes overlapping. The mesh: the same
// cylinder at `around` x `along` cells with fans on the caps, its side pushed in and out by up to
// 0.3 mm, so that every distance is its own. The tree search must give the brute-force
// distances: at 64 x 24 cells (3200 facets), and at 256 x 36 (18944 facets), whose tree builds
// its two halves at once (TriangleTree's kParallelBuild, 16384).
void expect_brute_force_distances(int around, int along) {
    gp_Trsf turn;
    turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 2, 3)), 0.7);
    constexpr double kRadius = 10, kHeight = 30;
    const TopoDS_Shape shape =
        BRepBuilderAPI_Transform(BRepPrimAPI_MakeCylinder(kRadius, kHeight).Shape(), turn, true)
            .Shape();
    const auto moved = [&](Vec3 p) {
        gp_Pnt q(p.x, p.y, p.z);
        q.Transform(turn);
        return Vec3{q.X(), q.Y(), q.Z()};
    };
    test::Rng rng(5);
    TriangleSoup soup;
    for (int j = 0; j <= along; ++j)
        for (int i = 0; i < around; ++i) {
            const double a = 2 * std::numbers::pi * i / around;
            const double r =
                j == 0 || j == along ? kRadius : kRadius + 0.3 * (2 * rng.uniform() - 1);
            soup.points.push_back(
                moved(Vec3{r * std::cos(a), r * std::sin(a), kHeight * j / along}));
        }
    const auto at = [&](int i, int j) {
        return static_cast<std::uint32_t>(j * around + i % around);
    };
    for (int j = 0; j < along; ++j)
        for (int i = 0; i < around; ++i) {
            soup.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            soup.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    const auto bottom = static_cast<std::uint32_t>(soup.points.size());
    soup.points.push_back(moved(Vec3{0, 0, 0}));
    soup.points.push_back(moved(Vec3{0, 0, kHeight}));
    for (int i = 0; i < around; ++i) {
        soup.triangles.push_back({bottom, at(i + 1, 0), at(i, 0)});
        soup.triangles.push_back({bottom + 1, at(i, along), at(i + 1, along)});
    }
    const Mesh mesh = build_mesh(soup).value().mesh;
    const SolidDeviation dev = brep_detail::measure_deviation(shape, mesh, 0.01);
    // The triangulation the measure made and kept on the shape.
    std::vector<std::array<Vec3, 3>> solid;
    std::vector<Vec3> nodes;
    for (TopExp_Explorer x(shape, TopAbs_FACE); x.More(); x.Next()) {
        TopLoc_Location loc;
        const Handle(Poly_Triangulation) t =
            BRep_Tool::Triangulation(TopoDS::Face(x.Current()), loc);
        ASSERT_FALSE(t.IsNull());
        const auto node = [&](int i) {
            const gp_Pnt p = t->Node(i).Transformed(loc.Transformation());
            return Vec3{p.X(), p.Y(), p.Z()};
        };
        for (int i = 1; i <= t->NbNodes(); ++i) nodes.push_back(node(i));
        for (int i = 1; i <= t->NbTriangles(); ++i) {
            int a = 0, b = 0, c = 0;
            t->Triangle(i).Get(a, b, c);
            solid.push_back({node(a), node(b), node(c)});
        }
    }
    std::vector<std::array<Vec3, 3>> tris;
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(f);
        tris.push_back({mesh.position(mesh.vertex(ff, 0)), mesh.position(mesh.vertex(ff, 1)),
                        mesh.position(mesh.vertex(ff, 2))});
    }
    const auto brute = [](const std::vector<Vec3>& points,
                          const std::vector<std::array<Vec3, 3>>& to) {
        double mx = 0, sum = 0;
        for (const Vec3& p : points) {
            double best = 1e300;
            for (const auto& t : to) {
                const Vec3 q = detail::closest_on_triangle(p, t[0], t[1], t[2]);
                best = std::min(best, dot(p - q, p - q));
            }
            mx = std::max(mx, std::sqrt(best));
            sum += std::sqrt(best);
        }
        return std::pair{mx, sum / static_cast<double>(points.size())};
    };
    std::vector<Vec3> vertices;
    for (std::uint32_t v = 0; v < mesh.num_vertices(); ++v)
        vertices.push_back(mesh.position(VertexId(v)));
    const auto [to_solid_max, to_solid_mean] = brute(vertices, solid);
    const auto [to_mesh_max, to_mesh_mean] = brute(nodes, tris);
    EXPECT_GT(to_solid_max, 0.2);   // the mesh's bumps
    EXPECT_GT(solid.size(), 300u);  // long thin triangles along the side
    EXPECT_EQ(dev.mesh_to_solid.max, to_solid_max);
    EXPECT_NEAR(dev.mesh_to_solid.mean, to_solid_mean, 1e-12);
    EXPECT_EQ(dev.solid_to_mesh.max, to_mesh_max);
    EXPECT_NEAR(dev.solid_to_mesh.mean, to_mesh_mean, 1e-12);
}

TEST(Deviation, TreeDistancesAreTheBruteForceOnes) {
    expect_brute_force_distances(64, 24);
    expect_brute_force_distances(256, 36);
}

}  // namespace
}  // namespace ncrev
