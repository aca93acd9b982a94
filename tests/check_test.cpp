// The volume we report against BRepGProp's own (an internal module: src/brep/check.h).
#include "brep/check.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_Transform.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <filesystem>
#include <gp_Trsf.hxx>

#include "step_readback.h"

namespace ncrev {
namespace {

double brepgprop_volume(const TopoDS_Shape& shape) {
    GProp_GProps props;
    BRepGProp::VolumeProperties(shape, props, brep_detail::kVolumeRelativeError);
    return props.Mass();
}

// solid_volume() integrates the faces in parallel and sums them in order: the same bits as
// BRepGProp's one face after the other, on real parts of planes, cylinders, cones, tori and
// B-splines, and on a located copy (measured whole, BRepGProp's way).
TEST(SolidVolume, IsBRepGPropsToTheBit) {
    const auto dir = std::filesystem::path(NCREV_SOURCE_DIR) / ".." / "shared" / "corpus" / "step";
    int measured = 0, unplaced = 0;  // parts measured face by face in parallel
    for (const char* name : {"nist_ctc_01_asme1_rd.stp", "nist_ftc_10_asme1_rb.stp",
                             "occt_linkrods.step", "trimesh_featuretype.step"}) {
        const auto path = dir / name;
        if (!std::filesystem::exists(path)) continue;
        const test::ReadBack back = test::read_step(path);
        ASSERT_FALSE(back.shape.IsNull()) << name;
        ASSERT_EQ(back.solids, 1u) << name;
        TopTools_IndexedMapOfShape faces;
        TopExp::MapShapes(back.shape, TopAbs_FACE, faces);
        ASSERT_GT(faces.Extent(), 10) << name;
        bool placed = !back.shape.Location().IsIdentity();
        for (TopExp_Explorer x(back.shape, TopAbs_FACE); x.More(); x.Next())
            placed = placed || !x.Current().Location().IsIdentity();
        if (!placed) ++unplaced;
        const double v = brep_detail::solid_volume(back.shape);
        EXPECT_GT(v, 0) << name;
        EXPECT_EQ(v, brepgprop_volume(back.shape)) << name;

        gp_Trsf move;
        move.SetTranslation(gp_Vec(12.5, -3, 40));
        const TopoDS_Shape located = BRepBuilderAPI_Transform(back.shape, move, false).Shape();
        ASSERT_FALSE(located.Location().IsIdentity()) << name;
        EXPECT_EQ(brep_detail::solid_volume(located), brepgprop_volume(located)) << name;
        EXPECT_NEAR(brep_detail::solid_volume(located), v, 1e-6 * v) << name;
        ++measured;
    }
    if (measured == 0) GTEST_SKIP() << "no corpus at " << dir;
    EXPECT_GT(unplaced, 0) << "no part took the parallel path";
}

}  // namespace
}  // namespace ncrev
