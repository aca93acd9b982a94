#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

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

}  // namespace
}  // namespace ncrev
