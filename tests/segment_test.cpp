// Segmentation against the sample parts' truth (every facet knows its face), both methods, fine
// and coarse; SRE surface indices; labels, PLY; determinism.
#include "ncrev/segment.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <string>

#include "analytic_shapes.h"
#include "ncrev/mesh.h"
#include "ncrev/sample.h"
#include "sample_cases.h"
#include "scratch.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

struct Score {
    double iou = 0;           ///< area-weighted mean over true faces of the best region's IoU
    double area = 0;          ///< the mesh area
    std::size_t regions = 0;  ///< regions found
    std::size_t faces = 0;    ///< true faces with at least one facet
    double kind_right = 0;    ///< share of the area whose region has the true face's kind
    double seconds = 0;
    std::string worst;  ///< the true face with the lowest IoU, for messages
};

/// The truth kind as fit names it ("bezier" and other free-form kinds are B-splines).
std::string truth_kind(const std::string& k) {
    for (const char* a : {"plane", "cylinder", "cone", "sphere", "torus"})
        if (k == a) return k;
    return "bspline";
}

Score score(const Mesh& mesh, const SegmentResult& r, const SamplePart& part) {
    const std::size_t nf = mesh.num_faces();
    std::map<std::pair<std::int64_t, std::int32_t>, double> inter;
    std::map<std::int64_t, double> face_area;
    std::map<std::int32_t, double> region_area;
    double total = 0, right = 0;
    for (std::size_t f = 0; f < nf; ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const double a = mesh.face_area(ff);
        const std::int64_t t = mesh.cuts()[f];
        const std::int32_t g = r.region[ff];
        inter[{t, g}] += a;
        face_area[t] += a;
        region_area[g] += a;
        total += a;
        const std::string want = truth_kind(part.faces[static_cast<std::size_t>(t)].kind);
        if (g >= 0 && want == to_string(r.regions[static_cast<std::size_t>(g)].fit.surface.kind))
            right += a;
    }
    std::map<std::int64_t, double> best;
    for (const auto& [key, a] : inter) {
        const double u = face_area[key.first] + region_area[key.second] - a;
        best[key.first] = std::max(best[key.first], a / u);
    }
    Score s;
    double worst = 2;
    for (const auto& [t, iou] : best) {
        s.iou += iou * face_area[t] / total;
        if (iou < worst) {
            worst = iou;
            s.worst = "face " + std::to_string(t) + " (" +
                      part.faces[static_cast<std::size_t>(t)].kind + ") IoU " + std::to_string(iou);
        }
    }
    s.regions = r.regions.size();
    s.faces = face_area.size();
    s.kind_right = right / total;
    s.area = total;
    return s;
}

using test::corpus_step_dir;
using test::corpus_steps;
using test::kCoarse;
using test::kFine;

struct Case {
    SamplePart part;
    Mesh mesh;
};

Case make_case(std::string_view name, double relative_deflection) {
    SamplePart part = test::sample_case(name, relative_deflection);
    Result<BuildResult> b = build_mesh(part.mesh);
    EXPECT_TRUE(b.ok());
    return {std::move(part), std::move(b.value().mesh)};
}

Score run(const Case& c, SegmentMethod method) {
    SegmentOptions o;
    o.method = method;
    const auto t0 = std::chrono::steady_clock::now();
    Result<SegmentResult> r = segment(c.mesh, o);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_TRUE(r.ok());
    Score s = score(c.mesh, r.value(), c.part);
    s.seconds = secs;
    return s;
}

// The targets of issue 7 on every sample part, fine and coarse, with the default method.
TEST(Segment, SamplePartsMeetTheTargets) {
    double iou = 0, area = 0, kind_area = 0;
    int cases = 0, count_right = 0;
    for (const SamplePartInfo& info : sample_parts()) {
        for (const double d : {kFine, kCoarse}) {
            const Case c = make_case(info.name, d);
            const Score s = run(c, SegmentMethod::kFacets);
            EXPECT_GE(s.iou, 0.95) << info.name << " " << d << ": " << s.worst;
            iou += s.iou;
            area += s.area;
            kind_area += s.kind_right * s.area;
            count_right += s.regions == s.faces;
            ++cases;
        }
    }
    EXPECT_GE(iou / cases, 0.98);
    EXPECT_GE(count_right, 0.9 * cases) << count_right << " of " << cases;
    EXPECT_GE(kind_area / area, 0.99);
}

// The paper's method is complete: on parts whose faces have vertices of their own type (planes
// between sharp edges, strips of cylinders) it finds every face; elsewhere every facet still
// gets a region and every region a surface.
TEST(Segment, PaperMethodFindsTheFacesOfPrismaticParts) {
    for (const char* name : {"l_bracket", "slot_plate", "keyway_shaft", "thin_slot"}) {
        const Case c = make_case(name, kFine);
        const Score s = run(c, SegmentMethod::kPaper);
        EXPECT_GE(s.iou, 0.99) << name << ": " << s.worst;
        EXPECT_EQ(s.regions, s.faces) << name;
    }
    const Case c = make_case("flange", kFine);
    SegmentOptions o;
    o.method = SegmentMethod::kPaper;
    const SegmentResult r = segment(c.mesh, o).value();
    EXPECT_GT(r.curvature_seconds, 0.0);
    for (std::size_t f = 0; f < c.mesh.num_faces(); ++f) {
        const std::int32_t g = r.region[FaceId(static_cast<std::uint32_t>(f))];
        ASSERT_GE(g, 0);
        ASSERT_LT(static_cast<std::size_t>(g), r.regions.size());
    }
    for (const Region& g : r.regions) EXPECT_GT(g.facets, 0u);
}

// SRE input: the given surfaces are the regions; only the free-form face (index -1) is
// segmented, and comes back as one B-spline.
TEST(Segment, KeepsTheSreSurfacesAndSegmentsTheRest) {
    const Case c = make_case("freeform_die", kFine);
    SegmentOptions o;
    o.surfaces = c.part.mesh.surfaces;
    const SegmentResult r = segment(c.mesh, o).value();
    std::uint64_t given = 0;
    for (const std::int32_t sidx : c.mesh.surfaces()) given += sidx >= 0;
    EXPECT_EQ(r.given_facets, given);
    EXPECT_GT(given, 0u);
    EXPECT_LT(given, c.mesh.num_faces());
    ASSERT_EQ(r.regions.size(), c.part.faces.size());
    const Score s = score(c.mesh, r, c.part);
    EXPECT_GT(s.iou, 1 - 1e-9);
    int bsplines = 0;
    for (const Region& g : r.regions) {
        if (g.surface_index >= 0) {
            EXPECT_TRUE(g.within_tolerance) << g.id;
            EXPECT_LT(g.fit.max, 1e-3) << g.id;
        } else {
            bsplines += g.fit.surface.kind == FitKind::kBSpline;
        }
    }
    EXPECT_EQ(bsplines, 1);
    // Without the indices, the same mesh is segmented from its shape alone.
    o.use_surface_indices = false;
    EXPECT_EQ(segment(c.mesh, o).value().given_facets, 0u);
}

TEST(Segment, SameResultWhateverTheThreadCount) {
    const Case c = make_case("flange", kCoarse);
    const SegmentResult many = segment(c.mesh).value();
    SegmentResult one;
    {
        tbb::global_control g(tbb::global_control::max_allowed_parallelism, 1);
        one = segment(c.mesh).value();
    }
    EXPECT_EQ(many.region.data(), one.region.data());
    ASSERT_EQ(many.regions.size(), one.regions.size());
    for (std::size_t i = 0; i < one.regions.size(); ++i) {
        EXPECT_EQ(many.regions[i].fit.surface.kind, one.regions[i].fit.surface.kind);
        EXPECT_EQ(many.regions[i].fit.rms, one.regions[i].fit.rms);
        EXPECT_EQ(many.regions[i].fit.surface.radius, one.regions[i].fit.surface.radius);
    }
}

// Regions carry exact surfaces: on the counterbore plate every region is within the tolerance,
// the kinds are the true faces' kinds, and the countersinks' half-angle is the drawn 45 degrees.
TEST(Segment, RegionsCarryTheirSurfaces) {
    const Case c = make_case("counterbore_countersink", kFine);
    const SegmentResult r = segment(c.mesh).value();
    std::map<std::string, int> kinds;
    for (const Region& g : r.regions) {
        EXPECT_TRUE(g.within_tolerance) << g.id;
        ++kinds[to_string(g.fit.surface.kind)];
        if (g.fit.surface.kind == FitKind::kCone) {
            EXPECT_NEAR(g.fit.surface.angle, std::numbers::pi / 4, 1e-6);
        }
    }
    std::map<std::string, int> want;
    for (const SampleFace& f : c.part.faces) ++want[truth_kind(f.kind)];
    EXPECT_EQ(kinds, want);
    // Each step's seconds, in order (one pass: the mesh is clean); the stage totals are theirs.
    std::vector<std::string> steps;
    double sum = 0;
    for (const auto& [name, seconds] : r.step_seconds) {
        steps.push_back(name);
        sum += seconds;
    }
    EXPECT_EQ(steps,
              (std::vector<std::string>{"edges", "grow", "merge", "freeform", "refine", "fit"}));
    EXPECT_NEAR(sum, r.curvature_seconds + r.segment_seconds + r.fit_seconds, 1e-9);
    EXPECT_EQ(r.fit_seconds, r.step_seconds.back().second);
}

/// The largest error of `s`'s values against `t`'s (same kind): lengths in mm, angles in rad.
double value_error(const Surface& s, const Surface& t) {
    const Vec3 w = t.point - s.point;
    const double tilt = norm(cross(s.axis, t.axis));
    const double line = norm(w - dot(w, s.axis) * s.axis);
    switch (s.kind) {
        case FitKind::kPlane:
            return std::max(tilt, std::fabs(dot(w, s.axis)));
        case FitKind::kSphere:
            return std::max(norm(w), std::fabs(s.radius - t.radius));
        case FitKind::kCylinder:
            return std::max({tilt, line, std::fabs(s.radius - t.radius)});
        case FitKind::kCone:  // its apex along the axis is not snapped
            return std::max({tilt, line, std::fabs(s.angle - t.angle)});
        case FitKind::kTorus:
            return std::max({tilt, line, std::fabs(dot(w, s.axis)),
                             std::fabs(std::fabs(s.radius) - std::fabs(t.radius)),
                             std::fabs(s.minor_radius - t.minor_radius)});
        default:
            return std::numeric_limits<double>::infinity();
    }
}

/// Whether every value of `t` that snapping rounds is round: its axis or normal a coordinate
/// axis; places across it, plane offsets, centers and radii in hundredths; cone angles in half
/// degrees.
bool round_values(const Surface& t) {
    auto round = [](double x, double n) { return std::fabs(std::round(x * n) - x * n) < 1e-6; };
    int k = -1;
    for (int i = 0; i < 3; ++i)
        if (std::fabs(std::fabs(t.axis[i]) - 1) < 1e-12) k = i;
    const bool sphere = t.kind == FitKind::kSphere;
    if (k < 0 && !sphere) return false;
    bool ok = true;
    for (int i = 0; i < 3; ++i) {
        const bool across = i != k;
        const bool along = t.kind == FitKind::kPlane || t.kind == FitKind::kTorus || sphere;
        if (across ? t.kind != FitKind::kPlane || sphere : along) ok = ok && round(t.point[i], 100);
    }
    if (t.kind != FitKind::kPlane && t.kind != FitKind::kCone)
        ok = ok && round(std::fabs(t.radius), 100);
    if (t.kind == FitKind::kTorus) ok = ok && round(t.minor_radius, 100);
    if (t.kind == FitKind::kCone) ok = ok && round(t.angle * 360 / std::numbers::pi, 1);
    return ok;
}

// Machined parts have round numbers (method.md Step 4). Every sample part is segmented from its
// facets alone, as tessellated (the free fits already exact to 1e-9 but for a few regions:
// snapping must lose none) and with Gaussian noise of a tenth of the tolerance on every vertex
// (an NC simulator's mesh: no free fit is exact). The analytic regions whose true face has round
// values get them to 1e-9 (axis, axis line or plane, radii, cone angle): on the noisy meshes 95 %
// of them at least (each change is a statistical test); the others (a torus of major radius
// 20.976..., inclined walls) stay within twice their free fit's error.
TEST(Segment, SnappedSurfacesHaveThePartsValues) {
    constexpr double kExact = 1e-9;
    for (const bool noisy : {false, true}) {
        std::size_t matched = 0, exact = 0, exact_free = 0, round_truth = 0;
        std::string missed;
        test::Rng rng(7);
        for (const SamplePartInfo& info : sample_parts()) {
            SamplePart part = test::sample_case(info.name, kFine);
            if (noisy) {
                const double sigma =
                    0.1 * default_segment_tolerance(build_mesh(part.mesh).value().mesh);
                for (Vec3& p : part.mesh.points)
                    p += sigma * Vec3{rng.gaussian(), rng.gaussian(), rng.gaussian()};
            }
            const Mesh mesh = build_mesh(part.mesh).value().mesh;
            SegmentOptions off;
            off.snap = false;
            const SegmentResult r = segment(mesh).value();
            const SegmentResult free = segment(mesh, off).value();
            ASSERT_EQ(r.regions.size(), free.regions.size()) << info.name;
            EXPECT_EQ(free.snapped, 0u);
            // Each region's true face: the one with most of its area.
            std::vector<std::map<std::int64_t, double>> area(r.regions.size());
            for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
                const std::int32_t g = r.region[FaceId(f)];
                if (g >= 0)
                    area[static_cast<std::size_t>(g)][mesh.cuts()[f]] += mesh.face_area(FaceId(f));
            }
            for (std::size_t g = 0; g < r.regions.size(); ++g) {
                const Surface& s = r.regions[g].fit.surface;
                if (!(fit_kind_bit(s.kind) & kRevolutionFitKinds)) continue;
                const auto best = std::max_element(
                    area[g].begin(), area[g].end(),
                    [](const auto& a, const auto& b) { return a.second < b.second; });
                const SampleFace& face = part.faces[static_cast<std::size_t>(best->first)];
                if (face.surface < 0) continue;
                const Surface t =
                    surface_from_record(part.mesh.surfaces[static_cast<std::size_t>(face.surface)]);
                const Surface& u = free.regions[g].fit.surface;
                if (t.kind != s.kind || u.kind != s.kind) continue;
                ++matched;
                const double e = value_error(s, t), e_free = value_error(u, t);
                exact += e <= kExact;
                exact_free += e_free <= kExact;
                const bool round = round_values(t);
                round_truth += round;
                if (round && e > kExact) {
                    missed += std::string(info.name) + " region " + std::to_string(g) + " (" +
                              to_string(s.kind) + ") off by " + std::to_string(e) + "; ";
                }
                // Values not all round: axes held along a coordinate axis may move the rest
                // (a narrow fillet's place across its axis), by chance, not to a round value.
                if (!round) {
                    EXPECT_LE(e, 2 * e_free + kExact) << info.name << " region " << g;
                }
            }
        }
        std::printf(
            "%s: %zu analytic regions on their true face's kind (%zu with round values); "
            "exact values: %zu snapped, %zu free\n",
            noisy ? "noisy" : "as tessellated", matched, round_truth, exact, exact_free);
        EXPECT_GE(matched, 200u);
        EXPECT_GE(round_truth, matched * 9 / 10);
        if (noisy) {
            // A 99.9 % test per change (kSnapChi2) over some 700 changes: a few may fail.
            EXPECT_GE(exact, round_truth * 95 / 100) << missed;
            EXPECT_EQ(exact_free, 0u);
        } else {
            // Float-exact vertices: the free fits are exact to 1e-9 already, but where a
            // region took a few vertices of its neighbour (the pocket's corner cylinders, 1e-5
            // off): its RMS is above the noise, and it is not snapped (kSnapFitNoise).
            EXPECT_GE(exact, matched - 5) << missed;
            EXPECT_GE(exact, exact_free);
        }
    }
}

// A ball-end pocket's sphere of radius 3.175 (a quarter-inch tool), with noise of a tenth of the
// tolerance: no round value in hundredths is within the noise of it (3.17 and 3.18 are 0.005 off,
// the fit's standard error 3e-6), so the free fit stays; with the SRE's tool of diameter 6.35
// its radius is exactly the tool's, and its center the round one.
TEST(Segment, RadiiSnapToTheSreTools) {
    test::Rng rng(5);
    TriangleSoup soup = test::to_indexed_soup(test::icosphere(3.175, 4, {10, 20, 5}));
    const double sigma = 0.1 * default_segment_tolerance(build_mesh(soup).value().mesh);
    for (Vec3& p : soup.points) p += sigma * Vec3{rng.gaussian(), rng.gaussian(), rng.gaussian()};
    const Mesh mesh = build_mesh(soup).value().mesh;
    const SegmentResult plain = segment(mesh).value();
    ASSERT_EQ(plain.regions.size(), 1u);
    ASSERT_EQ(plain.regions[0].fit.surface.kind, FitKind::kSphere);
    EXPECT_NE(plain.regions[0].fit.surface.radius, 3.175);
    EXPECT_NEAR(plain.regions[0].fit.surface.radius, 3.175, 1e-4);
    EXPECT_EQ(plain.regions[0].fit.surface.point, (Vec3{10, 20, 5}));
    ToolRecord ball;
    ball.kind = ToolKind::kBall;
    ball.diameter = 6.35;
    ball.corner_radius = 3.175;
    const ToolRecord tools[] = {ball};
    SegmentOptions o;
    o.tools = tools;
    const SegmentResult r = segment(mesh, o).value();
    ASSERT_EQ(r.regions.size(), 1u);
    EXPECT_EQ(r.regions[0].fit.surface.radius, 3.175);
    EXPECT_EQ(r.regions[0].fit.surface.point, (Vec3{10, 20, 5}));
    EXPECT_EQ(r.snapped, 1u);
}

TEST(Segment, LabelsFollowTheInputFacets) {
    // Two triangles of a square, a degenerate one between them (removed by healing).
    TriangleSoup soup;
    soup.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    soup.triangles = {{0, 1, 2}, {0, 1, 1}, {0, 2, 3}};
    const BuildResult b = build_mesh(soup).value();
    const SegmentResult r = segment(b.mesh).value();
    ASSERT_EQ(r.regions.size(), 1u);
    EXPECT_EQ(r.regions[0].fit.surface.kind, FitKind::kPlane);
    EXPECT_EQ(input_labels(b.mesh, r, 3), (std::vector<std::int32_t>{0, -1, 0}));
    const std::vector<std::byte> ply = encode_segments_ply(b.mesh, r);
    const std::string text(reinterpret_cast<const char*>(ply.data()), ply.size());
    EXPECT_NE(text.find("element face 2\nproperty list uchar int vertex_indices\nproperty int "
                        "region\nproperty uchar red\nproperty uchar green\nproperty uchar blue"),
              std::string::npos)
        << text.substr(0, 300);
}

// Vertex noise up to the size-derived tolerance: segment() measures it and segments again at
// six times it.
TEST(Segment, NoisyMeshesAreSegmentedAtTheirNoise) {
    for (const char* name : {"pocket_block", "counterbore_countersink"}) {
        SampleOptions so;
        so.with_step = false;
        SamplePart part = make_sample_part(name, so).value();
        test::Rng rng(7);
        for (Vec3& p : part.mesh.points)
            for (int i = 0; i < 3; ++i) p[i] += 0.02 * rng.gaussian();
        Mesh mesh = build_mesh(part.mesh).value().mesh;
        const Case c{std::move(part), std::move(mesh)};
        const SegmentResult r = segment(c.mesh).value();
        EXPECT_NE(r.tolerance_rule.find("noise"), std::string::npos) << r.tolerance_rule;
        EXPECT_GT(r.tolerance, 0.06);  // about 6 x 0.02, against 0.025 from the size
        // The passes before the last are one step, first.
        ASSERT_FALSE(r.step_seconds.empty());
        EXPECT_EQ(r.step_seconds.front().first, "earlier passes");
        EXPECT_GT(r.step_seconds.front().second, 0);
        const Score s = score(c.mesh, r, c.part);
        EXPECT_GE(s.iou, 0.98) << name << ": " << s.worst;
        EXPECT_GE(s.kind_right, 0.98) << name;
    }
}

// The die's free-form top meshed at 3 degrees (1536 facets): doubling the net from 4 x 4 went
// from one that misses the chordal deflection to one of more poles than a face may have (this
// fails with kNetGrowth 2: 95 regions, after a noise pass that took the pieces' misfit for
// noise); nets growing by half reach it within the limit.
TEST(Segment, FinelyMeshedFreeFormFaceIsOneBSpline) {
    SampleOptions so;
    so.with_step = false;
    so.angular_deflection = 0.05;
    SamplePart part = make_sample_part("freeform_die", so).value();
    Mesh mesh = build_mesh(part.mesh).value().mesh;
    const Case c{std::move(part), std::move(mesh)};
    const SegmentResult r = segment(c.mesh).value();
    EXPECT_EQ(r.tolerance_rule.find("noise"), std::string::npos) << r.tolerance_rule;
    ASSERT_EQ(r.regions.size(), 6u);
    EXPECT_EQ(
        std::count_if(r.regions.begin(), r.regions.end(),
                      [](const Region& g) { return g.fit.surface.kind == FitKind::kBSpline; }),
        1);
    const Score s = score(c.mesh, r, c.part);
    EXPECT_GE(s.iou, 0.98) << s.worst;
}

// Every region of the fillet-and-chamfer block meshed finely (0.6 um, 0.05 rad: 80k facets) is
// one piece, or its other pieces are larger than a few facets: border refinement leaves one-
// and two-facet pieces where fillets meet (on the same part at 345k facets, dozens — each a
// face of its own in the B-rep, too small to build), and those go to their neighbours.
TEST(Segment, NoRegionKeepsATinyDetachedPiece) {
    SampleOptions so;
    so.with_step = false;
    so.deflection = 0.0006;
    so.angular_deflection = 0.05;
    const SamplePart part = make_sample_part("fillet_chamfer_block", so).value();
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult sr = segment(mesh).value();
    // Pieces: components of each region across shared edges.
    const std::size_t nf = mesh.num_faces();
    std::vector<std::uint32_t> piece(nf, std::numeric_limits<std::uint32_t>::max());
    std::vector<std::size_t> size;
    std::map<std::int32_t, std::vector<std::size_t>> pieces_of;
    for (std::uint32_t f0 = 0; f0 < nf; ++f0) {
        if (piece[f0] != std::numeric_limits<std::uint32_t>::max()) continue;
        const auto id = static_cast<std::uint32_t>(size.size());
        size.push_back(0);
        const std::int32_t r = sr.region[FaceId(f0)];
        pieces_of[r].push_back(id);
        std::vector<std::uint32_t> stack{f0};
        piece[f0] = id;
        while (!stack.empty()) {
            const std::uint32_t f = stack.back();
            stack.pop_back();
            ++size[id];
            for (int i = 0; i < 3; ++i) {
                const HalfedgeId t = mesh.twin(Mesh::halfedge(FaceId(f), i));
                if (!t.is_valid()) continue;
                const std::uint32_t g = Mesh::face(t).idx();
                if (sr.region[FaceId(g)] != r || piece[g] == id) continue;
                piece[g] = id;
                stack.push_back(g);
            }
        }
    }
    std::size_t tiny = 0;
    for (const auto& [r, ids] : pieces_of) {
        if (ids.size() < 2) continue;
        std::size_t largest = 0;
        for (const std::size_t id : ids) largest = std::max(largest, size[id]);
        for (const std::size_t id : ids) tiny += size[id] != largest && size[id] <= 8;
    }
    EXPECT_EQ(tiny, 0u);
}

TEST(Segment, RejectsNonFiniteOptions) {
    const Case c = make_case("slot_plate", kFine);
    SegmentOptions o;
    o.tolerance = std::numeric_limits<double>::quiet_NaN();
    const Result<SegmentResult> r = segment(c.mesh, o);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kBadValue);
}

// The table of docs/segmentation.md:
//   build/bin/ncrev_tests --gtest_also_run_disabled_tests --gtest_filter='SegmentStudy.*'
TEST(SegmentStudy, DISABLED_Table) {
    std::printf(
        "| part | mesh | facets | faces | facets: IoU | regions | kind | s | paper: IoU | "
        "regions | kind | s |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    double sum[2][3] = {}, area[2] = {}, kind_area[2] = {};
    int n = 0;
    for (const SamplePartInfo& info : sample_parts()) {
        for (const double d : {kFine, kCoarse}) {
            const Case c = make_case(info.name, d);
            const Score a = run(c, SegmentMethod::kFacets);
            const Score b = run(c, SegmentMethod::kPaper);
            ++n;
            int k = 0;
            for (const Score* x : {&a, &b}) {
                sum[k][0] += x->iou;
                sum[k][1] += x->regions == x->faces;
                sum[k][2] += x->kind_right;
                area[k] += x->area;
                kind_area[k] += x->kind_right * x->area;
                ++k;
            }
            std::printf(
                "| %s | %s | %zu | %zu | %.4f | %zu | %.4f | %.2f | %.4f | %zu | %.4f | "
                "%.2f |\n",
                std::string(info.name).c_str(), d == kFine ? "fine" : "coarse", c.mesh.num_faces(),
                a.faces, a.iou, a.regions, a.kind_right, a.seconds, b.iou, b.regions, b.kind_right,
                b.seconds);
            if (a.iou < 0.98) std::printf("    facets worst: %s\n", a.worst.c_str());
        }
    }
    for (int k = 0; k < 2; ++k) {
        std::printf(
            "%s: mean IoU %.4f, count right %.0f/%d, kind %.4f (parts' mean), %.4f (of "
            "all area)\n",
            k == 0 ? "facets" : "paper", sum[k][0] / n, sum[k][1], n, sum[k][2] / n,
            kind_area[k] / area[k]);
    }
}

}  // namespace
}  // namespace ncrev
namespace ncrev {
// One part's regions against its true faces, and each small region's fit to its neighbours,
// for looking into a part of the table: PART=flange [COARSE=1] build/bin/ncrev_tests
// --gtest_also_run_disabled_tests --gtest_filter='SegmentStudy.*Regions'
TEST(SegmentStudy, DISABLED_Regions) {
    const char* name = std::getenv("PART") ? std::getenv("PART") : "l_bracket";
    const Case c = make_case(name, std::getenv("COARSE") ? kCoarse : kFine);
    SegmentOptions o;
    Result<SegmentResult> r = segment(c.mesh, o);
    const SegmentResult& s = r.value();
    std::printf("sag %g tol %g patches %llu merges %llu freeform %llu moved %llu\n",
                s.chordal_deflection, s.tolerance, (unsigned long long)s.patches,
                (unsigned long long)s.merges, (unsigned long long)s.freeform_groups,
                (unsigned long long)s.reassigned_facets);
    for (std::size_t f = 0; f < c.mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const Region& g = s.regions[static_cast<std::size_t>(s.region[ff])];
        if (g.facets > 4) continue;
        for (int i = 0; i < 3; ++i) {
            const HalfedgeId t = c.mesh.twin(Mesh::halfedge(ff, i));
            if (!t.is_valid()) continue;
            const Region& nb = s.regions[static_cast<std::size_t>(s.region[Mesh::face(t)])];
            if (nb.facets <= 4) continue;
            double dmax = 0;
            Vec3 cen{0, 0, 0};
            for (int k = 0; k < 3; ++k) {
                const Vec3 p = c.mesh.position(c.mesh.vertex(ff, k));
                dmax = std::max(dmax, distance(nb.fit.surface, p));
                cen += p / 3.0;
            }
            const Vec3 n = c.mesh.face_normal(ff);
            const Vec3 q = cen + n * 0.05;
            const Vec3 sn = normalized(q - closest_point(nb.fit.surface, q));
            std::printf(
                "small %d facet %zu vs region %d (%s): corners %g centroid %g normal cos %g\n",
                g.id, f, nb.id, to_string(nb.fit.surface.kind), dmax, distance(nb.fit.surface, cen),
                std::abs(dot(sn, n)));
        }
    }
    std::map<std::pair<std::int32_t, std::int64_t>, int> m;
    for (std::size_t f = 0; f < c.mesh.num_faces(); ++f)
        ++m[{s.region[FaceId(static_cast<std::uint32_t>(f))], c.mesh.cuts()[f]}];
    for (const auto& [k, n] : m) {
        const Region& g = s.regions[static_cast<std::size_t>(k.first)];
        std::printf("region %d (%s r=%g ax %g %g %g max %g) truth %lld (%s) facets %d\n", k.first,
                    to_string(g.fit.surface.kind), g.fit.surface.radius, g.fit.surface.axis.x,
                    g.fit.surface.axis.y, g.fit.surface.axis.z, g.fit.max, (long long)k.second,
                    c.part.faces[static_cast<std::size_t>(k.second)].kind.c_str(), n);
    }
}
}  // namespace ncrev

namespace ncrev {
namespace {

// Border chains and corners of the true labelling of the drilled plate: the box's 12 edges
// between its 8 corners, and one closed loop per rim: 4 through holes x 2 ends, 3 blind holes'
// entries and their cylinder-cone rims.
TEST(SegmentBorders, ChainsAndCornersOfTheDrilledPlate) {
    const Case c = make_case("drilled_plate", kFine);
    FaceMap<std::int32_t> truth(c.mesh.num_faces());
    for (std::size_t f = 0; f < c.mesh.num_faces(); ++f)
        truth[FaceId(static_cast<std::uint32_t>(f))] = static_cast<std::int32_t>(c.mesh.cuts()[f]);
    const RegionBorders b = region_borders(c.mesh, truth);
    EXPECT_EQ(b.corners.size(), 8u);
    std::size_t closed = 0;
    std::size_t edges = 0;
    for (const BorderChain& ch : b.chains) {
        EXPECT_GT(ch.left, ch.right);
        EXPECT_GE(ch.vertices.size(), 2u);
        closed += ch.closed;
        edges += ch.vertices.size() - 1;
        if (ch.closed) {
            EXPECT_EQ(ch.vertices.front(), ch.vertices.back());
        } else {
            EXPECT_TRUE(
                std::binary_search(b.corners.begin(), b.corners.end(), ch.vertices.front()));
            EXPECT_TRUE(std::binary_search(b.corners.begin(), b.corners.end(), ch.vertices.back()));
        }
        // Consecutive vertices are joined by a mesh edge with `left` on its left.
        for (std::size_t i = 0; i + 1 < ch.vertices.size(); ++i) {
            bool found = false;
            c.mesh.for_each_outgoing(ch.vertices[i], [&](HalfedgeId h) {
                found = found || (c.mesh.target(h) == ch.vertices[i + 1] &&
                                  truth[Mesh::face(h)] == ch.left &&
                                  truth[Mesh::face(c.mesh.twin(h))] == ch.right);
            });
            ASSERT_TRUE(found) << "chain between " << ch.left << " and " << ch.right;
        }
    }
    EXPECT_EQ(b.chains.size(), 26u);
    EXPECT_EQ(closed, 14u);
    // Every border edge once.
    std::size_t border_edges = 0;
    for (std::uint32_t h = 0; h < c.mesh.num_halfedges(); ++h) {
        const HalfedgeId t = c.mesh.twin(HalfedgeId(h));
        border_edges += t.idx() > h && truth[Mesh::face(HalfedgeId(h))] != truth[Mesh::face(t)];
    }
    EXPECT_EQ(edges, border_edges);
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

// Vertex noise (a simulator's rounding, a scanner's jitter) on the sample parts: what the
// default method keeps of the faces. docs/segmentation.md, "Noise":
//   build/bin/ncrev_tests --gtest_also_run_disabled_tests --gtest_filter='SegmentStudy.*Noise'
TEST(SegmentStudy, DISABLED_Noise) {
    std::printf(
        "| part | sigma (mm) | tolerance | deflection | IoU | regions / faces | kind | "
        "IoU at the size tolerance, one pass |\n|---|---|---|---|---|---|---|---|\n");
    for (const char* name : {"pocket_block", "flange", "counterbore_countersink", "turned_shaft"}) {
        for (const double sigma : {0.0, 0.002, 0.005, 0.01, 0.02}) {
            SampleOptions so;
            so.with_step = false;
            SamplePart part = make_sample_part(name, so).value();
            test::Rng rng(7);
            for (Vec3& p : part.mesh.points)
                for (int i = 0; i < 3; ++i) p[i] += sigma * rng.gaussian();
            Mesh mesh = build_mesh(part.mesh).value().mesh;
            const Case c{std::move(part), std::move(mesh)};
            const SegmentResult r = segment(c.mesh).value();
            const Score s = score(c.mesh, r, c.part);
            // A given tolerance is used as it is: the size-derived one, without the noise pass.
            SegmentOptions fixed;
            fixed.tolerance = default_segment_tolerance(c.mesh);
            const Score one = score(c.mesh, segment(c.mesh, fixed).value(), c.part);
            std::printf(
                "| %s | %.3f | %.4f | %.4f | %.4f | %zu / %zu | %.4f | %.4f (%zu regions) |\n",
                name, sigma, r.tolerance, r.chordal_deflection, s.iou, s.regions, s.faces,
                s.kind_right, one.iou, one.regions);
        }
    }
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

// A corpus STEP part tessellated at 1e-3 of its size and `angular`, its points rounded to
// float32 as an STL stores them (the corpus study's and `ncrev reverse`'s input).
Result<SamplePart> corpus_part_as_stl(const std::string& name, double angular) {
    SampleOptions so;
    so.with_step = false;
    so.relative_deflection = 1e-3;
    so.angular_deflection = angular;
    Result<SamplePart> made = sample_from_step(corpus_step_dir() / name, so);
    if (made.ok()) test::round_to_float(made.value().mesh.points);
    return made;
}

// Prismatic real parts (the MFCAD feature models, two NIST test cases) come back face for face.
TEST(Segment, FindsTheFacesOfPrismaticCorpusParts) {
    const auto dir = corpus_step_dir();
    if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no corpus at " << dir;
    for (const char* name : {"mfcad_2-3-3-3-3-23.step", "mfcad_4-5-6-13-19.step",
                             "nist_ctc_01_asme1_rd.stp", "nist_ctc_03_asme1_rc.stp"}) {
        SampleOptions so;
        so.with_step = false;
        so.relative_deflection = 1e-3;
        Result<SamplePart> made = sample_from_step(dir / name, so);
        ASSERT_TRUE(made.ok()) << name << ": " << made.error().describe();
        Mesh mesh = build_mesh(made.value().mesh).value().mesh;
        const Case c{std::move(made).value(), std::move(mesh)};
        const Score s = run(c, SegmentMethod::kFacets);
        EXPECT_GE(s.iou, 0.999) << name << ": " << s.worst;
        EXPECT_EQ(s.regions, s.faces) << name;
        EXPECT_GE(s.kind_right, 0.999) << name;
    }
    // A file that is not STEP is an error that names it.
    const auto bogus = test::scratch_dir() / "ncrev_not_a_step.step";
    { std::ofstream(bogus) << "solid x\nendsolid x\n"; }
    const Result<SamplePart> bad = sample_from_step(bogus);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().describe().find("ncrev_not_a_step.step"), std::string::npos);
    std::filesystem::remove(bogus);
}

// trimesh_featuretype's pocket wall is one B-spline face in the file: a 10-pole cubic outline,
// folding back over its mean plane, extruded 4.8 mm. It was 18 pieces (cylinders of radius
// 0.3-13 mm, small planes); now at most two extrusions (a flat stretch of the outline, a plane
// of a tenth of the wall, may part them), and the rest of the part one region per face.
TEST(Segment, SplineWallOfACorpusPartIsFreeForm) {
    const auto dir = corpus_step_dir();
    if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no corpus at " << dir;
    // As the corpus study meshes it (3344 facets), and at 0.02 rad (81 592 facets, the time
    // benchmark's case: the wall in 39 pieces, a few of them rim leftovers that are no chords of
    // it, and a bend that a profile spread by length misses), its points rounded to float32 as
    // an STL stores them. Once the leftovers are left out, the fine wall's 29 pieces (cylinders,
    // 127 parameters, RMS 0.0038 mm) give way to an extrusion of 130 at 0.00076 mm; until the
    // fifteenth session they were refused for their three more parameters, one of the pieces,
    // 7926 facets that its cylinder fits to 0.0034 mm RMS, was the largest region and taken for
    // noise, and the whole part was segmented again at 0.020 mm instead of 0.015 mm.
    for (const double angular : {kSampleAngularDeflection, 0.02}) {
        SCOPED_TRACE(angular);
        Result<SamplePart> made = corpus_part_as_stl("trimesh_featuretype.step", angular);
        ASSERT_TRUE(made.ok()) << made.error().describe();
        const SamplePart& part = made.value();
        const Mesh mesh = build_mesh(part.mesh).value().mesh;
        const SegmentResult r = segment(mesh).value();
        EXPECT_EQ(r.tolerance_rule.find("noise"), std::string::npos) << r.tolerance_rule;
        std::int64_t wall = -1;
        for (const SampleFace& f : part.faces)
            if (f.kind == "bspline") wall = f.index;
        ASSERT_GE(wall, 0);
        std::map<std::int32_t, std::size_t> regions;  // of the wall's facets
        std::size_t facets = 0;
        for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
            if (mesh.cuts()[f] != wall) continue;
            ++regions[r.region[FaceId(static_cast<std::uint32_t>(f))]];
            ++facets;
        }
        // At most two B-spline regions hold nearly all of it (a facet or two at its edges may
        // stay with a small plane).
        std::size_t freeform = 0, covered = 0;
        for (const auto& [g, n] : regions) {
            if (r.regions[static_cast<std::size_t>(g)].fit.surface.kind != FitKind::kBSpline)
                continue;
            ++freeform;
            covered += n;
        }
        EXPECT_GE(freeform, 1u);
        EXPECT_LE(freeform, 2u);
        EXPECT_GE(covered, facets * 9 / 10) << covered << " of " << facets;
        const std::size_t on_wall = regions.size();
        // Its other 95 faces are 78 once their split cylinder halves are unified.
        EXPECT_LE(r.regions.size(), 78 + on_wall) << on_wall << " regions on the wall";
    }
}

// NIST CTC 02's drafted walls (cones of radius 101 mm at 3 degrees) are meshed from rim to rim;
// their facets' middles sag 1.6 x the deflection estimated from the part's curved edges, which
// are mostly small fillets held by the angular deflection. Until the sixteenth session growing
// refused such facets as a cone's chords, and 102 of them stayed one-facet planes (640 faces for
// 491 right ones). A facet's middle may sag twice the estimate where its own edges turn that
// much (docs/segmentation.md, "Loose facets"): no region of one facet is left on a cone face.
TEST(Segment, DraftedWallsOfACorpusPartAreCones) {
    const auto dir = corpus_step_dir();
    if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no corpus at " << dir;
    Result<SamplePart> made =
        corpus_part_as_stl("nist_ctc_02_asme1_rc.stp", kSampleAngularDeflection);
    ASSERT_TRUE(made.ok()) << made.error().describe();
    const SamplePart& part = made.value();
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    const SegmentResult r = segment(mesh).value();
    std::map<std::int64_t, std::string> kind;  // of each true face
    for (const SampleFace& f : part.faces) kind[f.index] = f.kind;
    // Each region's facets and the true face of its first one, and whether all lie on that one.
    std::vector<std::size_t> count(r.regions.size(), 0);
    std::vector<std::int64_t> face(r.regions.size(), -1);
    std::vector<std::uint8_t> one_face(r.regions.size(), 1);
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const auto g = static_cast<std::size_t>(r.region[FaceId(static_cast<std::uint32_t>(f))]);
        const std::int64_t truth = mesh.cuts()[f];
        if (count[g]++ == 0) face[g] = truth;
        if (face[g] != truth) one_face[g] = 0;
    }
    std::size_t lone = 0, on_cones = 0;
    for (std::size_t g = 0; g < r.regions.size(); ++g) {
        if (!one_face[g] || kind[face[g]] != "cone") continue;
        ++on_cones;
        lone += count[g] == 1;
    }
    EXPECT_GT(on_cones, 0u);
    EXPECT_EQ(lone, 0u) << "one-facet regions on cone faces, of " << on_cones;
    EXPECT_LE(r.regions.size(), 540u);
}

// NIST CTC 03 is 86 planes and 53 cylinders. Meshed at 2e-5 x its size and 0.02 rad (68k
// facets), growing took into its large planes the rows of the fillets tangent to them that lie
// within the tolerance; those rows pulled each plane's least-squares fit off its own facets by
// more than a firm plane allows (kFirmPlaneShare), and at the next ring six planes became
// cones of half-angle 0.02-0.34 degrees and radius 3.7-5.4 m. Merging then fitted every union
// with their neighbours as such a cone (2.5 s), and two small planes came back as cones. A
// plane is now firm on the plane of its nearest facets when the rest hold a few percent of its
// area (firm_plane()): one region a cone, the other planes planes.
TEST(Segment, PlanesWithTangentFilletRowsStayPlanes) {
    const auto dir = corpus_step_dir();
    if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no corpus at " << dir;
    SampleOptions so;
    so.with_step = false;
    so.relative_deflection = 2e-5;
    so.angular_deflection = 0.02;
    Result<SamplePart> made = sample_from_step(dir / "nist_ctc_03_asme1_rc.stp", so);
    ASSERT_TRUE(made.ok()) << made.error().describe();
    test::round_to_float(made.value().mesh.points);  // as its STL stores it
    const SamplePart& part = made.value();
    const Mesh mesh = build_mesh(part.mesh).value().mesh;
    ASSERT_GT(mesh.num_faces(), 60'000u);
    const SegmentResult r = segment(mesh).value();
    std::map<std::int64_t, std::string> kind;  // of each true face
    for (const SampleFace& f : part.faces) kind[f.index] = truth_kind(f.kind);
    // The true face holding most of each region's area (by count, a plane's few large facets
    // are outnumbered by the small ones it keeps of the fillets tangent to it, which lie within
    // the tolerance of both), and whether the region has its kind.
    std::vector<std::map<std::int64_t, double>> on(r.regions.size());
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        on[static_cast<std::size_t>(r.region[ff])][mesh.cuts()[f]] += mesh.face_area(ff);
    }
    std::size_t wrong = 0;
    for (std::size_t g = 0; g < r.regions.size(); ++g) {
        const auto most = std::max_element(on[g].begin(), on[g].end(),
                                           [](auto& a, auto& b) { return a.second < b.second; });
        ASSERT_NE(most, on[g].end());
        wrong += to_string(r.regions[g].fit.surface.kind) != kind[most->first];
    }
    EXPECT_EQ(r.regions.size(), part.faces.size());
    EXPECT_LE(wrong, 1u) << "regions of another kind than their true face's";
}

// Real parts: each corpus STEP solid tessellated at 1e-3 of its size (as issue 8 asks), the
// default method against its faces. docs/segmentation.md, "Real parts":
//   build/bin/ncrev_tests --gtest_also_run_disabled_tests --gtest_filter='SegmentStudy.*Corpus'
TEST(SegmentStudy, DISABLED_Corpus) {
    std::printf(
        "| file | facets | true faces | IoU | regions | kind | s |\n"
        "|---|---|---|---|---|---|---|\n");
    for (const auto& path : corpus_steps()) {
        SampleOptions so;
        so.with_step = false;
        so.relative_deflection = 1e-3;
        Result<SamplePart> made = sample_from_step(path, so);
        if (!made.ok()) {
            std::printf("| %s | %s |\n", path.filename().string().c_str(),
                        made.error().describe().c_str());
            continue;
        }
        Result<BuildResult> b = build_mesh(made.value().mesh);
        if (!b.ok()) continue;
        const Case c{std::move(made).value(), std::move(b.value().mesh)};
        const Score s = run(c, SegmentMethod::kFacets);
        std::printf("| %s | %zu | %zu | %.4f | %zu | %.4f | %.2f |\n",
                    path.filename().string().c_str(), c.mesh.num_faces(), s.faces, s.iou, s.regions,
                    s.kind_right, s.seconds);
    }
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

// Corners solved onto the surfaces that meet there (method.md Step 2b.3), from mesh vertices
// pushed 0.03 mm off: back on the true corner, on every surface, wherever three surfaces cross.
// Where two are tangent (a fillet and its plane) first-order steps cannot find their tangency
// line: the point only gets closer (not yet solved: issue 8).
TEST(SegmentBorders, CornersSolveOntoTheirSurfaces) {
    int solved = 0, exact = 0;
    for (const char* name : {"pocket_block", "counterbore_countersink", "boss_plate"}) {
        const Case c = make_case(name, kFine);
        FaceMap<std::int32_t> truth(c.mesh.num_faces());
        for (std::size_t f = 0; f < c.mesh.num_faces(); ++f)
            truth[FaceId(static_cast<std::uint32_t>(f))] =
                static_cast<std::int32_t>(c.mesh.cuts()[f]);
        const RegionBorders b = region_borders(c.mesh, truth);
        test::Rng rng(3);
        for (const VertexId v : b.corners) {
            std::vector<Surface> surfaces;
            std::vector<std::int32_t> seen;
            bool analytic = true;
            c.mesh.for_each_outgoing(v, [&](HalfedgeId h) {
                const std::int32_t face = truth[Mesh::face(h)];
                if (std::find(seen.begin(), seen.end(), face) != seen.end()) return;
                seen.push_back(face);
                const std::int32_t sidx = c.part.faces[static_cast<std::size_t>(face)].surface;
                if (sidx < 0) {
                    analytic = false;
                    return;
                }
                surfaces.push_back(
                    surface_from_record(c.part.mesh.surfaces[static_cast<std::size_t>(sidx)]));
            });
            if (!analytic) continue;
            const Vec3 truth_point = c.mesh.position(v);
            const Vec3 offset{0.03 * (2 * rng.uniform() - 1), 0.03 * (2 * rng.uniform() - 1),
                              0.03 * (2 * rng.uniform() - 1)};
            const CommonPoint p = common_point(surfaces, truth_point + offset);
            // Never farther from the surfaces than the start, never farther from the corner.
            double before = 0;
            for (const Surface& sf : surfaces)
                before = std::max(before, distance(sf, truth_point + offset));
            EXPECT_LE(p.residual, before) << name << " corner " << v.idx();
            const double moved = norm(p.point - truth_point);
            EXPECT_LE(moved, norm(offset) + 1e-6) << name << " corner " << v.idx();
            ++solved;
            // Three surfaces crossing there (normals spanning space) fix the point.
            bool crossing = false;
            for (std::size_t i = 0; i < surfaces.size() && !crossing; ++i)
                for (std::size_t j = i + 1; j < surfaces.size() && !crossing; ++j)
                    for (std::size_t k = j + 1; k < surfaces.size() && !crossing; ++k)
                        crossing = std::abs(dot(normal_at(surfaces[i], truth_point),
                                                cross(normal_at(surfaces[j], truth_point),
                                                      normal_at(surfaces[k], truth_point)))) > 0.1;
            if (crossing) {
                ++exact;
                EXPECT_LT(moved, 1e-5) << name << " corner " << v.idx();
                EXPECT_LT(p.residual, 1e-9) << name << " corner " << v.idx();
            }
        }
    }
    EXPECT_GT(solved, 50);
    EXPECT_GT(exact, 10);
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

// A cone's face as a CAD system may tessellate it: one row of slivers from rim to rim (8 tall,
// radii 10 to 14), each rim in steps of 30 degrees, the bottom's half a step off the top's, so
// that only the two end facets have an edge along a generator. Growing and merging left seven
// one-facet planes (pairwise merging never reaches the seven vertices a cone needs);
// merge_fans() grows one cone through them, taking its first facets on trust until a cone can
// be fitted (a cylinder, tried at six vertices, does not fit).
TEST(Segment, AConeFanOfOneFacetPlanesIsOneCone) {
    const double deg = std::numbers::pi / 180;
    const std::vector<double> top{0, 30, 60, 90}, bottom{0, 15, 45, 75, 90};
    TriangleSoup soup;
    const auto at = [&](double a, double z) {
        const double r = 10 + 0.5 * z;  // a half-angle of atan(1/2) about z
        return Vec3{r * std::cos(a * deg), r * std::sin(a * deg), z};
    };
    for (const double a : top) soup.points.push_back(at(a, 8));
    for (const double a : bottom) soup.points.push_back(at(a, 0));
    const auto nt = static_cast<std::uint32_t>(top.size());
    std::size_t i = 0, j = 0;  // a zipper: the rim whose next vertex comes first advances
    while (i + 1 < top.size() || j + 1 < bottom.size()) {
        const auto ti = static_cast<std::uint32_t>(i), bj = nt + static_cast<std::uint32_t>(j);
        if (j + 1 == bottom.size() || (i + 1 < top.size() && top[i + 1] <= bottom[j + 1])) {
            soup.triangles.push_back({ti, bj, ti + 1});
            ++i;
        } else {
            soup.triangles.push_back({ti, bj, bj + 1});
            ++j;
        }
    }
    ASSERT_EQ(soup.triangles.size(), 7u);
    const Mesh mesh = build_mesh(soup).value().mesh;
    const SegmentResult r = segment(mesh).value();
    ASSERT_EQ(r.regions.size(), 1u);
    const Surface& s = r.regions[0].fit.surface;
    EXPECT_EQ(s.kind, FitKind::kCone);
    EXPECT_NEAR(s.angle, std::atan(0.5), 1e-6);
    EXPECT_NEAR(std::abs(s.axis.z), 1, 1e-9);
}

}  // namespace
}  // namespace ncrev
