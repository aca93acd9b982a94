#include <gtest/gtest.h>

#include "ncrev/io.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

using test::bytes_of;

// The example of ../shared/docs/sre-format.md, verbatim.
const std::string kCube = R"(SRE 1
unit mm
tools 1
tool 16711680 flat 10 0 T1 D10 flat end mill
surfaces 1
0 plane 0 0 1  0 0 1
vertices 8
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
facets 12
0 2 1 0 -1 -1
0 3 2 0 -1 -1
4 5 6 16711680 7 0
4 6 7 16711680 7 0
0 1 5 0 -1 -1
0 5 4 0 -1 -1
1 2 6 0 -1 -1
1 6 5 0 -1 -1
2 3 7 0 -1 -1
2 7 6 0 -1 -1
3 0 4 0 -1 -1
3 4 7 0 -1 -1
)";

TEST(SreReader, ReadsTheFormatPageExample) {
    auto soup = read_sre(bytes_of(kCube), "cube.sre");
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->format, InputFormat::kSre);
    EXPECT_EQ(soup->unit, Unit::kMillimetre);
    ASSERT_EQ(soup->tools.size(), 1u);
    EXPECT_EQ(soup->tools[0].color, 16711680);
    EXPECT_EQ(soup->tools[0].kind, ToolKind::kFlat);
    EXPECT_EQ(soup->tools[0].diameter, 10);
    EXPECT_EQ(soup->tools[0].name, "T1 D10 flat end mill");
    ASSERT_EQ(soup->surfaces.size(), 1u);
    EXPECT_EQ(soup->surfaces[0].kind, SurfaceKind::kPlane);
    EXPECT_EQ(soup->surfaces[0].params[5], 1.0);
    EXPECT_EQ(soup->points.size(), 8u);
    ASSERT_EQ(soup->num_facets(), 12u);
    EXPECT_EQ(soup->triangles[2], (std::array<std::uint32_t, 3>{4, 5, 6}));
    EXPECT_EQ(soup->color[2], 16711680);
    EXPECT_EQ(soup->cut[2], 7);
    EXPECT_EQ(soup->surface[2], 0);
    EXPECT_EQ(soup->surface[0], -1);
    EXPECT_EQ(soup->cut[0], -1);
}

TEST(SreReader, AcceptsCommentsBlankLinesTabsNoUnitNoToolsAndEveryKind) {
    const std::string text =
        "# written by a simulator\n\nSRE\t1   # header\nsurfaces 7\n"
        "6 swept_torus 0 0 0 0 0 1 5 1 1 0 0\n"
        "0 plane 0 0 0 0 0 2\n1 cylinder 0 0 0 0 0 1 3\n2 cone 0 0 0 0 0 1 0 0.5\n"
        "3 sphere 1 2 3 4\n4 torus 0 0 0 0 1 0 1 2   # spindle torus: legal\n"
        "5 shear_cylinder 0 0 0 0 0 1 2 1 0 1\n"
        "vertices 3\n0 0 0\n1 0 0\n0 1 0\nfacets 1\n0 1 2 0 -1 6\n\n# end\n";
    auto soup = read_sre(bytes_of(text));
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->unit, Unit::kMillimetre);
    ASSERT_EQ(soup->surfaces.size(), 7u);
    EXPECT_EQ(soup->surfaces[6].kind, SurfaceKind::kSweptTorus);
    EXPECT_EQ(soup->surfaces[6].params[8], 1.0);
    EXPECT_EQ(soup->surfaces[4].kind, SurfaceKind::kTorus);
    EXPECT_EQ(soup->surfaces[3].params[3], 4.0);
    EXPECT_EQ(soup->surface[0], 6);
}

TEST(SreReader, ReadsInchUnit) {
    auto soup = read_sre(bytes_of("SRE 1\nunit inch\nsurfaces 0\nvertices 0\nfacets 0\n"));
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->unit, Unit::kInch);
    EXPECT_EQ(soup->num_facets(), 0u);
}

struct SreErrorCase {
    const char* name;
    std::string text;
    ErrorCode code;
    std::int64_t line;
};

std::string with_tail(const std::string& head,
                      const std::string& facets = "facets 1\n0 1 2 0 -1 -1\n") {
    return head + "vertices 3\n0 0 0\n1 0 0\n0 1 0\n" + facets;
}

// One fixture per error the format page lists, each with the line it must name.
TEST(SreReader, ReportsEveryListedErrorWithItsLine) {
    const std::string h = "SRE 1\nsurfaces 0\n";
    const std::vector<SreErrorCase> cases = {
        {"missing header", "# nothing\n\n", ErrorCode::kBadSyntax, 2},
        {"wrong header", "SRF 1\nsurfaces 0\n", ErrorCode::kBadSyntax, 1},
        {"header with extra field", "SRE 1 2\n", ErrorCode::kBadSyntax, 1},
        {"unknown version", "SRE 2\nsurfaces 0\n", ErrorCode::kBadValue, 1},
        {"unknown unit", "SRE 1\nunit furlong\n", ErrorCode::kBadValue, 2},
        {"block out of order", "SRE 1\nvertices 0\nsurfaces 0\nfacets 0\n", ErrorCode::kBadSyntax,
         2},
        {"tools after surfaces", "SRE 1\nsurfaces 0\ntools 0\n", ErrorCode::kBadSyntax, 3},
        {"missing facets block", "SRE 1\nsurfaces 0\nvertices 0\n", ErrorCode::kBadSyntax, 3},
        {"negative count", "SRE 1\nsurfaces -1\n", ErrorCode::kBadCount, 2},
        {"fractional count", "SRE 1\nsurfaces 1.5\n", ErrorCode::kBadCount, 2},
        {"word count", "SRE 1\nsurfaces some\n", ErrorCode::kBadCount, 2},
        {"fewer records than announced", h + "vertices 4\n0 0 0\n1 0 0\n0 1 0\nfacets 0\n",
         ErrorCode::kBadCount, 7},
        {"file ends inside a block", h + "vertices 4\n0 0 0\n", ErrorCode::kBadCount, 4},
        {"more records than announced", h + "vertices 2\n0 0 0\n1 0 0\n0 1 0\nfacets 0\n",
         ErrorCode::kBadCount, 6},
        {"more tools than announced", "SRE 1\ntools 0\ntool 1 flat 1 0\n", ErrorCode::kBadCount, 3},
        {"more facets than announced", with_tail(h, "facets 1\n0 1 2 0 -1 -1\n0 2 1 0 -1 -1\n"),
         ErrorCode::kBadCount, 9},
        {"too few fields", h + "vertices 1\n0 0\n", ErrorCode::kBadSyntax, 4},
        {"too many fields", with_tail(h, "facets 1\n0 1 2 0 -1 -1 7\n"), ErrorCode::kBadSyntax, 8},
        {"number that does not parse", h + "vertices 1\n0 0x1 0\n", ErrorCode::kBadNumber, 4},
        {"nan", h + "vertices 1\n0 nan 0\n", ErrorCode::kBadNumber, 4},
        {"infinity", h + "vertices 1\n0 0 -inf\n", ErrorCode::kBadNumber, 4},
        {"integer with exponent", with_tail(h, "facets 1\n0 1 2e0 0 -1 -1\n"),
         ErrorCode::kBadNumber, 8},
        {"unknown surface kind", "SRE 1\nsurfaces 1\n0 paraboloid 1 2 3\n", ErrorCode::kBadValue,
         3},
        {"unknown tool kind", "SRE 1\ntools 1\ntool 5 router 10 0\n", ErrorCode::kBadValue, 3},
        {"tool with zero diameter", "SRE 1\ntools 1\ntool 5 flat 0 0\n", ErrorCode::kBadValue, 3},
        {"wrong parameter count", "SRE 1\nsurfaces 1\n0 sphere 0 0 0\n", ErrorCode::kBadSyntax, 3},
        {"zero direction", "SRE 1\nsurfaces 1\n0 cylinder 0 0 0 0 0 0 1\n", ErrorCode::kBadValue,
         3},
        {"zero plane normal", "SRE 1\nsurfaces 1\n0 plane 0 0 0 0 0 0\n", ErrorCode::kBadValue, 3},
        {"non-positive radius", "SRE 1\nsurfaces 1\n0 sphere 0 0 0 0\n", ErrorCode::kBadValue, 3},
        {"negative cylinder radius", "SRE 1\nsurfaces 1\n0 cylinder 0 0 0 0 0 1 -2\n",
         ErrorCode::kBadValue, 3},
        {"cone angle too large", "SRE 1\nsurfaces 1\n0 cone 0 0 0 0 0 1 1 1.6\n",
         ErrorCode::kBadValue, 3},
        {"cone angle zero", "SRE 1\nsurfaces 1\n0 cone 0 0 0 0 0 1 1 0\n", ErrorCode::kBadValue, 3},
        {"torus R <= 0", "SRE 1\nsurfaces 1\n0 torus 0 0 0 0 0 1 0 1\n", ErrorCode::kBadValue, 3},
        {"shear cylinder swept in its plane",
         "SRE 1\nsurfaces 1\n0 shear_cylinder 0 0 0 0 0 1 2 1 0 0\n", ErrorCode::kBadValue, 3},
        {"duplicated surface index", "SRE 1\nsurfaces 2\n0 sphere 0 0 0 1\n0 sphere 0 0 0 2\n",
         ErrorCode::kDuplicateIndex, 4},
        {"missing surface index", "SRE 1\nsurfaces 2\n1 sphere 0 0 0 1\n2 sphere 0 0 0 2\n",
         ErrorCode::kIndexOutOfRange, 4},
        {"surface index never given",
         "SRE 1\nsurfaces 3\n0 sphere 0 0 0 1\n2 sphere 0 0 0 2\n2 sphere 0 0 0 3\n",
         ErrorCode::kDuplicateIndex, 5},
        {"vertex index out of range", with_tail(h, "facets 1\n0 1 3 0 -1 -1\n"),
         ErrorCode::kIndexOutOfRange, 8},
        {"negative vertex index", with_tail(h, "facets 1\n-1 1 2 0 -1 -1\n"),
         ErrorCode::kIndexOutOfRange, 8},
        {"surface index out of range", with_tail(h, "facets 1\n0 1 2 0 -1 0\n"),
         ErrorCode::kIndexOutOfRange, 8},
        {"cut below -1", with_tail(h, "facets 1\n0 1 2 0 -2 -1\n"), ErrorCode::kBadValue, 8},
        {"facet repeats a vertex", with_tail(h, "facets 1\n0 1 1 0 -1 -1\n"), ErrorCode::kBadValue,
         8},
        {"trailing content", with_tail(h) + "extra words\n", ErrorCode::kTrailingContent, 9},
    };
    for (const auto& c : cases) {
        auto r = read_sre(bytes_of(c.text), "t.sre");
        ASSERT_FALSE(r.ok()) << c.name;
        EXPECT_EQ(r.error().code, c.code) << c.name << ": " << r.error().describe();
        EXPECT_EQ(r.error().line, c.line) << c.name << ": " << r.error().describe();
        EXPECT_EQ(r.error().describe().rfind("t.sre: line ", 0), 0u) << r.error().describe();
    }
}

TEST(SreReader, MissingSurfaceIndexShowsAsShortBlockOrDuplicate) {
    // Two records, both valid and distinct, but index 1 of 0..2 is never given: count says 3.
    const std::string text =
        "SRE 1\nsurfaces 3\n0 sphere 0 0 0 1\n2 sphere 0 0 0 2\nvertices 0\nfacets 0\n";
    auto r = read_sre(bytes_of(text));
    ASSERT_FALSE(r.ok());
    // The third record is missing: the block is short before 'vertices'.
    EXPECT_EQ(r.error().code, ErrorCode::kBadCount);
    const std::string complete =
        "SRE 1\nsurfaces 3\n0 sphere 0 0 0 1\n2 sphere 0 0 0 2\n2 sphere 0 0 0 3\n";
    auto d = read_sre(bytes_of(complete));
    ASSERT_FALSE(d.ok());
    EXPECT_EQ(d.error().code, ErrorCode::kDuplicateIndex);
}

TEST(SreReader, RefusesHugeCountWithoutAllocating) {
    auto r = read_sre(bytes_of("SRE 1\nsurfaces 0\nvertices 4000000000\n0 0 0\n"));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kBadCount);
    auto s = read_sre(bytes_of("SRE 1\nsurfaces 100000000000000\n"));
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::kTooLarge);
    auto t = read_sre(bytes_of("SRE 1\nsurfaces 4000000000\n0 sphere 0 0 0 1\n"));
    ASSERT_FALSE(t.ok());
    EXPECT_EQ(t.error().code, ErrorCode::kBadCount);
}

TEST(SreReader, RoundTripsThroughTheWriter) {
    auto soup = read_sre(bytes_of(kCube));
    ASSERT_TRUE(soup.ok());
    soup->points[3] = {0.1, 1.0 / 3.0, -2.5e-7};
    const std::string text = encode_sre(*soup);
    auto again = read_sre(bytes_of(text));
    ASSERT_TRUE(again.ok()) << again.error().describe();
    EXPECT_EQ(again->points, soup->points);
    EXPECT_EQ(again->triangles, soup->triangles);
    EXPECT_EQ(again->color, soup->color);
    EXPECT_EQ(again->cut, soup->cut);
    EXPECT_EQ(again->surface, soup->surface);
    ASSERT_EQ(again->surfaces.size(), 1u);
    EXPECT_EQ(again->surfaces[0].params, soup->surfaces[0].params);
    ASSERT_EQ(again->tools.size(), 1u);
    EXPECT_EQ(again->tools[0].name, soup->tools[0].name);
}

TEST(SreReader, EveryPrefixIsAnErrorOrAShorterMesh) {
    const auto bytes = bytes_of(kCube);
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        auto r = read_sre(std::span(bytes.data(), n));
        if (!r.ok()) {
            if (n > 0) {
                EXPECT_GE(r.error().line, 1) << n;
            }
            continue;
        }
        // Only a prefix that cuts the last line's trailing newline (or within its last
        // number) can parse; it must then be the same 12 facets or a shorter cut of the last.
        EXPECT_EQ(r->num_facets(), 12u);
    }
}

TEST(ReadMesh, RecognisesSreByHeaderAndStlOtherwise) {
    auto sre = read_mesh(bytes_of("# c\nSRE 1\nsurfaces 0\nvertices 0\nfacets 0\n"));
    ASSERT_TRUE(sre.ok()) << sre.error().describe();
    EXPECT_EQ(sre->format, InputFormat::kSre);
    const auto c = test::cube();
    auto stl = read_mesh(encode_stl_binary(c.points, c.triangles));
    ASSERT_TRUE(stl.ok());
    EXPECT_EQ(stl->format, InputFormat::kStlBinary);
}

}  // namespace
}  // namespace ncrev
