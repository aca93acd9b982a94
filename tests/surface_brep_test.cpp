// The exact B-rep's build rounds (an internal module: src/brep).
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <BRepGProp.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Geom_BSplineCurve.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "brep/check.h"
#include "brep/surfaces.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"
#include "ncrev/segment.h"
#include "sample_cases.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

using brep_detail::RegionSurface;
using brep_detail::SurfaceBrep;
using brep_detail::SurfaceBrepOptions;

double volume(const SurfaceBrep& b) { return brep_detail::solid_volume(b.shape); }

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

// A region absorbed by its neighbour after its face failed changes the borders and the labels:
// the chains, corners and faces away from it are kept under their new indices, not made again.
// What was kept gives the B-rep solving everything again gives; and less than half of what
// solving again makes after the first round is made. The case: the fillet-and-chamfer block
// meshed at 2 um, 0.05 rad (36k facets, three rounds). Its segmentation had two regions that
// failed and were absorbed until merging left stray facets to their neighbours; now the row of
// a plane's facets along a fillet is given a region of its own, on a plane parallel to it a few
// tolerances outside: that meets the plane nowhere, its face fails, and the plane, whose chords
// its facets are, absorbs it.
Mesh fillet_block_36k() {
    SampleOptions so;
    so.with_step = false;
    so.deflection = 0.002;
    so.angular_deflection = 0.05;
    const SamplePart part = make_sample_part("fillet_chamfer_block", so).value();
    return build_mesh(part.mesh).value().mesh;
}

TEST(SurfaceBrep, AnAbsorbedRegionKeepsTheGeometryAwayFromIt) {
    const Mesh mesh = fillet_block_36k();
    SegmentResult sr = segment(mesh).value();
    // The largest plane beside a cylinder, and its facets along the first such cylinder.
    const auto kind = [&](std::int32_t r) {
        return sr.regions[static_cast<std::size_t>(r)].fit.surface.kind;
    };
    const auto beside = [&](FaceId f, std::int32_t want) {  // its neighbour across a cylinder
        for (int i = 0; i < 3; ++i) {
            const HalfedgeId t = mesh.twin(Mesh::halfedge(f, i));
            if (!t.is_valid()) continue;
            const std::int32_t q = sr.region[Mesh::face(t)];
            if (kind(q) == FitKind::kCylinder && (want < 0 || q == want)) return q;
        }
        return std::int32_t{-1};
    };
    std::int32_t plane = -1;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const std::int32_t r = sr.region[ff];
        if (kind(r) != FitKind::kPlane || beside(ff, -1) < 0) continue;
        if (plane < 0 || sr.regions[static_cast<std::size_t>(r)].area >
                             sr.regions[static_cast<std::size_t>(plane)].area) {
            plane = r;
        }
    }
    ASSERT_GE(plane, 0);
    std::int32_t fillet = -1;
    std::vector<FaceId> row;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        if (sr.region[ff] != plane) continue;
        const std::int32_t q = beside(ff, fillet);
        if (q < 0) continue;
        fillet = q;
        row.push_back(ff);
    }
    ASSERT_GT(row.size(), 2u);
    Region strip = sr.regions[static_cast<std::size_t>(plane)];
    strip.id = static_cast<std::int32_t>(sr.regions.size());
    Vec3 out = strip.fit.surface.axis;
    if (dot(out, mesh.face_normal(row.front())) < 0) out = -1.0 * out;
    strip.fit.surface.point = strip.fit.surface.point + 4 * sr.tolerance * out;
    for (const FaceId f : row) sr.region[f] = strip.id;
    sr.regions.push_back(strip);

    const Builds b = build_both(mesh, sr, region_surfaces(sr));
    expect_same(b, "fillet_chamfer_block");
    std::size_t absorbed = 0;
    for (const auto& r : b.kept.regions) absorbed += r.absorbed_into >= 0;
    ASSERT_GE(absorbed, 1u) << "the case no longer absorbs a region";
    ASSERT_GE(b.fresh.rounds, 2);
    const auto rounds = static_cast<std::uint64_t>(b.fresh.rounds);
    const std::uint64_t chains = region_borders(mesh, sr.region).chains.size();
    EXPECT_LT(b.kept.curves_made, chains + (b.fresh.curves_made - chains) / 2);
    const std::uint64_t corners = b.fresh.corners_solved / rounds;
    EXPECT_LT(b.kept.corners_solved, corners + (b.fresh.corners_solved - corners) / 2);
}

// Chains' curves and new faces' checks run in parallel; the B-rep is the same on one thread
// (the fillet block above, as segmented: faces failing, three rounds).
TEST(SurfaceBrep, SameBRepWhateverTheThreadCount) {
    const Mesh mesh = fillet_block_36k();
    const SegmentResult sr = segment(mesh).value();
    SurfaceBrepOptions o;
    o.tolerance = sr.tolerance;
    o.chordal_deflection = std::max(sr.chordal_deflection, sr.tolerance);
    o.mesh_deflection = 0.5 * o.chordal_deflection;
    Builds b;
    b.kept = brep_detail::build_surface_brep(mesh, sr.region, region_surfaces(sr), o);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        b.fresh = brep_detail::build_surface_brep(mesh, sr.region, region_surfaces(sr), o);
    }
    expect_same(b, "fillet_chamfer_block, one thread");
    EXPECT_EQ(b.kept.curves_made, b.fresh.curves_made);
    EXPECT_EQ(b.kept.faces_checked, b.fresh.faces_checked);
    EXPECT_EQ(volume(b.kept), volume(b.fresh));
}

// A real part whose first shell fails the check (the screw's thread flanks: B-splines whose
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

// A prism whose curved side is a linear extrusion of a B-spline profile (as fit_bspline() makes
// for a spline pocket wall), closed by a flat wall, floor and top; meshed exactly on its
// surfaces. The flat wall's plane is y = flat_y (the profile's ends lie on y = 0).
struct ExtrusionPrism {
    static constexpr double kHeight = 12;
    std::shared_ptr<BSplineSurface> wall = std::make_shared<BSplineSurface>();
    Mesh mesh;
    std::vector<RegionSurface> surfaces;
    FaceMap<std::int32_t> region;
};

ExtrusionPrism extrusion_prism(double flat_y) {
    constexpr double kHeight = ExtrusionPrism::kHeight;
    ExtrusionPrism out;
    BSplineSurface& wall = *out.wall;
    wall.extruded = true;
    // The profile leaves y = 0 square at both ends.
    const std::vector<Vec3> profile{{-20, 0, 0}, {-20, 15, 0}, {-5, 25, 0},
                                    {5, 22, 0},  {20, 15, 0},  {20, 0, 0}};
    wall.num_u = static_cast<int>(profile.size());
    wall.num_v = 4;
    for (int j = 0; j < 4; ++j)
        for (const Vec3& p : profile) {
            // Past the floor and the top (an extrusion spans its points, not the planes'):
            // the planes cross it inside, not along its boundary rows.
            wall.poles.push_back(p + Vec3{0, 0, -3 + (kHeight + 6) * j / 3.0});
        }
    TriangleSoup soup;
    constexpr int kAlong = 60;
    for (int k = 0; k <= kAlong; ++k) {
        Vec3 p = wall.evaluate(static_cast<double>(k) / kAlong, 0);
        p.z = 0;
        soup.points.push_back(p);
        soup.points.push_back(p + Vec3{0, 0, kHeight});
    }
    const auto bottom = [](int k) { return static_cast<std::uint32_t>(2 * k); };
    const auto top = [](int k) { return static_cast<std::uint32_t>(2 * k + 1); };
    // The profile runs clockwise seen from above: outward is to the left of its direction.
    for (int k = 0; k < kAlong; ++k) {
        soup.triangles.push_back({bottom(k), top(k), top(k + 1)});
        soup.triangles.push_back({bottom(k), top(k + 1), bottom(k + 1)});
    }
    soup.triangles.push_back({bottom(kAlong), top(kAlong), top(0)});  // the flat wall, y = 0
    soup.triangles.push_back({bottom(kAlong), top(0), bottom(0)});
    const auto centre = static_cast<std::uint32_t>(soup.points.size());
    soup.points.push_back({0, 10, 0});
    soup.points.push_back({0, 10, kHeight});
    for (int k = 0; k <= kAlong; ++k) {
        const int n = (k + 1) % (kAlong + 1);
        soup.triangles.push_back({centre, bottom(k), bottom(n)});
        soup.triangles.push_back({centre + 1, top(n), top(k)});
    }
    out.mesh = build_mesh(soup).value().mesh;
    out.surfaces.resize(4);
    for (RegionSurface& r : out.surfaces) r.has_surface = true;
    out.surfaces[0].surface.kind = FitKind::kBSpline;
    out.surfaces[0].surface.bspline = out.wall;
    out.surfaces[1].surface.point = {0, flat_y, 0};  // planes: the flat wall, the floor, the top
    out.surfaces[1].surface.axis = {0, -1, 0};
    out.surfaces[2].surface.point = {0, 0, 0};
    out.surfaces[2].surface.axis = {0, 0, -1};
    out.surfaces[3].surface.point = {0, 0, kHeight};
    out.surfaces[3].surface.axis = {0, 0, 1};
    out.region = FaceMap<std::int32_t>(out.mesh.num_faces(), 0);
    for (std::uint32_t f = 0; f < out.mesh.num_faces(); ++f) {
        const Vec3 n = out.mesh.face_normal(FaceId(f));
        out.region[FaceId(f)] = n.z > 0.9 ? 3 : n.z < -0.9 ? 2 : n.y < -0.999 ? 1 : 0;
    }
    return out;
}

// The prism's B-rep: valid, no fallback; returns its edges that are the profile moved onto the
// floor or the top (a cubic of the profile's poles, on the wall and the plane to rounding).
int profile_edges(const ExtrusionPrism& p) {
    SurfaceBrepOptions o;
    o.tolerance = 0.005;
    o.chordal_deflection = 0.05;  // the side's chords sag ~0.01 mm
    const SurfaceBrep b = brep_detail::build_surface_brep(p.mesh, p.region, p.surfaces, o);
    EXPECT_TRUE(b.valid && b.solid) << b.problem;
    for (const auto& r : b.regions) EXPECT_FALSE(r.fallback) << r.reason;
    int profiles = 0;
    TopTools_IndexedMapOfShape edges;
    TopExp::MapShapes(b.shape, TopAbs_EDGE, edges);
    for (int i = 1; i <= edges.Extent(); ++i) {
        double t0 = 0, t1 = 0;
        const auto c =
            Handle(Geom_BSplineCurve)::DownCast(BRep_Tool::Curve(TopoDS::Edge(edges(i)), t0, t1));
        if (c.IsNull() || c->NbPoles() != p.wall->num_u) continue;
        ++profiles;
        EXPECT_EQ(c->Degree(), 3);
        for (int k = 0; k <= 20; ++k) {
            const gp_Pnt q = c->Value(t0 + (t1 - t0) * k / 20);
            const Vec3 v{q.X(), q.Y(), q.Z()};
            EXPECT_LT(distance(p.surfaces[0].surface, v), 1e-9);
            EXPECT_LT(std::min(std::abs(v.z), std::abs(v.z - ExtrusionPrism::kHeight)), 1e-9);
        }
    }
    return profiles;
}

// Where the floor and the top cross the extrusion, the edge is the profile itself moved onto
// the plane — not OpenCASCADE's general intersection (degree 8, hundreds of poles, within its
// approximation).
TEST(SurfaceBrep, PlaneMeetsAnExtrusionAlongItsProfile) {
    const ExtrusionPrism p = extrusion_prism(0);
    EXPECT_EQ(profile_edges(p), 2);
}

// The flat wall's plane a little outside the profile's ends (within the tolerance, as a fitted
// plane may lie): the corners are solved just past the ends of the profile, where they have no
// normal projection onto it, and their nearest one mid-way made the edge look doubled back — it
// was fitted to the chain instead. The ends are candidates too: still the profile.
TEST(SurfaceBrep, CornersJustPastACurvesEndTrimItAtTheEnd) {
    const ExtrusionPrism p = extrusion_prism(-0.004);
    EXPECT_EQ(profile_edges(p), 2);
}

// A fallback region whose face bounded by its mesh edges fails on its own surface comes back as
// one face on a B-spline fitted to it, not as its facets. FTC 07's five were corner caps fitted
// with a torus whose tube circle is nearly on its axis, the cap over the torus's tip, where no
// face on the torus closes (NotClosed): 123 facet faces. Here the spherical pocket's cap is
// given such a torus (tube circle 0.1 tolerance from the axis through the cap, within the
// tolerance of the sphere): its exact face and its mesh-edge face fail the same way.
TEST(SurfaceBrep, AFallbackFaceThatFailsOnItsSurfaceGoesOnABSpline) {
    const SamplePart part = test::sample_case("spherical_pocket", test::kFine);
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    std::vector<RegionSurface> surfaces = region_surfaces(sr);
    std::size_t cap = sr.regions.size();
    for (std::size_t r = 0; r < sr.regions.size(); ++r) {
        if (sr.regions[r].fit.surface.kind == FitKind::kSphere &&
            (cap == sr.regions.size() || sr.regions[r].facets > sr.regions[cap].facets))
            cap = r;
    }
    ASSERT_LT(cap, sr.regions.size());
    SurfaceBrepOptions o;
    o.tolerance = sr.tolerance;
    o.chordal_deflection = std::max(sr.chordal_deflection, sr.tolerance);
    const SurfaceBrep exact = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    ASSERT_TRUE(exact.valid && exact.solid) << exact.problem;

    Vec3 centroid{};
    double area = 0;
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        if (sr.region[FaceId(f)] != static_cast<std::int32_t>(cap)) continue;
        const double a = mesh.face_area(FaceId(f));
        for (int i = 0; i < 3; ++i) centroid += (a / 3) * mesh.position(mesh.vertex(FaceId(f), i));
        area += a;
    }
    const Surface sphere = sr.regions[cap].fit.surface;
    Surface& torus = surfaces[cap].surface;
    torus.kind = FitKind::kTorus;
    torus.axis = normalized(centroid / area - sphere.point);
    torus.radius = 0.1 * sr.tolerance;
    torus.minor_radius = sphere.radius;
    const SurfaceBrep b = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    EXPECT_TRUE(b.valid && b.solid) << b.problem;
    const auto& g = b.regions[cap];
    EXPECT_TRUE(g.fallback);
    EXPECT_TRUE(g.mesh_edges) << g.reason;
    EXPECT_TRUE(g.spline);
    EXPECT_EQ(g.faces.size(), 1u);  // not its 1200 facets
    EXPECT_NEAR(volume(b), volume(exact), 1e-4 * volume(exact));
}

// A valid solid can still not be the part: a face built over the wrong piece of its surface (a
// torus that took a cone strip of the M6 screw once made a valid solid 41 % short of the mesh's
// volume, corpus study, thirteenth session). A closed sphere has no edges to hold its face to
// the mesh: given a sphere 30 % wider than its facets, the B-rep is a valid solid, its volume is
// off by more than the mesh's chordal error allows, and the region whose faces lie farthest from
// the mesh is the sphere. Built from its facets, the volume is the part's again.
TEST(SurfaceBrep, ASolidOfTheWrongVolumeIsFoundAndItsFaceLocated) {
    const Mesh mesh = build_mesh(test::to_bucket(test::icosphere(10.0, 4))).value().mesh;
    const MeshStats stats = compute_stats(mesh);
    const SegmentResult sr = segment(mesh).value();
    ASSERT_EQ(sr.regions.size(), 1u);
    std::vector<RegionSurface> surfaces = region_surfaces(sr);
    ASSERT_EQ(surfaces[0].surface.kind, FitKind::kSphere);
    SurfaceBrepOptions o;
    o.tolerance = sr.tolerance;
    o.chordal_deflection = std::max(sr.chordal_deflection, sr.tolerance);
    const double deflection = 0.5 * o.chordal_deflection;
    const auto is_the_parts = [&](const SurfaceBrep& b) {
        return brep_detail::volume_is_the_parts(volume(b), stats.volume, stats.area, stats.area,
                                                o.chordal_deflection, o.tolerance);
    };
    const SurfaceBrep exact = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    ASSERT_TRUE(exact.valid && exact.solid) << exact.problem;
    EXPECT_TRUE(is_the_parts(exact)) << volume(exact) << " against " << stats.volume;

    surfaces[0].surface.radius *= 1.3;
    const SurfaceBrep wrong = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    ASSERT_TRUE(wrong.valid && wrong.solid) << wrong.problem;
    EXPECT_FALSE(wrong.regions[0].fallback) << wrong.regions[0].reason;
    EXPECT_FALSE(is_the_parts(wrong)) << volume(wrong) << " against " << stats.volume;
    std::vector<std::string> facets_only(surfaces.size());
    EXPECT_EQ(brep_detail::farthest_region(mesh, wrong, facets_only, deflection), 0);

    o.facets_only = facets_only;
    o.facets_only[0] = "its face lies the farthest from the mesh";
    const SurfaceBrep fixed = brep_detail::build_surface_brep(mesh, sr.region, surfaces, o);
    ASSERT_TRUE(fixed.valid && fixed.solid) << fixed.problem;
    EXPECT_TRUE(fixed.regions[0].fallback);
    EXPECT_TRUE(is_the_parts(fixed)) << volume(fixed) << " against " << stats.volume;
    // A region built from its facets is not named again.
    EXPECT_EQ(brep_detail::farthest_region(mesh, fixed, o.facets_only, deflection), -1);
}
}  // namespace
}  // namespace ncrev
