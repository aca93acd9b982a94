// Meshes made the way a mesh-based NC simulator makes them: booleans of faceted solids. The
// cutting solid is a polygon prism, not a cylinder, so where two cuts cross, the vertices of
// their intersection lie on both prisms' facets: inside both cylinders by up to the sag of a
// facet, several times the segmentation tolerance. A CAD tessellation never does this (its
// vertices lie on the exact surfaces); trimesh's angle block (corpus_test.cpp) does.
#include <gtest/gtest.h>
#include <unistd.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeSolid.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <STEPControl_Writer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Shell.hxx>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "ncrev/brep.h"
#include "ncrev/mesh.h"
#include "ncrev/sample.h"
#include "ncrev/segment.h"
#include "scratch.h"

namespace ncrev {
namespace {

/// A prism of `sides` sides inscribed in the cylinder of radius `r` about the axis through `o`
/// along `dir` (unit), from `o` to `o + length * dir`: a drill as a faceted solid.
TopoDS_Shape faceted_drill(gp_Pnt o, gp_Dir dir, double r, double length, int sides) {
    const gp_Dir x = std::abs(dir.Z()) < 0.9 ? gp_Dir(dir.Crossed(gp::DZ())) : gp::DX();
    const gp_Dir y = dir.Crossed(x);
    BRepBuilderAPI_MakePolygon poly;
    for (int k = 0; k < sides; ++k) {
        const double a = 2 * std::numbers::pi * k / sides;
        poly.Add(o.Translated(gp_Vec(x) * (r * std::cos(a)) + gp_Vec(y) * (r * std::sin(a))));
    }
    poly.Close();
    const TopoDS_Face base = BRepBuilderAPI_MakeFace(poly.Wire(), true).Face();
    return BRepPrimAPI_MakePrism(base, gp_Vec(dir) * length).Shape();
}

/// A polyhedron of `rings` x 2 `rings` corners on the sphere of radius `r` about `o`, its faces
/// flat triangles: a ball as a faceted solid.
TopoDS_Shape faceted_ball(gp_Pnt o, double r, int rings) {
    const auto at = [&](int i, int j) {
        const double t = std::numbers::pi * i / rings, p = std::numbers::pi * j / rings;
        return gp_Pnt(o.X() + r * std::sin(t) * std::cos(p), o.Y() + r * std::sin(t) * std::sin(p),
                      o.Z() + r * std::cos(t));
    };
    BRepBuilderAPI_Sewing sew(1e-6 * r);
    const auto triangle = [&](gp_Pnt a, gp_Pnt b, gp_Pnt c) {
        sew.Add(
            BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakePolygon(a, b, c, true).Wire(), true).Face());
    };
    for (int i = 0; i < rings; ++i) {
        for (int j = 0; j < 2 * rings; ++j) {
            const gp_Pnt a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
            if (i > 0) triangle(a, b, d);
            if (i + 1 < rings) triangle(b, c, d);
        }
    }
    sew.Perform();
    return BRepBuilderAPI_MakeSolid(TopoDS::Shell(sew.SewedShape())).Solid();
}

// A 60 x 40 x 30 mm block with a vertical bore of radius 8, a cross bore of radius 5 and a
// ball of radius 9 sunk into its top across the bore's rim, each a faceted solid (prisms of 16
// to 48 sides, a polyhedron of 12 to 24 rings): where two cuts cross, the mesh's vertices lie
// on facets of both, inside both surfaces by up to their sag (0.03 mm for the 36-sided bore,
// four times the tolerance of 0.0078 mm). The part comes back as its 6 planes, 3 cylinders of
// radius 8 and 5 and a sphere of 9 (each within 1e-3), no fallback, within the deflection of
// the mesh. Before the chord fits: 20 faces for the 36-sided bores alone (6 pieces of the
// large bore, 4 of the small one, 4 prism facets as planes). 12 sides (30 degrees between
// facets, the sharp angle): the cross bore's band failed (BRepCheck_NotClosed: its closed edge
// round the vertical bore, split in three by that bore's face, came back in the wrong order)
// until in_walk_order(). There the mesh's vertices where the prisms cross lie inside both
// cylinders by their sag (0.27 and 0.17 mm), and their distance to the exact edge where the
// cylinders meet, 0.43 mm, is more than the deflection the mesh shows elsewhere (0.31 mm).
TEST(FacetedCuts, CrossedFacetedBoresAreCylinders) {
    const auto dir = test::scratch_dir() / "faceted_cuts";
    std::filesystem::create_directories(dir);
    for (const int sides : {12, 16, 24, 48}) {
        SCOPED_TRACE(std::to_string(sides) + " sides");
        TopoDS_Shape part = BRepPrimAPI_MakeBox(60, 40, 30).Shape();
        part = BRepAlgoAPI_Cut(part, faceted_drill({30, 20, -1}, gp::DZ(), 8, 32, sides)).Shape();
        part = BRepAlgoAPI_Cut(part, faceted_drill({-1, 20, 15}, gp::DX(), 5, 62, sides)).Shape();
        part =
            BRepAlgoAPI_Cut(part, faceted_ball({45, 20, 30}, 9, std::max(12, sides / 2))).Shape();
        const auto step = dir / "crossed_bores.step";
        {
            STEPControl_Writer w;
            ASSERT_EQ(w.Transfer(part, STEPControl_AsIs), IFSelect_RetDone);
            ASSERT_EQ(w.Write(step.string().c_str()), IFSelect_RetDone);
        }
        const SamplePart made = sample_from_step(step).value();
        const Mesh mesh = build_mesh(TriangleSoup(made.mesh)).value().mesh;
        const SegmentResult sr = segment(mesh).value();
        std::size_t bore8 = 0, bore5 = 0, ball = 0;
        for (const Region& g : sr.regions) {
            const Surface& s = g.fit.surface;
            if (s.kind == FitKind::kSphere) ball += std::abs(s.radius - 9) < 1e-3;
            if (s.kind != FitKind::kCylinder) continue;
            bore8 += std::abs(s.radius - 8) < 1e-3;
            bore5 += std::abs(s.radius - 5) < 1e-3;
        }
        EXPECT_EQ(bore8, 1u);
        EXPECT_EQ(bore5, 2u);
        EXPECT_EQ(ball, 1u);
        const ReverseReport r = reverse_to_step(mesh, dir / "out.step").value();
        EXPECT_TRUE(r.solid && r.valid && r.written);
        EXPECT_TRUE(r.fallbacks.empty());
        EXPECT_EQ(r.faces, 10u);
        EXPECT_EQ(r.faces_by_kind.at("plane"), 6u);
        EXPECT_EQ(r.faces_by_kind.at("cylinder"), 3u);
        EXPECT_EQ(r.faces_by_kind.at("sphere"), 1u);
        ASSERT_TRUE(r.deviation.has_value());
        EXPECT_LE(r.deviation->mesh_to_solid.max, (sides > 12 ? 1.0 : 1.5) * r.chordal_deflection);
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ncrev
