// Real meshes of machined parts from ../shared/corpus (public, see its SOURCES.md): every one
// must read and heal into one closed, outward, manifold body. Skipped when the corpus is not
// beside the checkout.
#include <gtest/gtest.h>

#include <filesystem>

#include "ncrev/report.h"

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
    auto open = inspect_file(path, exact);
    ASSERT_TRUE(open.ok());
    EXPECT_FALSE(open->mesh.closed);
    auto healed = inspect_file(path);
    ASSERT_TRUE(healed.ok());
    EXPECT_TRUE(healed->mesh.closed);
    EXPECT_GT(healed->heal.welded_vertices, 0u);
}

}  // namespace
}  // namespace ncrev
