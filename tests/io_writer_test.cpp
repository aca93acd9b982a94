#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "ncrev/io.h"
#include "scratch.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

std::size_t count_entries(const std::filesystem::path& dir) {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir),
                                                  std::filesystem::directory_iterator()));
}

std::filesystem::path temp_dir(const std::string& name) {
    auto d = test::scratch_dir() / name;
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

TEST(PlyWriter, WritesHeaderAndBinaryBodyWithFaceLabels) {
    const auto c = test::cube();
    PlyColumn region{"region", PlyColumn::Type::kInt32, {}};
    PlyColumn red{"red", PlyColumn::Type::kUint8, {}};
    for (std::size_t f = 0; f < 12; ++f) {
        region.values.push_back(static_cast<double>(f / 2));
        red.values.push_back(
            static_cast<double>((label_color(static_cast<std::uint32_t>(f / 2)) >> 16) & 0xff));
    }
    const std::vector<PlyColumn> face_cols = {region, red};
    const auto bytes = encode_ply(c.points, c.triangles, {}, face_cols);
    const std::string text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    const std::size_t end = text.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    const std::string header = text.substr(0, end);
    EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
    EXPECT_NE(header.find("element vertex 8"), std::string::npos);
    EXPECT_NE(header.find("element face 12"), std::string::npos);
    EXPECT_NE(header.find("property int region"), std::string::npos);
    EXPECT_NE(header.find("property uchar red"), std::string::npos);
    const std::size_t body = end + 11;
    EXPECT_EQ(bytes.size(), body + 8 * 12 + 12 * (1 + 12 + 4 + 1));
    // The last face: 3, its indices, region 5, red.
    const std::byte* last = bytes.data() + bytes.size() - 18;
    EXPECT_EQ(static_cast<int>(last[0]), 3);
    std::int32_t idx[3], reg;
    std::memcpy(idx, last + 1, 12);
    std::memcpy(&reg, last + 13, 4);
    EXPECT_EQ(idx[0], 3);
    EXPECT_EQ(idx[1], 7);
    EXPECT_EQ(idx[2], 5);
    EXPECT_EQ(reg, 5);
}

TEST(LabelColor, NeighbouringLabelsDiffer) {
    for (std::uint32_t i = 0; i < 100; ++i) {
        EXPECT_NE(label_color(i), label_color(i + 1));
        EXPECT_LE(label_color(i), 0xFFFFFFu);
    }
}

TEST(AtomicWrite, ReplacesExistingFileAndLeavesNoTemporary) {
    const auto dir = temp_dir("atomic");
    const auto path = dir / "out.stl";
    { std::ofstream(path) << "old"; }
    const auto c = test::cube();
    ASSERT_TRUE(write_file_atomic(path, encode_stl_binary(c.points, c.triangles)).ok());
    EXPECT_EQ(std::filesystem::file_size(path), 84u + 50u * 12u);
    EXPECT_EQ(count_entries(dir), 1u);
    std::filesystem::remove_all(dir);
}

TEST(AtomicWrite, FailsCleanlyInMissingFolder) {
    const auto path = test::scratch_dir() / "no_such_dir" / "x.stl";
    auto s = write_file_atomic(path, std::vector<std::byte>(10));
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().code, ErrorCode::kCannotWrite);
    EXPECT_FALSE(std::filesystem::exists(path.parent_path()));
}

TEST(StlWriter, BinaryHeaderNeverBeginsWithSolid) {
    const auto c = test::cube();
    const auto bytes = encode_stl_binary(c.points, c.triangles, "solid part");
    EXPECT_NE(std::memcmp(bytes.data(), "solid", 5), 0);
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

TEST(AtomicFileWriter, WritesInPiecesAndLeavesNothingWithoutCommit) {
    const auto dir = temp_dir("atomic_writer");
    const auto path = dir / "out.txt";
    {
        auto w = AtomicFileWriter::open(path);
        ASSERT_TRUE(w.ok());
        const std::string a = "hello ", b = "world";
        ASSERT_TRUE(w->write(std::as_bytes(std::span(a))).ok());
        ASSERT_TRUE(w->write(std::as_bytes(std::span(b))).ok());
    }  // abandoned
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    {
        auto w = AtomicFileWriter::open(path);
        ASSERT_TRUE(w.ok());
        const std::string a = "hello ", b = "world";
        ASSERT_TRUE(w->write(std::as_bytes(std::span(a))).ok());
        ASSERT_TRUE(w->write(std::as_bytes(std::span(b))).ok());
        ASSERT_TRUE(w->commit().ok());
    }
    std::ifstream in(path);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "hello world");
    EXPECT_EQ(count_entries(dir), 1u);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ncrev
