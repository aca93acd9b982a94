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
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <STEPControl_Writer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Shape.hxx>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "ncrev/brep.h"
#include "ncrev/mesh.h"
#include "ncrev/sample.h"
#include "ncrev/segment.h"

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

// A 60 x 40 x 30 mm block with a vertical bore of radius 8 and a cross bore of radius 5 through
// it, each a 36-sided prism (sag 0.030 and 0.019 mm; tolerance 1e-4 x the diagonal, 0.0078 mm):
// the cross bore's rims on the vertical bore have their vertices on facets of both. Each bore
// comes back as cylinders (the vertical one whole, the cross one in its two pieces), the block
// as its six planes, in a valid closed solid.
TEST(FacetedCuts, CrossedFacetedBoresAreCylinders) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("ncrev_faceted_cut_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    for (const int sides : {12, 24, 48, 120}) {
        SCOPED_TRACE(std::to_string(sides) + " sides");
        TopoDS_Shape part = BRepPrimAPI_MakeBox(60, 40, 30).Shape();
        part = BRepAlgoAPI_Cut(part, faceted_drill({30, 20, -1}, gp::DZ(), 8, 32, sides)).Shape();
        part = BRepAlgoAPI_Cut(part, faceted_drill({-1, 20, 15}, gp::DX(), 5, 62, sides)).Shape();
        const auto step = dir / "crossed_bores.step";
        {
            STEPControl_Writer w;
            ASSERT_EQ(w.Transfer(part, STEPControl_AsIs), IFSelect_RetDone);
            ASSERT_EQ(w.Write(step.string().c_str()), IFSelect_RetDone);
        }
        const SamplePart made = sample_from_step(step).value();
        const Mesh mesh = build_mesh(TriangleSoup(made.mesh)).value().mesh;
        const SegmentResult sr = segment(mesh).value();
        std::size_t bore8 = 0, bore5 = 0;
        for (const Region& g : sr.regions) {
            const Surface& s = g.fit.surface;
            if (s.kind != FitKind::kCylinder) continue;
            bore8 += std::abs(s.radius - 8) < 1e-3;
            bore5 += std::abs(s.radius - 5) < 1e-3;
        }
        EXPECT_EQ(bore8, 1u);
        EXPECT_EQ(bore5, 2u);
        const ReverseReport r = reverse_to_step(mesh, dir / "out.step").value();
        EXPECT_TRUE(r.solid && r.valid && r.written);
        EXPECT_TRUE(r.fallbacks.empty());
        EXPECT_EQ(r.faces, 9u);
        EXPECT_EQ(r.faces_by_kind.at("plane"), 6u);
        EXPECT_EQ(r.faces_by_kind.at("cylinder"), 3u);
        ASSERT_TRUE(r.deviation.has_value());
        EXPECT_LE(r.deviation->mesh_to_solid.max, r.chordal_deflection);
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ncrev
