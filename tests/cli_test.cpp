// End-to-end: the ncrev binary as a user runs it (exit codes, stdout holds exactly one JSON
// document, errors name the file and the place).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "ncrev/curvature.h"
#include "ncrev/io.h"
#include "scratch.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

struct CliRun {
    int code = -1;
    std::string out, err;
};

CliRun run(const std::string& args) {
    // ctest runs tests in parallel processes: one stderr file per process and call.
    static int calls = 0;
    const auto err_path = test::scratch_dir() / ("cli." + std::to_string(++calls) + ".err");
    const std::string cmd = std::string(NCREV_CLI_PATH) + " " + args + " 2>" + err_path.string();
    CliRun r;
    FILE* p = ::popen(cmd.c_str(), "r");
    if (p == nullptr) return r;
    std::array<char, 4096> buf;
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
    const int status = ::pclose(p);
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    {
        std::ifstream e(err_path);
        r.err.assign(std::istreambuf_iterator<char>(e), {});
    }
    std::filesystem::remove(err_path);
    return r;
}

std::filesystem::path write_temp(const std::string& name, const std::vector<std::byte>& bytes) {
    const auto path = test::scratch_dir() / name;
    EXPECT_TRUE(write_file_atomic(path, bytes).ok());
    return path;
}

TEST(CliInfo, PrintsOneJsonDocumentWithTheDocumentedKeys) {
    auto m = test::merge(test::cube(), test::cube({3, 0, 0}, 2.0));
    m.triangles.push_back(m.triangles[0]);  // a duplicate
    const auto path = write_temp("ncrev_cli_cubes.stl", encode_stl_binary(m.points, m.triangles));
    const CliRun r = run("info --json " + path.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);  // throws (fails the test) unless one document
    EXPECT_EQ(j["input"]["format"], "stl-binary");
    EXPECT_EQ(j["input"]["facets"], 25);
    EXPECT_EQ(j["input"]["unit"], "mm");
    EXPECT_EQ(j["healing"]["duplicate_facets_removed"], 1);
    for (const char* k :
         {"tolerance", "welded_vertices", "degenerate_facets_removed", "flipped_facets",
          "components_turned_outward", "nonmanifold_edges", "nonmanifold_vertices"}) {
        EXPECT_TRUE(j["healing"].contains(k)) << k;
    }
    EXPECT_EQ(j["mesh"]["vertices"], 16);
    EXPECT_EQ(j["mesh"]["facets"], 24);
    EXPECT_EQ(j["mesh"]["edges"], 36);
    EXPECT_EQ(j["mesh"]["components"], 2);
    EXPECT_EQ(j["mesh"]["boundary_loops"], 0);
    EXPECT_EQ(j["mesh"]["boundary_edges"], 0);
    EXPECT_EQ(j["mesh"]["euler_characteristic"], 4);
    EXPECT_EQ(j["mesh"]["closed"], true);
    EXPECT_DOUBLE_EQ(j["mesh"]["volume"].template get<double>(), 9.0);
    EXPECT_DOUBLE_EQ(j["mesh"]["area"].template get<double>(), 30.0);
    EXPECT_EQ(j["mesh"]["bbox"][1][0], 5.0);
    std::filesystem::remove(path);
}

// A cube of side 3 with a cubic cavity of side 1, the cavity's shell facing out of it as
// some writers leave it: healing faces it into the cavity, the volume is the material's, and
// reverse builds one solid with a void.
TEST(CliInfo, ACavityIsCountedAndItsVolumeIsNotMaterial) {
    auto inner = test::cube({1, 1, 1}, 1.0);
    const auto m = test::merge(test::cube({0, 0, 0}, 3.0), inner);
    const auto path = write_temp("ncrev_cli_cavity.stl", encode_stl_binary(m.points, m.triangles));
    const CliRun r = run("info --json " + path.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["healing"]["cavities"], 1);
    EXPECT_EQ(j["healing"]["cavities_turned_inward"], 1);
    EXPECT_EQ(j["healing"]["nesting_checked"], true);
    EXPECT_DOUBLE_EQ(j["mesh"]["volume"].template get<double>(), 26.0);
    const CliRun text = run("info " + path.string());
    EXPECT_NE(text.out.find("cavities: 1"), std::string::npos) << text.out;
    EXPECT_NE(text.err.find("1 cavity shells turned inward"), std::string::npos) << text.err;
    const auto step = test::scratch_dir() / "ncrev_cli_cavity.step";
    for (const char* method : {"auto", "planar"}) {
        const CliRun rev = run("reverse " + path.string() + " -o " + step.string() + " --method " +
                               method + " --json");
        ASSERT_EQ(rev.code, 0) << method << rev.err;
        const auto jr = nlohmann::json::parse(rev.out);
        EXPECT_EQ(jr["reverse"]["bodies"], 1) << method;
        EXPECT_EQ(jr["reverse"]["voids"], 1) << method;
        EXPECT_EQ(jr["reverse"]["faces"], 12) << method;
        const CliRun said =
            run("reverse " + path.string() + " -o " + step.string() + " --method " + method);
        EXPECT_NE(said.err.find("closed solid with 1 cavity"), std::string::npos) << said.err;
    }
    std::filesystem::remove(step);
    std::filesystem::remove(path);
}

// Two cubes overlapping without their union (a part's bodies written as one mesh): info and
// reverse say they cross; reverse keeps each a solid of its own, the volume both cubes'.
TEST(CliInfo, PartsThatCrossAreReported) {
    const auto m = test::merge(test::cube({0, 0, 0}, 2.0), test::cube({1, 1, 1}, 2.0));
    const auto path = write_temp("ncrev_cli_cross.stl", encode_stl_binary(m.points, m.triangles));
    const CliRun r = run("info --json " + path.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["healing"]["crossing_components"], 2);
    EXPECT_EQ(j["healing"]["crossing_checked"], true);
    EXPECT_EQ(j["healing"]["cavities"], 0);
    EXPECT_NE(r.err.find("2 closed components cross one another"), std::string::npos) << r.err;
    const auto step = test::scratch_dir() / "ncrev_cli_cross.step";
    for (const char* method : {"auto", "planar"}) {
        const CliRun rev = run("reverse " + path.string() + " -o " + step.string() + " --method " +
                               method + " --json");
        ASSERT_EQ(rev.code, 0) << method << rev.err;
        const auto jr = nlohmann::json::parse(rev.out);
        EXPECT_EQ(jr["reverse"]["bodies"], 2) << method;
        EXPECT_EQ(jr["healing"]["crossing_components"], 2) << method;
        EXPECT_NEAR(jr["reverse"]["solid_volume"].template get<double>(), 16.0, 1e-9) << method;
        bool warned = false;
        for (const auto& w : jr["warnings"])
            warned = warned || w.get<std::string>().find("cross one another") != std::string::npos;
        EXPECT_TRUE(warned) << method;
    }
    std::filesystem::remove(step);
    std::filesystem::remove(path);
}

// A cube with a corner pushed through the opposite wall: `info` and `reverse` say the mesh
// passes through itself, and where; `reverse` still writes what it built, unless told to
// write solids only.
TEST(CliInfo, AMeshThatPassesThroughItselfIsReported) {
    auto m = test::cube({0, 0, 0}, 10.0);
    for (Vec3& p : m.points)
        if (p.x == 10 && p.y == 10 && p.z == 10) p = Vec3{-3, 4, 6.5};  // off the diagonals
    const auto path = write_temp("ncrev_cli_self.stl", encode_stl_binary(m.points, m.triangles));
    const CliRun r = run("info --json " + path.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_GT(j["healing"]["self_intersections"].get<int>(), 0);
    EXPECT_EQ(j["healing"]["self_intersection_checked"], true);
    EXPECT_NEAR(j["healing"]["self_intersection_at"][0].get<double>(), 0.0, 1e-9);  // x = 0 wall
    EXPECT_NE(r.err.find("the mesh passes through itself"), std::string::npos) << r.err;
    const auto step = test::scratch_dir() / "ncrev_cli_self.step";
    const CliRun rev = run("reverse " + path.string() + " -o " + step.string() + " --json");
    ASSERT_EQ(rev.code, 0) << rev.err;
    const auto jr = nlohmann::json::parse(rev.out);
    EXPECT_EQ(jr["healing"]["self_intersections"], j["healing"]["self_intersections"]);
    bool warned = false;
    for (const auto& w : jr["warnings"])
        warned = warned || w.get<std::string>().find("passes through itself") != std::string::npos;
    EXPECT_TRUE(warned);
    std::filesystem::remove(step);
    // Not a solid a CAD system takes: --require-solid writes nothing.
    const CliRun required =
        run("reverse " + path.string() + " -o " + step.string() + " --require-solid");
    EXPECT_EQ(required.code, 3) << required.err;
    EXPECT_NE(required.err.find("passes through itself"), std::string::npos) << required.err;
    EXPECT_FALSE(std::filesystem::exists(step));
    const auto cube = test::cube();
    const auto clean_path =
        write_temp("ncrev_cli_clean.stl", encode_stl_binary(cube.points, cube.triangles));
    const CliRun clean = run("info --json " + clean_path.string());
    ASSERT_EQ(clean.code, 0) << clean.err;
    EXPECT_EQ(nlohmann::json::parse(clean.out)["healing"]["self_intersections"], 0);
    for (const auto& f : {step, path, clean_path}) std::filesystem::remove(f);
}

// A ball that lost a facet: healing fills the hole and says so; --keep-holes shows it open.
TEST(CliInfo, FillsASmallHoleUnlessToldToKeepIt) {
    auto m = test::icosphere(10.0, 3);
    m.triangles.erase(m.triangles.begin() + 7);
    const auto path = write_temp("ncrev_cli_hole.stl", encode_stl_binary(m.points, m.triangles));
    const CliRun filled = run("info --json " + path.string());
    ASSERT_EQ(filled.code, 0) << filled.err;
    const auto j = nlohmann::json::parse(filled.out);
    EXPECT_EQ(j["healing"]["holes_filled"], 1);
    EXPECT_EQ(j["healing"]["hole_facets_added"], 1);
    EXPECT_EQ(j["mesh"]["closed"], true);
    EXPECT_EQ(j["mesh"]["facets"], m.triangles.size() + 1);
    const CliRun kept = run("info --json --keep-holes " + path.string());
    ASSERT_EQ(kept.code, 0) << kept.err;
    const auto k = nlohmann::json::parse(kept.out);
    EXPECT_EQ(k["healing"]["holes_filled"], 0);
    EXPECT_EQ(k["mesh"]["closed"], false);
    EXPECT_EQ(k["mesh"]["boundary_loops"], 1);
    std::filesystem::remove(path);
}

TEST(CliInfo, BadInputExitsTwoWithFileAndPlaceAndNoStdout) {
    const auto path =
        write_temp("ncrev_cli_bad.stl", test::bytes_of("solid x\nfacet normal 0 0 1\nouter lop\n"));
    const CliRun r = run("info --json " + path.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find("error: " + path.string() + ": line 3: expected 'loop'"),
              std::string::npos)
        << r.err;
    std::filesystem::remove(path);
    const CliRun missing = run("info /nonexistent/file.stl");
    EXPECT_EQ(missing.code, 2);
    EXPECT_NE(missing.err.find("/nonexistent/file.stl"), std::string::npos);
}

TEST(CliInfo, UsageErrorsExitOne) {
    EXPECT_EQ(run("info").code, 1);
    EXPECT_EQ(run("no-such-command").code, 1);
    EXPECT_EQ(run("info --no-such-flag x.stl").code, 1);
    const CliRun help = run("info --help");
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("--json"), std::string::npos);
}

TEST(CliInfo, ReadsSreAndReportsItsUnit) {
    const std::string text =
        "SRE 1\nunit inch\nsurfaces 0\nvertices 4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nfacets 4\n"
        "0 2 1 0 -1 -1\n0 1 3 0 -1 -1\n0 3 2 0 -1 -1\n1 2 3 0 -1 -1\n";
    const auto path = write_temp("ncrev_cli_tet.sre", test::bytes_of(text));
    const CliRun r = run("info --json " + path.string());
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["input"]["format"], "sre");
    EXPECT_EQ(j["input"]["unit"], "inch");
    EXPECT_EQ(j["mesh"]["closed"], true);
    EXPECT_NEAR(j["mesh"]["volume"].template get<double>(), 1.0 / 6.0, 1e-15);
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

TEST(CliReverse, WritesAStepAndAReportAndRefusesToOverwriteItsInput) {
    const auto c = test::cube({0, 0, 0}, 10.0);
    const auto stl = write_temp("ncrev_cli_rev_cube.stl", encode_stl_binary(c.points, c.triangles));
    const auto step = test::scratch_dir() / "ncrev_cli_rev_cube.step";
    const auto report = test::scratch_dir() / "ncrev_cli_rev_cube.json";
    std::filesystem::remove(step);
    const CliRun r = run("reverse " + stl.string() + " -o " + step.string() +
                         " --method planar --report " + report.string() + " --json -q");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["reverse"]["faces"], 6);
    EXPECT_EQ(j["reverse"]["closed_valid_solid"], true);
    EXPECT_TRUE(std::filesystem::exists(step));
    std::ifstream in(report);
    EXPECT_EQ(nlohmann::json::parse(in), j);
    // The input as the output: refused, with no warning about its extension first.
    const CliRun self = run("reverse " + stl.string() + " -o " + stl.string());
    EXPECT_EQ(self.code, 1);
    EXPECT_NE(self.err.find("is the input; ncrev never overwrites its input"), std::string::npos)
        << self.err;
    EXPECT_EQ(self.err.find("warning"), std::string::npos) << self.err;
    EXPECT_EQ(std::filesystem::file_size(stl), 84u + 50u * 12u);  // untouched
    EXPECT_EQ(run("reverse " + stl.string() + " -o /nonexistent/dir/x.step -q").code, 4);
    // An unknown keyword is named with the ones there are; keywords take any case.
    const CliRun nurbs =
        run("reverse " + stl.string() + " -o " + step.string() + " --method nurbs");
    EXPECT_EQ(nurbs.code, 1);
    EXPECT_NE(nurbs.err.find("--method: 'nurbs' is not one of: auto, facets, planar, surfaces"),
              std::string::npos)
        << nurbs.err;
    EXPECT_EQ(run("reverse " + stl.string() + " -o " + step.string() + " --method PLANAR -q").code,
              0);
    std::filesystem::remove(step);
    std::filesystem::remove(report);
    std::filesystem::remove(stl);
}

// A folder given where a file is to be written is refused before any work (exit 4), not
// when the result is renamed into place after it; numbers out of range are named plainly.
TEST(CliReverse, RefusesAFolderForAnOutputAndNamesBadNumbersPlainly) {
    const auto c = test::cube({0, 0, 0}, 10.0);
    const auto stl = write_temp("ncrev_cli_dir_cube.stl", encode_stl_binary(c.points, c.triangles));
    // An input that fails to read: a command that read before it looked at its outputs would
    // exit 2, not 4.
    const auto unreadable = test::scratch_dir() / "truncated.stl";
    { std::ofstream(unreadable) << "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"; }
    const auto dir = test::scratch_dir() / "a_folder";
    std::filesystem::create_directories(dir);
    const auto step = test::scratch_dir() / "x.step", ply = test::scratch_dir() / "x.ply";
    for (const auto& in : {stl, unreadable}) {
        for (const std::string& args :
             {"reverse " + in.string() + " -o " + dir.string(),
              "reverse " + in.string() + " -o " + step.string() + " --labels " + dir.string(),
              "reverse " + in.string() + " -o " + step.string() + " --report " + dir.string(),
              "segment " + in.string() + " -o " + dir.string(),
              "segment " + in.string() + " -o " + ply.string() + " --labels " + dir.string(),
              "curvature " + in.string() + " -o " + dir.string()}) {
            const CliRun r = run(args);
            EXPECT_EQ(r.code, 4) << args << "\n" << r.err;
            EXPECT_NE(r.err.find(dir.string() + ": is a directory"), std::string::npos) << r.err;
        }
    }
    EXPECT_FALSE(std::filesystem::exists(step));
    EXPECT_FALSE(std::filesystem::exists(ply));
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    for (const char* bad : {"-1", "0", "abc", "inf"}) {
        const CliRun r = run("segment " + stl.string() + " -o " +
                             (test::scratch_dir() / "x.ply").string() + " --tolerance " + bad);
        EXPECT_EQ(r.code, 1) << bad;
        EXPECT_NE(
            r.err.find(std::string("--tolerance: must be a positive number, got '") + bad + "'"),
            std::string::npos)
            << r.err;
    }
    // Written as STEP whatever its name, and said so.
    const auto odd = test::scratch_dir() / "cube.stl";
    const CliRun named =
        run("reverse " + stl.string() + " -o " + odd.string() + " --method planar");
    EXPECT_EQ(named.code, 0) << named.err;
    EXPECT_NE(named.err.find("written as STEP whatever its name"), std::string::npos) << named.err;
    std::ifstream written(odd);
    std::string first;
    std::getline(written, first);
    EXPECT_EQ(first.rfind("ISO-10303-21;", 0), 0u) << first;
}

TEST(CliReverse, OpenMeshWithRequireSolidExitsThreeAndWritesNothing) {
    auto c = test::cube({0, 0, 0}, 10.0);
    c.triangles.resize(c.triangles.size() - 2);  // an open box: no hole healing fills
    const auto stl = write_temp("ncrev_cli_rev_open.stl", encode_stl_binary(c.points, c.triangles));
    const auto step = test::scratch_dir() / "ncrev_cli_rev_open.step";
    std::filesystem::remove(step);
    const CliRun r = run("reverse " + stl.string() + " -o " + step.string() + " --require-solid");
    EXPECT_EQ(r.code, 3);
    EXPECT_FALSE(std::filesystem::exists(step));
    const CliRun shell = run("reverse " + stl.string() + " -o " + step.string());
    EXPECT_EQ(shell.code, 0);
    EXPECT_NE(shell.err.find("warning: the mesh is open"), std::string::npos) << shell.err;
    std::filesystem::remove(step);
    std::filesystem::remove(stl);
    // A closed cube with a stray facet beside it: the cube is the solid, the facet left out.
    auto stray = test::cube({0, 0, 0}, 10.0);
    const auto base = static_cast<std::uint32_t>(stray.points.size());
    stray.points.insert(stray.points.end(), {{20, 0, 0}, {21, 0, 0}, {20, 1, 0}});
    stray.triangles.push_back({base, base + 1, base + 2});
    const auto with_stray =
        write_temp("ncrev_cli_rev_stray.stl", encode_stl_binary(stray.points, stray.triangles));
    const CliRun solid =
        run("reverse " + with_stray.string() + " -o " + step.string() + " --require-solid");
    EXPECT_EQ(solid.code, 0) << solid.err;
    EXPECT_NE(solid.err.find("1 open component of the mesh (1 facet"), std::string::npos)
        << solid.err;
    EXPECT_NE(solid.err.find("closed solid"), std::string::npos) << solid.err;
    std::filesystem::remove(step);
    std::filesystem::remove(with_stray);
}

// The default method on the bundled example: the true faces, the extended report, labels in
// input order and the regions PLY; --method surfaces refuses an open mesh (exit 3).
TEST(CliReverse, AutoGivesTheTrueFacesWithLabelsSegmentsAndReport) {
    const auto stl = std::filesystem::path(NCREV_SOURCE_DIR) / "examples" / "pocket_block.stl";
    const auto dir = test::scratch_dir();
    const auto step = dir / "ncrev_cli_auto.step", labels = dir / "ncrev_cli_auto.labels",
               ply = dir / "ncrev_cli_auto.ply";
    const CliRun r = run("reverse " + stl.string() + " -o " + step.string() + " --labels " +
                         labels.string() + " --segments " + ply.string() + " --json -q");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const auto& rev = j["reverse"];
    EXPECT_EQ(rev["method"], "auto");
    EXPECT_EQ(rev["faces"], 27);
    EXPECT_EQ(rev["regions"], 27);
    EXPECT_EQ(rev["faces_by_kind"]["torus"], 4);
    EXPECT_TRUE(rev["fallbacks"].empty());
    EXPECT_EQ(rev["closed_valid_solid"], true);
    EXPECT_LT(std::abs(rev["volume_difference"].get<double>()), 1e-3);
    EXPECT_GT(rev["deviation"]["mesh_to_solid"]["points"].get<int>(), 0);
    EXPECT_LT(rev["deviation"]["mesh_to_solid"]["max"].get<double>(),
              2 * rev["segment"]["chordal_deflection"].get<double>());
    ASSERT_FALSE(rev["segment"]["steps"].empty());  // the segmentation's steps, timed
    EXPECT_EQ(rev["segment"]["steps"][0]["name"], "edges");
    std::ifstream in(labels);
    std::set<int> ids;
    std::size_t lines = 0;
    for (int id = 0; in >> id; ++lines) ids.insert(id);
    EXPECT_EQ(lines, 900u);
    EXPECT_EQ(ids.size(), 27u);
    EXPECT_GT(std::filesystem::file_size(ply), 900u * 13u);
    EXPECT_EQ(
        run("reverse " + stl.string() + " -o " + step.string() + " --labels " + stl.string()).code,
        1);
    for (const auto& p : {step, labels, ply}) std::filesystem::remove(p);

    auto c = test::cube({0, 0, 0}, 10.0);
    c.triangles.resize(c.triangles.size() - 2);  // an open box: no hole healing fills
    const auto open =
        write_temp("ncrev_cli_surfaces_open.stl", encode_stl_binary(c.points, c.triangles));
    const CliRun s =
        run("reverse " + open.string() + " -o " + step.string() + " --method surfaces");
    EXPECT_EQ(s.code, 3);
    EXPECT_FALSE(std::filesystem::exists(step));
    std::filesystem::remove(open);
}

/// The vertex records of a PLY written by `ncrev curvature`, after checking its header.
struct CurvatureVertex {
    float x, y, z, k1, k2, shape_index, curvedness;
    std::uint8_t type, high, red, green, blue;
};
std::vector<CurvatureVertex> read_curvature_ply(const std::filesystem::path& path) {
    std::ifstream f(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(f)), {});
    const std::size_t end = text.find("end_header\n");
    EXPECT_NE(end, std::string::npos);
    const std::string header = text.substr(0, end);
    const std::string want =
        "property float x\nproperty float y\nproperty float z\nproperty float k1\n"
        "property float k2\nproperty float shape_index\nproperty float curvedness\n"
        "property uchar type\nproperty uchar high\nproperty uchar red\nproperty uchar green\n"
        "property uchar blue\nelement face ";
    EXPECT_NE(header.find(want), std::string::npos) << header;
    EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
    const std::size_t at = header.find("element vertex ");
    const std::size_t n = std::stoul(header.substr(at + 15));
    std::vector<CurvatureVertex> v(n);
    const char* p = text.data() + end + 11;
    EXPECT_GE(text.size() - (end + 11), n * 33);
    for (std::size_t i = 0; i < n && text.size() - (end + 11) >= n * 33; ++i, p += 33) {
        std::memcpy(&v[i], p, 28);
        std::memcpy(&v[i].type, p + 28, 5);
    }
    return v;
}

TEST(CliCurvature, WritesTheTypedPlyAndOneJsonDocument) {
    const auto m = test::icosphere(5.0, 5);
    const auto in = write_temp("ncrev_cli_sphere.stl", encode_stl_binary(m.points, m.triangles));
    const auto out = test::scratch_dir() / "ncrev_cli_sphere.ply";
    std::filesystem::remove(out);
    const CliRun r = run("curvature " + in.string() + " -o " + out.string() + " --json -q");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const auto& c = j["curvature"];
    EXPECT_EQ(c["estimator"], "plain");
    // The CLI runs the library's default neighbourhood.
    EXPECT_EQ(c["neighbourhood"].get<std::string>().rfind("3 smoothing passes", 0), 0u)
        << c["neighbourhood"];
    EXPECT_GT(c["thresholds"]["planar_curvedness"].get<double>(), 0.0);
    EXPECT_EQ(c["thresholds"]["sharp_edge_angle"], kDefaultSharpEdgeAngle);
    std::uint64_t total = 0;
    for (const auto& [name, n] : c["vertices_by_type"].items()) total += n.get<std::uint64_t>();
    EXPECT_EQ(total, j["mesh"]["vertices"].get<std::uint64_t>());
    EXPECT_EQ(c["vertices_by_type"]["cap"].get<std::uint64_t>(), total);
    const auto v = read_curvature_ply(out);
    ASSERT_EQ(v.size(), total);
    for (const CurvatureVertex& x : v) {
        EXPECT_EQ(x.type, 9);
        EXPECT_EQ(x.high, 0);
        EXPECT_NEAR(x.k1, 0.2, 0.01);
        EXPECT_NEAR(x.k2, 0.2, 0.01);
        EXPECT_NEAR(x.shape_index, 1.0, 0.05);
        EXPECT_EQ(x.red, 220);  // the color of "cap"
    }
    const CliRun k = run("curvature " + in.string() + " -o " + out.string() +
                         " --json -q --neighbourhood kernel");
    ASSERT_EQ(k.code, 0) << k.err;
    EXPECT_EQ(nlohmann::json::parse(k.out)["curvature"]["neighbourhood"].get<std::string>().rfind(
                  "kernel", 0),
              0u);
    // Without --json: a text summary, and the same PLY.
    const CliRun t = run("curvature " + in.string() + " -o " + out.string() + " -q");
    ASSERT_EQ(t.code, 0) << t.err;
    EXPECT_NE(t.out.find("types: plane 0"), std::string::npos) << t.out;
}

TEST(CliCurvature, BadInputAndUsageErrorsWriteNothing) {
    const auto out = test::scratch_dir() / "ncrev_cli_bad.ply";
    std::filesystem::remove(out);
    const auto bad =
        write_temp("ncrev_cli_bad.stl", test::bytes_of("solid x\n facet normal 0 0 1\n"));
    const CliRun r = run("curvature " + bad.string() + " -o " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_TRUE(r.out.empty());
    EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    const auto m = test::cube();
    const auto in = write_temp("ncrev_cli_cube_c.stl", encode_stl_binary(m.points, m.triangles));
    EXPECT_EQ(run("curvature " + in.string() + " -o " + in.string()).code, 1);
    EXPECT_EQ(
        run("curvature " + in.string() + " -o " + out.string() + " --neighbourhood geodesic").code,
        1);
    EXPECT_EQ(run("curvature " + in.string() + " -o " + out.string() + " --estimator fancy").code,
              1);
    EXPECT_FALSE(std::filesystem::exists(out));
    // The cube's corners and edges are all high-curvature points.
    const CliRun ok = run("curvature " + in.string() + " -o " + out.string() + " --json -q");
    ASSERT_EQ(ok.code, 0) << ok.err;
    EXPECT_EQ(nlohmann::json::parse(ok.out)["curvature"]["high_points"], 8);
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

// The spherical pocket's end walls are 2-facet planes whose vertices an intersection put 1e-7
// off x = 0 and x = 90: fitted, a normal leans by 4e-9; snapped (the default), they are exactly
// -x and +x; --no-snap keeps the fits.
TEST(CliSegment, SnapsToRoundValuesUnlessTold) {
    const auto dir = test::scratch_dir() / "cli_segment_snap";
    std::filesystem::remove_all(dir);
    ASSERT_EQ(run("sample spherical_pocket -q -o " + dir.string()).code, 0);
    const auto stl = dir / "spherical_pocket" / "spherical_pocket.stl";
    const auto ply = dir / "regions.ply";
    auto leaning_planes = [](const nlohmann::json& j) {
        int n = 0;
        for (const auto& g : j["regions"]) {
            if (g["kind"] != "plane") continue;
            int zeros = 0;
            for (const auto& c : g["params"]["normal"]) zeros += c.get<double>() == 0.0;
            n += zeros != 2;
        }
        return n;
    };
    const CliRun snapped = run("segment " + stl.string() + " -o " + ply.string() + " --json -q");
    ASSERT_EQ(snapped.code, 0) << snapped.err;
    const auto js = nlohmann::json::parse(snapped.out);
    EXPECT_GE(js["segment"]["snapped"].get<int>(), 2);
    EXPECT_EQ(leaning_planes(js), 0);
    const CliRun free =
        run("segment " + stl.string() + " -o " + ply.string() + " --no-snap --json -q");
    ASSERT_EQ(free.code, 0) << free.err;
    const auto jf = nlohmann::json::parse(free.out);
    EXPECT_EQ(jf["segment"]["snapped"].get<int>(), 0);
    EXPECT_GE(leaning_planes(jf), 1);
    EXPECT_EQ(jf["regions"].size(), js["regions"].size());
}

TEST(CliSegment, WritesRegionsLabelsAndOneJsonDocument) {
    const auto dir = test::scratch_dir() / "cli_segment";
    std::filesystem::remove_all(dir);
    ASSERT_EQ(run("sample slot_plate -q -o " + dir.string()).code, 0);
    const auto stl = dir / "slot_plate" / "slot_plate.stl";
    const auto ply = dir / "regions.ply", labels = dir / "regions.labels";
    const CliRun r = run("segment " + stl.string() + " -o " + ply.string() + " --labels " +
                         labels.string() + " --json -q");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["segment"]["method"], "facets");
    EXPECT_GT(j["segment"]["tolerance"].get<double>(), 0.0);
    ASSERT_EQ(j["segment"]["steps"].size(), 6u);  // edges, grow, merge, freeform, refine, fit
    EXPECT_EQ(j["segment"]["steps"][1]["name"], "grow");
    EXPECT_GE(j["segment"]["steps"][1]["seconds"].get<double>(), 0.0);
    const auto& regions = j["regions"];
    ASSERT_EQ(regions.size(), 15u);  // the slot plate's faces
    std::uint64_t facets = 0;
    for (std::size_t i = 0; i < regions.size(); ++i) {
        const auto& g = regions[i];
        EXPECT_EQ(g["id"], static_cast<int>(i));
        facets += g["facets"].get<std::uint64_t>();
        const std::string kind = g["kind"];
        if (kind == "plane") {
            EXPECT_EQ(g["params"]["point"].size(), 3u);
            EXPECT_EQ(g["params"]["normal"].size(), 3u);
        } else {
            ASSERT_EQ(kind, "cylinder");
            EXPECT_EQ(g["params"]["axis_point"].size(), 3u);
            EXPECT_EQ(g["params"]["axis_dir"].size(), 3u);
            EXPECT_GT(g["params"]["radius"].get<double>(), 0.0);
        }
        EXPECT_GT(g["area"].get<double>(), 0.0);
        EXPECT_LE(g["max"].get<double>(), j["segment"]["tolerance"].get<double>());
    }
    EXPECT_EQ(facets, j["mesh"]["facets"].get<std::uint64_t>());
    // One label per input facet; the true labels and ours describe the same partition.
    std::ifstream lf(labels), tf(dir / "slot_plate" / "slot_plate.labels");
    std::vector<int> ours, truth;
    for (int x; lf >> x;) ours.push_back(x);
    for (int x; tf >> x;) truth.push_back(x);
    ASSERT_EQ(ours.size(), truth.size());
    std::map<int, int> ours_to_truth;
    for (std::size_t i = 0; i < ours.size(); ++i) {
        const auto [it, fresh] = ours_to_truth.emplace(ours[i], truth[i]);
        EXPECT_EQ(it->second, truth[i]) << "facet " << i;
    }
    std::ifstream pf(ply, std::ios::binary);
    std::string head(400, '\0');
    pf.read(head.data(), 400);
    EXPECT_NE(head.find("property int region\nproperty uchar red"), std::string::npos);
    // The paper method from the CLI, and an SRE input keeping its surfaces.
    const CliRun paper =
        run("segment " + stl.string() + " -o " + ply.string() + " --method paper --json -q");
    ASSERT_EQ(paper.code, 0) << paper.err;
    EXPECT_EQ(nlohmann::json::parse(paper.out)["segment"]["method"], "paper");
    const CliRun sre = run("segment " + (dir / "slot_plate" / "slot_plate.sre").string() + " -o " +
                           ply.string() + " --json -q");
    ASSERT_EQ(sre.code, 0) << sre.err;
    const auto js = nlohmann::json::parse(sre.out);
    EXPECT_EQ(js["segment"]["given_facets"], js["mesh"]["facets"]);
    std::filesystem::remove_all(dir);
}

TEST(CliSegment, RefusesToOverwriteItsInputAndReportsBadInput) {
    const auto m = test::icosphere(5.0, 2);
    const auto in =
        write_temp("ncrev_cli_segment_in.stl", encode_stl_binary(m.points, m.triangles));
    const auto before = std::filesystem::file_size(in);
    EXPECT_EQ(run("segment " + in.string() + " -o " + in.string() + " -q").code, 1);
    EXPECT_EQ(
        run("segment " + in.string() + " -o /tmp/ncrev_x.ply --labels " + in.string() + " -q").code,
        1);
    EXPECT_EQ(std::filesystem::file_size(in), before);
    const auto bad =
        write_temp("ncrev_cli_segment_bad.stl", {std::byte{'s'}, std::byte{'o'}, std::byte{'l'}});
    const auto out = test::scratch_dir() / "ncrev_cli_segment_bad.ply";
    std::filesystem::remove(out);
    const CliRun r = run("segment " + bad.string() + " -o " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_TRUE(r.out.empty());
    EXPECT_NE(r.err.find("ncrev_cli_segment_bad.stl"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_EQ(run("segment " + in.string() + " -o " + out.string() + " --method magic").code, 1);
}

}  // namespace
}  // namespace ncrev
