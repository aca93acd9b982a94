#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>

#include "ncrev/mesh.h"
#include "test_meshes.h"

namespace ncrev {
namespace {

BuildResult build_ok(const TriangleSoup& soup, const HealOptions& opt = {}) {
    auto r = build_mesh(soup, opt);
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().describe());
    const std::string broken = r->mesh.validate();
    EXPECT_EQ(broken, "") << broken;
    return std::move(r).value();
}

TEST(MeshBuild, CubeFromFacetBucket) {
    auto b = build_ok(test::to_bucket(test::cube()));
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.vertices, 8u);
    EXPECT_EQ(s.faces, 12u);
    EXPECT_EQ(s.edges, 18u);
    EXPECT_EQ(s.components, 1u);
    EXPECT_EQ(s.euler_characteristic, 2);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.boundary_loops, 0u);
    EXPECT_DOUBLE_EQ(s.volume, 1.0);
    EXPECT_DOUBLE_EQ(s.area, 6.0);
    EXPECT_EQ(b.heal.exact_welded_points, 36u - 8u);
    EXPECT_EQ(b.heal.welded_vertices, 0u);
    EXPECT_EQ(b.heal.flipped_facets, 0u);
    EXPECT_EQ(b.heal.components_turned_outward, 0u);
    EXPECT_NEAR(b.heal.tolerance, 1e-6 * std::sqrt(3.0), 1e-12);
}

TEST(MeshBuild, SphereIsClosedOutwardWithEulerTwo) {
    auto b = build_ok(test::to_bucket(test::icosphere(10.0, 3)));
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.faces, 1280u);
    EXPECT_EQ(s.vertices, 642u);
    EXPECT_EQ(s.euler_characteristic, 2);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(b.heal.components_turned_outward, 0u);
    EXPECT_GT(s.volume, 0.95 * 4.0 / 3.0 * std::numbers::pi * 1000.0);
    EXPECT_LT(s.volume, 4.0 / 3.0 * std::numbers::pi * 1000.0);
}

TEST(MeshBuild, ClosesCracksAtFloatPrecision) {
    auto soup = test::to_bucket(test::cube({10, 20, 30}, 5.0));
    // Vertex (15, 25, 35) appears in several facets; nudge two of its copies by 1 and 3 ulps
    // in different facets, as an exporter that recomputes vertices per facet does.
    int nudged = 0;
    for (Vec3& p : soup.points) {
        if (p == Vec3{15, 25, 35}) {
            if (nudged == 0) p.x = std::nextafter(static_cast<float>(p.x), 100.f);
            if (nudged == 2) {
                float z = static_cast<float>(p.z);
                for (int i = 0; i < 3; ++i) z = std::nextafter(z, 0.f);
                p.z = z;
            }
            ++nudged;
        }
    }
    ASSERT_GE(nudged, 3);
    auto exact = build_ok(soup, HealOptions{.weld_tolerance = 0});
    EXPECT_FALSE(compute_stats(exact.mesh).closed);
    auto b = build_ok(soup);
    EXPECT_EQ(b.heal.welded_vertices, 2u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.vertices, 8u);
    EXPECT_TRUE(s.closed);
    EXPECT_NEAR(s.volume, 125.0, 1e-4);
}

TEST(MeshBuild, FlipsTheMinorityOfFacets) {
    auto m = test::icosphere(1.0, 2);
    for (int f : {3, 50, 51, 200}) std::swap(m.triangles[f][1], m.triangles[f][2]);
    auto b = build_ok(test::to_bucket(m));
    EXPECT_EQ(b.heal.flipped_facets, 4u);
    EXPECT_EQ(b.heal.components_turned_outward, 0u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_TRUE(s.closed);
    EXPECT_GT(s.volume, 0);
}

TEST(MeshBuild, TurnsInsideOutMeshOutward) {
    auto m = test::icosphere(1.0, 2);
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
    auto b = build_ok(test::to_bucket(m));
    EXPECT_EQ(b.heal.flipped_facets, 0u);
    EXPECT_EQ(b.heal.components_turned_outward, 1u);
    EXPECT_GT(compute_stats(b.mesh).volume, 0);
}

TEST(MeshBuild, InsideOutWithFewFlippedFacetsCountsBoth) {
    auto m = test::cube();
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
    std::swap(m.triangles[5][1], m.triangles[5][2]);  // back to outward: the minority
    auto b = build_ok(test::to_bucket(m));
    EXPECT_EQ(b.heal.flipped_facets, 1u);
    EXPECT_EQ(b.heal.components_turned_outward, 1u);
    EXPECT_DOUBLE_EQ(compute_stats(b.mesh).volume, 1.0);
}

// Balls of radius 3, 2 and 1 round one center: a part, a cavity in it, an island in the
// cavity. The cavity's shell faces into the cavity, whichever way it came, so the signed volume
// is the material's; the balls side by side are three parts.
TEST(MeshBuild, TurnsACavitysShellIntoTheCavity) {
    const auto balls = [](double shift, std::array<bool, 3> inward) {
        test::Indexed all;
        for (int k = 0; k < 3; ++k) {
            test::Indexed b = test::icosphere(3.0 - k, 3, {k * shift, 0, 0});
            if (inward[k]) {
                for (auto& t : b.triangles) std::swap(t[1], t[2]);
            }
            const auto base = static_cast<std::uint32_t>(all.points.size());
            all.points.insert(all.points.end(), b.points.begin(), b.points.end());
            for (const auto& t : b.triangles)
                all.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
        }
        return test::to_bucket(all);
    };
    const auto volume = [](double r) {
        const test::Indexed b = test::icosphere(r, 3);
        double v6 = 0;
        for (const auto& t : b.triangles)
            v6 += dot(b.points[t[0]], cross(b.points[t[1]], b.points[t[2]]));
        return v6 / 6;
    };
    const double nested = volume(3) - volume(2) + volume(1);
    for (const std::array<bool, 3> inward :
         {std::array{false, false, false}, std::array{false, true, false},
          std::array{true, false, true}, std::array{true, true, true}}) {
        const BuildResult b = build_ok(balls(0, inward));
        EXPECT_EQ(b.heal.cavities, 1u);
        EXPECT_EQ(b.heal.cavities_turned_inward, inward[1] ? 0u : 1u);
        EXPECT_EQ(b.heal.components_turned_outward, (inward[0] ? 1u : 0u) + (inward[2] ? 1u : 0u));
        EXPECT_FALSE(b.heal.nesting_unchecked);
        const MeshStats s = compute_stats(b.mesh);
        EXPECT_EQ(s.components, 3u);
        EXPECT_NEAR(s.volume, nested, 1e-6 * nested);
        const ComponentNesting n = component_nesting(b.mesh);
        EXPECT_TRUE(n.complete);
        // Components in the order of their first facet: the balls' order.
        EXPECT_EQ(n.depth, (std::vector<std::uint32_t>{0, 1, 2}));
        EXPECT_EQ(n.parent, (std::vector<std::uint32_t>{ComponentNesting::kNone, 0, 1}));
    }
    const BuildResult apart = build_ok(balls(7, {false, true, false}));
    EXPECT_EQ(apart.heal.cavities, 0u);
    EXPECT_EQ(apart.heal.components_turned_outward, 1u);
    EXPECT_NEAR(compute_stats(apart.mesh).volume, volume(3) + volume(2) + volume(1), 1e-6 * nested);
    EXPECT_EQ(component_nesting(apart.mesh).depth, (std::vector<std::uint32_t>{0, 0, 0}));
    // With orientation off, nothing is turned.
    HealOptions keep;
    keep.orient = false;
    EXPECT_EQ(build_ok(balls(0, {false, false, false}), keep).heal.cavities, 0u);
}

// Two parts that cross (meshes overlapping without a union): a bar inside the ball's box that
// pokes out of the ball at the top is no cavity, though most of its vertices are in the ball.
TEST(MeshBuild, APartPokingThroughAnotherIsNoCavity) {
    const test::Indexed ball = test::icosphere(5.0, 3, {5, 5, 5});
    double top = 0;
    for (const Vec3& p : ball.points) top = std::max(top, p.z);
    // The bar's top corners, at x, y = 4 or 6, are out of the ball above z 5 + sqrt(23), and
    // the bar's box stays in the ball's (else it is not even a candidate).
    top -= 0.01;
    ASSERT_GT(top, 5 + std::sqrt(23.0) + 0.05);
    test::Indexed bar = test::cube();
    for (Vec3& p : bar.points) p = Vec3{4, 4, 4} + Vec3{2 * p.x, 2 * p.y, (top - 4) * p.z};
    test::Indexed inside = bar;
    for (Vec3& p : inside.points) p.z = 4 + (p.z - 4) * 0.5;  // in the ball
    for (const bool pokes : {true, false}) {
        const BuildResult b = build_ok(test::to_bucket(test::merge(ball, pokes ? bar : inside)));
        EXPECT_EQ(b.heal.cavities, pokes ? 0u : 1u) << pokes;
        EXPECT_EQ(b.heal.crossing_components, pokes ? 2u : 0u) << pokes;
        EXPECT_EQ(component_nesting(b.mesh).depth[1], pokes ? 0u : 1u) << pokes;
    }
}

// Parts that cross (meshes overlapping without their union) are found, whether a corner of one
// lies in the other (two cubes) or none does (a plus of two bars through each other's sides), and
// are never nested; parts that only touch (a cube resting on another, turned and written in
// float32, so that the contact is off by rounding) and a cavity do not cross.
TEST(MeshBuild, PartsThatCrossAreFoundAndNeverNested) {
    const auto box = [](Vec3 lo, Vec3 hi) {
        test::Indexed b = test::cube();
        for (Vec3& p : b.points)
            p = lo + Vec3{(hi.x - lo.x) * p.x, (hi.y - lo.y) * p.y, (hi.z - lo.z) * p.z};
        return b;
    };
    const auto crossing = [](const test::Indexed& m, bool turn) {
        TriangleSoup soup = test::to_bucket(m);
        if (turn) {
            test::rigid_motion(soup, 0.7, {3, -2, 5});
            for (Vec3& p : soup.points)
                p = Vec3{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
        }
        return build_ok(soup);
    };
    // Each facet in four at its edges' middles, `times` times.
    const auto finer = [](test::Indexed m, int times) {
        for (int k = 0; k < times; ++k) {
            std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
            const auto mid = [&](std::uint32_t a, std::uint32_t b) {
                const auto key = std::minmax(a, b);
                const auto [it, fresh] =
                    middle.try_emplace(key, static_cast<std::uint32_t>(m.points.size()));
                if (fresh) m.points.push_back(0.5 * (m.points[a] + m.points[b]));
                return it->second;
            };
            std::vector<test::Tri> next;
            for (const test::Tri& t : m.triangles) {
                const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]),
                                    ca = mid(t[2], t[0]);
                next.insert(next.end(),
                            {{t[0], ab, ca}, {ab, t[1], bc}, {ca, bc, t[2]}, {ab, bc, ca}});
            }
            m.triangles = std::move(next);
        }
        return m;
    };
    const test::Indexed cubes = test::merge(test::cube({0, 0, 0}, 10), test::cube({5, 5, 5}, 10));
    // The same, the first cube in 49152 facets: the second's edges pass through its facets'
    // corners, and which end is inside is asked in a tree of the whole first cube, built in
    // parallel. (Both so fine would share vertices where they cross, which the weld joins.)
    const test::Indexed fine_cubes =
        test::merge(finer(test::cube({0, 0, 0}, 10), 6), test::cube({5, 5, 5}, 10));
    const test::Indexed plus =
        test::merge(box({0, 10, 0}, {30, 20, 10}), box({10, 0, 2}, {20, 30, 8}));
    const test::Indexed resting =
        test::merge(test::cube({0, 0, 0}, 10), test::cube({3, 3, 10}, 10));
    const test::Indexed fine_resting =
        test::merge(finer(test::cube({0, 0, 0}, 10), 5), test::cube({3, 3, 10}, 10));
    const test::Indexed cavity = test::merge(test::cube({0, 0, 0}, 10), test::cube({2, 2, 2}, 6));
    for (const bool turn : {false, true}) {
        for (const test::Indexed* m : {&cubes, &plus, &fine_cubes}) {
            const BuildResult b = crossing(*m, turn);
            EXPECT_EQ(b.heal.crossing_components, 2u) << turn;
            EXPECT_FALSE(b.heal.crossing_unchecked);
            EXPECT_EQ(b.heal.cavities, 0u);
            const ComponentNesting n = component_nesting(b.mesh);
            EXPECT_TRUE(n.crossing_complete);
            EXPECT_EQ(n.crossing, (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{0, 1}}));
            EXPECT_EQ(n.depth, (std::vector<std::uint32_t>{0, 0}));
        }
        // Also with the lower cube in 12288 facets: more facet pairs near the contact than are
        // compared one by one (kEveryPair), so they come from a search.
        for (const test::Indexed* m : {&resting, &fine_resting}) {
            const BuildResult r = crossing(*m, turn);
            EXPECT_EQ(r.heal.crossing_components, 0u) << turn;
            EXPECT_FALSE(r.heal.crossing_unchecked);
            EXPECT_TRUE(component_nesting(r.mesh).crossing.empty());
        }
        const BuildResult c = crossing(cavity, turn);
        EXPECT_EQ(c.heal.crossing_components, 0u) << turn;
        EXPECT_EQ(c.heal.cavities, 1u);
    }
}

// A mesh that passes through itself: a ball with one vertex pushed out through the far wall,
// a cube's corner pushed through the opposite wall's diagonal, two facets folded onto each
// other across their edge, a fan whose third facet comes back through its first. Healing counts the
// facet pairs that cross and says where the first does, the same on any thread count and in any
// facet order; it mends none. A ball and a plate thinner than the mesh's resolution (walls close,
// not crossing) have none.
TEST(MeshBuild, AMeshThatPassesThroughItselfIsFound) {
    const test::Indexed ball = test::icosphere(10.0, 4);
    EXPECT_EQ(build_ok(test::to_bucket(ball)).heal.self_intersections, 0u);
    test::Indexed plate = test::cube();
    for (Vec3& p : plate.points) p = Vec3{10 * p.x, 10 * p.y, 1e-3 * p.z};
    const BuildResult thin = build_ok(test::to_bucket(plate));
    EXPECT_EQ(thin.heal.self_intersections, 0u);
    EXPECT_FALSE(thin.heal.self_intersection_unchecked);

    test::Indexed pushed = ball;
    std::size_t far = 0;
    for (std::size_t i = 0; i < pushed.points.size(); ++i)
        if (pushed.points[i].x > pushed.points[far].x) far = i;
    pushed.points[far] = Vec3{-12, 0.1, 0.2};
    std::vector<BuildResult> runs;
    for (const int threads : {1, 2, 4}) {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
        runs.push_back(build_ok(test::to_bucket(pushed)));
    }
    const HealReport& h = runs.front().heal;
    // The pushed vertex's fan (six facets) crosses the far wall and the facets it passes.
    EXPECT_GE(h.self_intersections, 6u);
    EXPECT_FALSE(h.self_intersection_unchecked);
    EXPECT_LT(norm(h.self_intersection_at), 10.0 + 1e-9);  // inside the ball or on its wall
    EXPECT_GT(norm(h.self_intersection_at), 1.0);
    for (const BuildResult& r : runs) {
        EXPECT_EQ(r.heal.self_intersections, h.self_intersections);
        EXPECT_EQ(r.heal.self_intersection_at, h.self_intersection_at);
    }
    TriangleSoup shuffled = test::to_bucket(pushed);
    test::permute_facets(shuffled, 7);
    EXPECT_EQ(build_ok(shuffled).heal.self_intersections, h.self_intersections);
    // Missing a facet away from the pushed vertex: checked once, on the mesh its filled hole
    // closes, the same pairs.
    test::Indexed holed = pushed;
    for (std::size_t k = 0; k < holed.triangles.size(); ++k) {
        const test::Tri& tri = holed.triangles[k];
        if (tri[0] != far && tri[1] != far && tri[2] != far && holed.points[tri[0]].x > 5) {
            holed.triangles.erase(holed.triangles.begin() + static_cast<std::ptrdiff_t>(k));
            break;
        }
    }
    const BuildResult filled = build_ok(test::to_bucket(holed));
    EXPECT_EQ(filled.heal.holes_filled, 1u);
    EXPECT_EQ(filled.heal.self_intersections, h.self_intersections);

    // A cube's corner pushed straight through the diagonal of the opposite wall: the edges that
    // cross pass through the border between the wall's two facets (told by the wedge those
    // make). Pushed in but not through, or onto the wall, it does not cross.
    for (const auto& [to, crosses] :
         {std::pair{Vec3{-3, 5, 5}, true}, std::pair{Vec3{3, 5, 5}, false},
          std::pair{Vec3{0, 5, 5}, false}}) {
        test::Indexed corner = test::cube({0, 0, 0}, 10);
        corner.points[7] = to;  // was (10, 10, 10)
        EXPECT_EQ(build_ok(test::to_bucket(corner)).heal.self_intersections > 0, crosses) << to.x;
    }

    // Folded: the second facet's third corner on the first's side of their edge, in its plane.
    test::Indexed fold;
    fold.points = {{0, 0, 0}, {4, 0, 0}, {1, 3, 0}, {3, 2, 0}};
    fold.triangles = {{0, 1, 2}, {1, 0, 3}};
    const BuildResult folded = build_ok(test::to_bucket(fold));
    EXPECT_EQ(folded.heal.self_intersections, 1u);
    EXPECT_NEAR(folded.heal.self_intersection_at.x, 7.0 / 3, 1e-6);  // the second's centre
    EXPECT_NEAR(folded.heal.self_intersection_at.y, 2.0 / 3, 1e-6);
    // Opened out flat (the corner across the edge), it does not cross.
    fold.points[3] = {3, -2, 0};
    EXPECT_EQ(build_ok(test::to_bucket(fold)).heal.self_intersections, 0u);

    // A fan about the origin: the third facet's outer edge passes through the first facet,
    // which it shares only the origin with.
    test::Indexed fan;
    fan.points = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.3, 1.2, 1}, {0.7, 0.2, -1}};
    fan.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}};
    const BuildResult fanned = build_ok(test::to_bucket(fan));
    EXPECT_EQ(fanned.heal.self_intersections, 1u);
    EXPECT_NEAR(fanned.heal.self_intersection_at.x, 0.5, 1e-6);
    EXPECT_NEAR(fanned.heal.self_intersection_at.y, 0.7, 1e-6);
    EXPECT_NEAR(fanned.heal.self_intersection_at.z, 0.0, 1e-6);
}

// Too many overlapping components to check which cross within kCrossingWork (two thousand
// cubes over one another: two million pairs of 24 facets): none is counted, and the report says
// the check was not made. Nesting is still checked (no box lies in another).
TEST(MeshBuild, TooManyCrossingComponentsAreNotChecked) {
    test::Indexed m;
    for (int k = 0; k < 2000; ++k) {
        const double d = 0.001 * k;  // along the diagonal: no shared vertex, no common plane
        m = test::merge(m, test::cube({d, d, d}, 1.0));
    }
    const BuildResult b = build_ok(test::to_indexed_soup(m));
    EXPECT_TRUE(b.heal.crossing_unchecked);
    EXPECT_EQ(b.heal.crossing_components, 0u);
    EXPECT_FALSE(b.heal.nesting_unchecked);
    const ComponentNesting n = component_nesting(b.mesh);
    EXPECT_FALSE(n.crossing_complete);
    EXPECT_TRUE(n.crossing.empty());
}

// Too many components to tell which lies inside which within kNestingWork (a ball of 20k
// facets round a thousand small cubes, each to be tested against it): no ray is cast, every
// closed component is turned outward, and the report says the check was not made.
TEST(MeshBuild, TooManyComponentsToNestAreAllTurnedOutward) {
    test::Indexed m = test::icosphere(50.0, 5);
    for (int k = 0; k < 1000; ++k) {
        const Vec3 o{-10.0 + 2 * (k % 10), -10.0 + 2 * ((k / 10) % 10), -10.0 + 2 * (k / 100)};
        test::Indexed cube = test::cube(o, 1.0);
        for (auto& t : cube.triangles) std::swap(t[1], t[2]);  // given as cavities would be
        m = test::merge(m, cube);
    }
    const BuildResult b = build_ok(test::to_indexed_soup(m));
    EXPECT_TRUE(b.heal.nesting_unchecked);
    EXPECT_EQ(b.heal.cavities, 0u);
    EXPECT_EQ(b.heal.components_turned_outward, 1000u);
    EXPECT_FALSE(component_nesting(b.mesh).complete);
}

// A cube whose top is a 4 x 4 grid while its sides are two facets each, as a CAD system
// tessellating faces apart writes it: three top vertices lie in the middle of each side's top
// edge (T-junctions), four cracks of no area. Closed by splitting the sides' facets there.
TEST(MeshBuild, ClosesCracksAlongTJunctions) {
    test::Indexed m = test::cube({0, 0, 0}, 4.0);
    // Drop the top's two facets (those with all vertices at z = 4) for a grid.
    std::erase_if(m.triangles, [&](const test::Tri& t) {
        return m.points[t[0]].z == 4 && m.points[t[1]].z == 4 && m.points[t[2]].z == 4;
    });
    const auto base = static_cast<std::uint32_t>(m.points.size());
    for (int j = 0; j <= 4; ++j) {
        for (int i = 0; i <= 4; ++i) m.points.push_back({double(i), double(j), 4.0});
    }
    const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(5 * j + i); };
    for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    for (const bool fill : {false, true}) {
        HealOptions o;
        o.fill_holes = fill;
        const BuildResult b = build_ok(test::to_bucket(m), o);
        const MeshStats s = compute_stats(b.mesh);
        EXPECT_EQ(b.mesh.validate(), "");
        EXPECT_EQ(s.closed, fill);
        EXPECT_EQ(b.heal.facets_split_at_t_junctions, fill ? 4u : 0u);
        EXPECT_EQ(b.heal.holes_filled, 0u);
        if (fill) {
            EXPECT_EQ(s.euler_characteristic, 2);
            EXPECT_DOUBLE_EQ(s.volume, 64.0);
            // Every face still names its input facet (split ones both theirs).
            for (const std::uint32_t f : b.mesh.source_faces()) EXPECT_LT(f, m.triangles.size());
        }
    }
    // With a cube touching it at one corner (a non-manifold vertex): closing the cracks builds
    // the mesh again, which finds that vertex again; the report counts what the input had, once.
    test::Indexed touching = test::merge(m, test::cube({-1, -1, -1}, 1.0));
    HealOptions keep_open;
    keep_open.fill_holes = false;
    const HealReport as_read = build_ok(test::to_bucket(touching), keep_open).heal;
    const HealReport closed = build_ok(test::to_bucket(touching)).heal;
    EXPECT_GE(as_read.nonmanifold_vertices, 1u);
    EXPECT_EQ(closed.nonmanifold_vertices, as_read.nonmanifold_vertices);
    EXPECT_EQ(closed.nonmanifold_edges, as_read.nonmanifold_edges);
    EXPECT_EQ(closed.flipped_facets, as_read.flipped_facets);
    EXPECT_EQ(closed.facets_split_at_t_junctions, 4u);
}

// A ball that lost a facet, and one that lost the six round a vertex: small holes in a closed
// part, filled. A hemisphere's rim and a loose facet are openings, not holes: left open.
TEST(MeshBuild, FillsSmallHolesButNotOpenings) {
    const test::Indexed ball = test::icosphere(10.0, 3);
    const MeshStats whole = compute_stats(build_ok(test::to_bucket(ball)).mesh);
    test::Indexed one = ball;
    one.triangles.erase(one.triangles.begin() + 100);
    test::Indexed six = ball;
    const std::uint32_t v = six.triangles[200][0];
    std::erase_if(six.triangles,
                  [&](const test::Tri& t) { return t[0] == v || t[1] == v || t[2] == v; });
    ASSERT_EQ(six.triangles.size() + 6, ball.triangles.size());
    for (const auto& [holed, added] : {std::pair{one, 1u}, std::pair{six, 4u}}) {
        const BuildResult b = build_ok(test::to_bucket(holed));
        const MeshStats s = compute_stats(b.mesh);
        EXPECT_EQ(b.mesh.validate(), "");
        EXPECT_TRUE(s.closed);
        EXPECT_EQ(b.heal.holes_filled, 1u);
        EXPECT_EQ(b.heal.hole_facets_added, added);
        EXPECT_EQ(b.mesh.num_faces(), holed.triangles.size() + added);
        EXPECT_NEAR(s.volume, whole.volume, 1e-3 * whole.volume);
        // The added facets name no input facet.
        std::size_t unnamed = 0;
        for (const std::uint32_t f : b.mesh.source_faces()) unnamed += f >= holed.triangles.size();
        EXPECT_EQ(unnamed, added);
    }
    test::Indexed half = ball;
    std::erase_if(half.triangles, [&](const test::Tri& t) {
        return half.points[t[0]].z + half.points[t[1]].z + half.points[t[2]].z < 0;
    });
    half = test::merge(half, test::Indexed{{{30, 0, 0}, {31, 0, 0}, {30, 1, 0}}, {{0, 1, 2}}});
    const BuildResult b = build_ok(test::to_bucket(half));
    EXPECT_EQ(b.heal.holes_filled, 0u);
    EXPECT_EQ(compute_stats(b.mesh).boundary_loops, 2u);
}

// A part closed only by its filled hole is reported as the closed part it then is: its cavity
// is one, turned to face into it, and a part crossing it crosses. (The first build saw the
// part open, with neither; its report was kept until the forty-fifth session.)
TEST(MeshBuild, APartClosedByItsFilledHoleHasItsCavitiesAndCrossings) {
    test::Indexed holed = test::cube({0, 0, 0}, 10);
    holed.triangles.erase(holed.triangles.begin());  // one facet of the bottom
    const BuildResult cavity =
        build_ok(test::to_bucket(test::merge(holed, test::cube({3, 3, 3}, 4))));
    EXPECT_EQ(cavity.heal.holes_filled, 1u);
    EXPECT_EQ(cavity.heal.cavities, 1u);
    EXPECT_EQ(cavity.heal.cavities_turned_inward, 1u);  // given facing out of the cavity
    EXPECT_EQ(cavity.heal.components_turned_outward, 0u);
    EXPECT_DOUBLE_EQ(compute_stats(cavity.mesh).volume, 1000.0 - 64.0);
    const BuildResult crossing =
        build_ok(test::to_bucket(test::merge(holed, test::cube({5, 5, 5}, 10))));
    EXPECT_EQ(crossing.heal.holes_filled, 1u);
    EXPECT_EQ(crossing.heal.crossing_components, 2u);
    EXPECT_EQ(crossing.heal.cavities, 0u);
}

// A mesh of some of the components: valid on its own, each face with its input facet.
TEST(MeshBuild, KeepsWholeComponentsAsAMeshOfTheirOwn) {
    test::Indexed m = test::merge(test::cube({0, 0, 0}, 1.0), test::icosphere(1.0, 1, {5, 0, 0}));
    m = test::merge(m, test::cube({9, 0, 0}, 1.0));
    m.triangles.erase(m.triangles.begin() + 12);  // the ball is open now
    HealOptions keep_open;
    keep_open.fill_holes = false;
    const BuildResult b = build_ok(test::to_indexed_soup(m), keep_open);
    const Components comp = face_components(b.mesh);
    EXPECT_EQ(comp.closed, (std::vector<std::uint8_t>{1, 0, 1}));
    std::vector<std::uint8_t> keep = {1, 0, 1};
    const Mesh cubes = keep_components(b.mesh, comp, keep);
    EXPECT_EQ(cubes.validate(), "");
    EXPECT_EQ(cubes.num_faces(), 24u);
    EXPECT_EQ(cubes.num_vertices(), 16u);
    const MeshStats s = compute_stats(cubes);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.components, 2u);
    EXPECT_DOUBLE_EQ(s.volume, 2.0);
    std::uint32_t k = 0;
    for (std::uint32_t f = 0; f < b.mesh.num_faces(); ++f) {
        if (!keep[comp.of_face[f]]) continue;
        EXPECT_EQ(cubes.source_face(FaceId(k++)), b.mesh.source_face(FaceId(f)));
    }
    keep = {0, 1, 0};
    const Mesh ball = keep_components(b.mesh, comp, keep);
    EXPECT_EQ(ball.validate(), "");
    EXPECT_EQ(compute_stats(ball).boundary_loops, 1u);
}

TEST(MeshBuild, RemovesDuplicateFacetsInAnyOrderOrOrientation) {
    auto m = test::cube();
    m.triangles.push_back(m.triangles[0]);
    m.triangles.push_back({m.triangles[4][1], m.triangles[4][2], m.triangles[4][0]});
    m.triangles.push_back({m.triangles[7][0], m.triangles[7][2], m.triangles[7][1]});
    auto b = build_ok(test::to_bucket(m));
    EXPECT_EQ(b.heal.duplicate_facets_removed, 3u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.faces, 12u);
    EXPECT_TRUE(s.closed);
    // The first of each duplicate pair stays.
    for (std::size_t f = 0; f < 12; ++f) EXPECT_EQ(b.mesh.source_face(FaceId(f)), f);
}

TEST(MeshBuild, RemovesDegenerateFacets) {
    auto m = test::cube();
    m.points.push_back({0.5, 0, 0});  // on the edge 0-1
    const auto mid = static_cast<std::uint32_t>(m.points.size() - 1);
    m.triangles.push_back({0, 0, 3});    // repeated vertex
    m.triangles.push_back({0, 1, mid});  // zero area: three distinct, collinear vertices
    m.triangles.push_back({2, 6, 2});    // repeated vertex
    auto b = build_ok(test::to_bucket(m));
    EXPECT_EQ(b.heal.degenerate_facets_removed, 3u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.faces, 12u);
    EXPECT_EQ(s.vertices, 8u);  // the collinear point is no longer used
    EXPECT_TRUE(s.closed);
}

/// The unit cube `m` with caps added, healed: `removed` facets dropped, `split` caps split in,
/// and a closed unit cube of `faces` facets and `vertices` vertices left.
void expect_healed_cube(const test::Indexed& m, std::uint64_t removed, std::uint64_t split,
                        std::size_t faces, std::size_t vertices) {
    auto built = build_ok(test::to_bucket(m));
    EXPECT_EQ(built.heal.degenerate_facets_removed, removed);
    EXPECT_EQ(built.heal.caps_split, split);
    const MeshStats s = compute_stats(built.mesh);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.faces, faces);
    EXPECT_EQ(s.vertices, vertices);
    EXPECT_NEAR(s.volume, 1.0, 1e-12);
    EXPECT_EQ(built.mesh.validate(), "");
}

// A cap stitched into the surface (a T-junction's zero-area facet, as CAD tessellations make
// them) is removed by splitting the facet beyond its long edge: no crack opens.
TEST(MeshBuild, SplitsStitchedCapsInsteadOfOpeningACrack) {
    auto m = test::cube();
    // Facet 0 (a, b, x): split its edge a-b at the midpoint c into (a, c, x) and (c, b, x),
    // then close the T-junction with the cap (a, b, c).
    const auto t = m.triangles[0];
    const std::uint32_t a = t[0], b = t[1], x = t[2];
    const Vec3 pa = m.points[a], pb = m.points[b];
    m.points.push_back(0.5 * (pa + pb));
    const auto c = static_cast<std::uint32_t>(m.points.size() - 1);
    m.triangles[0] = {a, c, x};
    m.triangles.push_back({c, b, x});
    m.triangles.push_back({a, b, c});
    // 12 + 1 (facet 0 split) + 1 (the facet beyond a-b split)
    expect_healed_cube(m, 1, 1, 14, 9);
}

// A strip of caps: a sliver between an edge (a, b) and the finer polyline a, c1, c2, b of the
// face beside it, filled with two zero-area facets, as BRepMesh makes them along curved edges
// at fine angular deflections. The first cap (a, b, c2) has the second beyond a short edge;
// the second (c2, c1, a) has the first beyond its long edge, and waits for it. Until the
// forty-ninth session both were dropped ("not stitched in") and the cube had a hole.
TEST(MeshBuild, SplitsAStripOfCapsInsteadOfOpeningACrack) {
    auto m = test::cube();
    const auto t = m.triangles[0];
    const std::uint32_t a = t[0], b = t[1], x = t[2];
    const Vec3 pa = m.points[a], pb = m.points[b];
    m.points.push_back(pa + (1.0 / 3) * (pb - pa));
    const auto c1 = static_cast<std::uint32_t>(m.points.size() - 1);
    m.points.push_back(pa + (2.0 / 3) * (pb - pa));
    const auto c2 = static_cast<std::uint32_t>(m.points.size() - 1);
    m.triangles[0] = {a, c1, x};
    m.triangles.push_back({c1, c2, x});
    m.triangles.push_back({c2, b, x});
    m.triangles.push_back({a, b, c2});
    m.triangles.push_back({c2, c1, a});
    // 12 + 2 (facet 0 in three) + 2 (the facet beyond a-b in three)
    expect_healed_cube(m, 2, 2, 16, 10);
}

// Two caps over each other hanging off a closed cube's edge (a, b): a fin of zero area, one cap
// running a -> b as the cube's facet there does. Neither is stitched in: both go and the cube
// stays as it was. Splitting the facet beyond the first cap's long edge would leave its
// pieces' edges to the second cap, which goes: a crack where there was none.
TEST(MeshBuild, AFinOfCapsOffAnEdgeIsDroppedAndSplitsNothing) {
    auto m = test::cube();
    const auto t = m.triangles[0];
    const std::uint32_t a = t[0], b = t[1];
    m.points.push_back(0.5 * (m.points[a] + m.points[b]));
    const auto c = static_cast<std::uint32_t>(m.points.size() - 1);
    m.triangles.push_back({b, a, c});
    m.triangles.push_back({a, b, c});
    expect_healed_cube(m, 2, 0, 12, 8);
}

TEST(MeshBuild, FindsHolesAsBoundaryLoops) {
    auto m = test::cube();
    m.triangles.erase(m.triangles.begin() + 2, m.triangles.begin() + 4);  // the top square
    auto b = build_ok(test::to_bucket(m));
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_FALSE(s.closed);
    EXPECT_EQ(s.boundary_loops, 1u);
    EXPECT_EQ(s.boundary_edges, 4u);
    ASSERT_EQ(s.boundary_loop_sizes.size(), 1u);
    EXPECT_EQ(s.boundary_loop_sizes[0], 4u);
    EXPECT_EQ(s.euler_characteristic, 1);  // a disc

    auto m2 = test::cube();
    m2.triangles.erase(m2.triangles.begin() + 2);  // one top triangle (vertices 4 5 6)
    m2.triangles.erase(m2.triangles.begin());      // one bottom triangle (0 2 1): no shared vertex
    HealOptions keep_open;                         // else each, one missing facet, is filled
    keep_open.fill_holes = false;
    auto b2 = build_ok(test::to_bucket(m2), keep_open);
    const MeshStats s2 = compute_stats(b2.mesh);
    EXPECT_EQ(s2.boundary_loops, 2u);
    EXPECT_EQ(s2.boundary_edges, 6u);
}

TEST(MeshBuild, SplitsTwoCubesSharingOneEdge) {
    // Cube B touches cube A only along A's edge x=1, y=1 (z from 0 to 1).
    auto m = test::merge(test::cube(), test::cube({1, 1, 0}, 1.0));
    auto soup = test::to_bucket(m);
    auto b = build_ok(soup);
    EXPECT_EQ(b.heal.nonmanifold_edges, 1u);
    EXPECT_EQ(b.heal.nonmanifold_vertices, 2u);
    EXPECT_EQ(b.heal.flipped_facets, 0u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.components, 2u);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.vertices, 16u);
    EXPECT_EQ(s.edges, 36u);
    EXPECT_EQ(s.euler_characteristic, 4);
    EXPECT_DOUBLE_EQ(s.volume, 2.0);
    // Any facet order gives the same split.
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
        auto p = soup;
        test::permute_facets(p, seed);
        auto bp = build_ok(p);
        const MeshStats sp = compute_stats(bp.mesh);
        EXPECT_EQ(sp.components, 2u) << seed;
        EXPECT_TRUE(sp.closed) << seed;
        EXPECT_EQ(bp.heal.nonmanifold_edges, 1u);
    }
}

TEST(MeshBuild, CountsTwoDisjointBodies) {
    auto m = test::merge(test::icosphere(1.0, 2), test::cube({5, 0, 0}, 2.0));
    auto b = build_ok(test::to_bucket(m));
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.components, 2u);
    EXPECT_TRUE(s.closed);
    EXPECT_EQ(s.euler_characteristic, 4);
    EXPECT_EQ(b.heal.nonmanifold_edges, 0u);
    EXPECT_EQ(b.heal.nonmanifold_vertices, 0u);
}

TEST(MeshBuild, TwoCubesSharingOneVertexComeApart) {
    auto m = test::merge(test::cube(), test::cube({1, 1, 1}, 1.0));
    auto b = build_ok(test::to_bucket(m));
    EXPECT_EQ(b.heal.nonmanifold_edges, 0u);
    EXPECT_EQ(b.heal.nonmanifold_vertices, 1u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.components, 2u);
    EXPECT_EQ(s.vertices, 16u);
}

TEST(MeshBuild, CutsANonOrientableBand) {
    auto b = build_ok(test::to_bucket(test::mobius(24)));
    EXPECT_EQ(b.heal.orientation_conflicts, 1u);
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_FALSE(s.closed);
    EXPECT_EQ(s.faces, 48u);
}

TEST(MeshBuild, CarriesAttributesAndSourceIndices) {
    auto soup = test::to_indexed_soup(test::cube());
    for (std::size_t f = 0; f < soup.num_facets(); ++f) {
        soup.color.push_back(static_cast<std::int64_t>(100 + f));
        soup.cut.push_back(static_cast<std::int64_t>(f % 3) - 1);
        soup.surface.push_back(static_cast<std::int32_t>(f / 2));
    }
    soup.triangles.insert(soup.triangles.begin(), {0, 0, 1});  // degenerate: dropped
    soup.color.insert(soup.color.begin(), 7);
    soup.cut.insert(soup.cut.begin(), 7);
    soup.surface.insert(soup.surface.begin(), 7);
    auto b = build_ok(soup);
    ASSERT_TRUE(b.mesh.has_attributes());
    ASSERT_EQ(b.mesh.num_faces(), 12u);
    for (std::size_t f = 0; f < 12; ++f) {
        const std::uint32_t src = b.mesh.source_face(FaceId(f));
        EXPECT_EQ(src, f + 1);
        EXPECT_EQ(b.mesh.colors()[f], soup.color[src]);
        EXPECT_EQ(b.mesh.cuts()[f], soup.cut[src]);
        EXPECT_EQ(b.mesh.surfaces()[f], soup.surface[src]);
    }
}

TEST(MeshBuild, RejectsTriangleNamingMissingPoint) {
    TriangleSoup soup;
    soup.points = {{0, 0, 0}, {1, 0, 0}};
    soup.triangles = {{0, 1, 2}};
    auto r = build_mesh(soup);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kIndexOutOfRange);
}

TEST(MeshBuild, EmptySoupGivesEmptyMesh) {
    auto b = build_ok(TriangleSoup{});
    const MeshStats s = compute_stats(b.mesh);
    EXPECT_EQ(s.faces, 0u);
    EXPECT_FALSE(s.closed);
}

void expect_same_stats(const MeshStats& a, const MeshStats& b, double rel) {
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_EQ(a.edges, b.edges);
    EXPECT_EQ(a.components, b.components);
    EXPECT_EQ(a.boundary_loops, b.boundary_loops);
    EXPECT_EQ(a.euler_characteristic, b.euler_characteristic);
    EXPECT_EQ(a.closed, b.closed);
    EXPECT_NEAR(a.area, b.area, rel * a.area);
    EXPECT_NEAR(a.volume, b.volume, rel * std::abs(a.volume));
}

TEST(MeshBuildInvariance, FacetAndVertexPermutation) {
    auto m = test::merge(test::icosphere(3.0, 3), test::cube({10, 0, 0}, 2.0));
    auto base = build_ok(test::to_indexed_soup(m));
    const MeshStats s0 = compute_stats(base.mesh);
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        auto soup = test::to_indexed_soup(m);
        test::permute_facets(soup, seed);
        test::permute_points(soup, seed + 10);
        auto b = build_ok(soup);
        expect_same_stats(s0, compute_stats(b.mesh), 1e-12);
        auto bucket = test::to_bucket(m);
        test::permute_facets(bucket, seed);
        expect_same_stats(s0, compute_stats(build_ok(bucket).mesh), 1e-12);
    }
}

TEST(MeshBuildInvariance, RigidMotion) {
    auto m = test::icosphere(3.0, 3);
    const MeshStats s0 = compute_stats(build_ok(test::to_bucket(m)).mesh);
    auto soup = test::to_bucket(m);
    test::rigid_motion(soup, 0.7, {100, -50, 20});
    auto b = build_ok(soup);
    expect_same_stats(s0, compute_stats(b.mesh), 1e-9);
}

TEST(MeshBuildInvariance, AsciiAndBinaryGiveTheSameMesh) {
    auto m = test::icosphere(25.0, 3);
    for (Vec3& p : m.points) p = {0.1 + p.x, p.y / 3.0, p.z * 1.7};  // digits float cannot hold
    auto bin = read_stl(encode_stl_binary(m.points, m.triangles));
    auto asc = read_stl(test::bytes_of(encode_stl_ascii(m.points, m.triangles)));
    ASSERT_TRUE(bin.ok());
    ASSERT_TRUE(asc.ok()) << asc.error().describe();
    auto a = build_ok(*bin), c = build_ok(*asc);
    expect_same_stats(compute_stats(a.mesh), compute_stats(c.mesh), 0.0);
    EXPECT_EQ(a.mesh.origins().size(), c.mesh.origins().size());
    EXPECT_TRUE(
        std::equal(a.mesh.origins().begin(), a.mesh.origins().end(), c.mesh.origins().begin()));
}

TEST(MeshBuildInvariance, AllFacetsFlippedGivesTheSameSolid) {
    auto m = test::icosphere(2.0, 2);
    const MeshStats s0 = compute_stats(build_ok(test::to_bucket(m)).mesh);
    for (auto& t : m.triangles) std::swap(t[0], t[1]);
    expect_same_stats(s0, compute_stats(build_ok(test::to_bucket(m)).mesh), 1e-12);
}

TEST(MeshBuildDeterminism, SameMeshWhateverTheThreadCount) {
    // Large enough for several parallel chunks (> 32768 points).
    auto m = test::merge(test::icosphere(5.0, 5), test::merge(test::cube(), test::cube({1, 1, 0})));
    auto soup = test::to_bucket(m);
    test::permute_facets(soup, 42);
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return build_ok(soup);
    };
    const BuildResult one = run(1), many = run(4);
    EXPECT_TRUE(std::ranges::equal(one.mesh.origins(), many.mesh.origins()));
    EXPECT_TRUE(std::ranges::equal(one.mesh.twins(), many.mesh.twins()));
    EXPECT_TRUE(std::ranges::equal(one.mesh.source_faces(), many.mesh.source_faces()));
    EXPECT_TRUE(std::ranges::equal(one.mesh.positions(), many.mesh.positions()));
}

}  // namespace
}  // namespace ncrev

namespace ncrev {
namespace {

// Small files are welded in one pass, large ones (from 262144 facets) in two halves at once and
// merged: the same mesh either way, numbered as the file orders its points, on any thread count.
TEST(MeshBuildInvariance, WeldingWhileReadingGivesTheSameMeshAndCounts) {
    for (const int level : {3, 7}) {
        auto m = test::merge(test::icosphere(4.0, level), test::cube({9, 0, 0}, 2.0));
        m.triangles.push_back(m.triangles[5]);  // a duplicate
        const auto bytes = encode_stl_binary(m.points, m.triangles);
        ReadOptions weld;
        weld.weld_exact = true;
        auto a = read_stl(bytes);
        auto b = read_stl(bytes, {}, weld);
        auto c = [&] {
            tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
            return read_stl(bytes, {}, weld);
        }();
        ASSERT_TRUE(a.ok() && b.ok() && c.ok());
        EXPECT_TRUE(b->points == c->points) << level;
        EXPECT_TRUE(b->triangles == c->triangles) << level;
        // Numbered by first occurrence in the file, as an ordered map of the bucket's points
        // numbers them (-0 and +0 are one point).
        std::map<std::array<double, 3>, std::uint32_t> number;
        std::vector<Vec3> first_seen;
        bool same = b->triangles.size() == a->triangles.size();
        for (std::size_t f = 0; same && f < a->triangles.size(); ++f) {
            for (int k = 0; k < 3; ++k) {
                const Vec3 p = a->points[a->triangles[f][static_cast<std::size_t>(k)]];
                const std::array<double, 3> key{p.x + 0.0, p.y + 0.0, p.z + 0.0};
                const auto [at, added] =
                    number.emplace(key, static_cast<std::uint32_t>(first_seen.size()));
                if (added) first_seen.push_back({key[0], key[1], key[2]});
                same = same && b->triangles[f][static_cast<std::size_t>(k)] == at->second;
            }
        }
        EXPECT_TRUE(same) << level;
        EXPECT_TRUE(b->points == first_seen) << level;
        auto ma = build_ok(*a), mb = build_ok(std::move(b).value());
        EXPECT_TRUE(std::ranges::equal(ma.mesh.origins(), mb.mesh.origins())) << level;
        EXPECT_TRUE(std::ranges::equal(ma.mesh.twins(), mb.mesh.twins())) << level;
        EXPECT_TRUE(std::ranges::equal(ma.mesh.positions(), mb.mesh.positions())) << level;
        EXPECT_EQ(ma.heal.input_points, mb.heal.input_points);
        EXPECT_EQ(ma.heal.exact_welded_points, mb.heal.exact_welded_points);
        EXPECT_EQ(ma.heal.duplicate_facets_removed, 1u);
        EXPECT_EQ(mb.heal.duplicate_facets_removed, 1u);
    }
}

// The two halves of a large file are read at once; a non-finite coordinate is still reported
// at its byte, the earliest one when both halves have one.
TEST(MeshBuildInvariance, WeldingWhileReadingReportsTheFirstBadCoordinate) {
    const auto m = test::icosphere(4.0, 7);  // 327680 facets: welded in two halves
    const auto good = encode_stl_binary(m.points, m.triangles);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    // Facet f, vertex 1, z: header 84 + f records + normal 12 + vertex 12 + 8.
    const auto at = [](std::size_t f) { return 84 + 50 * f + 12 + 12 + 8; };
    ReadOptions weld;
    weld.weld_exact = true;
    for (const std::vector<std::size_t>& bad :
         {std::vector<std::size_t>{200000}, {100, 200000}, {163840, 200000}, {163839}}) {
        auto bytes = good;
        for (const std::size_t f : bad) std::memcpy(bytes.data() + at(f), &nan, 4);
        for (const bool welding : {false, true}) {
            auto r = read_stl(bytes, {}, welding ? weld : ReadOptions{});
            ASSERT_FALSE(r.ok());
            EXPECT_EQ(r.error().code, ErrorCode::kBadNumber);
            EXPECT_EQ(r.error().byte_offset, static_cast<std::int64_t>(at(bad.front())))
                << bad.front() << (welding ? " welding" : "");
        }
    }
}

}  // namespace
}  // namespace ncrev
