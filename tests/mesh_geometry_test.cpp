#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "ncrev/mesh.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

/// Sum of the mixed areas, each asserted positive.
double positive_area_sum(const Mesh& m) {
    const VertexMap<double> areas = mixed_voronoi_areas(m);
    double sum = 0;
    for (double x : areas.data()) {
        EXPECT_GT(x, 0);
        sum += x;
    }
    return sum;
}

Mesh build(const TriangleSoup& soup, bool orient = true) {
    HealOptions o;
    o.orient = orient;
    auto r = build_mesh(soup, o);
    EXPECT_TRUE(r.ok());
    return std::move(r->mesh);
}

TEST(MeshGeometry, CubeEdgesAreConvexRightAnglesAndDiagonalsFlat) {
    const Mesh m = build(test::to_bucket(test::cube({0, 0, 0}, 3.0)));
    int right = 0, flat = 0;
    for (std::size_t h = 0; h < m.num_halfedges(); ++h) {
        const double a = dihedral_angle(m, HalfedgeId(static_cast<std::uint32_t>(h)));
        if (std::abs(a - std::numbers::pi / 2) < 1e-12) ++right;
        if (std::abs(a) < 1e-12) ++flat;
    }
    EXPECT_EQ(right, 24);  // 12 edges, both half-edges
    EXPECT_EQ(flat, 12);   // 6 face diagonals
}

TEST(MeshGeometry, InsideOutCubeHasConcaveEdges) {
    auto c = test::cube();
    for (auto& t : c.triangles) std::swap(t[1], t[2]);
    const Mesh m = build(test::to_bucket(c), /*orient=*/false);
    for (std::size_t h = 0; h < m.num_halfedges(); ++h) {
        const double a = dihedral_angle(m, HalfedgeId(static_cast<std::uint32_t>(h)));
        EXPECT_TRUE(std::abs(a + std::numbers::pi / 2) < 1e-12 || std::abs(a) < 1e-12) << a;
    }
}

TEST(MeshGeometry, BoundaryEdgesHaveNoDihedral) {
    auto c = test::cube();
    c.triangles.pop_back();
    const Mesh m = build(test::to_bucket(c));
    for (std::size_t h = 0; h < m.num_halfedges(); ++h) {
        const HalfedgeId hh(static_cast<std::uint32_t>(h));
        if (m.is_boundary(hh)) {
            EXPECT_EQ(dihedral_angle(m, hh), 0.0);
        }
    }
}

TEST(MeshGeometry, MixedAreasSumToTheAreaAndStayPositiveOnThinTriangles) {
    const Mesh sphere = build(test::to_bucket(test::icosphere(2.0, 3)));
    const double sum = positive_area_sum(sphere);
    EXPECT_NEAR(sum, compute_stats(sphere).area, 1e-12 * sum);
    // A strip of long thin, obtuse triangles, as CAD systems tessellate a cylinder.
    test::Indexed strip;
    for (int i = 0; i <= 20; ++i) {
        strip.points.push_back({0.0, 5.0 * i, 0.0});
        strip.points.push_back({0.3, 5.0 * i + 2.5, 0.01 * i});
    }
    for (std::uint32_t i = 0; i < 20; ++i) {
        strip.triangles.push_back({2 * i, 2 * i + 1, 2 * i + 2});
        strip.triangles.push_back({2 * i + 1, 2 * i + 3, 2 * i + 2});
    }
    const Mesh thin = build(test::to_indexed_soup(strip));
    const double sum_b = positive_area_sum(thin);
    EXPECT_NEAR(sum_b, compute_stats(thin).area, 1e-12 * sum_b);
}

TEST(MeshGeometry, SphereVertexNormalsAreRadial) {
    const Vec3 c{1, -2, 3};
    const Mesh m = build(test::to_bucket(test::icosphere(5.0, 3, c)));
    const auto n = vertex_normals(m);
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
        const Vec3 radial = normalized(m.position(VertexId(static_cast<std::uint32_t>(v))) - c);
        EXPECT_GT(dot(n[VertexId(static_cast<std::uint32_t>(v))], radial), 0.9999);
    }
}

/// A prism of height h over the convex polygon `outline` (counter-clockwise in z = 0), its caps
/// fans from their first corner, outward.
test::Indexed prism(const std::vector<Vec3>& outline, double h) {
    test::Indexed m;
    const auto n = static_cast<std::uint32_t>(outline.size());
    for (const Vec3& p : outline) m.points.push_back(p);
    for (const Vec3& p : outline) m.points.push_back(p + Vec3{0, 0, h});
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t j = (i + 1) % n;
        m.triangles.push_back({i, j, n + j});
        m.triangles.push_back({i, n + j, n + i});
    }
    for (std::uint32_t i = 1; i + 1 < n; ++i) {
        m.triangles.push_back({0, i + 1, i});
        m.triangles.push_back({n, n + i, n + i + 1});
    }
    return m;
}

double box_diagonal(const Mesh& m) {
    Box3 box;
    for (const Vec3& p : m.positions()) box.add(p);
    return box.diagonal();
}

TEST(PartSize, ABlockIsItsBoxDiagonalInEveryPose) {
    const test::Indexed block = prism({{0, 0, 0}, {100, 0, 0}, {100, 60, 0}, {0, 60, 0}}, 20);
    const Mesh in_axes = build(test::to_indexed_soup(block));
    const double diagonal = std::sqrt(100.0 * 100 + 60 * 60 + 20 * 20);
    EXPECT_NEAR(part_size(in_axes), diagonal, 1e-12 * diagonal);
    TriangleSoup turned = test::to_indexed_soup(block);
    test::rigid_motion(turned, 0.7, {40, -25, 10});
    const Mesh moved = build(turned);
    EXPECT_NEAR(part_size(moved), diagonal, 1e-12 * diagonal);
    EXPECT_GT(box_diagonal(moved), 1.2 * diagonal);  // what the box alone would say
}

TEST(PartSize, ATurnedPartsSizeIsItsBoxDiagonalAlongItsAxis) {
    // A disc of radius 50 and thickness 10 in 64 sides, a vertex on each axis: its box is
    // 100 x 100 x 10, the smallest with a side along an edge of its outline a hair narrower.
    std::vector<Vec3> outline;
    for (int i = 0; i < 64; ++i) {
        const double a = i * std::numbers::pi / 32;
        outline.push_back({50 * std::cos(a), 50 * std::sin(a), 0});
    }
    const test::Indexed disc = prism(outline, 10);
    const Mesh in_axes = build(test::to_indexed_soup(disc));
    const double size = part_size(in_axes);
    const double across = 100 * std::cos(std::numbers::pi / 64);  // between parallel sides
    EXPECT_NEAR(size, std::sqrt(2 * across * across + 10 * 10), 1e-9 * size);
    EXPECT_LE(size, box_diagonal(in_axes));
    TriangleSoup turned = test::to_indexed_soup(disc);
    test::rigid_motion(turned, 1.1, {-7, 3, 12});
    EXPECT_NEAR(part_size(build(turned)), size, 1e-12 * size);
}

TEST(PartSize, AnLShapedOutlineIsMeasuredAlongItsEdges) {
    // An L: 80 x 50 overall, arms 20 wide, 30 high; the smallest box is its bounding box.
    const test::Indexed ell =
        prism({{0, 0, 0}, {80, 0, 0}, {80, 20, 0}, {20, 20, 0}, {20, 50, 0}, {0, 50, 0}}, 30);
    // (Its caps are fans from the corner at the origin, which sees every other corner.)
    const Mesh in_axes = build(test::to_indexed_soup(ell));
    const double diagonal = std::sqrt(80.0 * 80 + 50 * 50 + 30 * 30);
    EXPECT_NEAR(part_size(in_axes), diagonal, 1e-12 * diagonal);
    TriangleSoup turned = test::to_indexed_soup(ell);
    test::rigid_motion(turned, 2.3, {0, 0, 0});
    EXPECT_NEAR(part_size(build(turned)), diagonal, 1e-12 * diagonal);
}

TEST(PartSize, ADenselyMeshedBlockIsMeasuredOnAllCores) {
    // A 100 x 60 x 20 block, each face a grid of 120 x 120 squares: 86k vertices, more than
    // one task's share of the passes over the points.
    TriangleSoup soup;
    const Vec3 size{100, 60, 20};
    constexpr int kCells = 120;
    for (int axis = 0; axis < 3; ++axis) {
        for (const double side : {0.0, 1.0}) {
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            const auto corner = [&](int i, int j) {
                Vec3 p;
                p[axis] = side * size[axis];
                p[a] = size[a] * i / kCells;
                p[b] = size[b] * j / kCells;
                return p;
            };
            for (int i = 0; i < kCells; ++i) {
                for (int j = 0; j < kCells; ++j) {
                    const auto n = static_cast<std::uint32_t>(soup.points.size());
                    soup.points.push_back(corner(i, j));
                    soup.points.push_back(corner(i + 1, j));
                    soup.points.push_back(corner(i + 1, j + 1));
                    soup.points.push_back(corner(i, j + 1));
                    // Outward: (a, b, axis) is right-handed, the far side faces +axis.
                    if (side > 0) {
                        soup.triangles.push_back({n, n + 1, n + 2});
                        soup.triangles.push_back({n, n + 2, n + 3});
                    } else {
                        soup.triangles.push_back({n, n + 2, n + 1});
                        soup.triangles.push_back({n, n + 3, n + 2});
                    }
                }
            }
        }
    }
    test::rigid_motion(soup, 0.7, {40, -25, 10});
    const Mesh m = build(soup);
    ASSERT_GT(m.num_vertices(), 65536u);
    const double diagonal = std::sqrt(100.0 * 100 + 60 * 60 + 20 * 20);
    EXPECT_NEAR(part_size(m), diagonal, 1e-12 * diagonal);
    EXPECT_GT(box_diagonal(m), 1.2 * diagonal);
}

TEST(PartSize, AnEmptyMeshHasNone) { EXPECT_EQ(part_size(Mesh{}), 0.0); }

}  // namespace
}  // namespace ncrev
