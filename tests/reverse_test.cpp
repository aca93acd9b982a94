// Issue 8: the exact B-rep (reverse --method auto|surfaces) on every sample part, fine and
// coarse, from STL and from SRE, and on real STEP parts; each STEP read back with OpenCASCADE.
// Targets (issue 8): valid closed solids; face count = truth on >= 90 % from STL and on every
// part from SRE; volume within 0.1 % of the exact solid's; max deviation from the mesh <= 2 x
// the mesh's chordal deflection; no fallback on parts made of planes to tori only.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <ShapeUpgrade_UnifySameDomain.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <gp_Pnt.hxx>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "analytic_shapes.h"
#include "ncrev/brep.h"
#include "ncrev/fit.h"
#include "ncrev/io.h"
#include "ncrev/report.h"
#include "ncrev/sample.h"
#include "ncrev/segment.h"
#include "sample_cases.h"
#include "scratch.h"
#include "step_readback.h"

namespace ncrev {
namespace {

const std::filesystem::path& out_dir() { return test::scratch_dir(); }

using test::corpus_step_dir;
using test::corpus_steps;
using test::kCoarse;
using test::kFine;

struct Outcome {
    ReverseReport report;
    test::ReadBack back;
    std::size_t true_faces = 0;
    /// The exact solid's faces once faces of one surface that meet along an edge are one
    /// (ShapeUpgrade_UnifySameDomain): CAD systems split bores and cones into half faces, a
    /// split no mesh shows. 0 when the part came without its STEP text.
    std::size_t unified_faces = 0;
    /// Likewise by geometry (faces_on_one_surface()): also the halves of a sphere or torus a
    /// CAD system wrote as two B-spline faces. 0 when the part came without its STEP text.
    std::size_t one_surface_faces = 0;
    std::map<std::string, std::size_t> true_kinds;  ///< the exact solid's faces by kind
    double true_volume = 0;
    double deflection = 0;  ///< the chordal deflection the mesh was made with
    bool analytic_only = true;
    double seconds = 0;
    std::string step_text;
    MeshStats mesh;  ///< of the healed mesh
    HealReport heal;
};

/// How far, in units of the chordal deflection δ, the nodes of two exact faces' triangulations
/// may lie from one fitted surface for the two faces to count as one. The nodes lie on the exact
/// surfaces but for the nodes of shared edges, which lie on the edge curve, within the STEP
/// file's edge tolerance of both faces (0.0166 mm, 0.014 δ, on CTC 02's split bores). A mesh
/// made at δ cannot show two surfaces within a tenth of δ of each other apart.
constexpr double kSameSurface = 0.1;

/// The exact solid's faces once every two that meet along an edge and lie on one plane, sphere,
/// cylinder, cone or torus are one. ShapeUpgrade_UnifySameDomain compares the faces' surface
/// records; this compares geometry: the nodes of both faces (the mesh's vertices, labelled by
/// their true face in `mesh.cuts()`) are fitted as one surface and must stay within
/// kSameSurface x `deflection` of it. So it also joins a sphere or torus a CAD system exported
/// as two B-spline halves (827-9999-904), which no mesh can tell apart either. Pairs of faces
/// of two different elementary kinds are not tried; a face of an elementary kind is tried
/// against its own kind only.
std::size_t faces_on_one_surface(const Mesh& mesh, std::span<const SampleFace> faces,
                                 double deflection) {
    const auto cuts = mesh.cuts();
    std::map<std::int64_t, std::size_t> index;  // true face -> dense index
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) index.emplace(cuts[f], 0);
    std::vector<std::string> kind;  // by dense index
    for (auto& [t, i] : index) {
        i = kind.size();
        const bool known = t >= 0 && static_cast<std::size_t>(t) < faces.size();
        kind.push_back(known ? faces[static_cast<std::size_t>(t)].kind : "other");
    }
    const std::size_t n = kind.size();
    std::vector<std::size_t> dense(mesh.num_faces());  // facet -> its true face's index
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) dense[f] = index[cuts[f]];
    // Each true face's vertices, with normals from its own facets only.
    std::vector<std::map<std::uint32_t, Vec3>> nodes(n);
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const Vec3 an = mesh.face_normal_area2(ff);
        for (int k = 0; k < 3; ++k) nodes[dense[f]][mesh.vertex(ff, k).idx()] += an;
    }
    const std::map<std::string, FitKind> elementary = {{"plane", FitKind::kPlane},
                                                       {"sphere", FitKind::kSphere},
                                                       {"cylinder", FitKind::kCylinder},
                                                       {"cone", FitKind::kCone},
                                                       {"torus", FitKind::kTorus}};
    std::set<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t h = 0; h < mesh.num_halfedges(); ++h) {
        const HalfedgeId hh(static_cast<std::uint32_t>(h));
        if (mesh.is_boundary(hh)) continue;
        const std::size_t a = dense[h / 3], b = dense[mesh.twin(hh).idx() / 3];
        if (a < b) pairs.emplace(a, b);
    }
    std::vector<std::size_t> parent(n);
    for (std::size_t i = 0; i < n; ++i) parent[i] = i;
    const auto root = [&](std::size_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    std::size_t count = n;
    for (const auto& [a, b] : pairs) {
        if (root(a) == root(b)) continue;
        const auto ea = elementary.find(kind[a]), eb = elementary.find(kind[b]);
        FitKindSet kinds = kRevolutionFitKinds;
        if (ea != elementary.end() && eb != elementary.end() && ea->second != eb->second) continue;
        if (ea != elementary.end()) kinds = fit_kind_bit(ea->second);
        if (eb != elementary.end()) kinds = fit_kind_bit(eb->second);
        std::vector<Vec3> points, normals;
        for (const std::size_t i : {a, b}) {
            for (const auto& [v, an] : nodes[i]) {
                points.push_back(mesh.position(VertexId(v)));
                normals.push_back(normalized(an));
            }
        }
        FitInput in;
        in.points = points;
        in.normals = normals;
        const double tol = kSameSurface * deflection;
        const KindSelection sel = fit_simplest(in, tol, kinds);
        if (!sel.best.ok || sel.best.max > tol) continue;
        parent[root(a)] = root(b);
        --count;
    }
    return count;
}

/// What an STL carries of a sample's mesh: the triangles only.
TriangleSoup as_stl(TriangleSoup soup) {
    soup.format = InputFormat::kStlBinary;
    soup.color.clear();
    soup.cut.clear();
    soup.surface.clear();
    soup.surfaces.clear();
    soup.tools.clear();
    return soup;
}

/// The sample part (or STEP file's solid) tessellated, healed, reversed, written and read back.
Outcome reverse_part(const SamplePart& part, bool sre, ReverseMethod method,
                     const std::string& tag) {
    Outcome o;
    o.true_faces = part.faces.size();
    if (!part.step.empty()) {
        const auto exact = out_dir() / (tag + ".exact.step");
        { std::ofstream(exact, std::ios::binary) << part.step; }
        const test::ReadBack rb = test::read_step(exact);
        std::filesystem::remove(exact);
        ShapeUpgrade_UnifySameDomain unify(rb.shape, true, true, false);
        unify.Build();
        for (TopExp_Explorer x(unify.Shape(), TopAbs_FACE); x.More(); x.Next()) ++o.unified_faces;
        const Result<BuildResult> labelled = build_mesh(part.mesh);  // with each facet's face
        EXPECT_TRUE(labelled.ok());
        if (labelled.ok() && labelled->mesh.cuts().size() == labelled->mesh.num_faces()) {
            o.one_surface_faces = faces_on_one_surface(labelled->mesh, part.faces, part.deflection);
        }
    }
    o.true_volume = part.solid.volume;
    o.deflection = part.deflection;
    for (const SampleFace& f : part.faces) {
        if (f.surface < 0) o.analytic_only = false;
        ++o.true_kinds[f.kind];
    }
    TriangleSoup soup = sre ? part.mesh : as_stl(part.mesh);
    if (sre) soup.format = InputFormat::kSre;
    Result<BuildResult> built = build_mesh(std::move(soup));
    EXPECT_TRUE(built.ok());
    o.mesh = compute_stats(built->mesh);
    o.heal = built->heal;
    ReverseOptions ro;
    ro.method = method;
    ro.segment.surfaces = part.mesh.surfaces;
    ro.segment.use_surface_indices = sre;
    const auto path = out_dir() / (tag + ".step");
    Result<ReverseReport> rev = reverse_to_step(built->mesh, path, ro);
    EXPECT_TRUE(rev.ok()) << tag;
    if (!rev.ok()) return o;
    o.report = std::move(rev).value();
    for (const auto& [stage, s] : o.report.stage_seconds) o.seconds += s;
    if (o.report.written) {
        o.back = test::read_step(path);
        std::ifstream in(path);
        o.step_text.assign(std::istreambuf_iterator<char>(in), {});
    }
    std::filesystem::remove(path);
    return o;
}

SamplePart make(std::string_view name, double relative) {
    return test::sample_case(name, relative);
}

void expect_solid(const Outcome& o, const std::string& tag) {
    EXPECT_TRUE(o.report.written) << tag;
    EXPECT_TRUE(o.report.solid && o.report.valid) << tag;
    EXPECT_TRUE(o.back.valid) << tag << ": read back invalid";
    EXPECT_EQ(o.back.solids, 1u) << tag;
    EXPECT_EQ(o.back.faces, o.report.faces) << tag;
}

// The issue's volume and deviation targets: the solid's volume within 0.1 % of the original's,
// the mesh and the solid within 2 chordal deflections of each other both ways.
void expect_near_the_part(const Outcome& o, const std::string& tag) {
    EXPECT_NEAR(o.report.solid_volume, o.true_volume, 1e-3 * o.true_volume) << tag;
    ASSERT_TRUE(o.report.deviation.has_value()) << tag;
    EXPECT_LE(o.report.deviation->mesh_to_solid.max, 2 * o.deflection) << tag;
    EXPECT_LE(o.report.deviation->solid_to_mesh.max, 2 * o.deflection) << tag;
}

// A valid closed solid with no fallback, within the volume and deviation targets.
void expect_exact(const Outcome& o, const std::string& tag) {
    expect_solid(o, tag);
    for (const ReverseFallback& f : o.report.fallbacks) ADD_FAILURE() << tag << ": " << f.reason;
    expect_near_the_part(o, tag);
}

TEST(ReverseSurfaces, EverySamplePartFromStlFineAndCoarse) {
    int cases = 0, count_right = 0;
    for (const SamplePartInfo& info : sample_parts()) {
        for (const double d : {kFine, kCoarse}) {
            const std::string tag =
                std::string(info.name) + (d == kFine ? "_fine" : "_coarse") + "_stl";
            const Outcome o = reverse_part(make(info.name, d), false, ReverseMethod::kAuto, tag);
            ++cases;
            expect_solid(o, tag);
            if (o.report.faces == o.true_faces) ++count_right;
            EXPECT_NEAR(o.report.solid_volume, o.true_volume, 1e-3 * o.true_volume) << tag;
            EXPECT_NEAR(o.back.volume, o.report.solid_volume, 1e-5 * o.true_volume) << tag;
            ASSERT_TRUE(o.report.deviation.has_value()) << tag;
            EXPECT_LE(o.report.deviation->mesh_to_solid.max, 2 * o.deflection) << tag;
            EXPECT_LE(o.report.deviation->solid_to_mesh.max, 2 * o.deflection) << tag;
            // Every face can be triangulated (viewers, FE meshers), so the deviation saw it.
            EXPECT_EQ(o.report.deviation->faces_without_triangles, 0u) << tag;
            if (o.analytic_only) {
                EXPECT_TRUE(o.report.fallbacks.empty())
                    << tag << ": " << o.report.fallbacks.front().reason;
            }
            // Colors, one per kind (no tool colors in an STL).
            EXPECT_NE(o.step_text.find("COLOUR_RGB"), std::string::npos) << tag;
        }
    }
    EXPECT_GE(count_right, (9 * cases + 9) / 10) << count_right << " of " << cases;
}

TEST(ReverseSurfaces, EverySamplePartFromSreHasItsTrueFaces) {
    for (const SamplePartInfo& info : sample_parts()) {
        const std::string tag = std::string(info.name) + "_sre";
        const Outcome o = reverse_part(make(info.name, kFine), true, ReverseMethod::kSurfaces, tag);
        expect_solid(o, tag);
        EXPECT_EQ(o.report.faces, o.true_faces) << tag;
        EXPECT_NEAR(o.report.solid_volume, o.true_volume, 1e-3 * o.true_volume) << tag;
        EXPECT_TRUE(o.report.fallbacks.empty()) << tag;
    }
}

// The kinds of the faces come back: the pocket block's 15 planes, 8 cylinders, 4 tori.
TEST(ReverseSurfaces, FacesHaveTheirTrueKinds) {
    const Outcome o = reverse_part(make("pocket_block", kFine), false, ReverseMethod::kSurfaces,
                                   "pocket_block_kinds");
    expect_solid(o, "pocket_block");
    const std::map<std::string, std::uint64_t> want{{"plane", 15}, {"cylinder", 8}, {"torus", 4}};
    EXPECT_EQ(o.report.faces_by_kind, want);
    EXPECT_EQ(o.report.edges_by_curve.at("polyline"), 0u);
    EXPECT_GT(o.report.edges_by_curve.at("intersection"), 0u);
    EXPECT_LE(std::abs(o.report.volume_difference), 1e-3);
}

// A shape's edges (not degenerated) and, of them, those whose curve is not a line, circle or
// ellipse.
std::pair<std::size_t, std::size_t> edges_and_splines(const TopoDS_Shape& shape) {
    TopTools_IndexedMapOfShape all;
    TopExp::MapShapes(shape, TopAbs_EDGE, all);
    std::size_t edges = 0, splines = 0;
    for (int i = 1; i <= all.Extent(); ++i) {
        const TopoDS_Edge& e = TopoDS::Edge(all(i));
        if (BRep_Tool::Degenerated(e)) continue;
        ++edges;
        const GeomAbs_CurveType type = BRepAdaptor_Curve(e).GetType();
        if (type != GeomAbs_Line && type != GeomAbs_Circle && type != GeomAbs_Ellipse) ++splines;
    }
    return {edges, splines};
}

// Fillets meet their neighbours where the tube's spine has its foot on them: the pocket
// block's 8 corner cylinders and 4 floor tori are tangent to the walls and the floor, and those
// junctions get curves through the exact contact points, close to both surfaces.
TEST(ReverseSurfaces, FilletJunctionsFollowTheExactContact) {
    const Outcome o = reverse_part(make("pocket_block", kFine), false, ReverseMethod::kSurfaces,
                                   "pocket_block_tangency");
    expect_solid(o, "pocket_block");
    EXPECT_GE(o.report.edges_by_curve.at("tangency"), 16u);
    EXPECT_LE(o.report.max_tolerance, o.report.chordal_deflection);
    // Where the contact is a line or circle (a corner cylinder along a wall, a floor torus on
    // the floor and round its corner cylinder), the edge is that line or circle in the STEP,
    // not a B-spline through the contact points; so is a junction of two corners only. Of
    // the block's 60 edges 32 were B-splines; 4 are left: the corner cylinders' junctions
    // with the floor tori, whose contact points lie up to a tolerance off any circle, and
    // whose edges are fitted to points on both surfaces.
    const auto [edges, splines] = edges_and_splines(o.back.shape);
    EXPECT_GT(edges, 0u);
    EXPECT_LE(splines, 4u) << "of " << edges << " edges";
    // The report counts them with the exact intersections.
    EXPECT_GT(o.report.edges_by_curve.at("analytic"), o.report.edges_by_curve.at("intersection"));
}

// The same on a finely meshed part (the fillet block at 1e-5 of its diagonal, about 48k
// facets), whose borders zigzag across the fillets' contact lines: the contact points step
// back and forth along a line or circle, and that line or circle is still the edge. Of the
// block's 56 edges about 40 were B-splines; 6 are (8 while a point that stepped back made the
// line or circle look doubled back; the bound leaves one junction's slack).
TEST(ReverseSurfaces, FinelyMeshedFilletJunctionsAreLinesAndCircles) {
    const Outcome o = reverse_part(make("fillet_chamfer_block", 1e-5), false, ReverseMethod::kAuto,
                                   "fillet_block_fine_edges");
    expect_solid(o, "fillet_chamfer_block");
    EXPECT_GT(o.mesh.faces, 40000u);
    EXPECT_EQ(o.report.faces, o.true_faces);
    const auto [edges, splines] = edges_and_splines(o.back.shape);
    EXPECT_GT(edges, 0u);
    EXPECT_LE(splines, 7u) << "of " << edges << " edges";
    EXPECT_TRUE(o.report.fallbacks.empty());
}

// SRE tool colors are written as the faces' colors.
TEST(ReverseSurfaces, SreToolColorsBecomeFaceColors) {
    const SamplePart part = make("slot_plate", kFine);
    const Outcome o = reverse_part(part, true, ReverseMethod::kAuto, "slot_colors");
    ASSERT_TRUE(o.report.written);
    ASSERT_FALSE(part.mesh.tools.empty());
    // Read back with XDE: every face has a color, and each is one of the tools' colors.
    const auto path_colors = out_dir() / "slot_colors_read.step";
    {
        Result<BuildResult> b = build_mesh(TriangleSoup(part.mesh));
        ASSERT_TRUE(b.ok());
        ReverseOptions ro;
        ro.segment.surfaces = part.mesh.surfaces;
        ASSERT_TRUE(reverse_to_step(b->mesh, path_colors, ro).ok());
    }
    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    STEPCAFControl_Reader reader;
    reader.SetColorMode(true);
    ASSERT_EQ(reader.ReadFile(path_colors.c_str()), IFSelect_RetDone);
    ASSERT_TRUE(reader.Transfer(doc));
    const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    const Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(doc->Main());
    TDF_LabelSequence roots;
    shapes->GetFreeShapes(roots);
    ASSERT_EQ(roots.Length(), 1);
    const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(roots.Value(1));
    std::set<std::uint32_t> tool_colors;
    for (const ToolRecord& t : part.mesh.tools) {
        tool_colors.insert(static_cast<std::uint32_t>(t.color & 0xFFFFFF));
    }
    std::size_t faces = 0, colored = 0;
    for (TopExp_Explorer x(shape, TopAbs_FACE); x.More(); x.Next()) {
        ++faces;
        Quantity_Color c;
        if (!colors->GetColor(x.Current(), XCAFDoc_ColorSurf, c)) continue;
        ++colored;
        double r = 0, g = 0, b = 0;
        c.Values(r, g, b, Quantity_TOC_sRGB);
        const auto byte = [](double v) { return static_cast<std::uint32_t>(std::lround(v * 255)); };
        const std::uint32_t rgb = (byte(r) << 16) | (byte(g) << 8) | byte(b);
        EXPECT_TRUE(tool_colors.count(rgb)) << std::hex << rgb;
    }
    EXPECT_EQ(faces, o.report.faces);
    EXPECT_EQ(colored, faces);
    // Without colors: plain geometry.
    Result<BuildResult> built = build_mesh(TriangleSoup(part.mesh));
    ASSERT_TRUE(built.ok());
    ReverseOptions ro;
    ro.colors = false;
    ro.segment.surfaces = part.mesh.surfaces;
    const auto path = out_dir() / "plain.step";
    ASSERT_TRUE(reverse_to_step(built->mesh, path, ro).ok());
    std::ifstream in(path);
    const std::string text(std::istreambuf_iterator<char>(in), {});
    EXPECT_EQ(text.find("COLOUR_RGB"), std::string::npos);
}

// --method surfaces refuses an open mesh (nothing written); auto builds it as planar faces.
// The opening is a whole true face (its facets gone): an opening, not a hole healing fills.
TEST(ReverseSurfaces, OpenMeshIsPlanarInAutoAndNothingInSurfaces) {
    SamplePart part = make("slot_plate", kFine);
    const std::int64_t face = part.mesh.cut.front();
    TriangleSoup open = as_stl(part.mesh);
    open.triangles.clear();
    for (std::size_t k = 0; k < part.mesh.triangles.size(); ++k) {
        if (part.mesh.cut[k] != face) open.triangles.push_back(part.mesh.triangles[k]);
    }
    Result<BuildResult> built = build_mesh(std::move(open));
    ASSERT_TRUE(built.ok());
    EXPECT_EQ(built->heal.holes_filled, 0u);
    ReverseOptions ro;
    ro.method = ReverseMethod::kSurfaces;
    const auto path = out_dir() / "open_surfaces.step";
    Result<ReverseReport> s = reverse_to_step(built->mesh, path, ro);
    ASSERT_TRUE(s.ok());
    EXPECT_FALSE(s->written);
    EXPECT_FALSE(std::filesystem::exists(path));
    ro.method = ReverseMethod::kAuto;
    Result<ReverseReport> a = reverse_to_step(built->mesh, path, ro);
    ASSERT_TRUE(a.ok());
    EXPECT_TRUE(a->written);
    EXPECT_FALSE(a->solid);
}

// A part whose file lost facets, here and there, comes back as if it had them: the holes are
// filled while healing, and the faces, their kinds and the volume are the whole part's.
TEST(ReverseSurfaces, MissingFacetsAreFilledAndThePartIsWhole) {
    const SamplePart part = make("slot_plate", kFine);
    const Outcome whole = reverse_part(part, false, ReverseMethod::kAuto, "holes_reference");
    TriangleSoup holed = as_stl(part.mesh);
    // Every 37th facet but those sharing a point with one already gone: missing facets apart
    // from each other (on its planes, bores and slot walls), each a hole of three edges. Two
    // large planar facets gone side by side would be an opening (docs/healing.md 8).
    std::size_t gone = 0;
    std::vector<std::uint8_t> near(holed.points.size(), 0);
    std::vector<std::array<std::uint32_t, 3>> kept;
    for (std::size_t k = 0; k < holed.triangles.size(); ++k) {
        const auto& t = holed.triangles[k];
        // Points are shared by position here (the sample's indexed mesh).
        if (k % 37 == 0 && !near[t[0]] && !near[t[1]] && !near[t[2]]) {
            near[t[0]] = near[t[1]] = near[t[2]] = 1;
            ++gone;
            continue;
        }
        kept.push_back(t);
    }
    holed.triangles = std::move(kept);
    ASSERT_GE(gone, 4u);
    Result<BuildResult> built = build_mesh(std::move(holed));
    ASSERT_TRUE(built.ok());
    EXPECT_EQ(built->heal.hole_facets_added, gone);
    EXPECT_TRUE(compute_stats(built->mesh).closed);
    const auto path = out_dir() / "holes_filled.step";
    Result<ReverseReport> r = reverse_to_step(built->mesh, path, ReverseOptions{});
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->written && r->solid && r->valid);
    EXPECT_TRUE(r->fallbacks.empty());
    EXPECT_EQ(r->faces, whole.report.faces);
    EXPECT_EQ(r->faces_by_kind, whole.report.faces_by_kind);
    const test::ReadBack back = test::read_step(path);
    EXPECT_TRUE(back.valid);
    EXPECT_NEAR(back.volume, part.solid.volume, 1e-3 * part.solid.volume);
    std::filesystem::remove(path);
}

// A closed part with stray open pieces beside it (a loose facet, a scrap of a sheet, as exports
// and repairs leave them): auto and surfaces build the part and leave the open pieces out, with
// a warning, their facets labelled -1. Until the forty-fourth session the whole mesh, being
// open, went planar as a surface model. An open part with a small closed piece stays planar.
TEST(ReverseSurfaces, StrayOpenPiecesAreLeftOutOfTheSolid) {
    const SamplePart part = make("slot_plate", kFine);
    Box3 box;
    for (const Vec3& p : part.mesh.points) box.add(p);
    const double size = box.diagonal();
    TriangleSoup soup = part.mesh;
    const auto add = [&](Vec3 a, Vec3 b, Vec3 c) {
        const auto base = static_cast<std::uint32_t>(soup.points.size());
        soup.points.insert(soup.points.end(), {a, b, c});
        soup.triangles.push_back({base, base + 1, base + 2});
        if (!soup.color.empty()) {
            soup.color.push_back(soup.color.back());
            soup.cut.push_back(soup.cut.back());
            soup.surface.push_back(soup.surface.back());
        }
    };
    // A loose facet and a two-facet scrap, a part's length away.
    const Vec3 o = box.max + Vec3{size, 0, 0};
    const double s = 0.05 * size;
    add(o, o + Vec3{s, 0, 0}, o + Vec3{0, s, 0});
    add(o + Vec3{0, 0, s}, o + Vec3{s, 0, s}, o + Vec3{s, s, s});
    add(o + Vec3{0, 0, s}, o + Vec3{s, s, s}, o + Vec3{0, s, s});
    const std::size_t stray = 3;
    const Outcome whole = reverse_part(part, false, ReverseMethod::kAuto, "stray_reference");
    for (const ReverseMethod method : {ReverseMethod::kAuto, ReverseMethod::kSurfaces}) {
        const std::string tag = method == ReverseMethod::kAuto ? "stray_auto" : "stray_surfaces";
        Result<BuildResult> built = build_mesh(as_stl(soup));
        ASSERT_TRUE(built.ok());
        const auto path = out_dir() / (tag + ".step");
        ReverseOptions ro;
        ro.method = method;
        ro.require_solid = true;
        Result<ReverseReport> r = reverse_to_step(built->mesh, path, ro);
        ASSERT_TRUE(r.ok()) << tag;
        EXPECT_TRUE(r->written && r->solid && r->valid) << tag;
        EXPECT_EQ(r->left_out_facets, stray) << tag;
        EXPECT_EQ(r->faces, whole.report.faces) << tag;
        EXPECT_EQ(r->faces_by_kind, whole.report.faces_by_kind) << tag;
        EXPECT_DOUBLE_EQ(r->mesh_volume, whole.report.mesh_volume) << tag;
        ASSERT_FALSE(r->warnings.empty());
        EXPECT_NE(r->warnings.front().find("left out"), std::string::npos) << r->warnings.front();
        const test::ReadBack back = test::read_step(path);
        EXPECT_TRUE(back.valid) << tag;
        EXPECT_EQ(back.solids, 1u) << tag;
        EXPECT_NEAR(back.volume, part.solid.volume, 1e-3 * part.solid.volume) << tag;
        // Labels in input order: the part's facets have regions, the stray ones none.
        ASSERT_TRUE(r->segmentation.has_value());
        const std::vector<std::int32_t> labels =
            input_labels(built->mesh, *r->segmentation, soup.triangles.size());
        for (std::size_t i = 0; i < labels.size(); ++i) {
            if (i < part.mesh.triangles.size()) {
                EXPECT_GE(labels[i], 0) << tag << " facet " << i;
            } else {
                EXPECT_EQ(labels[i], -1) << tag << " facet " << i;
            }
        }
        std::filesystem::remove(path);
    }
    // Mostly open: the part with most of its facets gone, beside a closed cube. Planar as a
    // whole (shells), and nothing with require_solid.
    TriangleSoup open = as_stl(part.mesh);
    open.triangles.resize(open.triangles.size() / 2);
    {
        const auto base = static_cast<std::uint32_t>(open.points.size());
        const double c = 0.01 * size;
        for (int k = 0; k < 8; ++k)
            open.points.push_back(o + Vec3{k & 1 ? c : 0, k & 2 ? c : 0, k & 4 ? c : 0});
        for (const auto& q : std::array<std::array<std::uint32_t, 4>, 6>{{{0, 2, 3, 1},
                                                                          {4, 5, 7, 6},
                                                                          {0, 1, 5, 4},
                                                                          {2, 6, 7, 3},
                                                                          {0, 4, 6, 2},
                                                                          {1, 3, 7, 5}}}) {
            open.triangles.push_back({base + q[0], base + q[1], base + q[2]});
            open.triangles.push_back({base + q[0], base + q[2], base + q[3]});
        }
    }
    Result<BuildResult> built = build_mesh(std::move(open));
    ASSERT_TRUE(built.ok());
    const auto path = out_dir() / "mostly_open.step";
    ReverseOptions ro;
    Result<ReverseReport> r = reverse_to_step(built->mesh, path, ro);
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->written);
    EXPECT_FALSE(r->solid);
    EXPECT_EQ(r->left_out_facets, 0u);
    std::filesystem::remove(path);
    ro.require_solid = true;
    r = reverse_to_step(built->mesh, path, ro);
    ASSERT_TRUE(r.ok());
    EXPECT_FALSE(r->written);
    EXPECT_FALSE(std::filesystem::exists(path));
}

// Same mesh, same STEP, whatever the run and the thread count.
TEST(ReverseSurfaces, Deterministic) {
    const SamplePart part = make("fillet_chamfer_block", kFine);
    const Outcome a = reverse_part(part, false, ReverseMethod::kAuto, "det_a");
    const Outcome b = reverse_part(part, false, ReverseMethod::kAuto, "det_b");
    ASSERT_FALSE(a.step_text.empty());
    EXPECT_EQ(a.step_text, b.step_text);
    const Outcome one = [&] {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        return reverse_part(part, false, ReverseMethod::kAuto, "det_one");
    }();
    EXPECT_EQ(a.step_text, one.step_text);
}

// The fillet block's rolling-ball corners in `o` (see the test below): each within twice the
// tolerance of a vertex.
void expect_rolling_ball_corners(const Outcome& o, const std::string& tag) {
    std::vector<gp_Pnt> vertices;
    for (TopExp_Explorer x(o.back.shape, TopAbs_VERTEX); x.More(); x.Next()) {
        vertices.push_back(BRep_Tool::Pnt(TopoDS::Vertex(x.Current())));
    }
    ASSERT_FALSE(vertices.empty()) << tag;
    ASSERT_TRUE(o.report.segmentation.has_value()) << tag;
    const double tolerance = o.report.segmentation->tolerance;
    const double length = 80, width = 60, height = 40, rv = 10, rt = 4;
    std::vector<gp_Pnt> junctions;
    for (const double x : {0.0, length}) {
        for (const double y : {0.0, width}) {
            const double sx = x == 0 ? 1 : -1, sy = y == 0 ? 1 : -1;
            // On the top face: where each edge fillet's tangent line meets the torus's circle.
            junctions.emplace_back(x + sx * rt, y + sy * rv, height);
            junctions.emplace_back(x + sx * rv, y + sy * rt, height);
            // On the side walls, a fillet's radius below the top.
            junctions.emplace_back(x, y + sy * rv, height - rt);
            junctions.emplace_back(x + sx * rv, y, height - rt);
        }
    }
    for (const gp_Pnt& j : junctions) {
        double nearest = 1e300;
        for (const gp_Pnt& v : vertices) nearest = std::min(nearest, v.Distance(j));
        EXPECT_LE(nearest, 2 * tolerance) << tag << ": " << j.X() << " " << j.Y() << " " << j.Z();
    }
}

// The fillet block's top edges are rounded by 4 mm and its vertical ones by 10 mm: at each top
// corner a torus (spine radius 6, tube 4) runs into the two edge fillets, each a cylinder of
// the same radius whose axis touches the torus's spine circle. The corners where a fillet,
// its torus and the face they both run along meet are where those spines touch: on the top
// face (4, 10, 40), (10, 4, 40), ... and on the side walls (0, 10, 36), (10, 0, 36), ...
// Solved onto the three surfaces, which are tangent to each other there, such a corner slid
// along the contact: (4, 10, 40) stayed 1.04 mm off, about where the mesh's region borders met,
// and the volume was 1e-5 off. spine_junction() puts it where the spines touch, within the
// tolerance: two corners, on the fillet fitted 0.02 mm thin (its region reaches into the tori
// as far as they stay within the tolerance of it), are 0.011-0.012 mm off, the others 1e-3.
TEST(ReverseSurfaces, RollingBallCornersAreWhereTheSpinesTouch) {
    const SamplePart part = make("fillet_chamfer_block", kFine);
    const Outcome o = reverse_part(part, false, ReverseMethod::kAuto, "rolling_ball");
    expect_solid(o, "rolling_ball");
    expect_rolling_ball_corners(o, "rolling_ball");
    EXPECT_LE(std::abs(o.back.volume - o.true_volume), 1e-6 * o.true_volume);
}

// The sample part `name` meshed as `ncrev sample NAME --deflection D --angular A` meshes it
// (without its STEP text).
SamplePart finely_meshed(const char* name, double deflection, double angular) {
    SampleOptions so;
    so.with_step = false;
    so.deflection = deflection;
    so.angular_deflection = angular;
    Result<SamplePart> made = make_sample_part(name, so);
    EXPECT_TRUE(made.ok()) << name;
    return std::move(made).value();
}

// The fillet block meshed finely (0.0005 mm, 0.05 rad: 96 612 facets). Its fillets' regions
// grew across their tangent lines: each top fillet came as an exact piece and a cylinder
// between it and its neighbours (r 3.98 reaching 1.4 mm into the corner tori, or r 3.76 over a
// strip of the top face) at 345k facets, whose edges crossed near the corners (3 fallbacks).
// Border refinement now runs until nothing moves, and refits what it changed (docs/
// segmentation.md, "Refining borders"): 26 exact regions. The edge between a fillet and its
// corner torus is then the tube's section where their spines touch (tangency_points()), not the
// mesh's border anywhere in the band where they are within the tolerance (0.7 mm), and two
// corners solved to one point with a chain of a few mesh edges between them are one vertex.
// At this size its STL (from `ncrev sample`) came back 5.1e-4 off in volume before, 1.3e-5 with
// the refinement alone, as volumes were measured then (BRepGProp's default rule, before
// 60dd34f); here, measured adaptively, it is 1.6e-7 off.
TEST(ReverseSurfaces, AFinelyMeshedFilletBlockIsExact) {
    const SamplePart part = finely_meshed("fillet_chamfer_block", 0.0005, 0.05);
    const Outcome o = reverse_part(part, false, ReverseMethod::kAuto, "fine_block");
    expect_solid(o, "fine_block");
    EXPECT_TRUE(o.report.fallbacks.empty());
    EXPECT_EQ(o.report.faces, 26u);
    ASSERT_TRUE(o.report.segmentation.has_value());
    std::size_t cylinders = 0;
    for (const Region& g : o.report.segmentation->regions)
        cylinders += g.fit.surface.kind == FitKind::kCylinder;
    EXPECT_EQ(cylinders, 8u);  // 4 vertical fillets, 4 top ones: no compromise cylinder
    expect_rolling_ball_corners(o, "fine_block");
    EXPECT_LE(std::abs(o.back.volume - o.true_volume), 1e-5 * o.true_volume);
}

// The turned shaft meshed finely (0.0005 mm, 0.03 rad: 385 590 facets), read from its STL as a
// user would. Its shoulder fillet (a torus) touches the shoulder plane along a whole circle;
// the mesh's border there zigzags, and 6 of the 585 steps between its vertices' contact feet
// went back along the circle or repeated a foot. The periodic cubic through them looped: the
// plane's wire crossed itself and the torus's did not close (2 fallbacks). The feet are now taken
// in their order round the torus's axis (in_spine_order()).
TEST(ReverseSurfaces, AFinelyMeshedShaftsShoulderFilletIsExact) {
    SamplePart part = finely_meshed("turned_shaft", 0.0005, 0.03);
    const auto dir = out_dir() / "fine_shaft";
    Result<SampleFiles> files = write_sample_part(part, dir);
    ASSERT_TRUE(files.ok());
    Result<TriangleSoup> stl = read_mesh_file(files->stl);
    std::filesystem::remove_all(dir);
    ASSERT_TRUE(stl.ok());
    part.mesh = std::move(stl).value();
    const Outcome o = reverse_part(part, false, ReverseMethod::kAuto, "fine_shaft");
    expect_solid(o, "fine_shaft");
    EXPECT_TRUE(o.report.fallbacks.empty());
    EXPECT_EQ(o.report.faces, 17u);
    const auto tangency = o.report.edges_by_curve.find("tangency");
    EXPECT_TRUE(tangency != o.report.edges_by_curve.end() && tangency->second >= 1);
    EXPECT_LE(std::abs(o.back.volume - o.true_volume), 1e-5 * o.true_volume);
}

SamplePart corpus_part(const std::filesystem::path& path) {
    SampleOptions so;
    so.relative_deflection = 1e-3;  // issue 8: tessellated at 1e-3 x the part's size
    Result<SamplePart> made = sample_from_step(path, so);
    EXPECT_TRUE(made.ok()) << path;
    return std::move(made).value();
}

// Real parts: the MFCAD feature models, NIST CTC 03 and FTC 11 come back face for face, NIST
// FTC 09 (158 faces: planes, cylinders, cones; 125 once its half bores are unified: a mesh
// shows no such split) within one face of either, 827-9999-904 (117 faces; 99 unified by
// OpenCASCADE; 89 once its spheres and tori, each written as two B-spline halves, are one
// too: faces_on_one_surface()) within one of the last; each a valid closed solid.
TEST(ReverseSurfaces, RealPartsFaceForFace) {
    if (corpus_steps().empty()) GTEST_SKIP() << "no corpus at " << corpus_step_dir();
    for (const char* name :
         {"mfcad_2-3-3-3-3-23.step", "mfcad_4-5-6-13-19.step", "nist_ctc_03_asme1_rc.stp",
          "nist_ftc_09_asme1_rd.stp", "827-9999-904.stp",
          // Tori of 0.4 mm fillets round its pockets' corners: 146 faces until the spine
          // start (fitting.md), 144 now.
          "nist_ftc_06_asme1_rd.stp",
          // Bull-nose tori meshed with BRepMesh fans whose middles sag 1.3x the chordal
          // deflection: 6 faces, not 86 one-facet planes.
          "nist_ftc_11_asme1_rb.stp"}) {
        const Outcome o =
            reverse_part(corpus_part(corpus_step_dir() / name), false, ReverseMethod::kAuto, name);
        expect_solid(o, name);
        // Within one face of the original, or of the original with its split faces unified.
        const auto off = [&](std::size_t want) {
            return std::abs(static_cast<double>(o.report.faces) - static_cast<double>(want));
        };
        EXPECT_LE(std::min({off(o.true_faces), off(o.unified_faces), off(o.one_surface_faces)}),
                  1.0)
            << name << ": " << o.report.faces << " faces for " << o.true_faces << " ("
            << o.unified_faces << " unified, " << o.one_surface_faces << " on one surface)";
        EXPECT_TRUE(o.report.fallbacks.empty()) << name;
        EXPECT_NEAR(o.report.solid_volume, o.true_volume, 1e-3 * o.true_volume) << name;
        ASSERT_TRUE(o.report.deviation.has_value()) << name;
        EXPECT_EQ(o.report.deviation->faces_without_triangles, 0u) << name;
    }
}

// NIST CTC 05's two large fillets (tori of 6.35 mm along long arcs, meshed at 0.9 mm) are
// BRepMesh fans whose middles sag up to 3.5 x the deflection estimate, every corner on the
// torus: each facet is a chord of its torus (chord_fits()), not a one-facet plane. 183 faces
// and 5 fallbacks before; 157 now, for 162 unified and 156 on one surface.
TEST(ReverseSurfaces, CoarseFilletFansAreChords) {
    if (corpus_steps().empty()) GTEST_SKIP() << "no corpus at " << corpus_step_dir();
    const char* name = "nist_ctc_05_asme1_rd.stp";
    const Outcome o =
        reverse_part(corpus_part(corpus_step_dir() / name), false, ReverseMethod::kAuto, name);
    expect_solid(o, name);
    ASSERT_GT(o.one_surface_faces, 0u);
    EXPECT_LE(static_cast<double>(o.report.faces), 1.05 * static_cast<double>(o.one_surface_faces))
        << o.report.faces << " faces for " << o.one_surface_faces << " on one surface";
    EXPECT_LE(o.report.fallbacks.size(), 1u);
    expect_near_the_part(o, name);
}

// The NIST crada plate's lettering: walls along the letters' spline outlines, B-spline strips
// of 2-20 mm2 in 6-26 facets each, which the mesh (at 0.14 mm) shows as tangent cylinders of
// 0.4-3 mm radius. Two such cylinders (10 numbers) leave the cubic profile of an extrusion
// fitted to both 3 poles, so no group of them grew to the three pieces it takes to keep one:
// 180 faces for 150 on one surface (109 cylinders). A group too small to keep whose pieces are
// one wall's (merge_loose_pieces(): cylinders about one axis, planes along it) is held to the
// parameters of one that is: 153, with 18 B-splines.
TEST(ReverseSurfaces, LetteringWallsAreExtrusionsNotArcs) {
    const auto path = corpus_step_dir() / "nist_mtc_crada_plate.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "crada");
    expect_exact(o, "crada");
    ASSERT_GT(o.one_surface_faces, 0u);
    EXPECT_LE(static_cast<double>(o.report.faces), 1.05 * static_cast<double>(o.one_surface_faces))
        << o.report.faces << " faces for " << o.one_surface_faces << " on one surface";
    ASSERT_TRUE(o.report.deviation.has_value());
    EXPECT_EQ(o.report.deviation->faces_without_triangles, 0u);
}

// A region whose exact face cannot be built (no edge curve with a neighbour, a wire that
// crosses itself, a face that fails read back) comes back as one face on its own surface,
// bounded by the mesh edges of its border, not as its facets: the link rods' five (walls one
// facet tall between tangent free-form faces, see TangentJunctionsOfFittedPiecesHaveEdges).
// CTC 02's two were such faces until their tangent junctions took the curve midway between
// their surfaces (FinelyMeshedIllConditionedCornersAndTangentEdgesHoldTheMesh). (The occt_screw's
// thread flanks, 916 facets once, the cones of CTC 01 and CTC 05, and FTC 07's cylinder that
// BRepMesh could not triangulate and its tori were such faces; they build now, see
// ABandFaceThatFailsTakesItsOwnSeam and ACapRoundAConesApexGetsASeamAndADegeneratedEdge, and
// for FTC 07 the exact-surface refinement in docs/segmentation.md.) Those faces are within the
// chordal deflection like every other.
TEST(ReverseSurfaces, FallbackRegionsKeepTheirSurfaces) {
    const auto path = corpus_step_dir() / "occt_linkrods.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "linkrods");
    expect_solid(o, "linkrods");
    EXPECT_FALSE(o.report.fallbacks.empty()) << "nothing falls back any more";
    for (const ReverseFallback& f : o.report.fallbacks) {
        EXPECT_TRUE(f.mesh_edges) << "region " << f.region << " as facets";
    }
    EXPECT_EQ(o.report.faces_by_kind.count("facet"), 0u);
    expect_near_the_part(o, "linkrods");
    ASSERT_TRUE(o.report.deviation.has_value());
    EXPECT_EQ(o.report.deviation->faces_without_triangles, 0u);
}

// The occt_screw's countersunk head: a cone band round the axis whose top loop runs down and
// across the slot. ShapeFix_Face's seam on the ruling u = 0 dropped 6 of its 9 edges and the
// cone fell back (one face on mesh edges, the volume 0.062 % short). A band face that fails
// with the fix's seam is built again with its own (seamed_band()): no fallback, the volume
// within 0.001 % of the exact solid's.
TEST(ReverseSurfaces, ABandFaceThatFailsTakesItsOwnSeam) {
    const auto path = corpus_step_dir() / "occt_screw.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "screw");
    expect_exact(o, "screw");
    EXPECT_NEAR(o.report.solid_volume, o.true_volume, 1e-5 * o.true_volume);
}

// CTC 01's and CTC 05's drill points, cones cut across by a 2 mm slot: each region is a cap
// round its cone's apex, one loop going once round the axis. ShapeFix_Face left the wire open
// (BRepCheck_NotClosed) and the cone fell back. After that failure the face is built again
// with a seam up the ruling from the apex to a vertex of the loop and a degenerated edge at the
// apex (seamed_cap()): no fallback on either part, CTC 04 5 -> 3.
TEST(ReverseSurfaces, ACapRoundAConesApexGetsASeamAndADegeneratedEdge) {
    const auto path = corpus_step_dir() / "nist_ctc_01_asme1_rd.stp";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "ctc01");
    expect_exact(o, "ctc01");
    EXPECT_EQ(o.report.faces, o.true_faces);
}

// Where four surfaces meet, segmentation can leave two corners of three joined by a one-edge
// chain; solved onto their surfaces the two land 0.0001-0.04 mm apart on CTC 04 (deflection
// 0.94 mm), and an edge that short made the wires of both faces along it cross themselves: three
// of its fillets fell back. A chain whose solved ends are within the surfaces' tolerance of each
// other is now one vertex and no edge: no fallback.
TEST(ReverseSurfaces, CornersOfFourSurfacesAreOneVertex) {
    const auto path = corpus_step_dir() / "nist_ctc_04_asme1_rd.stp";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "ctc04");
    expect_exact(o, "ctc04");
}

/// The corpus part `file` with every mesh coordinate x replaced by round(x) (rounding another
/// program could have done: scripts/round_stl.py), reversed: a valid solid, no fallback.
template <class Round>
void expect_no_fallback_rounded(const char* file, const std::string& tag, Round round) {
    const auto path = corpus_step_dir() / file;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    SamplePart part = corpus_part(path);
    for (Vec3& p : part.mesh.points)
        for (int k = 0; k < 3; ++k) p[k] = round(static_cast<float>(p[k]));
    const Outcome o = reverse_part(part, false, ReverseMethod::kAuto, tag);
    expect_solid(o, tag);
    for (const ReverseFallback& f : o.report.fallbacks)
        ADD_FAILURE() << f.region << " (" << f.kind << "): " << f.reason;
}

// The same part with every coordinate moved by at most one float32 unit (up, down or not, by its
// own bits): rounding that any file can carry. Each countersunk hole's two circles then had their
// vertices at other places round the hole, and the face fix, adding a seam from the one to the
// other, split each loop there: where its own vertex already was, into the circle and a piece of
// no length from that vertex back to it. BRepCheck passes that, but a STEP file gives an edge
// its curve and ends only, and reading it back made the piece a whole circle: a hole's cylinder
// and another's cone failed once read back and fell back to mesh edges. Such a face now fails
// as it is built, and takes a seam of its own between its loops' vertices: no fallback.
TEST(ReverseSurfaces, NoEdgeClosesOnItsVertexWithNoLength) {
    expect_no_fallback_rounded("nist_ctc_04_asme1_rd.stp", "ctc04_nudged", [](float x) {
        std::uint32_t bits = 0;
        std::memcpy(&bits, &x, sizeof bits);
        const int step = static_cast<int>((bits * 2654435761u) >> 30) % 3 - 1;
        if (step == 0 || x == 0) return x;  // as scripts/round_stl.py: a zero stays
        return std::nextafter(x, step * std::numeric_limits<float>::infinity());
    });
}

// NIST FTC 07 as an ASCII STL written with six significant digits carries it: every coordinate
// rounded so. Six faces, a sphere's cap among them, then failed once read back, each with a loop
// split where its own vertex was (above). A sphere's cap is no band: the fix's seam runs from
// its loop to the pole, and the surface is now turned about its axis to put that seam
// elsewhere: no fallback.
TEST(ReverseSurfaces, ACapsSeamIsTurnedOffItsLoopsVertex) {
    expect_no_fallback_rounded("nist_ftc_07_asme1_rd.stp", "ftc07_six_digits", [](float x) {
        char text[32];
        std::snprintf(text, sizeof text, "%.5e", static_cast<double>(x));
        return static_cast<float>(std::strtod(text, nullptr));
    });
}

// The M6 screw's thread (~270 regions of cones, tori and planes along a helix): the face of
// its threaded core kept 11 of its 158 edges after ShapeFix_Face dropped a wire it found
// outside the surface's bounds; that face passed its check, its neighbours' edges stayed
// unpaired, 160 regions fell back one after the other and the whole part went planar (6217
// faces). A face whose fix drops edges now fails like any other. The thread root, a cylinder
// band whose outer loop winds down the thread round the axis nine times, then still fell back
// as its 717 facets: the fix's own seam, one ruling from the top loop down to the first
// crossing, cut off a sliver. seamed_band() joins the band's two loops by a seam of its own
// between them: 797 -> 81 faces, no fallback. Lone facets whose rings no surface took whole
// now grow by a greedy pick from their rings that keeps generators (strip_fit(), the second
// try): 81 -> 64 faces (34 -> 20 planes), volume 0.98 -> 0.58 % off. The volume is measured in
// pieces of one turn where a face goes round its surface more than once, as the thread's crest
// and root do (solid_volume()): measured whole, BRepGProp put it 1.41 % over (0.50 % by its
// default rule, which also put the original 1.3 % low); it is within 0.1 %. Its two flanks,
// each one face of 1000-1100 facets over seven turns, were 19 regions each (B-spline patches,
// cone and torus pieces, one-facet planes): 62 faces. A patch of half a turn fixes the flank's
// screw motion (fit_helical()) and merge_helical() takes the rest of the flank onto it: each
// flank is one helical sweep, 28 faces for the original's 28 — which the original writes for
// 18 surfaces, and 9 of those 28 were slivers on the thread's faded end. What the flanks leave
// of the patches that held their ends grows over the faded end's small pieces into one sweep
// (merge_helical()): 20 faces.
TEST(ReverseSurfaces, AThreadedScrewIsNotBuiltWhollyPlanar) {
    const auto path = corpus_step_dir() / "build123d_M6-1x12-countersunk-screw.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus at " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "m6_screw");
    expect_solid(o, "m6_screw");
    for (const ReverseFallback& f : o.report.fallbacks) ADD_FAILURE() << f.reason;
    EXPECT_EQ(o.report.faces_by_kind.count("facet"), 0u);
    ASSERT_GT(o.one_surface_faces, 0u);
    EXPECT_LE(static_cast<double>(o.report.faces), 1.15 * static_cast<double>(o.one_surface_faces))
        << o.report.faces << " faces for " << o.one_surface_faces << " surfaces";
    // The flanks and the thread's faded ends (the original's 6 B-splines).
    const auto bsplines = o.report.faces_by_kind.find("bspline");
    EXPECT_LE(bsplines == o.report.faces_by_kind.end() ? 0u : bsplines->second, 6u);
    EXPECT_NEAR(o.report.solid_volume, o.true_volume, 1e-3 * o.true_volume);
    EXPECT_NEAR(o.back.volume, o.true_volume, 1e-3 * o.true_volume);
    ASSERT_TRUE(o.report.deviation.has_value());
    EXPECT_LE(o.report.deviation->mesh_to_solid.max, 2 * o.deflection);
    EXPECT_LE(o.report.deviation->solid_to_mesh.max, 2 * o.deflection);
}

// A finer tessellation of a real part (NIST CTC 03 at 0.02 mm, 17k facets, as the benchmark
// runs it): its fillet edges have many more chain points, and a corner solved a little past
// the first of them used to fold the edge curve back on itself (self-intersecting wires, then
// neighbours' faces with them: 983 faces, 6 regions as facets). And where segmentation's
// border runs beside a tangent junction rather than on it (a plane strip between two tangent
// cylinders, with their first facet rows, fitted as one cone), a corner solved onto the
// surfaces stays anywhere in the band sqrt(2 r tol) wide where they are within the tolerance of
// each other: the cylinders came out 2 % short in area. Corners now go onto the contact line
// where the other surfaces cross it: the curved faces get their area back.
TEST(ReverseSurfaces, FineRealPartKeepsItsFaces) {
    const auto path = corpus_step_dir() / "nist_ctc_03_asme1_rc.stp";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    SampleOptions so;
    so.with_step = false;
    so.deflection = 0.02;
    so.angular_deflection = 0.08;
    Result<SamplePart> made = sample_from_step(path, so);
    ASSERT_TRUE(made.ok());
    const Outcome o = reverse_part(made.value(), false, ReverseMethod::kAuto, "ctc_03_fine");
    expect_solid(o, "ctc_03_fine");
    EXPECT_LE(o.report.fallbacks.size(), 1u);
    EXPECT_LE(o.report.faces, o.true_faces + 45);
    ASSERT_TRUE(o.report.deviation.has_value());
    EXPECT_EQ(o.report.deviation->faces_without_triangles, 0u);
    EXPECT_GT(o.report.tangent_corners, 0u);
    double true_curved = 0, curved = 0;
    for (const SampleFace& f : made.value().faces) {
        if (f.kind != "plane") true_curved += f.area;
    }
    for (TopExp_Explorer x(o.back.shape, TopAbs_FACE); x.More(); x.Next()) {
        const TopoDS_Face& face = TopoDS::Face(x.Current());
        const GeomAbs_SurfaceType type = BRepAdaptor_Surface(face).GetType();
        if (type == GeomAbs_Plane || type == GeomAbs_Cone) continue;  // the strip's cone too
        GProp_GProps props;
        BRepGProp::SurfaceProperties(face, props);
        curved += props.Mass();
    }
    // 2 % short with every corner solved plainly; 0.2 % where one chain's ends, past the
    // contact on the fillet's first row, still need it.
    EXPECT_NEAR(curved, true_curved, 5e-3 * true_curved);
}

// Two parts side by side in one mesh (an STL of several parts, or a workpiece cut in two): two
// components, each its own solid. Until the shell was split by its connected faces, the two
// came back as one shell that OpenCASCADE finds not connected, the planar method's too, and
// nothing was written.
TEST(ReverseSurfaces, PartsSideBySideAreSolidsOfTheirOwn) {
    const SamplePart one = make("drilled_plate", kFine);
    SamplePart two = one;
    two.step.clear();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& p : one.mesh.points) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
    const double shift = 1.2 * (hi - lo);  // a gap of a fifth of the part's length
    const auto base = static_cast<std::uint32_t>(one.mesh.points.size());
    for (const Vec3& p : one.mesh.points) two.mesh.points.push_back({p.x + shift, p.y, p.z});
    for (const auto& t : one.mesh.triangles)
        two.mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    two.mesh.color.clear();
    two.mesh.cut.clear();
    two.mesh.surface.clear();
    two.faces.insert(two.faces.end(), one.faces.begin(), one.faces.end());
    two.solid.volume = 2 * one.solid.volume;
    for (const ReverseMethod method : {ReverseMethod::kAuto, ReverseMethod::kPlanar}) {
        const std::string tag = method == ReverseMethod::kAuto ? "two_plates" : "two_plates_planar";
        const Outcome o = reverse_part(two, false, method, tag);
        EXPECT_TRUE(o.report.written) << tag;
        EXPECT_TRUE(o.report.solid && o.report.valid) << tag;
        EXPECT_EQ(o.report.bodies, 2u) << tag;
        EXPECT_TRUE(o.back.valid) << tag;
        EXPECT_EQ(o.back.solids, 2u) << tag;
        EXPECT_EQ(o.back.faces, o.report.faces) << tag;
        EXPECT_NEAR(o.back.volume, two.solid.volume, 1e-3 * two.solid.volume) << tag;
        if (method == ReverseMethod::kAuto) {
            EXPECT_TRUE(o.report.fallbacks.empty()) << tag;
            EXPECT_EQ(o.report.faces, two.faces.size()) << tag;
        }
    }
}

// A closed shell inside a part is a cavity: healing faces it into the cavity, whichever way
// the file had it, and every method builds it as a void of the part's solid (written as a
// BREP_WITH_VOIDS). Until the forty-fourth session healing turned it outward, so a cavity would
// have come back as a solid filling it, and such meshes were refused. A part inside the cavity
// is a solid of its own; side by side the same shells are two solids; an open sheet inside
// has no inside: a shell (planar), or left out of the cube's solid (auto).
TEST(ReverseSurfaces, ACavityIsAVoidOfItsSolid) {
    TriangleSoup soup;
    const auto cube = [&](Vec3 lo, Vec3 hi, bool inward) {
        const auto base = static_cast<std::uint32_t>(soup.points.size());
        for (int k = 0; k < 8; ++k)
            soup.points.push_back({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z});
        // Outward: counter-clockwise seen from outside.
        const std::array<std::array<std::uint32_t, 4>, 6> quads{
            {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
        for (const auto& q : quads) {
            for (const auto& t : {std::array<std::uint32_t, 3>{q[0], q[1], q[2]},
                                  std::array<std::uint32_t, 3>{q[0], q[2], q[3]}}) {
                soup.triangles.push_back(inward
                                             ? std::array{base + t[0], base + t[2], base + t[1]}
                                             : std::array{base + t[0], base + t[1], base + t[2]});
            }
        }
    };
    // A ball of radius r at c, in rings of latitude: outward unless `inward`.
    const auto ball = [&](Vec3 c, double r, bool inward) {
        constexpr int kRings = 24, kSectors = 48;
        const auto base = static_cast<std::uint32_t>(soup.points.size());
        soup.points.push_back(c + Vec3{0, 0, r});
        for (int i = 1; i < kRings; ++i) {
            const double theta = std::numbers::pi * i / kRings;
            for (int j = 0; j < kSectors; ++j) {
                const double phi = 2 * std::numbers::pi * j / kSectors;
                soup.points.push_back(c + r * Vec3{std::sin(theta) * std::cos(phi),
                                                   std::sin(theta) * std::sin(phi),
                                                   std::cos(theta)});
            }
        }
        soup.points.push_back(c - Vec3{0, 0, r});
        const auto at = [&](int i, int j) -> std::uint32_t {  // ring i in 1..kRings-1
            return base + 1 + static_cast<std::uint32_t>((i - 1) * kSectors + (j % kSectors));
        };
        const std::uint32_t bottom = base + 1 + (kRings - 1) * kSectors;
        const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t d) {
            soup.triangles.push_back(inward ? std::array{a, d, b} : std::array{a, b, d});
        };
        for (int j = 0; j < kSectors; ++j) {
            add(base, at(1, j), at(1, j + 1));
            add(bottom, at(kRings - 1, j + 1), at(kRings - 1, j));
            for (int i = 1; i + 1 < kRings; ++i) {
                add(at(i, j), at(i + 1, j), at(i + 1, j + 1));
                add(at(i, j), at(i + 1, j + 1), at(i, j + 1));
            }
        }
    };
    const auto reverse = [&](ReverseMethod method, const std::string& tag) {
        using Out = std::pair<std::pair<ReverseReport, test::ReadBack>, HealReport>;
        Result<BuildResult> built = build_mesh(soup);
        EXPECT_TRUE(built.ok()) << tag;
        if (!built.ok()) return Out{};
        const auto path = out_dir() / (tag + ".step");
        ReverseOptions ro;
        ro.method = method;
        Result<ReverseReport> rev = reverse_to_step(built->mesh, path, ro);
        EXPECT_TRUE(rev.ok()) << tag;
        std::pair<ReverseReport, test::ReadBack> out{rev.ok() ? *rev : ReverseReport{}, {}};
        if (rev.ok() && rev->written) out.second = test::read_step(path);
        std::filesystem::remove(path);
        return Out{std::move(out), built->heal};
    };
    const std::array methods{ReverseMethod::kAuto, ReverseMethod::kPlanar, ReverseMethod::kFacets};
    const auto name = [](ReverseMethod m) {
        return m == ReverseMethod::kAuto     ? "auto"
               : m == ReverseMethod::kPlanar ? "planar"
                                             : "facets";
    };
    // A cubic cavity, its shell given facing out of it and facing into it.
    for (const bool given_inward : {false, true}) {
        soup = {};
        cube({0, 0, 0}, {10, 10, 10}, false);
        cube({3, 3, 3}, {7, 7, 7}, given_inward);
        for (const ReverseMethod method : methods) {
            const std::string tag = std::string("cavity_") + name(method) +
                                    (given_inward ? "_given_inward" : "_given_outward");
            const auto [o, heal] = reverse(method, tag);
            EXPECT_EQ(heal.cavities, 1u) << tag;
            EXPECT_EQ(heal.cavities_turned_inward, given_inward ? 0u : 1u) << tag;
            EXPECT_EQ(heal.components_turned_outward, 0u) << tag;
            EXPECT_TRUE(o.first.written && o.first.solid && o.first.valid) << tag;
            EXPECT_EQ(o.first.bodies, 1u) << tag;
            EXPECT_EQ(o.first.voids, 1u) << tag;
            EXPECT_NEAR(o.first.mesh_volume, 1000 - 64, 1e-9) << tag;
            EXPECT_NEAR(o.first.solid_volume, 1000 - 64, 1e-6) << tag;
            EXPECT_TRUE(o.second.valid) << tag;
            EXPECT_EQ(o.second.solids, 1u) << tag;
            EXPECT_EQ(o.second.faces, o.first.faces) << tag;
            EXPECT_NEAR(o.second.volume, 1000 - 64, 1e-6) << tag;
        }
    }
    // An island in the cavity: two solids, one of them with a void.
    soup = {};
    cube({0, 0, 0}, {10, 10, 10}, false);
    cube({2, 2, 2}, {8, 8, 8}, false);
    cube({4, 4, 4}, {6, 6, 6}, true);
    for (const ReverseMethod method : methods) {
        const std::string tag = std::string("island_") + name(method);
        const auto [o, heal] = reverse(method, tag);
        EXPECT_EQ(heal.cavities, 1u) << tag;
        EXPECT_EQ(heal.components_turned_outward, 1u) << tag;  // the island
        EXPECT_TRUE(o.first.written && o.first.valid) << tag;
        EXPECT_EQ(o.first.bodies, 2u) << tag;
        EXPECT_EQ(o.first.voids, 1u) << tag;
        EXPECT_TRUE(o.second.valid) << tag;
        EXPECT_EQ(o.second.solids, 2u) << tag;
        EXPECT_NEAR(o.second.volume, 1000 - 216 + 8, 1e-6) << tag;
    }
    // A spherical cavity: one sphere face, concave.
    soup = {};
    cube({0, 0, 0}, {10, 10, 10}, false);
    ball({5, 5, 5}, 3, false);
    {
        const auto [o, heal] = reverse(ReverseMethod::kAuto, "ball_cavity");
        EXPECT_EQ(heal.cavities, 1u);
        EXPECT_TRUE(o.first.written && o.first.valid);
        EXPECT_TRUE(o.first.fallbacks.empty());
        EXPECT_EQ(o.first.voids, 1u);
        EXPECT_EQ(o.first.faces_by_kind.at("sphere"), 1u);
        EXPECT_EQ(o.first.faces, 7u);
        EXPECT_TRUE(o.second.valid);
        EXPECT_EQ(o.second.solids, 1u);
        // The exact ball, within the chords' sag over its volume: the mesh's cavity, inscribed
        // in it, is smaller, so the mesh has more material than the solid.
        const double exact = 1000 - 4.0 / 3.0 * std::numbers::pi * 27;
        EXPECT_NEAR(o.second.volume, exact, 1e-3 * exact);
        EXPECT_LT(o.second.volume, o.first.mesh_volume);
    }
    // Side by side: two solids, no void; an open sheet inside: shells, or left out (auto).
    soup = {};
    cube({0, 0, 0}, {10, 10, 10}, false);
    cube({23, 3, 3}, {27, 7, 7}, true);
    for (const ReverseMethod method : methods) {
        const std::string tag = std::string("apart_") + name(method);
        const auto [o, heal] = reverse(method, tag);
        EXPECT_EQ(heal.cavities, 0u) << tag;
        EXPECT_EQ(heal.components_turned_outward, 1u) << tag;
        EXPECT_TRUE(o.first.written && o.first.valid) << tag;
        EXPECT_EQ(o.first.bodies, 2u) << tag;
        EXPECT_EQ(o.first.voids, 0u) << tag;
        EXPECT_NEAR(o.second.volume, 1000 + 64, 1e-6) << tag;
    }
    soup = {};
    cube({0, 0, 0}, {10, 10, 10}, false);
    cube({3, 3, 3}, {7, 7, 7}, true);
    soup.triangles.resize(soup.triangles.size() - 2);  // one side open: no hole to fill
    for (const ReverseMethod method : methods) {
        const std::string tag = std::string("sheet_") + name(method);
        const auto [o, heal] = reverse(method, tag);
        EXPECT_EQ(heal.cavities, 0u) << tag;
        EXPECT_EQ(o.first.voids, 0u) << tag;
        if (method == ReverseMethod::kAuto) {
            // The closed cube is most of the mesh: built, the sheet left out (and said).
            EXPECT_TRUE(o.first.written && o.first.solid) << tag;
            EXPECT_EQ(o.first.bodies, 1u) << tag;
            EXPECT_EQ(o.first.left_out_facets, 10u) << tag;
            EXPECT_NEAR(o.second.volume, 1000, 1e-6) << tag;
        } else {
            EXPECT_TRUE(o.first.written && !o.first.solid) << tag;
            EXPECT_EQ(o.first.bodies, 2u) << tag;
        }
    }
}

// trimesh_featuretype meshed as the time benchmark meshes it (1e-3 of its size and 0.02 rad,
// 81.6k facets, float32 as an STL stores them): its spline pocket wall bends sharply at one
// end, whose facets' middles sag past twice the part's deflection estimate with their corners
// on the wall, and that end came back as small regions beside it (a torus of 42 facets, a cone
// of 37, bands of a few rows fitted to rounding, one-facet planes): 90 faces, a one-facet piece
// of the wall cut off by them a fallback. A facet is now a B-spline's chord when its middle is off
// no more than the surface bends between its corners (bspline_chord_sag()), and the wall, a surface
// known far better than the deflection (29k facets), takes the exact pieces whose vertices it holds
// within the tolerance (widen_freeform()): 84 faces for 79 (its split cylinder halves unified),
// none falls back.
TEST(ReverseSurfaces, ASplineWallKeepsItsSharplyBentEnd) {
    const auto path = corpus_step_dir() / "trimesh_featuretype.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    SampleOptions so;
    so.with_step = false;
    so.relative_deflection = 1e-3;
    so.angular_deflection = 0.02;
    Result<SamplePart> made = sample_from_step(path, so);
    ASSERT_TRUE(made.ok()) << made.error().describe();
    test::round_to_float(made.value().mesh.points);
    const Outcome o = reverse_part(made.value(), false, ReverseMethod::kAuto, "featuretype_fine");
    expect_exact(o, "featuretype_fine");
    EXPECT_LE(o.report.faces, 86u);  // 79 + 10 %
}

// The table of docs/results.md:
//   build/bin/ncrev_tests --gtest_also_run_disabled_tests --gtest_filter='ReverseStudy.*'
void print_row(const std::string& name, const char* input, const Outcome& o) {
    const ReverseReport& r = o.report;
    // In units of δ; "—" where none was measured (the whole part went planar).
    std::string dev1 = "—", dev2 = "—";
    if (r.deviation) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.3f", r.deviation->mesh_to_solid.max / o.deflection);
        dev1 = buf;
        std::snprintf(buf, sizeof buf, "%.3f", r.deviation->solid_to_mesh.max / o.deflection);
        dev2 = buf;
    }
    std::size_t as_facets = 0;
    for (const ReverseFallback& f : r.fallbacks) as_facets += f.mesh_edges ? 0 : 1;
    const std::string fallbacks =
        std::to_string(r.fallbacks.size()) +
        (as_facets > 0 ? " (" + std::to_string(as_facets) + " as facets)" : "");
    std::string kinds;
    for (const auto& [k, n] : r.faces_by_kind) {
        kinds += (kinds.empty() ? "" : " ") + std::to_string(n) + " " + k;
    }
    double seg = 0, brep = 0, step = 0;
    for (const auto& [stage, s] : r.stage_seconds) {
        // Summed: a STEP that read back wrong has the B-rep built and written again.
        if (stage == "segment") seg += s;
        if (stage == "brep") brep += s;
        if (stage == "step") step += s;
    }
    std::string truth = std::to_string(o.true_faces);
    if (o.unified_faces != 0 &&
        (o.unified_faces != o.true_faces || o.one_surface_faces != o.true_faces)) {
        truth += " (" + std::to_string(o.unified_faces) + "; " +
                 std::to_string(o.one_surface_faces) + ")";
    }
    std::printf(
        "| %s | %s | %llu | %s | %s | %llu | %s | %s | %+.4f %% | %.3f | %s | %s | %.2f / "
        "%.2f / %.2f | %.2f |\n",
        name.c_str(), input,
        static_cast<unsigned long long>(r.segmentation ? r.segmentation->region.size() : 0),
        r.solid && r.valid && o.back.valid ? "yes" : "**no**", truth.c_str(),
        static_cast<unsigned long long>(r.faces), kinds.c_str(), fallbacks.c_str(),
        o.true_volume > 0 ? 100 * (r.solid_volume - o.true_volume) / o.true_volume : 0.0,
        o.deflection, dev1.c_str(), dev2.c_str(), seg, brep, step, o.seconds);
    std::fflush(stdout);
}

void print_header() {
    std::printf(
        "| part | input | facets | valid closed solid | true faces (unified; on one surface) | "
        "faces | kinds | "
        "fallbacks | "
        "volume vs true | chordal deflection | max dev mesh→solid / δ | max dev solid→mesh / "
        "δ | segment / brep / step s | total s |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

TEST(ReverseStudy, DISABLED_Samples) {
    print_header();
    for (const SamplePartInfo& info : sample_parts()) {
        for (const double d : {kFine, kCoarse}) {
            const SamplePart part = make(info.name, d);
            const std::string tag = std::string(info.name) + (d == kFine ? "" : " (coarse)");
            print_row(tag, "STL", reverse_part(part, false, ReverseMethod::kAuto, "study"));
            if (d == kFine) {
                print_row(tag, "SRE", reverse_part(part, true, ReverseMethod::kAuto, "study"));
            }
        }
    }
}

/// Face for face: the true faces whose facets lie (by area) at least kMatchShare in one region
/// of the default segmentation, that region's facets at least kMatchShare on that face. Counts
/// say less: a wall in 18 pieces and 17 split bores unified can add up to the right number.
struct FaceMatch {
    std::size_t matched = 0, split = 0, joined = 0;  ///< true faces; regions over several
};
constexpr double kMatchShare = 0.9;
FaceMatch match_faces(const SamplePart& part, bool list = false) {
    FaceMatch fm;
    const Result<BuildResult> built = build_mesh(part.mesh);
    if (!built.ok()) return fm;
    const Mesh& mesh = built.value().mesh;
    const Result<SegmentResult> seg = segment(mesh);
    if (!seg.ok()) return fm;
    std::map<std::pair<std::int64_t, std::int32_t>, double> both;
    std::map<std::int64_t, double> face_area;
    std::map<std::int32_t, double> region_area;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const double a = mesh.face_area(ff);
        both[{mesh.cuts()[f], seg.value().region[ff]}] += a;
        face_area[mesh.cuts()[f]] += a;
        region_area[seg.value().region[ff]] += a;
    }
    std::map<std::int64_t, std::size_t> pieces;  // regions holding a tenth of a true face
    std::map<std::int32_t, std::size_t> faces;   // true faces holding a tenth of a region
    for (const auto& [key, a] : both) {
        const auto [t, g] = key;
        if (a >= (1 - kMatchShare) * face_area[t]) ++pieces[t];
        if (a >= (1 - kMatchShare) * region_area[g]) ++faces[g];
        if (a >= kMatchShare * face_area[t] && a >= kMatchShare * region_area[g]) ++fm.matched;
    }
    for (const auto& [t, n] : pieces) fm.split += n > 1;
    for (const auto& [g, n] : faces) fm.joined += n > 1;
    if (list) {  // each split true face: its kind and area, and its regions' shares
        const std::vector<Region>& regions = seg.value().regions;
        for (const auto& [t, n] : pieces) {
            if (n < 2 || t < 0 || static_cast<std::size_t>(t) >= part.faces.size()) continue;
            const SampleFace& sf = part.faces[static_cast<std::size_t>(t)];
            std::printf(
                "|   split: true face %lld (%s, %.1f mm2, %llu facets):", static_cast<long long>(t),
                sf.kind.c_str(), sf.area, static_cast<unsigned long long>(sf.num_facets));
            for (const auto& [key, a] : both) {
                if (key.first != t || a < (1 - kMatchShare) * face_area[t]) continue;
                const Region& r = regions[static_cast<std::size_t>(key.second)];
                std::printf(" region %d %s %.0f%% (%llu facets, its %.0f%%)", key.second,
                            to_string(r.fit.surface.kind), 100 * a / face_area[t],
                            static_cast<unsigned long long>(r.facets),
                            100 * a / region_area[key.second]);
            }
            std::printf(" |\n");
        }
        // Each region over several true faces: its kind and size, and the true faces' shares.
        for (const auto& [g, n] : faces) {
            if (n < 2) continue;
            const Region& r = regions[static_cast<std::size_t>(g)];
            std::printf("|   joined: region %d %s (%llu facets):", g, to_string(r.fit.surface.kind),
                        static_cast<unsigned long long>(r.facets));
            for (const auto& [key, a] : both) {
                const auto t = key.first;
                if (key.second != g || a < (1 - kMatchShare) * region_area[g]) continue;
                const bool known = t >= 0 && static_cast<std::size_t>(t) < part.faces.size();
                std::printf(" true face %lld %s %.0f%% (its %.0f%%)", static_cast<long long>(t),
                            known ? part.faces[static_cast<std::size_t>(t)].kind.c_str() : "?",
                            100 * a / region_area[g], 100 * a / face_area[t]);
            }
            std::printf(" |\n");
        }
        // Regions holding under a tenth of every true face they touch: invisible above.
        std::map<std::int32_t, std::pair<double, std::int64_t>> main_face;  // share, face
        for (const auto& [key, a] : both) {
            auto& m = main_face[key.second];
            if (a > m.first) m = {a, key.first};
        }
        std::size_t slivers = 0;
        for (const auto& [g, m] : main_face) {
            const double share = m.first / face_area[m.second];
            if (share >= 1 - kMatchShare) continue;
            ++slivers;
            const Region& r = regions[static_cast<std::size_t>(g)];
            const SampleFace* sf =
                m.second >= 0 && static_cast<std::size_t>(m.second) < part.faces.size()
                    ? &part.faces[static_cast<std::size_t>(m.second)]
                    : nullptr;
            std::printf(
                "|   sliver: region %d %s (%llu facets) mostly on true face %lld %s, %.1f%% of it "
                "|\n",
                g, to_string(r.fit.surface.kind), static_cast<unsigned long long>(r.facets),
                static_cast<long long>(m.second), sf ? sf->kind.c_str() : "?", 100 * share);
        }
        std::printf("|   %zu regions, %zu slivers |\n", regions.size(), slivers);
        if (const char* fe = std::getenv("FACE")) {  // FACE=n: that true face's facets
            const std::int64_t want = std::atoll(fe);
            for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
                if (mesh.cuts()[f] != want) continue;
                const FaceId ff(static_cast<std::uint32_t>(f));
                const Vec3 n = mesh.face_normal(ff);
                std::printf("|   facet %zu region %d n (%.3f %.3f %.3f):", f,
                            seg.value().region[ff], n.x, n.y, n.z);
                for (int i = 0; i < 3; ++i) {
                    const Vec3 p = mesh.position(mesh.vertex(ff, i));
                    std::printf(" (%.3f %.3f %.3f)", p.x, p.y, p.z);
                }
                std::printf("\n");
            }
        }
    }
    return fm;
}

// NIST FTC 06 written as a binary STL (float32), as a simulator writes it: on its floor a slot's
// arc (radius 22.225) runs on into a fillet (3.175), tangent by design. Fitted each on its own
// from the rounded vertices, the two cylinders overlapped by 1.3e-7 mm, so the floor's circles
// crossed 8.5e-4 mm either side of their corner, far past its tolerance: the floor's wire
// crossed itself and its 332 facets fell back. The smaller of two such cylinders is now moved a
// hair apart from the larger (brep_detail::exact_tangencies()). Written as text with six
// significant digits, the arcs' axes came 1e-6 off the fillets' too, the gap changing along
// them: the fillet is turned onto the arc's axis first.
TEST(ReverseSurfaces, AFilletMeetsTheArcItRunsOnFromAtTheirCornerFromARoundedMesh) {
    const auto path = corpus_step_dir() / "nist_ftc_06_asme1_rd.stp";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus at " << path;
    const SamplePart part = corpus_part(path);
    std::string text = "solid ftc06\n";
    char line[160];
    for (const auto& t : part.mesh.triangles) {
        text += "facet normal 0 0 0\nouter loop\n";
        for (const std::uint32_t i : t) {
            const Vec3 p = part.mesh.points[i];
            std::snprintf(line, sizeof line, "vertex %.5e %.5e %.5e\n", p.x, p.y, p.z);
            text += line;
        }
        text += "endloop\nendfacet\n";
    }
    text += "endsolid ftc06\n";
    const std::vector<std::byte> binary = encode_stl_binary(part.mesh.points, part.mesh.triangles);
    for (const bool six_digits : {false, true}) {
        SCOPED_TRACE(six_digits ? "six digits" : "float32");
        const std::span<const std::byte> bytes =
            six_digits ? std::as_bytes(std::span<const char>(text.data(), text.size()))
                       : std::span<const std::byte>(binary);
        const Result<TriangleSoup> read = read_stl(bytes, "ftc06.stl");
        ASSERT_TRUE(read.ok()) << read.error().describe();
        const Result<BuildResult> built = build_mesh(read.value());
        ASSERT_TRUE(built.ok());
        const auto out = out_dir() / "ftc06_rounded.step";
        const Result<ReverseReport> rev = reverse_to_step(built.value().mesh, out);
        std::filesystem::remove(out);
        ASSERT_TRUE(rev.ok()) << rev.error().describe();
        const ReverseReport& r = rev.value();
        EXPECT_TRUE(r.solid && r.valid && r.written);
        EXPECT_GE(r.exact_tangencies, 1u);
        for (const ReverseFallback& f : r.fallbacks)
            ADD_FAILURE() << "region " << f.region << " (" << f.kind << ", " << f.facets
                          << " facets): " << f.reason;
        EXPECT_EQ(r.faces, 144u);  // the original's
    }
}

// The M6 screw's flanks (true faces of 1000-1100 facets over seven turns) each ended in a
// B-spline patch of 93-97 facets that also held a tenth of the thread's faded end: no one
// helical sweep fits that patch, and 8 % of each flank stayed out of its region. The flank's
// region now takes the patch's facets that lie on its sweep unbounded along its helix
// (facets_along_helix()); the rest stays with the faded end.
TEST(ReverseSurfaces, AThreadFlankIsOneRegionToItsEnd) {
    const auto path = corpus_step_dir() / "build123d_M6-1x12-countersunk-screw.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus at " << path;
    const SamplePart part = corpus_part(path);
    const Result<BuildResult> built = build_mesh(part.mesh);
    ASSERT_TRUE(built.ok());
    const Mesh& mesh = built.value().mesh;
    const Result<SegmentResult> seg = segment(mesh);
    ASSERT_TRUE(seg.ok());
    std::map<std::int64_t, std::map<std::int32_t, double>> by_region;  // true face -> areas
    std::map<std::int64_t, std::size_t> facets;
    std::map<std::int32_t, double> region_area;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        by_region[mesh.cuts()[f]][seg.value().region[ff]] += mesh.face_area(ff);
        region_area[seg.value().region[ff]] += mesh.face_area(ff);
        ++facets[mesh.cuts()[f]];
    }
    // Each large free-form face of the original (the flanks, and the crest, a cylinder written
    // as a B-spline) in one region; the flanks are those whose region is a helical sweep.
    std::size_t flanks = 0;
    for (const auto& [t, areas] : by_region) {
        if (facets[t] < 500 || t < 0 || static_cast<std::size_t>(t) >= part.faces.size() ||
            part.faces[static_cast<std::size_t>(t)].kind != "bspline")
            continue;
        double total = 0, largest = 0;
        std::int32_t main = -1;
        for (const auto& [g, a] : areas) {
            total += a;
            if (a > largest) largest = a, main = g;
        }
        EXPECT_GE(largest, 0.99 * total) << "true face " << t << ": " << largest / total;
        ASSERT_GE(main, 0);
        const Surface& s = seg.value().regions[static_cast<std::size_t>(main)].fit.surface;
        if (!(s.kind == FitKind::kBSpline && s.bspline && s.bspline->helical)) continue;
        ++flanks;
        // Its screw motion is the thread's, as the JSON reports it: M6 x 1, about the z axis.
        const auto helix = nlohmann::json::parse(surface_params_json(s))["helix"];
        EXPECT_NEAR(std::abs(helix["pitch"].get<double>()), 1.0, 1e-3);
        EXPECT_NEAR(std::abs(helix["axis_dir"][2].get<double>()), 1.0, 1e-6);
        // And the flank's region takes little else (the faded end's facets on its sweep).
        EXPECT_GE(largest, 0.99 * region_area[main])
            << "flank region " << main << ": " << largest / region_area[main];
    }
    EXPECT_EQ(flanks, 2u);
}

// Parts full of coarse fillets (10-degree strips of long facets, corners of small tori and
// balls), face for face. FTC 10 had 191 of 214 true faces each one region (fillets one plane
// per strip; rings of fillets about rounded corners in ten pieces), FTC 07 200 of 269 (its
// 232 mm fillets' strips beside a few small facets of their end tori): strays left to their
// neighbours or to regions of their own, and the tori's spine start (docs/segmentation.md); one
// of FTC 07's corner balls is the sphere its two fillets make (corner_surfaces(): 227 -> 228).
TEST(ReverseSurfaces, CoarseFilletsFaceForFace) {
    if (corpus_steps().empty()) GTEST_SKIP() << "no corpus at " << corpus_step_dir();
    for (const auto& [name, matched] : {std::pair{"nist_ftc_10_asme1_rb.stp", 212u},
                                        std::pair{"nist_ftc_07_asme1_rd.stp", 228u}}) {
        const SamplePart part = corpus_part(corpus_step_dir() / name);
        EXPECT_GE(match_faces(part).matched, matched) << name;
    }
}

/// Of each true face of `part` of kind `kind`: the region holding most of its area, and the
/// share of the face's area that region holds.
struct MainRegion {
    std::size_t face = 0;
    std::int32_t region = -1;
    double share = 0;
};
std::vector<MainRegion> main_regions(const SamplePart& part, const Mesh& mesh,
                                     const SegmentResult& seg, const std::string& kind) {
    std::map<std::pair<std::int64_t, std::int32_t>, double> both;
    std::map<std::int64_t, double> face_area;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        both[{mesh.cuts()[f], seg.region[ff]}] += mesh.face_area(ff);
        face_area[mesh.cuts()[f]] += mesh.face_area(ff);
    }
    std::vector<MainRegion> out;
    for (std::size_t t = 0; t < part.faces.size(); ++t) {
        if (part.faces[t].kind != kind) continue;
        const auto key = static_cast<std::int64_t>(t);
        MainRegion m{t, -1, 0};
        for (const auto& [k, a] : both) {
            if (k.first == key && a > m.share) m.share = a, m.region = k.second;
        }
        if (face_area[key] > 0) m.share /= face_area[key];
        out.push_back(m);
    }
    return out;
}

/// Expects each true face of `kind` mostly (`share` of its area) in one region of that kind;
/// returns how many there are.
std::size_t expect_one_region_each(const SamplePart& part, const Mesh& mesh,
                                   const SegmentResult& seg, FitKind kind, double share) {
    const std::vector<MainRegion> faces = main_regions(part, mesh, seg, to_string(kind));
    for (const MainRegion& m : faces) {
        EXPECT_GE(m.share, share) << "true face " << m.face;
        if (m.region < 0) continue;
        EXPECT_EQ(seg.regions[static_cast<std::size_t>(m.region)].fit.surface.kind, kind)
            << "true face " << m.face;
    }
    return faces.size();
}

// NIST FTC 10's free-form blend (20.8 mm2 of B-spline between fillets of radius 1 and 13) was
// six tori and three planes: one B-spline fits them, but merge_freeform() takes the smooth
// component whole, 156 pieces of fillets round the part. Its loose pieces are now grown into
// one B-spline among the exact fillets (merge_loose_pieces()), and the part has 217 faces for
// its 214 (225 before, +5.1 %).
TEST(ReverseSurfaces, AFreeFormBlendAmongFilletsIsOneFace) {
    if (corpus_steps().empty()) GTEST_SKIP() << "no corpus at " << corpus_step_dir();
    const SamplePart part = corpus_part(corpus_step_dir() / "nist_ftc_10_asme1_rb.stp");
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult seg = segment(mesh).value();
    EXPECT_EQ(expect_one_region_each(part, mesh, seg, FitKind::kBSpline, kMatchShare), 1u);
    std::size_t bsplines = 0;
    for (const Region& g : seg.regions) bsplines += g.fit.surface.kind == FitKind::kBSpline;
    EXPECT_EQ(bsplines, 1u);  // no fillet taken for one
    EXPECT_LE(seg.regions.size(), 214u * 105 / 100);
}

// NIST FTC 08's bosses have corners rounded at 3.05 and a fillet of 1.52 at their base: round
// each corner the fillet is a torus of radii 4.57 and 1.52 (90 facets). A piece of it fits
// other tori within the tolerance (one of 5.31 and 3.83 took half of it) and the fillets took
// the rest: four tori in four pieces each, and six faces that failed. A torus between two
// fillets with perpendicular axes is now the one they make (corner_surfaces()).
TEST(ReverseSurfaces, CornerToriAreTheOnesTheirFilletsMake) {
    if (corpus_steps().empty()) GTEST_SKIP() << "no corpus at " << corpus_step_dir();
    const SamplePart part = corpus_part(corpus_step_dir() / "nist_ftc_08_asme1_rc.stp");
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult seg = segment(mesh).value();
    EXPECT_GE(expect_one_region_each(part, mesh, seg, FitKind::kTorus, 0.8), 4u);  // was half
    const Outcome o = reverse_part(part, false, ReverseMethod::kAuto, "corner_surfaces");
    EXPECT_TRUE(o.report.fallbacks.empty());
}

// NIST CTC 02's drafted walls (cones of radius 101 mm at 3 degrees, δ 1.17 mm) are meshed in
// facets from rim to rim whose middles sag 1.6 x the estimated deflection: each facet was a
// plane region of its own, 180 of them on four cones. A cone or cylinder may take a region of
// one or two facets whose middles sag up to twice (docs/segmentation.md, merging): 102 left.
// Its blends round those walls (B-spline rings, each written as two halves; 491 faces on one
// surface in all) came back in 5-7 analytic pieces each: every group of pieces that one
// B-spline fits met a piece of the ring it could not take (the whole ring is no height field)
// and stayed in pieces, 532 regions. A group now grows until then and becomes one region: each
// ring in a few B-splines, within 5 % of the part's count. Two of those B-splines meet at 15-18
// degrees without crossing on their junction (each within δ of its points): no intersection
// or solved point was on it and one fell back to mesh edges; the curve through points midway
// between the two takes it (docs/brep.md, 4). A B-spline refitted to its vertices alone swung
// 2.8 mm (2.4 δ) off a border edge's middle once a 27-facet ring piece took two leftover facets,
// and no edge curve followed it; a refit is kept only while its facets' and border edges'
// middles stay within 2 δ (docs/brep.md, 1).
TEST(ReverseSurfaces, WideDraftedWallsTakeTheirFacets) {
    if (corpus_steps().empty()) GTEST_SKIP() << "no corpus at " << corpus_step_dir();
    const SamplePart part = corpus_part(corpus_step_dir() / "nist_ctc_02_asme1_rc.stp");
    const Outcome o = reverse_part(part, false, ReverseMethod::kAuto, "ctc02");
    expect_solid(o, "ctc02");
    for (const ReverseFallback& f : o.report.fallbacks)
        EXPECT_EQ(f.reason.rfind("no edge curve", 0), std::string::npos)
            << f.region << ": " << f.reason;
    ASSERT_TRUE(o.report.segmentation.has_value());
    const SegmentResult& seg = *o.report.segmentation;
    std::size_t lone = 0;
    for (const Region& g : seg.regions)
        lone += g.facets == 1 && g.fit.surface.kind == FitKind::kPlane;
    EXPECT_LE(lone, 110u);
    std::size_t bsplines = 0;
    for (const Region& g : seg.regions) bsplines += g.fit.surface.kind == FitKind::kBSpline;
    EXPECT_GE(bsplines, 8u);
    EXPECT_LE(seg.regions.size(), 491u * 105 / 100);
}

// The link rods' free-form faces, tangent to each other all round, come in fitted pieces
// (tori, cylinders, planes) and B-spline patches (merge_loose_pieces()) whose junctions are
// tangent: solving a junction's points onto both surfaces slid them across the band where the
// two are within the tolerance of each other (up to 0.13 mm, 20 x the deflection), the edge's
// curve left the surfaces and the region fell back to mesh edges: 26 regions with the patches,
// 10 with the pieces alone (171 faces). A tangent junction's points are now also taken midway
// between the surfaces along their normal, at the mesh vertex along the junction
// (midway_points()): 138 faces, 8 fallbacks. Two walls one facet tall between free-form faces
// (20-25 facets in a row) were a plane per facet, 63 one-facet regions in all; such a strip
// of small pieces is now one extruded B-spline where one fits (merge_loose_pieces()): 26
// one-facet regions, 99 faces, 5 fallbacks (the two walls' faces among them: bounded by their
// mesh edges; the best curves along their junctions 2-4 x the deflection off both neighbours,
// a temporary print). The one-facet planes left along the B-spline patches' seams, their
// corners 0.0007-0.0010 mm off a patch (the tolerance 0.00056 mm, the deflection 0.0054 mm),
// now join it, as a patch holds its own facets (absorb_small_regions() after the patches are
// made): 75 -> 63 faces, 22 -> 7 one-facet regions. Fitted pieces along a B-spline patch
// (their RMS above 0.01 deflections: no exact face) now join it while one B-spline refitted to
// them holds their vertices within the deflection and their facets' middles within it too
// (widen_freeform()): 59 -> 54 faces, the solid 1.94 -> 1.70 deflections from the mesh at most.
// Then 5 -> 6 fallbacks (54 faces, 1.70 -> 1.91 deflections) when the tolerance followed the
// part's size in every pose (part_size(): 0.24 % smaller here): this part's count swings with
// the tolerance, 42-60 faces and 4-8 fallbacks within 2 % of it either way (its STL, `reverse
// --tolerance`, the build before).
TEST(ReverseSurfaces, TangentJunctionsOfFittedPiecesHaveEdges) {
    const auto path = corpus_step_dir() / "occt_linkrods.step";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "linkrods");
    ASSERT_TRUE(o.report.segmentation.has_value());
    std::size_t lone = 0;
    for (const Region& g : o.report.segmentation->regions) lone += g.facets == 1;
    EXPECT_LE(lone, 12u);
    expect_solid(o, "linkrods");
    EXPECT_LE(o.report.faces, 54u);
    // 6 until the nets that swung between their vertices were fitted again with the middles
    // of their facets and border edges as guides (FitInput::guides): tangent junctions with
    // them then have edge curves, and the farthest point of the solid from the mesh went 1.9
    // -> 1.2 deflections. Then 4 -> 2: the refitted nets reach 5 % past their vertices
    // (FitInput::margin), and the plane faces' edges along them, which bow out past the
    // outermost vertices, stay on them. (Then 1 here with a B-spline's chords bending with it,
    // bspline_chord_sag(), the mesh 1.68 -> 0.82 deflections from the solid; but the same
    // mesh in float32, as its STL, went 1 -> 2 and 0.80 -> 1.74: this part swings.)
    EXPECT_LE(o.report.fallbacks.size(), 2u);
    expect_near_the_part(o, "linkrods");
    ASSERT_TRUE(o.report.deviation.has_value());
    EXPECT_LE(o.report.deviation->solid_to_mesh.max, 1.1 * o.deflection);
}

// Two surfaces tangent along a whole circle (a cone and the torus that rounds its end, on NIST
// FTC 07) take the curve through their tangency points, which jitter along the junction: one
// such curve ran the long way round, a 271-degree arc for a junction of 89, on both surfaces
// but 2.5 mm off the chain, and the cone's face did not close (BRepCheck_NotClosed); so did a
// torus's. A tangency curve is now held to twice max_tol of its points (strays_from()): 5 -> 3
// fallbacks, the volume -0.072 % -> +0.003 % of the exact solid's. Then 3 -> 2: a corner blend
// fitted as a spindle torus (minor radius 21.7 over major 6.6) is a cap round the point where
// the torus meets its axis, closed by seamed_cap() like a cone's apex.
// A curve through tangency feet is now taken only within 2 tolerances of both surfaces
// (kTouchTolerances; it was 10): the solid's farthest point from the mesh 0.76 -> 0.21 δ.
TEST(ReverseSurfaces, TangencyCurvesStayAlongTheirJunction) {
    const auto path = corpus_step_dir() / "nist_ftc_07_asme1_rd.stp";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "no corpus file " << path;
    const Outcome o = reverse_part(corpus_part(path), false, ReverseMethod::kAuto, "ftc07");
    expect_solid(o, "ftc07");
    EXPECT_LE(o.report.fallbacks.size(), 2u);
    EXPECT_NEAR(o.report.solid_volume, o.true_volume, 2e-4 * o.true_volume);
    expect_near_the_part(o, "ftc07");
    ASSERT_TRUE(o.report.deviation.has_value());
    EXPECT_LE(o.report.deviation->solid_to_mesh.max, 0.4 * o.deflection);
}

// The corpus file `name` tessellated with `so` and reversed from its triangles; nullopt where
// the file is missing.
std::optional<Outcome> reverse_corpus_mesh(const char* name, const SampleOptions& so,
                                           const std::string& tag) {
    const auto path = corpus_step_dir() / name;
    if (!std::filesystem::exists(path)) return std::nullopt;
    Result<SamplePart> made = sample_from_step(path, so);
    EXPECT_TRUE(made.ok()) << made.error().describe();
    if (!made.ok()) return std::nullopt;
    return reverse_part(made.value(), false, ReverseMethod::kAuto, tag);
}

// NIST FTC 10 meshed at 0.04 mm / 0.1 rad (139k facets), reversed once for what follows. (One
// test, not two sharing the reversal: ctest runs each test in a process of its own, so two
// tests reversed it twice, 38 s each in Release.)
//
// A bore and the torus rounding its end touch along a circle round the bore's axis. The
// tangency feet were taken from the bore (the tube of smaller radius), whose spine points along
// that circle are one point: at 139k facets they heaped up, OpenCASCADE's interpolation threw
// through them, and the throw gave up every other curve of the chain. Four regions fell back: a
// bore and a plane with "no edge curve", a cylinder and a torus whose wires crossed themselves.
// The torus, whose spine runs along the circle, is now the tube there (kStillSpine), a throw
// costs only the curve through the points that caused it, and a curve through feet is held to 2
// tolerances (kTouchTolerances): none.
//
// FTC 10's one free-form face, a 20.8 mm2 blend among fillets, is one B-spline at the issue's
// resolution. Meshed finer its pieces (tori, cones, a sphere) met loose neighbours they could
// not take before they were three, and a group of fewer curved pieces is dropped: at 139k
// facets the blend came back as a B-spline and three tori (42 tori for the file's 39, 222
// faces for 214), at 2.5e-4 x the part's size as ten analytic faces. A group too small to keep
// now grows on past such a neighbour (merge_loose_pieces()): two B-splines, and the file's
// tori.
TEST(ReverseSurfaces, FinelyMeshedBoreRoundingsAndFreeFormBlendAreWhole) {
    SampleOptions so;
    so.deflection = 0.04;
    so.angular_deflection = 0.1;
    const std::optional<Outcome> o =
        reverse_corpus_mesh("nist_ftc_10_asme1_rb.stp", so, "ftc10_fine");
    if (!o) GTEST_SKIP() << "no corpus file nist_ftc_10_asme1_rb.stp";
    {
        SCOPED_TRACE("a bore meets the torus rounding its end");
        expect_solid(*o, "ftc10_fine");
        for (const ReverseFallback& f : o->report.fallbacks)
            ADD_FAILURE() << "region " << f.region << " (" << f.kind << "): " << f.reason;
        expect_near_the_part(*o, "ftc10_fine");
    }
    SCOPED_TRACE("the free-form blend is not in analytic pieces");
    EXPECT_LE(static_cast<double>(o->report.faces), 1.05 * static_cast<double>(o->true_faces));
    const auto count = [](const auto& by_kind, const char* kind) {
        const auto it = by_kind.find(kind);
        return it == by_kind.end() ? std::size_t{0} : static_cast<std::size_t>(it->second);
    };
    EXPECT_LE(count(o->report.faces_by_kind, "torus"), count(o->true_kinds, "torus"));
    EXPECT_GE(count(o->report.faces_by_kind, "bspline"), 1u);
}

// NIST FTC 07 meshed 4 x finer than issue 8's tessellation (87.8k facets), reversed once for
// what follows (one test, as for FTC 10 above).
//
// Two edge fillets and their corner torus are nearly tangent to one another and to the top
// plane, and their common point, solved 0.12 mm from the mesh vertex, lay past one fillet's
// tangent line with the plane: that fillet's wire crossed itself, and so did seven other
// regions' (8 fallbacks, 433 faces for 269). A corner of a face that still crosses itself after
// every other remedy goes back to its mesh vertex (vertex_at): 1 fallback. (Volume -0.0062 % of
// the exact solid's, then -0.0110 %, a trade taken for 257 -> 255 faces (254 on one surface):
// two B-spline regions that each hold a tenth of a sphere took two plane pieces of it, 39 and
// 11 facets, loose on it (widen_freeform() in segmentation). The sphere's own surface would
// have been closer; those regions are the fault.)
//
// Tori rounding cylinders, each fitted a few hundredths of a millimetre off tangency with its
// cylinder, so no point is on both. Their junctions' curves through the points solved onto both
// were 0.17 mm (1.7 delta) off the surfaces, and BRepMesh, which follows an edge's curves on
// its faces, put the tori's triangles 0.5 mm (4.97 delta) from mesh vertices that were on the
// solid. Such a junction now takes the curve midway between the two where that is nearer
// (0.015 mm): both ways within 0.46 delta.
TEST(ReverseSurfaces, FinelyMeshedIllConditionedCornersAndTangentEdgesHoldTheMesh) {
    SampleOptions so;
    so.relative_deflection = 2.5e-4;
    so.angular_deflection = 0.1;
    const std::optional<Outcome> o =
        reverse_corpus_mesh("nist_ftc_07_asme1_rd.stp", so, "ftc07_fine");
    if (!o) GTEST_SKIP() << "no corpus file nist_ftc_07_asme1_rd.stp";
    {
        SCOPED_TRACE("ill-conditioned corners go back to their mesh vertex");
        expect_solid(*o, "ftc07_fine");
        EXPECT_LE(o->report.fallbacks.size(), 1u);
        EXPECT_LE(o->report.faces, o->true_faces);
        EXPECT_NEAR(o->report.solid_volume, o->true_volume, 1.3e-4 * o->true_volume);
    }
    SCOPED_TRACE("tangent edges stay within the mesh's deflection");
    expect_near_the_part(*o, "ftc07_fine");
    ASSERT_TRUE(o->report.deviation.has_value());
    EXPECT_LE(o->report.deviation->mesh_to_solid.max, o->deflection);
    EXPECT_LE(o->report.deviation->solid_to_mesh.max, o->deflection);
}

// NIST CTC 01 meshed at 0.05 mm and 0.05 rad (34.6k facets): a plane of two long thin facets
// (2 x 22 mm) beside a small bore. One of them and a strip of the bore fitted a spindle torus
// within the tolerance at every corner and at the facet's middle, but its long edges' middles
// lay 0.91 mm off (ten tolerances): the face on the torus stood 1.24 mm (25 deflections) off
// the mesh, in a valid solid of 140 faces. A chord's longest edge is now held too
// (chords_agree()): the part face for face.
TEST(ReverseSurfaces, ALongThinFacetIsNoChordOfATorusThroughItsCorners) {
    SampleOptions so;
    so.deflection = 0.05;
    so.angular_deflection = 0.05;
    const std::optional<Outcome> o =
        reverse_corpus_mesh("nist_ctc_01_asme1_rd.stp", so, "ctc01_fine");
    if (!o) GTEST_SKIP() << "no corpus file nist_ctc_01_asme1_rd.stp";
    expect_solid(*o, "ctc01_fine");
    EXPECT_EQ(o->report.faces, o->true_faces);
    EXPECT_EQ(o->report.faces_by_kind.count("torus"), 0u);
    EXPECT_TRUE(o->report.fallbacks.empty());
    ASSERT_TRUE(o->report.deviation.has_value());
    EXPECT_LE(o->report.deviation->solid_to_mesh.max, 2 * o->deflection);
    EXPECT_LE(o->report.deviation->mesh_to_solid.max, 2 * o->deflection);
}

// NIST CTC 03 meshed by BRepMesh at 0.05 rad (27k facets) has strips of zero-area facets
// along its curved edges: slivers between a facet's edge and the finer polyline of the face
// beside it, two or three caps side by side (the tessellation is closed). Healing dropped every
// cap with a cap beside it as not stitched in, and 17 cracks stayed open: the part came back as
// a planar surface model of 6736 faces. Each cap now goes into the facet beyond its long edge
// (docs/healing.md 2): closed, and the part face for face.
TEST(ReverseSurfaces, StripsOfCapsAlongCurvedEdgesKeepThePartClosed) {
    SampleOptions so;
    so.relative_deflection = 1e-4;
    so.angular_deflection = 0.05;
    const std::optional<Outcome> o =
        reverse_corpus_mesh("nist_ctc_03_asme1_rc.stp", so, "ctc03_caps");
    if (!o) GTEST_SKIP() << "no corpus file nist_ctc_03_asme1_rc.stp";
    EXPECT_GT(o->heal.caps_split, 100u);
    EXPECT_EQ(o->heal.caps_split, o->heal.degenerate_facets_removed);
    EXPECT_EQ(o->heal.holes_filled, 0u);
    EXPECT_TRUE(o->mesh.closed);
    expect_solid(*o, "ctc03_caps");
    EXPECT_EQ(o->report.faces, o->true_faces);
    // One cone of 48 facets, beside a bore, fails once the STEP is read back and comes back on
    // its surface bounded by its mesh edges (a lead of its own: docs/results.md).
    EXPECT_LE(o->report.fallbacks.size(), 1u);
    expect_near_the_part(*o, "ctc03_caps");
}

TEST(ReverseStudy, DISABLED_Corpus) {
    // THREADS=n: at most n threads (results must not depend on it).
    std::optional<tbb::global_control> threads;
    if (const char* t = std::getenv("THREADS")) {
        threads.emplace(tbb::global_control::max_allowed_parallelism,
                        static_cast<std::size_t>(std::atoi(t)));
    }
    print_header();
    const char* only = std::getenv("PART");  // PART=name: that file only
    for (const auto& path : corpus_steps()) {
        if (only && path.filename().string().find(only) == std::string::npos) continue;
        SampleOptions so;
        so.relative_deflection = 1e-3;
        if (const char* d = std::getenv("RELATIVE")) so.relative_deflection = std::atof(d);
        if (const char* d = std::getenv("DEFLECTION")) so.deflection = std::atof(d);  // mm
        if (const char* a = std::getenv("ANGULAR")) so.angular_deflection = std::atof(a);
        Result<SamplePart> made = sample_from_step(path, so);
        if (!made.ok()) {
            std::printf("| %s | %s |\n", path.filename().string().c_str(),
                        made.error().describe().c_str());
            continue;
        }
        if (const char* dump = std::getenv("DUMP")) {  // DUMP=dir: NAME.stl and NAME.labels
            const SamplePart& p = made.value();        // (the true face of each facet) there
            const auto bytes = encode_stl_binary(p.mesh.points, p.mesh.triangles);
            const auto stem = std::filesystem::path(dump) / path.stem();
            std::ofstream(stem.string() + ".stl", std::ios::binary)
                .write(reinterpret_cast<const char*>(bytes.data()),
                       static_cast<std::streamsize>(bytes.size()));
            std::ofstream labels(stem.string() + ".labels");
            for (const std::int32_t l : p.labels) labels << l << '\n';
        }
        const Outcome o = reverse_part(made.value(), false, ReverseMethod::kAuto, "study");
        print_row(path.filename().string(), "STL", o);
        const FaceMatch fm = match_faces(made.value(), only != nullptr);
        std::printf(
            "|   face for face: %zu of %zu true faces one region each; %zu true faces in "
            "several regions, %zu regions over several true faces |\n",
            fm.matched, o.true_faces, fm.split, fm.joined);
        if (only) {
            for (const ReverseFallback& f : o.report.fallbacks) {
                std::printf("|   fallback: region %d (%s, %llu facets) as %s: %s |\n", f.region,
                            f.kind.c_str(), static_cast<unsigned long long>(f.facets),
                            f.mesh_edges ? "a face with mesh edges" : "facets", f.reason.c_str());
            }
        }
        if (!o.mesh.closed) {
            std::printf(
                "|   open mesh: %llu boundary edges in %llu loops, %llu components; healing: %llu "
                "non-manifold edges, %llu orientation cuts, %llu degenerate facets |\n",
                static_cast<unsigned long long>(o.mesh.boundary_edges),
                static_cast<unsigned long long>(o.mesh.boundary_loops),
                static_cast<unsigned long long>(o.mesh.components),
                static_cast<unsigned long long>(o.heal.nonmanifold_edges),
                static_cast<unsigned long long>(o.heal.orientation_conflicts),
                static_cast<unsigned long long>(o.heal.degenerate_facets_removed));
        }
    }
}

}  // namespace
}  // namespace ncrev
