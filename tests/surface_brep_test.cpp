// The exact B-rep's build rounds (an internal module: src/brep).
#include <gtest/gtest.h>

#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "brep/surfaces.h"
#include "ncrev/mesh.h"
#include "ncrev/segment.h"
#include "sample_cases.h"

namespace ncrev {
namespace {

using brep_detail::RegionSurface;
using brep_detail::SurfaceBrep;
using brep_detail::SurfaceBrepOptions;

double volume(const SurfaceBrep& b) {
    GProp_GProps p;
    BRepGProp::VolumeProperties(b.shape, p);
    return p.Mass();
}

// The region surfaces of a segmentation (every region must have one).
std::vector<RegionSurface> region_surfaces(const SegmentResult& sr) {
    std::vector<RegionSurface> surfaces(sr.regions.size());
    for (std::size_t r = 0; r < sr.regions.size(); ++r) {
        const Region& g = sr.regions[r];
        surfaces[r].surface = g.fit.surface;
        surfaces[r].has_surface = g.fit.ok && g.within_tolerance;
        if (!surfaces[r].has_surface) surfaces[r].no_surface_reason = "none fits";
    }
    return surfaces;
}

// The B-rep built keeping what later rounds leave alone, and solving everything each round.
struct Builds {
    SurfaceBrep kept, fresh;
};

Builds build_both(const Mesh& mesh, const SegmentResult& sr,
                  const std::vector<RegionSurface>& surfaces) {
    SurfaceBrepOptions o;
    o.tolerance = sr.tolerance;
    o.chordal_deflection = std::max(sr.chordal_deflection, sr.tolerance);
    o.mesh_deflection = 0.5 * o.chordal_deflection;
    Builds b;
    b.kept = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    o.reuse_geometry = false;
    b.fresh = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    return b;
}

// Both give the same B-rep: faces, edges by curve, corners, fallbacks, volume.
void expect_same(const Builds& b, const char* what) {
    const SurfaceBrep &kept = b.kept, &fresh = b.fresh;
    EXPECT_TRUE(kept.valid && kept.solid) << what << ": " << kept.problem;
    EXPECT_EQ(kept.valid, fresh.valid) << what;
    EXPECT_EQ(kept.rounds, fresh.rounds) << what;
    EXPECT_EQ(kept.intersection_edges, fresh.intersection_edges) << what;
    EXPECT_EQ(kept.analytic_edges, fresh.analytic_edges) << what;
    EXPECT_EQ(kept.tangency_edges, fresh.tangency_edges) << what;
    EXPECT_EQ(kept.fitted_edges, fresh.fitted_edges) << what;
    EXPECT_EQ(kept.polyline_edges, fresh.polyline_edges) << what;
    EXPECT_EQ(kept.corners, fresh.corners) << what;
    EXPECT_EQ(kept.tangent_corners, fresh.tangent_corners) << what;
    ASSERT_EQ(kept.regions.size(), fresh.regions.size()) << what;
    for (std::size_t r = 0; r < kept.regions.size(); ++r) {
        EXPECT_EQ(kept.regions[r].fallback, fresh.regions[r].fallback) << what << " region " << r;
        EXPECT_EQ(kept.regions[r].faces.size(), fresh.regions[r].faces.size())
            << what << " region " << r;
    }
    EXPECT_NEAR(volume(kept), volume(fresh), 1e-9 * volume(fresh)) << what;
}

// The drilled plate's smallest side wall is given a plane parallel to the plate's largest face
// instead of its own: it meets that face and the one opposite nowhere near their chains, so it
// becomes facets and the B-rep is built again. The second round keeps every corner and curve
// the change leaves alone, and must give what solving everything again gives.
TEST(SurfaceBrep, LaterRoundsKeepWhatTheirChangeLeavesAlone) {
    const SamplePart part = test::sample_case("drilled_plate", test::kFine);
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    std::vector<RegionSurface> surfaces = region_surfaces(sr);
    std::size_t largest = 0;
    for (std::size_t r = 0; r < sr.regions.size(); ++r) {
        ASSERT_TRUE(surfaces[r].has_surface) << "region " << r;
        if (sr.regions[r].fit.surface.kind == FitKind::kPlane &&
            sr.regions[r].area > sr.regions[largest].area) {
            largest = r;
        }
    }
    const Vec3 up = sr.regions[largest].fit.surface.axis;
    std::size_t wall = sr.regions.size();
    for (std::size_t r = 0; r < sr.regions.size(); ++r) {
        const Surface& s = sr.regions[r].fit.surface;
        if (s.kind != FitKind::kPlane || std::abs(dot(s.axis, up)) > 1e-6) continue;
        if (wall == sr.regions.size() || sr.regions[r].facets < sr.regions[wall].facets) wall = r;
    }
    ASSERT_LT(wall, sr.regions.size()) << "no side wall";
    surfaces[wall].surface.axis = up;

    const Builds b = build_both(mesh, sr, surfaces);
    expect_same(b, "drilled_plate");
    EXPECT_GE(b.fresh.rounds, 2);
    for (std::size_t r = 0; r < b.kept.regions.size(); ++r) {
        EXPECT_EQ(b.kept.regions[r].fallback, r == wall) << "region " << r;
    }
    // The first round solves every corner (and closed chain's start) and makes every chain's
    // curve; the second only the wall's four corners (now solved without its surface), and no
    // curve (the wall's chains are its mesh edges now).
    const RegionBorders borders = region_borders(mesh, sr.region);
    EXPECT_EQ(b.kept.curves_made, borders.chains.size());
    EXPECT_GT(b.fresh.curves_made, borders.chains.size());
    EXPECT_EQ(b.kept.corners_solved,
              b.fresh.corners_solved / static_cast<std::uint64_t>(b.fresh.rounds) + 4);
}

// A real part whose first shell fails the check (the M8 screw's thread flanks: B-splines whose
// edges with their neighbours do not close it): its faces are built in two rounds, and the
// faces of the second made from the same as in the first are not checked again.
TEST(SurfaceBrep, FacesMadeFromTheSameAreNotCheckedAgain) {
    const std::filesystem::path path = test::corpus_step_dir() / "occt_screw.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus at " << path;
    SampleOptions so;
    so.relative_deflection = 1e-3;
    const SamplePart part = sample_from_step(path, so).value();
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    const Builds b = build_both(mesh, sr, region_surfaces(sr));
    expect_same(b, "occt_screw");
    EXPECT_GE(b.fresh.rounds, 2);
    EXPECT_LT(b.kept.faces_checked, b.fresh.faces_checked);
    EXPECT_LT(b.kept.curves_made, b.fresh.curves_made);
}

}  // namespace
}  // namespace ncrev
