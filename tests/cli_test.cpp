// End-to-end: the ncrev binary as a user runs it (exit codes, stdout holds exactly one JSON
// document, errors name the file and the place).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ncrev/io.h"
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
    const auto err_path =
        std::filesystem::temp_directory_path() /
        ("ncrev_cli_test." + std::to_string(::getpid()) + "." + std::to_string(++calls) + ".err");
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
    const auto path = std::filesystem::temp_directory_path() / name;
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
    const auto step = std::filesystem::temp_directory_path() / "ncrev_cli_rev_cube.step";
    const auto report = std::filesystem::temp_directory_path() / "ncrev_cli_rev_cube.json";
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
    EXPECT_EQ(run("reverse " + stl.string() + " -o " + stl.string()).code, 1);
    EXPECT_EQ(std::filesystem::file_size(stl), 84u + 50u * 12u);  // untouched
    EXPECT_EQ(run("reverse " + stl.string() + " -o /nonexistent/dir/x.step -q").code, 4);
    EXPECT_EQ(run("reverse " + stl.string() + " -o " + step.string() + " --method nurbs").code, 1);
    std::filesystem::remove(step);
    std::filesystem::remove(report);
    std::filesystem::remove(stl);
}

TEST(CliReverse, OpenMeshWithRequireSolidExitsThreeAndWritesNothing) {
    auto c = test::cube({0, 0, 0}, 10.0);
    c.triangles.pop_back();
    const auto stl = write_temp("ncrev_cli_rev_open.stl", encode_stl_binary(c.points, c.triangles));
    const auto step = std::filesystem::temp_directory_path() / "ncrev_cli_rev_open.step";
    std::filesystem::remove(step);
    const CliRun r = run("reverse " + stl.string() + " -o " + step.string() + " --require-solid");
    EXPECT_EQ(r.code, 3);
    EXPECT_FALSE(std::filesystem::exists(step));
    const CliRun shell = run("reverse " + stl.string() + " -o " + step.string());
    EXPECT_EQ(shell.code, 0);
    EXPECT_NE(shell.err.find("warning: the mesh is open"), std::string::npos) << shell.err;
    std::filesystem::remove(step);
    std::filesystem::remove(stl);
}

}  // namespace
}  // namespace ncrev
