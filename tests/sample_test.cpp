// The sample parts know their answer; these tests check that the answer is right: the solids
// are valid, the written meshes are watertight and outward, the files agree with one another,
// and every vertex lies on the surface its truth JSON names (checked analytically, without
// OpenCASCADE). Parts are built at a coarse deflection (1 % of the diagonal) to stay fast;
// pocket_block is also checked at the default deflection.
#include "ncrev/sample.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <STEPControl_Reader.hxx>
#include <TopoDS_Shape.hxx>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "brep/check.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"
#include "scratch.h"

namespace ncrev {
namespace {

using nlohmann::json;

// Coarse enough that all parts build, mesh and check in a few seconds, fine enough that every
// feature still has facets of its own.
constexpr double kCoarseRelativeDeflection = 0.01;

std::filesystem::path test_dir() { return test::scratch_dir() / "samples"; }

/// Each part at the coarse deflection, built once for all tests.
const SamplePart& coarse_part(std::string_view name) {
    static std::map<std::string, SamplePart, std::less<>> cache;
    auto it = cache.find(name);
    if (it == cache.end()) {
        SampleOptions o;
        o.relative_deflection = kCoarseRelativeDeflection;
        Result<SamplePart> p = make_sample_part(name, o);
        if (!p) ADD_FAILURE() << name << ": " << p.error().describe();
        it = cache.emplace(std::string(name), p ? std::move(p).value() : SamplePart{}).first;
    }
    return it->second;
}

std::vector<std::string> part_names() {
    std::vector<std::string> v;
    for (const SamplePartInfo& p : sample_parts()) v.emplace_back(p.name);
    return v;
}

std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

Vec3 vec(const json& a) { return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()}; }

/// Distance from p to the surface a truth face names; negative when the kind has no
/// analytic form (free-form faces).
double surface_distance(const json& face, Vec3 p) {
    const std::string kind = face["kind"];
    const json& q = face["parameters"];
    if (kind == "plane") return std::abs(dot(p - vec(q["point"]), normalized(vec(q["normal"]))));
    if (kind == "sphere") return std::abs(norm(p - vec(q["center"])) - q["radius"].get<double>());
    // Axial frame: height h along the axis and distance rho from it.
    const auto axial = [&](Vec3 origin, Vec3 axis) {
        const Vec3 a = normalized(axis), w = p - origin;
        const double h = dot(w, a);
        return std::array<double, 2>{h, norm(w - h * a)};
    };
    if (kind == "cylinder") {
        return std::abs(axial(vec(q["axis_point"]), vec(q["axis_dir"]))[1] -
                        q["radius"].get<double>());
    }
    if (kind == "cone") {
        const auto [h, rho] = axial(vec(q["apex"]), vec(q["axis_dir"]));
        const double a = q["half_angle"].get<double>();
        // Distance to the generatrix ray from the apex in p's meridian half-plane.
        if (h * std::cos(a) + rho * std::sin(a) < 0) return std::hypot(h, rho);
        return std::abs(rho * std::cos(a) - h * std::sin(a));
    }
    if (kind == "torus") {
        const auto [h, rho] = axial(vec(q["center"]), vec(q["axis_dir"]));
        return std::abs(std::hypot(rho - q["major_radius"].get<double>(), h) -
                        q["minor_radius"].get<double>());
    }
    return -1;
}

TEST(SampleParts, ListsAtLeastTwelveDistinctDescribedParts) {
    const auto parts = sample_parts();
    EXPECT_GE(parts.size(), 12u);
    std::set<std::string_view> names;
    for (const SamplePartInfo& p : parts) {
        EXPECT_FALSE(p.description.empty()) << p.name;
        EXPECT_TRUE(is_sample_part(p.name));
        names.insert(p.name);
    }
    EXPECT_EQ(names.size(), parts.size());
    EXPECT_FALSE(is_sample_part("all"));
}

TEST(SampleParts, UnknownNameAndBadOptionsAreErrorsNotCrashes) {
    Result<SamplePart> p = make_sample_part("no_such_part");
    ASSERT_FALSE(p.ok());
    EXPECT_EQ(p.error().code, ErrorCode::kBadValue);
    SampleOptions o;
    o.angular_deflection = 0;
    EXPECT_FALSE(make_sample_part("pocket_block", o).ok());
    o = {};
    o.deflection = std::nan("");
    EXPECT_FALSE(make_sample_part("pocket_block", o).ok());
}

TEST(SampleParts, EveryPartIsAValidClosedSolidWithConsistentCounts) {
    for (const std::string& name : part_names()) {
        SCOPED_TRACE(name);
        const SamplePart& p = coarse_part(name);
        EXPECT_TRUE(p.solid.valid);
        EXPECT_TRUE(p.solid.closed);
        EXPECT_GT(p.solid.volume, 0);
        EXPECT_EQ(p.solid.num_faces, p.faces.size());
        // Dimensions in the 10-200 mm range of a machine shop part.
        const Vec3 size = p.solid.bbox.max - p.solid.bbox.min;
        EXPECT_GE(std::max({size.x, size.y, size.z}), 10.0);
        EXPECT_LE(std::max({size.x, size.y, size.z}), 200.0);
        ASSERT_EQ(p.labels.size(), p.mesh.num_facets());
        ASSERT_EQ(p.mesh.surface.size(), p.mesh.num_facets());
        std::vector<std::uint64_t> per_face(p.faces.size(), 0);
        for (std::size_t i = 0; i < p.labels.size(); ++i) {
            const auto f = static_cast<std::size_t>(p.labels[i]);
            ASSERT_LT(f, p.faces.size());
            ++per_face[f];
            EXPECT_EQ(p.mesh.cut[i], p.labels[i]);
            EXPECT_EQ(p.mesh.surface[i], p.faces[f].surface);
        }
        for (const SampleFace& f : p.faces) {
            EXPECT_EQ(per_face[f.index], f.num_facets);
            EXPECT_GT(f.num_facets, 0u) << "face " << f.index << " has no facet";
            EXPECT_EQ(f.surface >= 0, f.kind == "plane" || f.kind == "cylinder" ||
                                          f.kind == "cone" || f.kind == "sphere" ||
                                          f.kind == "torus");
        }
        // The topological weld found nodes that agree to the last float32 bit.
        EXPECT_EQ(p.weld.float32_mismatches, 0u);
        EXPECT_FALSE(p.step.empty());
    }
}

TEST(SampleParts, CoverTheMachinedSurfaceKinds) {
    std::set<std::string> kinds;
    for (const std::string& name : part_names()) {
        for (const SampleFace& f : coarse_part(name).faces) kinds.insert(f.kind);
    }
    for (const char* k : {"plane", "cylinder", "cone", "sphere", "torus", "bspline"}) {
        EXPECT_TRUE(kinds.count(k)) << k;
    }
}

/// The checks every written part must pass: what was read back from the files.
void check_written_part(const SamplePart& p, const std::filesystem::path& dir) {
    SCOPED_TRACE(p.name);
    Result<SampleFiles> files = write_sample_part(p, dir);
    ASSERT_TRUE(files.ok()) << files.error().describe();

    // STL: watertight and outward after an exact weld, one component; the volume within the
    // chordal error of the solid's: every facet is within `deflection` of the surface, so the
    // two differ by at most deflection x area.
    Result<TriangleSoup> stl = read_mesh_file(files->stl);
    ASSERT_TRUE(stl.ok()) << stl.error().describe();
    ASSERT_EQ(stl->num_facets(), p.mesh.num_facets());
    HealOptions exact;
    exact.weld_tolerance = 0;
    Result<BuildResult> built = build_mesh(*stl, exact);
    ASSERT_TRUE(built.ok()) << built.error().describe();
    const MeshStats st = compute_stats(built->mesh);
    EXPECT_TRUE(st.closed);
    EXPECT_EQ(st.boundary_edges, 0u);
    EXPECT_EQ(st.components, 1u);
    EXPECT_EQ(st.faces, p.mesh.num_facets());
    EXPECT_EQ(st.vertices, p.mesh.points.size());
    EXPECT_EQ(built->heal.flipped_facets, 0u);
    EXPECT_EQ(built->heal.components_turned_outward, 0u);
    EXPECT_EQ(built->heal.nonmanifold_edges, 0u);
    EXPECT_EQ(built->heal.degenerate_facets_removed, 0u);
    EXPECT_NEAR(st.volume, p.solid.volume, p.deflection * p.solid.area);
    EXPECT_GT(st.volume, 0);

    // Labels: one per facet, in STL order.
    std::istringstream labels(read_text(files->labels));
    std::vector<std::int32_t> read_labels;
    for (std::int32_t l = 0; labels >> l;) read_labels.push_back(l);
    EXPECT_EQ(read_labels, p.labels);

    // SRE: round-trips (same vertices, facets, attributes, surfaces, tools).
    Result<TriangleSoup> sre = read_mesh_file(files->sre);
    ASSERT_TRUE(sre.ok()) << sre.error().describe();
    EXPECT_EQ(sre->points, p.mesh.points);
    EXPECT_EQ(sre->triangles, p.mesh.triangles);
    EXPECT_EQ(sre->color, p.mesh.color);
    EXPECT_EQ(sre->cut, p.mesh.cut);
    EXPECT_EQ(sre->surface, p.mesh.surface);
    ASSERT_EQ(sre->surfaces.size(), p.mesh.surfaces.size());
    for (std::size_t i = 0; i < sre->surfaces.size(); ++i) {
        EXPECT_EQ(sre->surfaces[i].kind, p.mesh.surfaces[i].kind);
        EXPECT_EQ(sre->surfaces[i].params, p.mesh.surfaces[i].params);
    }
    EXPECT_EQ(sre->tools.size(), p.mesh.tools.size());
    // The SRE mesh itself is closed too.
    Result<BuildResult> sre_built = build_mesh(*sre, exact);
    ASSERT_TRUE(sre_built.ok());
    EXPECT_TRUE(compute_stats(sre_built->mesh).closed);
    EXPECT_EQ(sre_built->heal.flipped_facets, 0u);

    // Truth JSON: the file is the document; its counts match the mesh.
    const json truth = json::parse(read_text(files->truth));
    EXPECT_EQ(truth["part"], p.name);
    EXPECT_EQ(truth["faces"].size(), p.faces.size());
    EXPECT_EQ(truth["tessellation"]["facets"].get<std::size_t>(), p.mesh.num_facets());
    EXPECT_DOUBLE_EQ(truth["solid"]["volume"].get<double>(), p.solid.volume);

    // Every facet's vertices (as the STL stores them) lie on their face's surface, by the
    // truth parameters; the cone's SRE form names the same cone as its apex form.
    double worst = 0;
    for (std::size_t i = 0; i < p.labels.size(); ++i) {
        const json& face = truth["faces"][static_cast<std::size_t>(p.labels[i])];
        for (int k = 0; k < 3; ++k) {
            const double d = surface_distance(face, stl->points[stl->triangles[i][k]]);
            if (d < 0) break;
            worst = std::max(worst, d);
        }
    }
    EXPECT_LE(worst, p.deflection);
    for (const json& face : truth["faces"]) {
        if (face["kind"] != "cone") continue;
        const json& q = face["parameters"];
        const json& s = q["sre"];
        const double a = q["half_angle"];
        const Vec3 apex = vec(s["point"]) -
                          s["radius"].get<double>() / std::tan(a) * normalized(vec(s["axis_dir"]));
        EXPECT_LT(norm(apex - vec(q["apex"])), 1e-9 * (1 + norm(apex)));
        EXPECT_GT(a, 0);
        EXPECT_LT(a, 0.5 * M_PI);
        const SurfaceRecord& rec =
            p.mesh.surfaces[static_cast<std::size_t>(face["sre_surface"].get<int>())];
        EXPECT_EQ(rec.kind, SurfaceKind::kCone);
        EXPECT_DOUBLE_EQ(rec.params[7], a);
    }

    // STEP: reads back as one valid solid of the same volume.
    ASSERT_FALSE(files->step.empty());
    STEPControl_Reader reader;
    ASSERT_EQ(reader.ReadFile(files->step.c_str()), IFSelect_RetDone);
    ASSERT_GT(reader.TransferRoots(), 0);
    const TopoDS_Shape shape = reader.OneShape();
    EXPECT_TRUE(BRepCheck_Analyzer(shape).IsValid());
    const double volume = brep_detail::solid_volume(shape);
    EXPECT_NEAR(volume, p.solid.volume, 1e-6 * p.solid.volume);
}

TEST(SampleParts, WrittenFilesAgreeWithEachOtherAndWithTheSolid) {
    for (const std::string& name : part_names()) check_written_part(coarse_part(name), test_dir());
}

TEST(SampleParts, PocketBlockAtTheDefaultDeflection) {
    Result<SamplePart> p = make_sample_part("pocket_block");
    ASSERT_TRUE(p.ok()) << p.error().describe();
    EXPECT_DOUBLE_EQ(p->deflection, kSampleRelativeDeflection * p->solid.bbox.diagonal());
    EXPECT_DOUBLE_EQ(p->angular_deflection, kSampleAngularDeflection);
    // At this size the angular deflection (0.35 rad) already bounds the sag of the coarse
    // mesh, so the default need not have more facets; a five times finer one must.
    SampleOptions fine;
    fine.deflection = 0.2 * p->deflection;
    fine.with_step = false;
    Result<SamplePart> f = make_sample_part("pocket_block", fine);
    ASSERT_TRUE(f.ok());
    EXPECT_GT(f->mesh.num_facets(), p->mesh.num_facets());
    check_written_part(*p, test_dir() / "default");
}

TEST(SampleParts, SameSeedAndOptionsGiveByteIdenticalFiles) {
    const SamplePart& a = coarse_part("freeform_die");
    SampleOptions o;
    o.relative_deflection = kCoarseRelativeDeflection;
    Result<SamplePart> b = make_sample_part("freeform_die", o);
    ASSERT_TRUE(b.ok());
    const auto fa = write_sample_part(a, test_dir() / "det_a");
    const auto fb = write_sample_part(*b, test_dir() / "det_b");
    ASSERT_TRUE(fa.ok() && fb.ok());
    // Compared as booleans: a failure should not print a whole STEP file.
    EXPECT_TRUE(read_text(fa->stl) == read_text(fb->stl));
    EXPECT_TRUE(read_text(fa->sre) == read_text(fb->sre));
    EXPECT_TRUE(read_text(fa->step) == read_text(fb->step));
    EXPECT_TRUE(read_text(fa->labels) == read_text(fb->labels));
    EXPECT_TRUE(read_text(fa->truth) == read_text(fb->truth));
}

TEST(SampleParts, OtherSeedsVaryTheDimensionsAndStillGiveValidSolids) {
    for (const std::string& name : part_names()) {
        SCOPED_TRACE(name);
        const SamplePart& nominal = coarse_part(name);
        for (std::uint64_t seed : {1u, 2u, 3u}) {
            SampleOptions o;
            o.seed = seed;
            o.relative_deflection = 2 * kCoarseRelativeDeflection;
            o.with_step = false;
            Result<SamplePart> p = make_sample_part(name, o);
            ASSERT_TRUE(p.ok()) << "seed " << seed << ": " << p.error().describe();
            EXPECT_TRUE(p->solid.valid && p->solid.closed);
            EXPECT_NE(p->solid.volume, nominal.solid.volume);
            ASSERT_EQ(p->dimensions.size(), nominal.dimensions.size());
            bool differs = false;
            for (std::size_t i = 0; i < p->dimensions.size(); ++i) {
                EXPECT_EQ(p->dimensions[i].name, nominal.dimensions[i].name);
                differs = differs || p->dimensions[i].value != nominal.dimensions[i].value;
            }
            EXPECT_TRUE(differs);
            EXPECT_EQ(p->weld.float32_mismatches, 0u);
            // The variant's mesh is watertight and outward too.
            HealOptions exact;
            exact.weld_tolerance = 0;
            Result<BuildResult> built = build_mesh(p->mesh, exact);
            ASSERT_TRUE(built.ok());
            const MeshStats st = compute_stats(built->mesh);
            EXPECT_TRUE(st.closed);
            EXPECT_EQ(st.components, 1u);
            EXPECT_EQ(built->heal.flipped_facets, 0u);
            EXPECT_EQ(built->heal.components_turned_outward, 0u);
            EXPECT_NEAR(st.volume, p->solid.volume, p->deflection * p->solid.area);
        }
    }
}

struct CliRun {
    int code = -1;
    std::string out;
};

CliRun run_cli(const std::string& args) {
    CliRun r;
    FILE* pipe = ::popen((std::string(NCREV_CLI_PATH) + " " + args + " 2>/dev/null").c_str(), "r");
    if (pipe == nullptr) return r;
    char buf[4096];
    std::size_t n = 0;
    while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
    const int status = ::pclose(pipe);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

TEST(SampleCli, WritesOnePartAndPrintsOneJsonDocument) {
    const std::filesystem::path out = test_dir() / "cli";
    const CliRun r = run_cli("sample slot_plate -o " + out.string() + " --json");
    ASSERT_EQ(r.code, 0);
    const json doc = json::parse(r.out);  // throws (fails) unless exactly one document
    ASSERT_EQ(doc["parts"].size(), 1u);
    EXPECT_EQ(doc["parts"][0]["name"], "slot_plate");
    for (const char* ext : {".stl", ".sre", ".step", ".labels", ".truth.json"}) {
        EXPECT_TRUE(std::filesystem::exists(out / "slot_plate" / (std::string("slot_plate") + ext)))
            << ext;
    }
}

TEST(SampleCli, UsageErrorsExitWithOne) {
    EXPECT_EQ(run_cli("sample no_such_part -o " + (test_dir() / "cli").string()).code, 1);
    EXPECT_EQ(run_cli("sample pocket_block").code, 1);
    EXPECT_EQ(run_cli("sample pocket_block -o /tmp --deflection -1").code, 1);
    const CliRun list = run_cli("sample --list");
    EXPECT_EQ(list.code, 0);
    EXPECT_NE(list.out.find("pocket_block"), std::string::npos);
}

TEST(SampleCli, UnwritableOutputExitsWithFour) {
    EXPECT_EQ(run_cli("sample slot_plate -o /proc/ncrev_cannot_write").code, 4);
}

}  // namespace
}  // namespace ncrev
