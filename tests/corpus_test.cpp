// Real meshes of machined parts from ../shared/corpus (public, see its SOURCES.md): every one
// must read and heal into one closed, outward, manifold body. Skipped when the corpus is not
// beside the checkout.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>

#include "ncrev/brep.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"
#include "ncrev/report.h"
#include "ncrev/segment.h"
#include "scratch.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

std::filesystem::path corpus_stl_dir() {
    return std::filesystem::path(NCREV_SOURCE_DIR) / ".." / "shared" / "corpus" / "stl";
}

TEST(Corpus, EveryStlHealsIntoOneClosedOutwardBody) {
    const auto dir = corpus_stl_dir();
    if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no corpus at " << dir;
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        if (entry.path().extension() != ".stl") continue;
        ++files;
        auto r = inspect_file(entry.path());
        ASSERT_TRUE(r.ok()) << r.error().describe();
        const auto& m = r->mesh;
        SCOPED_TRACE(entry.path().filename().string());
        EXPECT_TRUE(m.closed);
        EXPECT_EQ(m.components, 1u);
        EXPECT_GT(m.volume, 0);
        EXPECT_EQ(r->heal.nonmanifold_edges, 0u);
        EXPECT_EQ(r->heal.flipped_facets, 0u);
        EXPECT_EQ(r->heal.components_turned_outward, 0u);
        EXPECT_EQ(r->heal.degenerate_facets_removed, 0u);
        // χ = 2 − 2g: even, at most 2.
        EXPECT_LE(m.euler_characteristic, 2);
        EXPECT_EQ(m.euler_characteristic % 2, 0);
    }
    EXPECT_GE(files, 10u);
}

TEST(Corpus, NistFtc08MatchesItsDocumentedCountsAndVolume) {
    const auto path = corpus_stl_dir() / "nist_ftc_08_asme1_ap242-e1-tg.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    auto r = inspect_file(path);
    ASSERT_TRUE(r.ok()) << r.error().describe();
    // SOURCES.md: closed and manifold, 3368 triangles, 1636 vertices, 503 281 mm³.
    EXPECT_EQ(r->mesh.faces, 3368u);
    EXPECT_EQ(r->mesh.vertices, 1636u);
    EXPECT_NEAR(r->mesh.volume, 503281.0, 1.0);
}

TEST(Corpus, TrimeshFilesWithDuplicatedVerticesCloseOnlyAfterTheToleranceWeld) {
    const auto path = corpus_stl_dir() / "trimesh_featuretype.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    HealOptions exact;
    exact.weld_tolerance = 0;
    exact.fill_holes = false;  // else its cracks are filled with slivers instead of welded
    auto open = inspect_file(path, exact);
    ASSERT_TRUE(open.ok());
    EXPECT_FALSE(open->mesh.closed);
    auto healed = inspect_file(path);
    ASSERT_TRUE(healed.ok());
    EXPECT_TRUE(healed->mesh.closed);
    EXPECT_GT(healed->heal.welded_vertices, 0u);
    EXPECT_EQ(healed->heal.holes_filled, 0u);  // the weld closed it
    EXPECT_EQ(healed->heal.facets_split_at_t_junctions, 0u);
}

// OCCT's TR12J housing is meshed coarsely: a bore of radius 5 is an octagonal prism and its end
// cap an octagon in six triangles, whose four ear triangles have their corners on the bore and
// their middles within twice the chordal deflection. Dissolving the cap (six facets, a small
// region) gave the ears to the bore across its sharp rim, and the two triangles left of the cap
// had no edge with it: 20 such caps, 20 fallbacks in `reverse`. No facet of a cylinder region
// may face along its axis, unless it is narrower than the deflection (a sliver's normal says
// nothing). The whole part: 27k facets, segmented in about 4 s.
TEST(Corpus, CoarseBoreCapsStayOffTheBore) {
    const auto path = corpus_stl_dir() / "occt_TR12J_OCC.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Mesh mesh = build_mesh(read_mesh_file(path).value()).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    std::size_t cylinders = 0, facing_along = 0;
    for (const Region& r : sr.regions) cylinders += r.fit.surface.kind == FitKind::kCylinder;
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        const Region& r = sr.regions[static_cast<std::size_t>(sr.region[FaceId(f)])];
        if (r.fit.surface.kind != FitKind::kCylinder) continue;
        const Vec3 n2 = mesh.face_normal_area2(FaceId(f));
        double longest = 0;
        for (int i = 0; i < 3; ++i) {
            longest = std::max(longest, norm(mesh.position(mesh.vertex(FaceId(f), (i + 1) % 3)) -
                                             mesh.position(mesh.vertex(FaceId(f), i))));
        }
        if (norm(n2) / longest <= sr.chordal_deflection) continue;  // a sliver
        const double along = std::abs(dot(n2, normalized(r.fit.surface.axis))) / norm(n2);
        facing_along += along > std::cos(std::numbers::pi / 4);
    }
    EXPECT_GE(cylinders, 100u);
    EXPECT_EQ(facing_along, 0u);
}

// NIST FTC 08 as a CAD system tessellated it (AP242, 3368 facets; labels.csv gives each
// triangle's true face): its fillets, 3.048 mm in radius, come in six slivers from rim to rim,
// every vertex on the cylinder. Each sliver was a plane of its own: a lone facet's next ring
// takes in the neighbouring faces' facets too, and no surface fits them all. Growing now takes
// the facets parallel to the seed's long edge one at a time while a cylinder or cone takes them
// along its generators (108 -> 113 of 159 cylindrical faces whole, 406 -> 381 regions).
// Short fillets come as fans, their rims divided unevenly: few facets have a generator for an
// edge and neighbours turn by up to 45 degrees, so growing stopped at their sharp edges and
// pairwise merging never joins one-facet planes into a cylinder (four facets make the six
// vertices it needs). merge_fans() grows a cylinder or cone through them: 167 -> 25 one-facet
// regions, 113 -> 135 cylindrical faces whole, 375 -> 254 regions (262 before fans of three
// facets, five vertices, were fitted too).
TEST(Corpus, CoarseFilletStripsAreCylinders) {
    const auto path = corpus_stl_dir() / "nist_ftc_08_asme1_ap242-e1-tg.stl";
    const auto labels = corpus_stl_dir() / "nist_ftc_08_asme1_ap242-e1-tg.labels.csv";
    if (!std::filesystem::exists(path) || !std::filesystem::exists(labels))
        GTEST_SKIP() << "no corpus file " << path;
    const TriangleSoup soup = read_mesh_file(path).value();
    const std::size_t facets = soup.triangles.size();
    const Mesh mesh = build_mesh(soup).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    const std::vector<std::int32_t> region = input_labels(mesh, sr, facets);
    // triangle,face_index,step_face_id,surface_type
    std::ifstream in(labels);
    std::string line;
    std::getline(in, line);
    std::map<std::string, std::set<std::int32_t>> regions_of;      // cylindrical true faces
    std::map<std::string, std::set<std::int32_t>> regions_of_any;  // every true face
    std::map<std::int32_t, std::set<std::string>> faces_of;        // every region
    while (std::getline(in, line)) {
        std::stringstream row(line);
        std::string triangle, face, id, type;
        std::getline(row, triangle, ',');
        std::getline(row, face, ',');
        std::getline(row, id, ',');
        std::getline(row, type, ',');
        const std::int32_t r = region.at(std::stoul(triangle));
        regions_of_any[face].insert(r);
        faces_of[r].insert(face);
        if (type == "CYLINDRICAL_SURFACE") regions_of[face].insert(r);
    }
    ASSERT_EQ(regions_of.size(), 159u);
    // Face for face: true faces that are one region which is theirs alone (148 before fans), and
    // regions over several true faces (43 before; most are the file's cylinder halves).
    std::size_t one_to_one = 0, joined = 0;
    for (const auto& [face, rs] : regions_of_any)
        one_to_one += rs.size() == 1 && faces_of.at(*rs.begin()).size() == 1;
    for (const auto& [r, fs] : faces_of) joined += fs.size() > 1;
    EXPECT_GE(one_to_one, 171u);
    EXPECT_LE(joined, 44u);
    std::size_t whole = 0;
    for (const auto& [face, rs] : regions_of) {
        if (rs.size() != 1 || *rs.begin() < 0) continue;
        const Surface& s = sr.regions[static_cast<std::size_t>(*rs.begin())].fit.surface;
        whole += s.kind == FitKind::kCylinder;
    }
    EXPECT_GE(whole, 135u);
    EXPECT_LE(sr.regions.size(), 254u);
    std::size_t lone = 0;
    for (const Region& g : sr.regions) lone += g.facets == 1;
    EXPECT_LE(lone, 25u);
    // True face 15: a fillet 3.4 mm long in a fan of six facets (triangles 1231-1236), its rims
    // in three steps each, offset; inside it edges turn by 7-35 degrees.
    const std::set<std::int32_t>& fan = regions_of.at("15");
    ASSERT_EQ(fan.size(), 1u);
    ASSERT_GE(*fan.begin(), 0);
    const Region& fan_region = sr.regions[static_cast<std::size_t>(*fan.begin())];
    EXPECT_EQ(fan_region.facets, 6u);
    EXPECT_EQ(fan_region.fit.surface.kind, FitKind::kCylinder);
    EXPECT_NEAR(fan_region.fit.surface.radius, 3.175, 0.01);
    // Fillets 42 mm long in three slivers each: five vertices, a cylinder all the same.
    for (const char* three : {"180", "181", "187"}) {
        const std::set<std::int32_t>& rs = regions_of.at(three);
        ASSERT_EQ(rs.size(), 1u) << "true face " << three;
        ASSERT_GE(*rs.begin(), 0);
        const Region& g = sr.regions[static_cast<std::size_t>(*rs.begin())];
        EXPECT_EQ(g.facets, 3u) << "true face " << three;
        EXPECT_EQ(g.fit.surface.kind, FitKind::kCylinder) << "true face " << three;
        EXPECT_NEAR(g.fit.surface.radius, 3.048, 0.01) << "true face " << three;
    }
    // True face 6: a fillet 151 mm long in six slivers (triangles 1163-1168).
    const std::set<std::int32_t>& six = regions_of.at("6");
    ASSERT_EQ(six.size(), 1u);
    const Surface& fillet = sr.regions[static_cast<std::size_t>(*six.begin())].fit.surface;
    EXPECT_EQ(fillet.kind, FitKind::kCylinder);
    EXPECT_NEAR(fillet.radius, 3.048, 0.01);
}

// A part turned out of its axes is the same part. The default tolerance followed the bounding
// box's diagonal, which grows as a part turns: this mesh turned by 0.7 rad about (1, 2, 3) had a
// tolerance 1.38 times its own and came out in 247 regions for 254 (its reversed solid in 246
// faces for 254, a fallback more). Now it follows the part's size (part_size(): its smallest
// box with an axis along a direction its largest facets face), and the turned mesh segments
// into as many regions of the same kinds, the same facets in each but for a facet or two that
// rounding puts on the other side of a border.
TEST(Corpus, ATurnedMeshSegmentsAsInItsAxes) {
    const auto path = corpus_stl_dir() / "nist_ftc_08_asme1_ap242-e1-tg.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const TriangleSoup soup = read_mesh_file(path).value();
    TriangleSoup turned = soup;
    test::rigid_motion(turned, 0.7, {40, -25, 10});
    const Mesh mesh = build_mesh(soup).value().mesh;
    const Mesh moved = build_mesh(turned).value().mesh;
    const double tol = default_segment_tolerance(mesh);
    EXPECT_NEAR(default_segment_tolerance(moved), tol, 1e-9 * tol);
    const SegmentResult a = segment(mesh).value();
    const SegmentResult b = segment(moved).value();
    const auto kinds = [](const SegmentResult& r) {
        std::map<FitKind, std::size_t> n;
        for (const Region& g : r.regions) ++n[g.fit.surface.kind];
        return n;
    };
    EXPECT_EQ(b.regions.size(), a.regions.size());
    EXPECT_EQ(kinds(b), kinds(a));
    // Region for region: the facets of each region of one lie in one region of the other,
    // each its own, but for the facets outside its share.
    std::map<std::pair<std::int32_t, std::int32_t>, std::size_t> pairs;
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f)
        ++pairs[{a.region[FaceId(f)], b.region[FaceId(f)]}];
    std::map<std::int32_t, std::pair<std::size_t, std::int32_t>> share;  // most facets, where
    for (const auto& [ab, n] : pairs) {
        auto& best = share[ab.first];
        if (n > best.first) best = {n, ab.second};
    }
    std::size_t kept = 0;
    std::set<std::int32_t> images;
    for (const auto& [r, best] : share) {
        kept += best.first;
        images.insert(best.second);
    }
    EXPECT_EQ(images.size(), a.regions.size());
    EXPECT_LE(mesh.num_faces() - kept, 2u);
}

/// `mesh` reversed (method auto) into a temporary STEP named after `stem`, removed after.
ReverseReport reversed(const Mesh& mesh, const std::string& stem) {
    const auto out = test::scratch_dir() / ("ncrev_" + stem + ".step");
    ReverseReport r = reverse_to_step(mesh, out).value();
    std::filesystem::remove(out);
    return r;
}

// OCCT's TR12J housing meshed coarsely (27k facets, deflection 0.79 mm): a 156-facet B-spline
// region's net, fitted to its vertices, swung 1.4 mm off the middle of a 15 mm border edge (1.7
// mm at three eighths of it) whose ends it held within 0.02 mm, and its two plane neighbours,
// tangent to it there, found no edge curve within the deflection: both fell back. The B-rep's
// refit fits such a net again with its facets' and border edges' middles as guides
// (FitInput::guides): 7 -> 5 fallbacks, none for want of an edge with a B-spline.
TEST(Corpus, ACoarseNetHoldsItsBorderEdgesBetweenTheirEnds) {
    const auto path = corpus_stl_dir() / "occt_TR12J_OCC.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Mesh mesh = build_mesh(read_mesh_file(path).value()).value().mesh;
    const ReverseReport r = reversed(mesh, "tr12j");
    EXPECT_TRUE(r.solid && r.valid && r.written);
    ASSERT_TRUE(r.segmentation.has_value());
    const std::string no_edge = "no edge curve with region ";
    for (const ReverseFallback& f : r.fallbacks) {
        if (!f.reason.starts_with(no_edge)) continue;
        const auto other = static_cast<std::size_t>(std::stoi(f.reason.substr(no_edge.size())));
        ASSERT_LT(other, r.segmentation->regions.size());
        EXPECT_NE(r.segmentation->regions[other].fit.surface.kind, FitKind::kBSpline)
            << "region " << f.region << ": " << f.reason;
    }
    EXPECT_LE(r.fallbacks.size(), 5u);
}

// trimesh's idler riser (1572 facets, inches): the wall round its boss is a ring of slivers
// from rim to rim, one plane each (143 of them, 172 faces in all). The ring is one extruded
// strip, but no one B-spline takes a closed ring: its row of pieces is now tried in halves
// until one fits each run. 28 faces, none fallen back, its deviations as before (0.38 δ); 27
// since the chord fits (two of its B-splines are spheres).
TEST(Corpus, ARingOfSliversBecomesAFewExtrudedFaces) {
    const auto path = corpus_stl_dir() / "trimesh_idler_riser.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Mesh mesh = build_mesh(read_mesh_file(path).value()).value().mesh;
    const ReverseReport r = reversed(mesh, "idler_riser");
    EXPECT_TRUE(r.solid && r.valid && r.written);
    EXPECT_LE(r.faces, 30u);
    EXPECT_TRUE(r.fallbacks.empty());
    EXPECT_TRUE(r.faces_by_kind.contains("bspline"));
    ASSERT_TRUE(r.deviation.has_value());
    EXPECT_LE(r.deviation->mesh_to_solid.max, r.chordal_deflection);
}

// trimesh's angle block (704 facets, inches) was made by booleans on faceted solids: the rim
// of its slanted bore (radius 0.25, 36 sides) has its vertices on the cutting solid's facets,
// up to 8e-4 in inside the bore, four times the tolerance (2.1e-4) though well within the
// mesh's sag (2e-3). No analytic kind took the bore within the tolerance; it was a B-spline
// whose face self-intersected and came back as 95 facets (121 faces, 2 fallbacks). A cylinder
// that holds the vertices as closely as that B-spline is the region's surface instead
// (analytic_instead(), docs/segmentation.md): 26 faces, all planes and cylinders.
TEST(Corpus, ABooleanMadeBoreIsOneCylinder) {
    const auto path = corpus_stl_dir() / "trimesh_angle_block.stl";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Mesh mesh = build_mesh(read_mesh_file(path).value()).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    std::size_t bores = 0;
    for (const Region& g : sr.regions) {
        const Surface& s = g.fit.surface;
        if (s.kind != FitKind::kCylinder || std::abs(s.radius - 0.25) > 0.002) continue;
        ++bores;
        EXPECT_GE(g.facets, 100u);
        EXPECT_TRUE(g.within_tolerance);
    }
    EXPECT_EQ(bores, 1u);
    const ReverseReport r = reversed(mesh, "angle_block");
    EXPECT_TRUE(r.solid && r.valid && r.written);
    EXPECT_LE(r.faces, 26u);
    EXPECT_TRUE(r.fallbacks.empty());
    EXPECT_FALSE(r.faces_by_kind.contains("bspline"));
    EXPECT_FALSE(r.faces_by_kind.contains("facet"));
    ASSERT_TRUE(r.deviation.has_value());
    EXPECT_LE(r.deviation->mesh_to_solid.max, r.chordal_deflection);
    EXPECT_LE(r.deviation->solid_to_mesh.max, r.chordal_deflection);
}

}  // namespace
}  // namespace ncrev
