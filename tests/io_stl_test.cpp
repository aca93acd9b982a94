#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "ncrev/io.h"
#include "scratch.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

using test::bytes_of;

std::vector<std::byte> cube_binary() {
    const auto c = test::cube();
    return encode_stl_binary(c.points, c.triangles, "cube");
}
std::string cube_ascii() {
    const auto c = test::cube();
    return encode_stl_ascii(c.points, c.triangles, "cube");
}

TEST(StlReader, ReadsBinaryCube) {
    const auto bytes = cube_binary();
    ASSERT_EQ(bytes.size(), 84u + 50u * 12u);
    auto soup = read_stl(bytes);
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->format, InputFormat::kStlBinary);
    EXPECT_EQ(soup->num_facets(), 12u);
    EXPECT_EQ(soup->points.size(), 36u);
    EXPECT_EQ(soup->name, "cube");
    EXPECT_FALSE(soup->has_attributes());
    const auto c = test::cube();
    for (std::size_t f = 0; f < 12; ++f) {
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(soup->points[soup->triangles[f][k]], c.points[c.triangles[f][k]]);
        }
    }
}

TEST(StlReader, ReadsAsciiCubeLikeBinary) {
    auto a = read_stl(bytes_of(cube_ascii()));
    auto b = read_stl(cube_binary());
    ASSERT_TRUE(a.ok()) << a.error().describe();
    ASSERT_TRUE(b.ok());
    EXPECT_EQ(a->format, InputFormat::kStlAscii);
    EXPECT_EQ(a->name, "cube");
    EXPECT_EQ(a->points, b->points);
    EXPECT_EQ(a->triangles, b->triangles);
}

TEST(StlReader, DetectsBinaryThatBeginsWithSolidBySize) {
    auto bytes = cube_binary();
    std::memcpy(bytes.data(), "solid cube exported by a CAD system", 35);
    auto soup = read_stl(bytes);
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->format, InputFormat::kStlBinary);
    EXPECT_EQ(soup->num_facets(), 12u);
}

TEST(StlReader, AcceptsUppercaseKeywordsPlusSignsAndSeveralSolids) {
    const std::string text =
        "SOLID a\n FACET NORMAL 0 0 +1\n OUTER LOOP\n VERTEX 0 0 0\n VERTEX +1 0 0\n"
        " VERTEX 0 1e0 0\n ENDLOOP\n ENDFACET\nENDSOLID a\nsolid b\nfacet normal nan nan nan\n"
        "outer loop\nvertex 0 0 1\nvertex 1 0 1\nvertex 0 1 1\nendloop\nendfacet\nendsolid b\n";
    auto soup = read_stl(bytes_of(text));
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->num_facets(), 2u);
    EXPECT_EQ(soup->points[4], (Vec3{1, 0, 1}));
}

struct StlErrorCase {
    const char* name;
    std::string text;
    ErrorCode code;
    std::int64_t line;
};

TEST(StlReader, ReportsEveryAsciiErrorWithItsLine) {
    const std::string facet =
        "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
        "endfacet\n";
    const std::vector<StlErrorCase> cases = {
        {"misspelt keyword", "solid x\nfacet normal 0 0 1\nouter loop\nvertx 0 0 0\n",
         ErrorCode::kBadSyntax, 4},
        {"bad number", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0.0.1 0\n",
         ErrorCode::kBadNumber, 4},
        {"nan vertex", "solid x\n" + facet.substr(0, 30) + "vertex nan 0 0\n",
         ErrorCode::kBadNumber, 4},
        {"infinite vertex", "solid x\nfacet normal 0 0 1\nouter loop\nvertex inf 0 0\n",
         ErrorCode::kBadNumber, 4},
        {"ends inside a facet", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
         ErrorCode::kTruncated, 5},
        {"no endsolid", "solid x\n" + facet, ErrorCode::kTruncated, 9},
        {"four vertices",
         "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\nvertex 1 1 0\nendloop\n",
         ErrorCode::kBadSyntax, 7},
        {"junk instead of facet", "solid x\n" + facet + "hello\nendsolid x\n",
         ErrorCode::kBadSyntax, 9},
        {"trailing content", "solid x\n" + facet + "endsolid x\ngarbage here\n",
         ErrorCode::kTrailingContent, 10},
    };
    for (const auto& c : cases) {
        auto r = read_stl(bytes_of(c.text), "t.stl");
        ASSERT_FALSE(r.ok()) << c.name;
        EXPECT_EQ(r.error().code, c.code) << c.name << ": " << r.error().describe();
        EXPECT_EQ(r.error().line, c.line) << c.name << ": " << r.error().describe();
        EXPECT_EQ(r.error().path, "t.stl");
        EXPECT_NE(r.error().describe().find("t.stl: line "), std::string::npos);
    }
}

TEST(StlReader, RejectsEmptyFile) {
    auto r = read_stl({});
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kEmpty);
}

TEST(StlReader, RejectsBinaryWhoseCountExceedsFileSize) {
    auto bytes = cube_binary();
    bytes.resize(bytes.size() - 7);
    auto r = read_stl(bytes);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kTruncated);
    EXPECT_NE(r.error().message.find("header says 12 facets, file holds 11"), std::string::npos)
        << r.error().message;
}

TEST(StlReader, RejectsBinaryWithExtraBytes) {
    auto bytes = cube_binary();
    bytes.resize(bytes.size() + 3);
    auto r = read_stl(bytes);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kSizeMismatch);
    EXPECT_EQ(r.error().byte_offset, 84 + 50 * 12);
}

TEST(StlReader, RefusesHugeCountInTinyFileWithoutAllocating) {
    // 100 bytes whose header claims 4,294,967,295 facets (~200 GB): an error, not an allocation.
    std::vector<std::byte> bytes(100, std::byte{0});
    const std::uint32_t n = 0xFFFFFFFFu;
    std::memcpy(bytes.data() + 80, &n, 4);
    auto r = read_stl(bytes);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kTruncated);
}

TEST(StlReader, RejectsShortNonAsciiFile) {
    std::vector<std::byte> bytes(40, std::byte{7});
    auto r = read_stl(bytes);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kTruncated);
}

TEST(StlReader, RejectsNonFiniteBinaryCoordinateWithItsOffset) {
    auto bytes = cube_binary();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    // facet 3, vertex 2, y: header 84 + 3 records + normal 12 + vertex 12 + 4
    const std::size_t at = 84 + 3 * 50 + 12 + 12 + 4;
    std::memcpy(bytes.data() + at, &nan, 4);
    auto r = read_stl(bytes);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kBadNumber);
    EXPECT_EQ(r.error().byte_offset, static_cast<std::int64_t>(at));
}

TEST(StlReader, ReportsBinarySizeErrorForBinaryThatBeginsWithSolid) {
    auto bytes = cube_binary();
    std::memcpy(bytes.data(), "solid x", 7);
    bytes.resize(bytes.size() - 50);
    auto r = read_stl(bytes);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kTruncated) << r.error().describe();
}

// Every prefix of a valid file: an error, or a correct shorter mesh; never a crash (the
// sanitizer build runs this too).
TEST(StlReader, EveryPrefixOfBinaryIsAnErrorOrAShorterMesh) {
    const auto bytes = cube_binary();
    const auto full = read_stl(bytes);
    ASSERT_TRUE(full.ok());
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        auto r = read_stl(std::span(bytes.data(), n));
        if (!r.ok()) continue;
        ASSERT_LE(r->num_facets(), full->num_facets());
        for (std::size_t i = 0; i < r->points.size(); ++i) EXPECT_EQ(r->points[i], full->points[i]);
    }
}

TEST(StlReader, EveryPrefixOfAsciiIsAnErrorOrAShorterMesh) {
    const auto bytes = bytes_of(cube_ascii());
    const auto full = read_stl(bytes);
    ASSERT_TRUE(full.ok());
    std::size_t accepted = 0;
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        auto r = read_stl(std::span(bytes.data(), n));
        if (!r.ok()) continue;
        ++accepted;
        ASSERT_LE(r->num_facets(), full->num_facets());
        for (std::size_t i = 0; i < r->points.size(); ++i) EXPECT_EQ(r->points[i], full->points[i]);
    }
    // Only the prefixes that end inside the final "endsolid cube" line can be complete.
    EXPECT_LE(accepted, 8u);
}

TEST(StlReader, ReadsFilesThroughThePathOverload) {
    const auto path = test::scratch_dir() / "ncrev_io_stl_test.stl";
    ASSERT_TRUE(write_file_atomic(path, cube_binary()).ok());
    auto soup = read_mesh_file(path);
    ASSERT_TRUE(soup.ok()) << soup.error().describe();
    EXPECT_EQ(soup->num_facets(), 12u);
    std::filesystem::remove(path);
    auto missing = read_mesh_file(path);
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.error().code, ErrorCode::kCannotOpen);
    EXPECT_EQ(missing.error().path, path.string());
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

TEST(StlReader, WeldsExactlyWhileReadingBinaryAndAscii) {
    ReadOptions weld;
    weld.weld_exact = true;
    auto bin = read_stl(cube_binary(), {}, weld);
    auto asc = read_stl(bytes_of(cube_ascii()), {}, weld);
    for (auto* soup : {&bin, &asc}) {
        ASSERT_TRUE(soup->ok());
        EXPECT_TRUE((*soup)->points_distinct);
        EXPECT_EQ((*soup)->points.size(), 8u);
        EXPECT_EQ((*soup)->welded_points, 28u);
        EXPECT_EQ((*soup)->num_facets(), 12u);
    }
    EXPECT_EQ(bin->points, asc->points);
    EXPECT_EQ(bin->triangles, asc->triangles);
    // The welded soup describes the same facets as the bucket.
    auto bucket = read_stl(cube_binary());
    ASSERT_TRUE(bucket.ok());
    for (std::size_t f = 0; f < 12; ++f) {
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(bin->points[bin->triangles[f][k]], bucket->points[bucket->triangles[f][k]]);
        }
    }
}

TEST(StlReader, WeldingReaderTreatsNegativeZeroAsZeroAndKeepsErrors) {
    auto c = test::cube();
    c.points[0] = {-0.0, 0.0, -0.0};
    ReadOptions weld;
    weld.weld_exact = true;
    auto bytes = encode_stl_binary(c.points, c.triangles);
    auto soup = read_stl(bytes, {}, weld);
    ASSERT_TRUE(soup.ok());
    EXPECT_EQ(soup->points.size(), 8u);
    bytes.resize(bytes.size() - 1);
    EXPECT_EQ(read_stl(bytes, {}, weld).error().code, ErrorCode::kTruncated);
}

}  // namespace
}  // namespace ncrev
