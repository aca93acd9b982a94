// The volume we report against BRepGProp's own (an internal module: src/brep/check.h).
#include "brep/check.h"

#include <gtest/gtest.h>

#include <BRepGProp.hxx>
#include <BRep_Builder.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Compound.hxx>
#include <filesystem>
#include <gp_Ax1.hxx>
#include <gp_Dir.hxx>
#include <gp_Pnt.hxx>
#include <gp_Trsf.hxx>
#include <gp_Vec.hxx>
#include <optional>

#include "step_readback.h"

namespace ncrev {
namespace {

double brepgprop_volume(const TopoDS_Shape& shape) {
    GProp_GProps props;
    BRepGProp::VolumeProperties(shape, props, brep_detail::kVolumeRelativeError);
    return props.Mass();
}

// volume_by_faces() integrates the faces in parallel and sums them in order: the same bits as
// BRepGProp's one face after the other, on real parts of planes, cylinders, cones, tori and
// B-splines, moved as a whole and as a compound of located faces. solid_volume() is the same
// on them (none has a face going round its surface more than once, which it measures cut).
TEST(SolidVolume, IsBRepGPropsToTheBit) {
    const auto dir = std::filesystem::path(NCREV_SOURCE_DIR) / ".." / "shared" / "corpus" / "step";
    if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no corpus at " << dir;
    gp_Trsf move;
    move.SetRotation(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(1, 1, 0)), 0.4);
    move.SetTranslationPart(gp_Vec(12.5, -3, 40));
    for (const char* name : {"nist_ctc_01_asme1_rd.stp", "nist_ftc_10_asme1_rb.stp",
                             "occt_linkrods.step", "trimesh_featuretype.step"}) {
        const test::ReadBack back = test::read_step(dir / name);
        ASSERT_FALSE(back.shape.IsNull()) << name;
        ASSERT_EQ(back.solids, 1u) << name;
        TopTools_IndexedMapOfShape faces;
        TopExp::MapShapes(back.shape, TopAbs_FACE, faces);
        ASSERT_GT(faces.Extent(), 10) << name;
        const std::optional<double> v =
            brep_detail::volume_by_faces(back.shape, brep_detail::kVolumeRelativeError);
        ASSERT_TRUE(v.has_value()) << name;
        EXPECT_GT(*v, 0) << name;
        EXPECT_EQ(*v, brepgprop_volume(back.shape)) << name;
        EXPECT_EQ(brep_detail::solid_volume(back.shape), *v) << name;

        const TopoDS_Shape moved = back.shape.Moved(TopLoc_Location(move));
        TopoDS_Compound holder;
        BRep_Builder builder;
        builder.MakeCompound(holder);
        builder.Add(holder, moved);
        for (const TopoDS_Shape& s : {moved, TopoDS_Shape(holder)}) {
            const std::optional<double> w =
                brep_detail::volume_by_faces(s, brep_detail::kVolumeRelativeError);
            ASSERT_TRUE(w.has_value()) << name;
            EXPECT_EQ(*w, brepgprop_volume(s)) << name;
            EXPECT_NEAR(*w, *v, 1e-6 * *v) << name;
        }
    }
}

}  // namespace
}  // namespace ncrev
