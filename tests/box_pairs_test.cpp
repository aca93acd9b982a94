// detail::BoxPairs (src/detail/box_pairs.h): every two boxes that meet, each pair once, as a
// comparison of all pairs finds them.
#include "detail/box_pairs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

#include "test_meshes.h"

namespace {

using ncrev::Box3;
using ncrev::Vec3;
using ncrev::detail::BoxPairs;
using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

Box3 grown(const Box3& b, double d) { return Box3{b.min - Vec3{d, d, d}, b.max + Vec3{d, d, d}}; }

bool meet(const Box3& a, const Box3& b) {
    for (int k = 0; k < 3; ++k)
        if (a.max[k] < b.min[k] || b.max[k] < a.min[k]) return false;
    return true;
}

// Sorted pairs (i < j) the search hands out; fails the test on a pair given twice.
Pairs searched(const std::vector<Box3>& boxes, double grow) {
    const BoxPairs search(
        static_cast<std::uint32_t>(boxes.size()), [&](std::uint32_t i) { return boxes[i]; }, grow);
    Pairs out;
    std::mutex m;
    std::atomic<bool> stop{false};
    search.for_each_pair(
        [&](std::span<const BoxPairs::Pair> batch) {
            std::lock_guard lock(m);
            for (auto [i, j] : batch) out.emplace_back(std::min(i, j), std::max(i, j));
        },
        stop);
    std::sort(out.begin(), out.end());
    EXPECT_EQ(std::adjacent_find(out.begin(), out.end()), out.end()) << "a pair given twice";
    return out;
}

// Every pair (i < j) whose boxes, each grown by `grow`, meet: sorted along x, each box against
// those that start before it ends.
Pairs every(const std::vector<Box3>& boxes, double grow) {
    std::vector<std::uint32_t> by_x(boxes.size());
    for (std::uint32_t i = 0; i < by_x.size(); ++i) by_x[i] = i;
    std::sort(by_x.begin(), by_x.end(),
              [&](std::uint32_t a, std::uint32_t b) { return boxes[a].min.x < boxes[b].min.x; });
    Pairs out;
    for (std::size_t a = 0; a < by_x.size(); ++a) {
        const Box3 ga = grown(boxes[by_x[a]], grow);
        for (std::size_t b = a + 1; b < by_x.size(); ++b) {
            const Box3 gb = grown(boxes[by_x[b]], grow);
            if (gb.min.x > ga.max.x) break;
            if (meet(ga, gb))
                out.emplace_back(std::min(by_x[a], by_x[b]), std::max(by_x[a], by_x[b]));
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<Box3> random_boxes(std::size_t n, double spread, double size, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> at(-spread, spread), side(0.0, size);
    std::vector<Box3> boxes(n);
    for (Box3& b : boxes) {
        const Vec3 lo{at(rng), at(rng), at(rng)};
        b = Box3{lo, lo + Vec3{side(rng), side(rng), side(rng)}};
    }
    return boxes;
}

}  // namespace

TEST(BoxPairs, FindsTheSamePairsAsComparingAll) {
    // Counts around the leaf size (8) and its powers of two, sparse and dense; 20000 boxes
    // make a tree deeper than the levels searched as tasks of their own (10).
    for (const std::size_t n : {0u, 1u, 2u, 7u, 8u, 9u, 17u, 100u, 1000u, 3000u, 20000u}) {
        for (const double size : {0.05, 0.5}) {
            if (n > 10000 && size > 0.1) continue;  // some ten million pairs: slow to compare
            const std::vector<Box3> boxes = random_boxes(n, 1.0, size, static_cast<unsigned>(n));
            const Pairs expected = every(boxes, 0.0);
            EXPECT_EQ(searched(boxes, 0.0), expected) << n << " boxes of up to " << size;
            if (n == 1000 && size > 0.1) {
                EXPECT_GT(expected.size(), 100u);  // the case has pairs to find
            }
        }
    }
}

TEST(BoxPairs, GrowsEveryBox) {
    // Boxes 0.1 apart meet once each is grown by 0.05 (exactly: 0.1 and 0.05 are not, in
    // binary, so a little more), not by 0.04.
    std::vector<Box3> row;
    for (int i = 0; i < 50; ++i) {
        const Vec3 lo{0.3 * i, 0, 0};
        row.push_back(Box3{lo, lo + Vec3{0.2, 0.2, 0.2}});
    }
    EXPECT_EQ(searched(row, 0.04), Pairs{});
    EXPECT_EQ(searched(row, 0.051).size(), 49u);
    EXPECT_EQ(searched(row, 0.051), every(row, 0.051));
}

TEST(BoxPairs, BoxesWithOneCentre) {
    // All centres in one point (one Morton code; the order falls back on the index), and all
    // in one plane (a flat extent).
    std::vector<Box3> same(40, Box3{Vec3{-1, -1, -1}, Vec3{1, 1, 1}});
    EXPECT_EQ(searched(same, 0.0).size(), 40u * 39u / 2);
    std::vector<Box3> flat = random_boxes(500, 1.0, 0.1, 7);
    for (Box3& b : flat) b.min.z = b.max.z = 0;
    EXPECT_EQ(searched(flat, 0.0), every(flat, 0.0));
}

TEST(BoxPairs, OnAMeshFacetsMeetTheirNeighbours) {
    // A closed mesh (a sphere of 5120 facets): every two facets sharing an edge have boxes that
    // meet, and the search finds them.
    const ncrev::test::Indexed ball = ncrev::test::icosphere(10.0, 4);
    std::vector<Box3> boxes(ball.triangles.size());
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> by_edge;
    for (std::uint32_t f = 0; f < ball.triangles.size(); ++f) {
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = ball.triangles[f][k], b = ball.triangles[f][(k + 1) % 3];
            boxes[f].add(ball.points[a]);
            by_edge[{std::min(a, b), std::max(a, b)}].push_back(f);
        }
    }
    const Pairs found = searched(boxes, 0.0);
    EXPECT_EQ(found, every(boxes, 0.0));
    for (const auto& [edge, facets] : by_edge) {
        ASSERT_EQ(facets.size(), 2u);
        const auto pair =
            std::make_pair(std::min(facets[0], facets[1]), std::max(facets[0], facets[1]));
        EXPECT_TRUE(std::binary_search(found.begin(), found.end(), pair));
    }
    EXPECT_EQ(by_edge.size(), ball.triangles.size() * 3 / 2);
}

TEST(BoxPairs, StopsWhenAsked) {
    const std::vector<Box3> boxes = random_boxes(3000, 1.0, 0.5, 3);
    const BoxPairs search(
        3000, [&](std::uint32_t i) { return boxes[i]; }, 0.0);
    std::atomic<bool> stop{false};
    std::atomic<std::uint64_t> batches{0};
    search.for_each_pair(
        [&](std::span<const BoxPairs::Pair>) {
            ++batches;
            stop = true;
        },
        stop);
    // Batches already begun on other threads may finish; no new ones start.
    EXPECT_GE(batches.load(), 1u);
    EXPECT_LE(batches.load(), 64u);
}
