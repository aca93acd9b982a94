// Surface fitting against known parameters (issue 6): whole and partial patches of every kind
// (down to a 30 degree arc of a cylinder, a 90 degree band of a torus, a small cap of a
// sphere), exact and with noise, float32-rounded, placed by random rigid motions; kind
// selection; distances and closest points; meshed surfaces.
#include "ncrev/fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "analytic_shapes.h"
#include "ncrev/curvature.h"
#include "ncrev/mesh.h"

namespace ncrev {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

struct Patch {
    std::string name;
    Surface truth;
    std::vector<Vec3> points, normals;
    double size = 0;  ///< bounding-box diagonal of the points
};

/// A random rotation (axis and angle from the rng) applied to v.
Vec3 rotate(Vec3 v, Vec3 axis, double angle) {
    const Vec3 k = normalized(axis);
    return std::cos(angle) * v + std::sin(angle) * cross(k, v) +
           (1 - std::cos(angle)) * dot(k, v) * k;
}

/// Builds a patch in a local frame (axis z, center at the origin), then moves it rigidly.
/// `sample(u, v)` gives a local point and its outward normal for u, v in [0, 1].
template <class F>
Patch make_patch(const std::string& name, Surface local, std::size_t n, test::Rng& rng,
                 F&& sample) {
    Patch p;
    p.name = name;
    const Vec3 axis{rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5};
    const double angle = 2 * kPi * rng.uniform();
    const Vec3 shift{200 * rng.uniform() - 100, 200 * rng.uniform() - 100,
                     200 * rng.uniform() - 100};
    Box3 box;
    for (std::size_t i = 0; i < n; ++i) {
        Vec3 q, nq;
        sample(rng.uniform(), rng.uniform(), q, nq);
        p.points.push_back(rotate(q, axis, angle) + shift);
        p.normals.push_back(rotate(nq, axis, angle));
        box.add(p.points.back());
    }
    p.size = norm(box.max - box.min);
    local.point = rotate(local.point, axis, angle) + shift;
    local.axis = rotate(local.axis, axis, angle);
    local.sweep = rotate(local.sweep, axis, angle);
    p.truth = local;
    return p;
}

Patch plane_patch(test::Rng& rng, std::size_t n = 1000) {
    Surface s;
    s.kind = FitKind::kPlane;
    return make_patch("plane", s, n, rng, [](double u, double v, Vec3& q, Vec3& nq) {
        q = {40 * u - 20, 30 * v - 15, 0};
        nq = {0, 0, 1};
    });
}

Patch sphere_patch(test::Rng& rng, double r, double cap_deg, std::size_t n = 1000) {
    Surface s;
    s.kind = FitKind::kSphere;
    s.radius = r;
    const double cmax = std::cos(cap_deg * kDeg);
    return make_patch("sphere cap " + std::to_string(int(cap_deg)) + " deg", s, n, rng,
                      [=](double u, double v, Vec3& q, Vec3& nq) {
                          const double z = 1 - u * (1 - cmax), phi = 2 * kPi * v;
                          const double sr = std::sqrt(std::max(0.0, 1 - z * z));
                          nq = {sr * std::cos(phi), sr * std::sin(phi), z};
                          q = r * nq;
                      });
}

Patch cylinder_patch(test::Rng& rng, double r, double arc_deg, double height,
                     std::size_t n = 1000) {
    Surface s;
    s.kind = FitKind::kCylinder;
    s.radius = r;
    return make_patch("cylinder arc " + std::to_string(int(arc_deg)) + " deg", s, n, rng,
                      [=](double u, double v, Vec3& q, Vec3& nq) {
                          const double phi = arc_deg * kDeg * u;
                          nq = {std::cos(phi), std::sin(phi), 0};
                          q = Vec3{r * nq.x, r * nq.y, height * (v - 0.5)};
                      });
}

/// Radius r at z = 0, growing along +z with half-angle alpha, for z in [-h/2, h/2].
Patch cone_patch(test::Rng& rng, double r, double alpha_deg, double arc_deg, double height,
                 std::size_t n = 1000) {
    Surface s;
    s.kind = FitKind::kCone;
    s.radius = r;
    s.angle = alpha_deg * kDeg;
    const double ta = std::tan(s.angle), ca = std::cos(s.angle), sa = std::sin(s.angle);
    return make_patch("cone arc " + std::to_string(int(arc_deg)) + " deg", s, n, rng,
                      [=](double u, double v, Vec3& q, Vec3& nq) {
                          const double phi = arc_deg * kDeg * u, z = height * (v - 0.5);
                          const double rho = r + z * ta;
                          q = {rho * std::cos(phi), rho * std::sin(phi), z};
                          nq = {ca * std::cos(phi), ca * std::sin(phi), -sa};
                      });
}

Patch torus_patch(test::Rng& rng, double R, double r, double u_deg, double v_deg,
                  std::size_t n = 1000) {
    Surface s;
    s.kind = FitKind::kTorus;
    s.radius = R;
    s.minor_radius = r;
    return make_patch("torus band " + std::to_string(int(u_deg)) + "x" + std::to_string(int(v_deg)),
                      s, n, rng, [=](double u, double v, Vec3& q, Vec3& nq) {
                          const double a = u_deg * kDeg * u, b = v_deg * kDeg * (v - 0.5);
                          nq = {std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b)};
                          q = Vec3{R * std::cos(a), R * std::sin(a), 0} + r * nq;
                      });
}

void add_noise(Patch& p, double sigma, test::Rng& rng) {
    for (Vec3& q : p.points)
        q += Vec3{sigma * rng.gaussian(), sigma * rng.gaussian(), sigma * rng.gaussian()};
}

double axis_angle_deg(Vec3 a, Vec3 b, bool oriented) {
    const double c = dot(normalized(a), normalized(b));
    return std::acos(std::clamp(oriented ? c : std::fabs(c), -1.0, 1.0)) / kDeg;
}

/// Distance from point q to the line through p along d.
double line_distance(Vec3 q, Vec3 p, Vec3 d) {
    const Vec3 w = q - p;
    return norm(w - dot(w, normalized(d)) * normalized(d));
}

struct ParamErrors {
    double radius = 0, minor = 0, angle = 0, axis_deg = 0, position = 0;  // relative / degrees
};

ParamErrors compare(const Surface& fit, const Patch& p) {
    const Surface& t = p.truth;
    ParamErrors e;
    switch (t.kind) {
        case FitKind::kPlane:
            e.axis_deg = axis_angle_deg(fit.axis, t.axis, false);
            e.position = std::fabs(dot(fit.point - t.point, t.axis)) / p.size;
            break;
        case FitKind::kSphere:
            e.radius = std::fabs(fit.radius - t.radius) / t.radius;
            e.position = norm(fit.point - t.point) / p.size;
            break;
        case FitKind::kCylinder:
            e.radius = std::fabs(fit.radius - t.radius) / t.radius;
            e.axis_deg = axis_angle_deg(fit.axis, t.axis, false);
            e.position = line_distance(fit.point, t.point, t.axis) / p.size;
            break;
        case FitKind::kCone: {
            e.axis_deg = axis_angle_deg(fit.axis, t.axis, true);
            e.position = line_distance(fit.point, t.point, t.axis) / p.size;
            e.angle = std::fabs(fit.angle - t.angle) / t.angle;
            // The true radius at the fitted reference point.
            const double h = dot(fit.point - t.point, t.axis);
            const double r_true = t.radius + h * std::tan(t.angle);
            e.radius = std::fabs(fit.radius - r_true) / r_true;
            break;
        }
        case FitKind::kTorus:
            e.radius = std::fabs(fit.radius - t.radius) / t.radius;
            e.minor = std::fabs(fit.minor_radius - t.minor_radius) / t.minor_radius;
            e.axis_deg = axis_angle_deg(fit.axis, t.axis, false);
            e.position = norm(fit.point - t.point) / p.size;
            break;
        case FitKind::kShearCylinder:
        case FitKind::kSweptTorus:
            e.radius = std::fabs(fit.radius - t.radius) / t.radius;
            if (t.kind == FitKind::kSweptTorus)
                e.minor = std::fabs(fit.minor_radius - t.minor_radius) / t.minor_radius;
            e.axis_deg = axis_angle_deg(fit.sweep, t.sweep, false);
            e.position = line_distance(fit.point, t.point, t.sweep) / p.size;
            break;
        case FitKind::kBSpline:
            break;
    }
    return e;
}

FitResult fit_patch(const Patch& p) { return fit(p.truth.kind, FitInput{p.points, p.normals, {}}); }

/// The patches of the targets, `n` points each.
std::vector<Patch> target_patches(test::Rng& rng, std::size_t n = 1000) {
    return {plane_patch(rng, n),
            sphere_patch(rng, 25, 20, n),
            sphere_patch(rng, 8, 90, n),
            cylinder_patch(rng, 12, 30, 20, n),
            cylinder_patch(rng, 5, 360, 30, n),
            cone_patch(rng, 10, 30, 30, 10, n),
            cone_patch(rng, 10, 5, 120, 20, n),
            torus_patch(rng, 30, 6, 90, 90, n),
            torus_patch(rng, 20, 5, 30, 180, n),
            torus_patch(rng, 10, 4, 360, 360, n)};
}

// The least-squares line and circle the B-rep tries for an edge: points on an arc of a tilted
// circle give its center, normal and radius; points on a line give it; points all in one place
// no line.
TEST(Fit, LineAndCircleThroughPoints) {
    const Vec3 center{1, -2, 3}, n = normalized(Vec3{1, 2, 2});
    const Vec3 u = normalized(cross(n, Vec3{0, 0, 1})), v = cross(n, u);
    std::vector<Vec3> arc;
    for (int i = 0; i <= 8; ++i) {
        const double t = 0.1 * i;  // under a radian and a half of the circle
        arc.push_back(center + 7.5 * (std::cos(t) * u + std::sin(t) * v));
    }
    Vec3 c, normal;
    double r = 0;
    EXPECT_LT(fit_circle(arc, c, normal, r), 1e-20);
    EXPECT_NEAR(r, 7.5, 1e-9);
    EXPECT_LT(norm(c - center), 1e-9);
    EXPECT_NEAR(std::abs(dot(normal, n)), 1.0, 1e-12);

    std::vector<Vec3> line;
    for (int i = 0; i < 5; ++i) line.push_back(center + (0.5 * i) * u);
    Vec3 at, along;
    ASSERT_TRUE(fit_line(line, at, along));
    EXPECT_NEAR(std::abs(dot(along, u)), 1.0, 1e-12);
    EXPECT_LT(norm(cross(at - center, u)), 1e-12);
    const std::vector<Vec3> one(3, center);
    EXPECT_FALSE(fit_line(one, at, along));
}

TEST(Fit, ExactPatchesGiveTheirParameters) {
    test::Rng rng(11);
    for (const Patch& p : target_patches(rng)) {
        const FitResult r = fit_patch(p);
        ASSERT_TRUE(r.ok) << p.name << ": " << r.failure;
        EXPECT_EQ(r.surface.kind, p.truth.kind);
        const ParamErrors e = compare(r.surface, p);
        EXPECT_LE(e.radius, 0.0005) << p.name;
        EXPECT_LE(e.minor, 0.0005) << p.name;
        EXPECT_LE(e.angle, 0.0005) << p.name;
        EXPECT_LE(e.axis_deg, 0.01) << p.name;
        EXPECT_LE(e.position, 1e-4) << p.name;
        EXPECT_LE(r.max, 1e-6 * p.size) << p.name;
    }
}

TEST(Fit, NoisyPatchesStayWithinHalfAPercent) {
    // 20000 points: on a 30 degree arc the radius error from the noise falls as 1/sqrt(n)
    // (DISABLED_Probe: worst of 20 arcs 1.3 % with 1000 points, 0.66 % with 4000, 0.48 %
    // with 16000).
    test::Rng rng(12);
    for (int round = 0; round < 5; ++round) {
        for (Patch p : target_patches(rng, 20000)) {
            add_noise(p, 0.001 * p.size, rng);
            const FitResult r = fit_patch(p);
            ASSERT_TRUE(r.ok) << p.name << ": " << r.failure;
            const ParamErrors e = compare(r.surface, p);
            EXPECT_LE(e.radius, 0.005) << p.name;
            EXPECT_LE(e.minor, 0.005) << p.name;
            // Only the noise across the surface counts: sigma per coordinate.
            EXPECT_NEAR(r.rms, 0.001 * p.size, 0.0002 * p.size) << p.name;
        }
    }
}

TEST(Fit, DISABLED_Probe) {
    for (std::size_t n : {1000u, 4000u, 16000u, 64000u}) {
        double worst = 0, mean = 0;
        for (int seed = 0; seed < 20; ++seed) {
            test::Rng rng(100 + seed);
            Patch p = cylinder_patch(rng, 12, 30, 20, n);
            add_noise(p, 0.001 * p.size, rng);
            const FitResult r = fit_patch(p);
            const double e = compare(r.surface, p).radius;
            worst = std::max(worst, e);
            mean += e / 20;
        }
        std::printf("n %zu: mean %.5f worst %.5f\n", n, mean, worst);
    }
}

TEST(Fit, SimplestKindIsChosenWithNoise) {
    test::Rng rng(13);
    int right = 0, total = 0;
    for (int round = 0; round < 10; ++round) {
        for (Patch p : target_patches(rng)) {
            const double sigma = 0.001 * p.size;
            add_noise(p, sigma, rng);
            // The tolerance a mesh's chordal error would give: a few sigma of the noise.
            const KindSelection s = fit_simplest(FitInput{p.points, p.normals, {}}, 5 * sigma);
            ++total;
            right += s.best.ok && s.best.surface.kind == p.truth.kind;
            EXPECT_EQ(s.best.surface.kind, p.truth.kind) << p.name << " round " << round;
        }
    }
    EXPECT_GE(right, 0.99 * total);
}

TEST(Fit, FloatRoundingKeepsTheTargets) {
    test::Rng rng(14);
    for (Patch p : target_patches(rng)) {
        for (Vec3& q : p.points)
            for (int k = 0; k < 3; ++k) q[k] = static_cast<float>(q[k]);
        const FitResult r = fit_patch(p);
        ASSERT_TRUE(r.ok) << p.name;
        const ParamErrors e = compare(r.surface, p);
        EXPECT_LE(e.radius, 0.0005) << p.name;
        EXPECT_LE(e.axis_deg, 0.01) << p.name;
        EXPECT_LE(e.position, 1e-4) << p.name;
    }
}

TEST(Fit, DistanceAndClosestPointAgree) {
    test::Rng rng(15);
    for (const Patch& p : target_patches(rng)) {
        const Surface& s = p.truth;
        for (std::size_t i = 0; i < 50; ++i) {
            // On the surface: distance 0, closest point itself.
            EXPECT_LE(distance(s, p.points[i]), 1e-9 * p.size) << p.name;
            // Moved along the normal by a small step: distance = the step, closest = back.
            const double step = 0.01 * p.size * (i % 2 ? 1 : -1);
            const Vec3 off = p.points[i] + step * p.normals[i];
            EXPECT_NEAR(distance(s, off), std::fabs(step), 1e-9 * p.size) << p.name;
            EXPECT_LE(norm(closest_point(s, off) - p.points[i]), 1e-8 * p.size) << p.name;
        }
    }
}

TEST(Fit, InvariantUnderRigidMotion) {
    test::Rng rng(17);
    const Vec3 turn{0.2, -0.7, 0.4};
    const double angle = 1.1;
    const Vec3 shift{-40, 25, 60};
    for (Patch p : target_patches(rng)) {
        add_noise(p, 0.001 * p.size, rng);
        const FitResult a = fit_patch(p);
        Patch moved = p;
        for (Vec3& q : moved.points) q = rotate(q, turn, angle) + shift;
        for (Vec3& n : moved.normals) n = rotate(n, turn, angle);
        const FitResult b = fit_patch(moved);
        ASSERT_TRUE(a.ok && b.ok) << p.name;
        // Equal to the convergence of the refinement (its stopping rule leaves ~1e-7).
        const double tol = 1e-6 * p.size;
        EXPECT_NEAR(b.surface.radius, a.surface.radius, tol) << p.name;
        EXPECT_NEAR(b.surface.minor_radius, a.surface.minor_radius, tol) << p.name;
        EXPECT_NEAR(b.surface.angle, a.surface.angle, 1e-6) << p.name;
        EXPECT_NEAR(b.rms, a.rms, tol) << p.name;
        if (p.truth.kind != FitKind::kSphere) {
            EXPECT_LE(axis_angle_deg(b.surface.axis, rotate(a.surface.axis, turn, angle),
                                     p.truth.kind == FitKind::kCone),
                      1e-4)
                << p.name;
        }
        // The same surface: every moved point at the same distance.
        for (std::size_t i = 0; i < 20; ++i) {
            EXPECT_NEAR(distance(b.surface, moved.points[i]), distance(a.surface, p.points[i]),
                        tol);
        }
    }
}

TEST(Fit, DegenerateInputFailsCleanly) {
    const std::vector<Vec3> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0},
                                    {4, 0, 0}, {5, 0, 0}, {6, 0, 0}, {7, 0, 0}};
    const std::vector<Vec3> up(line.size(), Vec3{0, 0, 1});
    for (int k = 0; k < kNumFitKinds; ++k) {
        const FitResult r = fit(static_cast<FitKind>(k), FitInput{line, up, {}});
        EXPECT_FALSE(r.ok) << to_string(static_cast<FitKind>(k));
        EXPECT_FALSE(r.failure.empty());
    }
    EXPECT_FALSE(fit(FitKind::kSphere, FitInput{std::span(line).first(2), {}, {}}).ok)
        << "2 points";
    const std::vector<Vec3> nan = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {NAN, 0, 0}};
    EXPECT_FALSE(fit(FitKind::kPlane, FitInput{nan, {}, {}}).ok) << "NaN";
    // A plane needs no normals; a cylinder does.
    test::Rng rng(16);
    const Patch c = cylinder_patch(rng, 10, 90, 10);
    EXPECT_FALSE(fit(FitKind::kCylinder, FitInput{c.points, {}, {}}).ok) << "no normals";
    const std::vector<double> bad_weights(c.points.size() - 1, 1.0);
    EXPECT_FALSE(fit(FitKind::kPlane, FitInput{c.points, {}, bad_weights}).ok) << "weights";
}

TEST(Fit, MeshedSurfacesFromVerticesAndVertexNormals) {
    // Isotropic and CAD-like meshes: the vertices lie on the surface; the vertex normals are
    // estimates (used only for the start).
    test::IsoOptions o;
    o.facets = 20000;
    o.jitter = 0.3;
    test::IsoOptions cad = o;
    cad.aspect = 6;
    struct Case {
        test::AnalyticMesh mesh;
        Surface truth;
    };
    Surface cyl;
    cyl.kind = FitKind::kCylinder, cyl.radius = 10, cyl.axis = {0, 0, 1};
    Surface tor;
    tor.kind = FitKind::kTorus, tor.radius = 30, tor.minor_radius = 10, tor.axis = {0, 0, 1};
    Surface sph;
    sph.kind = FitKind::kSphere, sph.radius = 10;
    const std::vector<Case> cases = {{test::iso_cylinder(10, 30, o), cyl},
                                     {test::iso_cylinder(10, 30, cad), cyl},
                                     {test::iso_torus(30, 10, o), tor},
                                     {test::iso_sphere(10, o), sph}};
    for (const Case& c : cases) {
        const Mesh mesh = build_mesh(test::to_indexed_soup(c.mesh.mesh)).value().mesh;
        const VertexMap<Vec3> normals = vertex_normals(mesh);
        const std::vector<Vec3> pts(mesh.positions().begin(), mesh.positions().end());
        const KindSelection s = fit_simplest(FitInput{pts, normals.data(), {}}, 1e-6);
        ASSERT_TRUE(s.best.ok) << c.mesh.name;
        EXPECT_EQ(s.best.surface.kind, c.truth.kind) << c.mesh.name;
        EXPECT_NEAR(s.best.surface.radius, c.truth.radius, 1e-6 * c.truth.radius) << c.mesh.name;
        EXPECT_NEAR(s.best.surface.minor_radius, c.truth.minor_radius, 1e-6 * 10) << c.mesh.name;
    }
}

/// A shear cylinder: the circle of radius r in the plane z = 0 swept along d, tilted by
/// gamma from z; `arc` degrees of the circle, `length` along d. With `tube` > 0, the swept
/// torus of major radius r and minor radius `tube` (its outer sheet).
Patch shear_patch(test::Rng& rng, double r, double gamma_deg, double arc_deg, double length,
                  double tube, std::size_t n) {
    Surface s;
    s.kind = tube > 0 ? FitKind::kSweptTorus : FitKind::kShearCylinder;
    s.radius = r;
    s.minor_radius = tube;
    const double g = gamma_deg * kDeg;
    const Vec3 d{std::sin(g), 0, std::cos(g)};
    s.sweep = d;
    Patch p =
        make_patch(std::string(tube > 0 ? "swept torus" : "shear cylinder") + " gamma " +
                       std::to_string(int(gamma_deg)) + " arc " + std::to_string(int(arc_deg)),
                   s, n, rng, [=](double u, double v, Vec3& q, Vec3& nq) {
                       const double th = arc_deg * kDeg * u, t = length * (v - 0.5);
                       const Vec3 t1{-r * std::sin(th), r * std::cos(th), 0};
                       nq = normalized(cross(t1, d));
                       q = Vec3{r * std::cos(th), r * std::sin(th), 0} + t * d + tube * nq;
                   });
    return p;
}

// A strip a few facets wide of a coarse cylinder or cone, with the vertex normals a mesh gives
// (its facets' normals averaged): the line that meets the normals is ill-determined there, and
// the points also lie on other surfaces — two rows of a 36-gon bore (NIST FTC 08) on a thin
// cylinder across them, a drafted wall's facets from rim to rim (NIST CTC 02, 3 degrees) on a
// flat cone. The fit must find the true one (or the bore's rows come back one plane each).
TEST(Fit, NarrowStripsOfCoarseCylindersAndConesFitTheTrueSurface) {
    // Quads between generator lines at angles k * step about z, each line through (r0, z0)
    // and (r1, z1), split into two triangles; each vertex has the area-weighted normal of its
    // triangles and a third of their area as its weight (as segmentation gathers them).
    struct Strip {
        std::vector<Vec3> points, normals;
        std::vector<double> weights;
    };
    // `shift` turns the second rim's vertices by that part of a step: a zigzag of triangles
    // from rim to rim (a tessellator's strip where the rims are divided independently).
    const auto strip = [](double r0, double z0, double r1, double z1, int lines, double step,
                          double shift = 0) {
        Strip s;
        for (int k = 0; k < lines; ++k) {
            for (const auto& [r, z, a] :
                 {std::tuple{r0, z0, k * step}, std::tuple{r1, z1, (k + shift) * step}}) {
                s.points.push_back({r * std::cos(a), r * std::sin(a), z});
                s.normals.push_back({0, 0, 0});
                s.weights.push_back(0);
            }
        }
        const auto triangle = [&s](std::size_t a, std::size_t b, std::size_t c) {
            Vec3 n = cross(s.points[b] - s.points[a], s.points[c] - s.points[a]);
            const Vec3 mid = s.points[a] + s.points[b] + s.points[c];
            if (dot(n, Vec3{mid.x, mid.y, 0}) < 0) n = -n;  // outward
            for (const std::size_t v : {a, b, c}) {
                s.normals[v] = s.normals[v] + 0.5 * n;  // area-weighted
                s.weights[v] += norm(n) / 6;
            }
        };
        for (std::size_t k = 0; k + 1 < static_cast<std::size_t>(lines); ++k) {
            triangle(2 * k, 2 * k + 2, 2 * k + 3);
            triangle(2 * k, 2 * k + 3, 2 * k + 1);
        }
        for (Vec3& n : s.normals) n = normalized(n);
        return s;
    };
    for (int lines : {3, 4, 6}) {
        SCOPED_TRACE("cylinder, lines " + std::to_string(lines));
        const Strip st = strip(7.62, 0, 7.62, 3.43, lines, 10 * kDeg);
        const FitResult r = fit(FitKind::kCylinder, FitInput{st.points, st.normals, st.weights});
        ASSERT_TRUE(r.ok) << r.failure;
        EXPECT_NEAR(r.surface.radius, 7.62, 1e-6);
        EXPECT_NEAR(std::abs(r.surface.axis.z), 1.0, 1e-9);
        EXPECT_LT(r.max, 1e-6);
    }
    const double draft = 3 * kDeg;
    for (const auto& [lines, shift] : {std::pair{5, 0.0}, std::pair{7, 0.0}, std::pair{5, 0.5},
                                       std::pair{6, 0.5}, std::pair{7, 0.5}}) {
        SCOPED_TRACE("cone, lines " + std::to_string(lines) + " shift " + std::to_string(shift));
        const Strip st = strip(101, 0, 101 - 40 * std::tan(draft), 40, lines, 11 * kDeg, shift);
        const FitResult r = fit(FitKind::kCone, FitInput{st.points, st.normals, st.weights});
        ASSERT_TRUE(r.ok) << r.failure;
        EXPECT_NEAR(r.surface.angle, draft, 1e-6);
        EXPECT_NEAR(std::abs(r.surface.axis.z), 1.0, 1e-9);
        EXPECT_LT(r.max, 1e-6);
    }
}

TEST(FitShear, ShearCylindersAndSweptToriFromExactAndNoisyPoints) {
    test::Rng rng(41);
    for (const double gamma : {10.0, 30.0}) {
        for (const double tube : {0.0, 2.0}) {
            for (const double noise : {0.0, 0.0005}) {
                Patch p = shear_patch(rng, 8, gamma, 240, 20, tube, 4000);
                if (noise > 0) add_noise(p, noise * p.size, rng);
                p.name += noise > 0 ? " noisy" : " exact";
                const double sigma = noise * p.size;
                if (tube > 0 && noise == 0 && gamma == 30.0) {
                    // Why noise hides the tube radius: the outer sheet is an elliptic cylinder
                    // to within ~0.0025 mm (docs/fitting.md).
                    const FitResult as_shear =
                        fit(FitKind::kShearCylinder, FitInput{p.points, p.normals, {}});
                    ASSERT_TRUE(as_shear.ok);
                    EXPECT_GT(as_shear.max, 0.001);
                    EXPECT_LT(as_shear.max, 0.003);
                }
                if (tube > 0 && noise > 0) {
                    // The outer sheet of a swept torus is an elliptic cylinder to within
                    // ~0.0025 mm here: under 0.015 mm of noise the two are one surface, and
                    // the tube radius is not determined. Kind selection must still describe
                    // the points within the tolerance, by either kind.
                    const KindSelection k =
                        fit_simplest(FitInput{p.points, p.normals, {}}, 5 * sigma);
                    ASSERT_TRUE(k.best.ok) << p.name;
                    EXPECT_TRUE(k.best.surface.kind == FitKind::kShearCylinder ||
                                k.best.surface.kind == FitKind::kSweptTorus)
                        << p.name << ": " << to_string(k.best.surface.kind);
                    EXPECT_LE(k.best.rms, 1.2 * sigma) << p.name;
                    continue;
                }
                const FitResult r = fit_patch(p);
                ASSERT_TRUE(r.ok) << p.name << ": " << r.failure;
                EXPECT_EQ(r.surface.kind, p.truth.kind);
                const double rel = noise > 0 ? 0.005 : 0.0005;
                EXPECT_NEAR(r.surface.radius, 8, rel * 8) << p.name;
                if (tube > 0) {
                    EXPECT_NEAR(r.surface.minor_radius, tube, rel * tube) << p.name;
                }
                // The circle's plane cuts the sweep at gamma; the sweep is the true one.
                EXPECT_NEAR(std::acos(std::fabs(dot(r.surface.axis, r.surface.sweep))) / kDeg,
                            gamma, noise > 0 ? 0.2 : 0.01)
                    << p.name;
                EXPECT_LE(compare(r.surface, p).axis_deg, noise > 0 ? 0.1 : 0.01) << p.name;
                EXPECT_LE(r.rms, 1.2 * sigma + 1e-9 * p.size) << p.name;
                // Every point at its distance.
                double worst = 0;
                for (const Vec3& q : p.points) worst = std::max(worst, distance(r.surface, q));
                EXPECT_NEAR(worst, r.max, 1e-9 * p.size);
                // Chosen as what it is: with 30 degrees of shear no circular cylinder fits.
                if (gamma == 30.0) {
                    const KindSelection k = fit_simplest(FitInput{p.points, p.normals, {}},
                                                         noise > 0 ? 5 * sigma : 1e-6 * p.size);
                    EXPECT_EQ(k.best.surface.kind, p.truth.kind) << p.name;
                }
                // Closest points lie on the surface.
                for (std::size_t i = 0; i < 20; ++i) {
                    const Vec3 off = p.points[i] + 0.05 * p.size * p.normals[i];
                    EXPECT_LE(distance(r.surface, closest_point(r.surface, off)), 1e-9 * p.size);
                }
            }
        }
    }
}

/// A free-form height field (a die's bumps) over 40 x 30, moved rigidly.
Patch freeform_patch(test::Rng& rng, std::size_t n) {
    Surface s;
    s.kind = FitKind::kBSpline;
    return make_patch("free-form", s, n, rng, [](double u, double v, Vec3& q, Vec3& nq) {
        const double x = 40 * u, y = 30 * v;
        q = {x, y, 3 * std::sin(x / 8) * std::cos(y / 11) + 0.02 * x * y};
        nq = normalized(Vec3{-(3.0 / 8 * std::cos(x / 8) * std::cos(y / 11) + 0.02 * y),
                             -(-3.0 / 11 * std::sin(x / 8) * std::sin(y / 11) + 0.02 * x), 1});
    });
}

TEST(FitBSpline, FreeFormPatchWithinToleranceAndChosenLast) {
    test::Rng rng(31);
    const Patch p = freeform_patch(rng, 5000);
    const double tol = 1e-3 * p.size;
    const FitInput in{p.points, p.normals, {}};
    const FitResult r = fit_bspline(in, tol);
    ASSERT_TRUE(r.ok) << r.failure;
    ASSERT_TRUE(r.surface.bspline);
    EXPECT_LE(r.max, tol);
    const BSplineSurface& b = *r.surface.bspline;
    EXPECT_LE(b.num_u * b.num_v, 32 * 32) << b.num_u << " x " << b.num_v;  // a sensible net
    EXPECT_EQ(b.poles.size(), static_cast<std::size_t>(b.num_u * b.num_v));
    // No analytic kind fits; the B-spline does.
    const KindSelection s = fit_simplest(in, tol);
    ASSERT_TRUE(s.best.ok);
    EXPECT_EQ(s.best.surface.kind, FitKind::kBSpline);
    // Distance and closest point: points moved off along their normals come back.
    for (std::size_t i = 0; i < 100; ++i) {
        const double step = 0.01 * p.size;
        const Vec3 off = p.points[i] + step * p.normals[i];
        EXPECT_NEAR(distance(r.surface, off), step, tol + 1e-3 * step);
        EXPECT_LE(norm(closest_point(r.surface, off) - p.points[i]), 3 * tol);
    }
}

// A height field over 40 x 30 (a die's bumps), and n of its points at random.
double bump_height(double x, double y) { return 3 * std::sin(x / 8) * std::cos(y / 11); }
std::vector<Vec3> bumps(test::Rng& rng, int n) {
    std::vector<Vec3> points;
    for (int i = 0; i < n; ++i) {
        const double x = 40 * rng.uniform(), y = 30 * rng.uniform();
        points.push_back({x, y, bump_height(x, y)});
    }
    return points;
}

// FitInput::margin: the net reaches past its points by that part of their extent, so a point
// of the surface just beyond them (a border curve bowing out between two border vertices) is
// on it; without, the nearest point is on the net's edge.
TEST(FitBSpline, AMarginCarriesTheNetPastItsPoints) {
    test::Rng rng(41);
    const std::vector<Vec3> points = bumps(rng, 3000);
    const double tol = 1e-3 * 40;
    FitInput in{points, {}, {}};
    const FitResult plain = fit_bspline(in, tol);
    in.margin = 0.05;
    const FitResult wide = fit_bspline(in, tol);
    ASSERT_TRUE(plain.ok && wide.ok) << plain.failure << wide.failure;
    EXPECT_LE(wide.max, tol);
    double plain_far = 0, wide_far = 0;
    for (double y = 2; y < 28; y += 2) {
        // 1 beyond the points' largest x (40): 2.5 % of the extent.
        const Vec3 q{41, y, bump_height(41, y)};
        plain_far = std::max(plain_far, distance(plain.surface, q));
        wide_far = std::max(wide_far, distance(wide.surface, q));
    }
    EXPECT_GT(plain_far, 10 * tol);
    EXPECT_LE(wide_far, 2 * tol);
}

// A caller that takes no net of more than max_net_poles poles: the fit tries none larger, and
// fails where the net it needs is larger (the die's bumps at a tenth of the tolerance above).
TEST(FitBSpline, NoNetLargerThanTheCallerTakes) {
    test::Rng rng(33);
    const Patch p = freeform_patch(rng, 5000);
    const double tol = 1e-4 * p.size;
    FitInput in{p.points, p.normals, {}};
    const FitResult free = fit_bspline(in, tol);
    ASSERT_TRUE(free.ok) << free.failure;
    const int poles = free.surface.bspline->num_u * free.surface.bspline->num_v;
    ASSERT_GT(poles, 16);
    in.max_net_poles = poles;  // what it needs: the same fit
    const FitResult enough = fit_bspline(in, tol);
    ASSERT_TRUE(enough.ok) << enough.failure;
    EXPECT_EQ(enough.surface.bspline->poles.size(), free.surface.bspline->poles.size());
    EXPECT_EQ(enough.max, free.max);
    in.max_net_poles = poles - 1;  // less: the fit fails, with the largest net it may have
    const FitResult capped = fit_bspline(in, tol);
    EXPECT_FALSE(capped.ok);
    ASSERT_TRUE(capped.surface.bspline);
    EXPECT_LT(capped.surface.bspline->num_u * capped.surface.bspline->num_v, poles);
    EXPECT_GT(capped.max, tol);
}

// A long thin strip (a cone's row of facets along a slot, 24 times longer than wide, sampled by
// 210 points): its first net, 4 poles across and 4 x 24 along, had more poles than half its
// points, so no net was tried and the fit failed ("singular"); it starts with as many poles
// along as the points allow.
TEST(FitBSpline, ALongThinStripFits) {
    test::Rng rng(35);
    std::vector<Vec3> points, normals;
    for (int i = 0; i < 210; ++i) {
        const double x = 96 * rng.uniform(), y = 4 * rng.uniform();
        const double z = 0.5 * std::sin(x / 15) + 0.02 * y * y;
        points.push_back({x, y, z});
        normals.push_back(normalized(Vec3{-0.5 / 15 * std::cos(x / 15), -0.04 * y, 1}));
    }
    const double tol = 1e-3 * 96;
    const FitResult r = fit_bspline(FitInput{points, normals, {}}, tol);
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_LE(r.max, tol);
    EXPECT_LE(r.surface.bspline->num_u * r.surface.bspline->num_v, 105);
}

TEST(FitBSpline, PlanesStayPlanesAndNonHeightFieldsFail) {
    test::Rng rng(32);
    const Patch plane = plane_patch(rng, 2000);
    const KindSelection s =
        fit_simplest(FitInput{plane.points, plane.normals, {}}, 1e-6 * plane.size);
    EXPECT_EQ(s.best.surface.kind, FitKind::kPlane);
    // A whole cylinder is no height field over any plane, nor an open profile extruded.
    const Patch tube = cylinder_patch(rng, 5, 360, 20, 4000);
    const FitResult r = fit_bspline(FitInput{tube.points, tube.normals, {}}, 1e-3 * tube.size);
    EXPECT_FALSE(r.ok);
    EXPECT_FALSE(r.failure.empty());
    // A tolerance below the noise: the net grows to its limit, then the fit fails (it once
    // looped for ever there).
    Patch noisy = freeform_patch(rng, 20000);
    add_noise(noisy, 0.001 * noisy.size, rng);
    const FitResult below = fit_bspline(FitInput{noisy.points, {}, {}}, 0.001 * noisy.size);
    EXPECT_FALSE(below.ok);
    ASSERT_TRUE(below.surface.bspline);
    EXPECT_EQ(below.surface.bspline->num_u * below.surface.bspline->num_v, 64 * 64);
}

// refuse_rms for B-splines, with the limits segmentation's free-form groups set (a net of at
// most 256 poles, a profile of at most 64, an RMS goal): a free-form patch of many points and a
// wall extruded along a hairpin profile (18003 points: the extrusion is fitted on them all, not
// on a sample) are fitted as they are without it, to the bit; a whole cylinder, no height
// field and no open profile, is refused on its sample's nets, and its whole fit fails too; a
// fit of fewer points than kSampledFitPoints is never sampled.
TEST(FitBSpline, ManyPointsOffTheirSampleFitAreRefusedWithoutTheWholeFit) {
    const auto as_segmentation = [](FitInput in, double tol) {
        in.max_net_poles = 256;
        in.max_profile_poles = 64;
        in.rms_goal = 0.5 * tol;
        return in;
    };
    const auto same = [](const FitResult& a, const FitResult& b) {
        return a.ok == b.ok && a.rms == b.rms && a.max == b.max && a.surface.bspline &&
               b.surface.bspline && a.surface.bspline->poles == b.surface.bspline->poles &&
               a.surface.bspline->extruded == b.surface.bspline->extruded;
    };
    test::Rng rng(37);
    const Patch p = freeform_patch(rng, 2 * kSampledFitPoints);
    const double tol = 1e-3 * p.size;
    FitInput in = as_segmentation(FitInput{p.points, p.normals, {}}, tol);
    const FitResult whole = fit_bspline(in, tol);
    ASSERT_TRUE(whole.ok) << whole.failure;
    in.refuse_rms = 3 * tol;
    const FitResult sampled = fit_bspline(in, tol);
    ASSERT_TRUE(sampled.ok) << sampled.failure;
    EXPECT_TRUE(same(sampled, whole));

    std::vector<Vec3> wall, wall_normals;
    for (int k = -3000; k <= 3000; ++k) {
        const double y = 6.0 * k / 3000, x = y * y / 0.5;
        for (const double z : {0.0, 2.0, 5.0}) {
            wall.push_back(Vec3{x, y, z});
            wall_normals.push_back(normalized(Vec3{1, -y / 0.25, 0}));
        }
    }
    ASSERT_GE(wall.size(), kSampledFitPoints);
    FitInput folded = as_segmentation(FitInput{wall, wall_normals, {}}, 0.01);
    const FitResult wall_whole = fit_bspline(folded, 0.01);
    ASSERT_TRUE(wall_whole.ok) << wall_whole.failure;
    EXPECT_TRUE(wall_whole.surface.bspline->extruded);
    folded.refuse_rms = 3 * 0.01;
    EXPECT_TRUE(same(fit_bspline(folded, 0.01), wall_whole));

    const Patch tube = cylinder_patch(rng, 5, 360, 20, 2 * kSampledFitPoints);
    const double t = 1e-3 * tube.size;
    FitInput round = as_segmentation(FitInput{tube.points, tube.normals, {}}, t);
    const FitResult tube_whole = fit_bspline(round, t);
    EXPECT_FALSE(tube_whole.ok);
    EXPECT_EQ(tube_whole.failure.find("sample"), std::string::npos) << tube_whole.failure;
    round.refuse_rms = 3 * t;
    const FitResult refused = fit_bspline(round, t);
    EXPECT_FALSE(refused.ok);
    EXPECT_NE(refused.failure.find("sample"), std::string::npos) << refused.failure;

    const std::size_t few = kSampledFitPoints / 2;
    FitInput small{std::span<const Vec3>(tube.points).first(few),
                   std::span<const Vec3>(tube.normals).first(few),
                   {}};
    small.refuse_rms = 3 * t;
    const FitResult small_fit = fit_bspline(small, t);
    EXPECT_FALSE(small_fit.ok);
    EXPECT_EQ(small_fit.failure.find("sample"), std::string::npos) << small_fit.failure;
}

// A pocket wall cut along a spline outline: a lobed profile over 270 degrees (it folds back
// over its mean plane, so no height field), extruded along a tilted direction, sampled as a
// mesh samples it — the two rims and a middle row, dense on the bends and sparse between.
TEST(FitBSpline, ExtrudedWallIsOneProfileExtruded) {
    const Vec3 e = normalized(Vec3{0.1, -0.2, 1});
    Vec3 u = normalized(cross(e, Vec3{1, 0, 0}));
    const Vec3 v = cross(e, u);
    const auto profile = [](double th) { return 10 + 2 * std::sin(3 * th); };
    std::vector<Vec3> points, normals;
    for (int k = 0; k <= 600; ++k) {
        const double s = static_cast<double>(k) / 600;
        const double th = 1.5 * std::numbers::pi * (s + 0.08 * std::sin(6 * std::numbers::pi * s));
        const double r = profile(th), dr = 6 * std::cos(3 * th);
        const Vec3 radial = std::cos(th) * u + std::sin(th) * v;
        const Vec3 tangent = dr * radial + r * (-std::sin(th) * u + std::cos(th) * v);
        const Vec3 n = normalized(cross(tangent, e));
        for (const double h : {-3.0, 0.5, 4.0}) {
            if (h == 0.5 && k % 3 != 0) continue;
            points.push_back(Vec3{5, -2, 7} + r * radial + h * e);
            normals.push_back(n);
        }
    }
    const double tol = 1e-3 * 24;
    const FitResult r = fit_bspline(FitInput{points, normals, {}}, tol);
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_LE(r.max, tol);
    ASSERT_TRUE(r.surface.bspline);
    EXPECT_EQ(r.surface.bspline->num_v, 4);  // a profile extruded, not a grid
    EXPECT_LE(r.surface.bspline->num_u, 64);
    // Points of the wall between the samples, and off it along its normal.
    for (int k = 0; k < 50; ++k) {
        const double th = 1.5 * std::numbers::pi * (0.01 + 0.98 * k / 50.0);
        const Vec3 radial = std::cos(th) * u + std::sin(th) * v;
        const Vec3 p = Vec3{5, -2, 7} + profile(th) * radial + 1.7 * e;
        EXPECT_LE(distance(r.surface, p), 2 * tol) << k;
    }
    // The same wall all round is closed: no open profile describes it, and it is no height
    // field either.
    std::vector<Vec3> ring, ring_normals;
    for (int k = 0; k < 720; ++k) {
        const double th = 2 * std::numbers::pi * k / 720;
        const Vec3 radial = std::cos(th) * u + std::sin(th) * v;
        const double rr = profile(th), dr = 6 * std::cos(3 * th);
        const Vec3 tangent = dr * radial + rr * (-std::sin(th) * u + std::cos(th) * v);
        for (const double h : {-3.0, 4.0}) {
            ring.push_back(rr * radial + h * e);
            ring_normals.push_back(normalized(cross(tangent, e)));
        }
    }
    EXPECT_FALSE(fit_bspline(FitInput{ring, ring_normals, {}}, tol).ok);
}

// A wall along a hairpin profile (a parabola of 0.25 mm vertex radius whose arms run 72 mm):
// nets spread by length along the profile put a pole or two on the bend and miss it (this fails
// with that start alone); the start by length and turning puts many there.
TEST(FitBSpline, ExtrusionFollowsATightBend) {
    const double radius = 0.25;
    std::vector<Vec3> points, normals;
    for (int k = -3000; k <= 3000; ++k) {
        const double y = 6.0 * k / 3000, x = y * y / (2 * radius);
        const Vec3 n = normalized(Vec3{1, -y / radius, 0});
        for (const double z : {0.0, 2.0, 5.0}) {
            points.push_back(Vec3{x, y, z});
            normals.push_back(n);
        }
    }
    const double tol = 0.01;
    const FitResult r = fit_bspline(FitInput{points, normals, {}}, tol);
    ASSERT_TRUE(r.ok) << r.failure;
    ASSERT_TRUE(r.surface.bspline);
    EXPECT_TRUE(r.surface.bspline->extruded);
    EXPECT_LE(r.max, tol);
    // On the bend, between the samples.
    for (int k = -20; k <= 20; ++k) {
        const double y = 0.05 * k + 0.001, x = y * y / (2 * radius);
        EXPECT_LE(distance(r.surface, Vec3{x, y, 3.3}), 2 * tol) << y;
    }
}

// A thread's flank: a curved profile (0.6 mm deep, leaning about 30 degrees) swept along a helix
// of 1 mm pitch over eight turns about a tilted axis — no height field, no extrusion — sampled
// along the helix in five rows that wander across it a little from sample to sample, as a
// mesh's vertices do, right- and left-handed. One helical sweep describes it: a profile of a few
// poles, not a net of hundreds; the axis and the pitch are found, not given.
TEST(FitHelical, ThreadFlankIsOneHelicalSweep) {
    const Vec3 a = normalized(Vec3{0.2, 0.1, 1});
    Vec3 e1 = normalized(cross(a, Vec3{1, 0, 0}));
    const Vec3 e2 = cross(a, e1);
    const Vec3 origin{3, -1, 2};
    for (const double hand : {1.0, -1.0}) {
        SCOPED_TRACE(hand > 0 ? "right-handed" : "left-handed");
        const double pitch = hand / (2 * std::numbers::pi);  // 1 mm a turn
        const auto flank = [&](double phi, double t, Vec3* normal) {
            const double r = 2.4 + 0.6 * t, h = 0.35 * t + 0.05 * t * t;
            const Vec3 d = std::cos(phi) * e1 + std::sin(phi) * e2;
            const Vec3 dd = -std::sin(phi) * e1 + std::cos(phi) * e2;
            if (normal)
                *normal = normalized(cross(r * dd + pitch * a, 0.6 * d + (0.35 + 0.1 * t) * a));
            return origin + r * d + (h + pitch * phi) * a;
        };
        std::vector<Vec3> points, normals;
        for (int k = 0; k <= 8 * 48; ++k) {
            const double phi = 2 * std::numbers::pi * k / 48;
            for (int j = 0; j <= 4; ++j) {
                Vec3 n;
                const double t = std::clamp((j + 0.3 * std::sin(1.7 * k + j)) / 4, 0.0, 1.0);
                points.push_back(flank(phi, t, &n));
                normals.push_back(n);
            }
        }
        const double tol = 1e-3;
        const FitResult r = fit_helical(FitInput{points, normals, {}}, tol);
        ASSERT_TRUE(r.ok) << r.failure;
        ASSERT_TRUE(r.surface.bspline);
        const BSplineSurface& b = *r.surface.bspline;
        EXPECT_TRUE(b.helical);
        EXPECT_FALSE(b.extruded);
        EXPECT_LE(r.max, tol);
        EXPECT_EQ(b.num_u, 4);  // the profile's poles: a cubic takes its parabola
        // The axis, a point on it and the pitch (its sign is the hand, whichever way the axis
        // points).
        EXPECT_GE(std::fabs(dot(b.helix.axis, a)), 1 - 1e-9);
        EXPECT_LE(norm(cross(b.helix.origin - origin, a)), 1e-6);
        EXPECT_NEAR(b.helix.pitch, pitch, 1e-7);
        // Points of the flank between the samples, on every turn.
        for (int k = 0; k < 200; ++k) {
            const double phi = 16 * std::numbers::pi * (0.003 + 0.994 * k / 200.0);
            const Vec3 p = flank(phi, 0.1 + 0.8 * ((k * 37) % 100) / 100.0, nullptr);
            EXPECT_LE(distance(r.surface, p), 2 * tol) << k;
        }
        // A point half a pitch off the flank along the axis is far from it (the next turn is
        // not the surface).
        EXPECT_GE(distance(r.surface, flank(9.0, 0.5, nullptr) + 0.5 * a), 0.1);
        // Half a turn of it is enough to find the same motion (a seed of merge_helical()).
        const std::size_t half = 5 * 25;
        const FitResult part = fit_helical(
            FitInput{std::span(points).first(half), std::span(normals).first(half), {}}, tol);
        ASSERT_TRUE(part.ok) << part.failure;
        EXPECT_GE(std::fabs(dot(part.surface.bspline->helix.axis, a)), 1 - 1e-9);
        EXPECT_LE(norm(cross(part.surface.bspline->helix.origin - origin, a)), 1e-6);
        EXPECT_NEAR(part.surface.bspline->helix.pitch, pitch, 1e-7);
        // Too few points, or points without normals, are refused.
        EXPECT_FALSE(
            fit_helical(FitInput{std::span(points).first(8), std::span(normals).first(8), {}}, tol)
                .ok);
        EXPECT_FALSE(fit_helical(FitInput{points, {}, {}}, tol).ok);
    }
    // A free-form bump swept by no screw motion is none; nor is a plane (only turns about its
    // normal and slides along it keep it in place, no helix).
    test::Rng rng(41);
    const Patch bump = freeform_patch(rng, 2000);
    EXPECT_FALSE(fit_helical(FitInput{bump.points, bump.normals, {}}, 1e-3 * bump.size).ok);
    const Patch flat = plane_patch(rng, 500);
    EXPECT_FALSE(fit_helical(FitInput{flat.points, flat.normals, {}}, 1e-3).ok);
}

TEST(FitSnap, NearlyRoundValuesBecomeRoundAndTrueOnesStay) {
    // A cylinder of radius 10.02 along z, 0.05 degrees off, with 0.001 mm noise.
    test::Rng rng(21);
    std::vector<Vec3> pts, nrm;
    const double tilt = 0.05 * kDeg;
    for (int i = 0; i < 5000; ++i) {
        const double a = 2.0 * kPi / 3 * rng.uniform(), z = 40 * rng.uniform();
        const Vec3 n{std::cos(a), std::sin(a), 0};
        Vec3 q = Vec3{10.02 * n.x, 10.02 * n.y, z};
        q = rotate(q, {1, 0, 0}, tilt) + Vec3{5, 7, -3};
        q += Vec3{0.001 * rng.gaussian(), 0.001 * rng.gaussian(), 0.001 * rng.gaussian()};
        pts.push_back(q);
        nrm.push_back(rotate(n, {1, 0, 0}, tilt));
    }
    const FitInput in{pts, nrm, {}};
    const FitResult f = fit(FitKind::kCylinder, in);
    ASSERT_TRUE(f.ok);
    SnapOptions o;
    o.tolerance = 0.1;
    o.positions = false;  // FitSnap.PositionsAndOnlyWhatThePointsCannotTellApart
    std::vector<std::string> applied;
    const FitResult s = snap(f, in, o, &applied);
    ASSERT_TRUE(s.ok);
    EXPECT_EQ(s.surface.radius, 10.0);
    EXPECT_EQ(std::fabs(s.surface.axis.z), 1.0);
    EXPECT_LE(s.max, 0.1);
    ASSERT_EQ(applied.size(), 2u);
    EXPECT_EQ(applied[0].substr(0, 7), "axis to");
    // With a tight tolerance the 0.035 mm of tilt and 0.02 mm of radius are real: the axis
    // stays, and the radius only rounds to its true 10.02.
    o.tolerance = 0.006;
    applied.clear();
    const FitResult tight = snap(f, in, o, &applied);
    EXPECT_EQ(tight.surface.radius, 10.02);
    EXPECT_LT(std::fabs(tight.surface.axis.z), 1.0);
    ASSERT_EQ(applied.size(), 1u);
    EXPECT_EQ(applied[0], "radius 10.0201 -> 10.02");
    // A tool radius close by wins over round values.
    o.tolerance = 0.1;
    o.tool_radii = {6.35, 10.025};
    applied.clear();
    const FitResult tool = snap(f, in, o, &applied);
    EXPECT_EQ(tool.surface.radius, 10.025);
}

// Float32 points of an exact bore (r 6.35, a quarter inch, along z through (12, -3.5)), a
// plane (z = 40) and a sphere (r 12 about (1, 2, 140)), as a CAD tessellation gives them. The
// fits are off by rounding; snapped, the values are exact. With the noise check, a loose tolerance
// takes no value the points can tell from the fit (6.3 or 6.4); without it, it does.
TEST(FitSnap, PositionsAndOnlyWhatThePointsCannotTellApart) {
    test::Rng rng(23);
    auto f32 = [](Vec3 p) {
        return Vec3{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
    };
    std::vector<Vec3> bore, bore_n, flat, flat_n, ball, ball_n;
    for (int i = 0; i < 2000; ++i) {
        const double a = 2 * kPi * rng.uniform(), b = kPi * (rng.uniform() - 0.5);
        const Vec3 radial{std::cos(a), std::sin(a), 0};
        bore.push_back(f32(Vec3{12, -3.5, 30 * rng.uniform()} + 6.35 * radial));
        bore_n.push_back(-radial);
        flat.push_back(f32(Vec3{50 * rng.uniform(), 30 * rng.uniform(), 40}));
        flat_n.push_back({0, 0, 1});
        const Vec3 dir{std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b)};
        ball.push_back(f32(Vec3{1, 2, 140} + 12 * dir));
        ball_n.push_back(dir);
    }
    const FitInput bin{bore, bore_n, {}}, pin{flat, flat_n, {}}, sin{ball, ball_n, {}};
    const FitResult fb = fit(FitKind::kCylinder, bin), fp = fit(FitKind::kPlane, pin),
                    fs = fit(FitKind::kSphere, sin);
    ASSERT_TRUE(fb.ok && fp.ok && fs.ok);
    EXPECT_NE(fb.surface.radius, 6.35);  // rounding: the fit is close, not exact
    SnapOptions o;
    o.tolerance = 0.1;  // loose: 6.4 keeps every point within it
    o.noise = 1e-6;     // float32 rounding of coordinates up to 140
    o.rms_floor = 1e-6;
    std::vector<std::string> applied;
    const FitResult sb = snap(fb, bin, o, &applied);
    EXPECT_EQ(std::fabs(sb.surface.axis.z), 1.0);
    EXPECT_EQ(sb.surface.point.x, 12.0);
    EXPECT_EQ(sb.surface.point.y, -3.5);
    EXPECT_EQ(sb.surface.radius, 6.35);
    EXPECT_NE(std::find(applied.begin(), applied.end(), "axis at x 12 y -3.5"), applied.end());
    const FitResult sp = snap(fp, pin, o);
    EXPECT_EQ(std::fabs(sp.surface.axis.z), 1.0);
    EXPECT_EQ(sp.surface.point.z, 40.0);
    const FitResult ss = snap(fs, sin, o);
    EXPECT_EQ(ss.surface.point, (Vec3{1, 2, 140}));
    EXPECT_EQ(ss.surface.radius, 12.0);
    // The tolerance alone: 6.3 or 6.4 (whichever rounding reaches first) is within it.
    o.noise = -1;
    EXPECT_NEAR(std::fabs(snap(fb, bin, o).surface.radius - 6.35), 0.05, 1e-12);
}

TEST(FitSnap, CounterboreAndHoleBecomeCoaxialAndTheShoulderParallel) {
    // A hole (r 5, z in [0, 10]), its counterbore (r 8, z in [10, 14]) and the shoulder ring
    // between them (z = 10), along an axis tilted off the coordinate axes, with noise.
    test::Rng rng(51);
    const Vec3 axis = normalized(Vec3{0.3, -0.2, 1.0});
    Vec3 u, v;
    u = normalized(cross(axis, Vec3{1, 0, 0}));
    v = cross(axis, u);
    const Vec3 origin{12, -4, 3};
    auto place = [&](double x, double y, double z) { return origin + x * u + y * v + z * axis; };
    std::vector<Vec3> hole, hole_n, bore, bore_n, ring, ring_n;
    for (int i = 0; i < 3000; ++i) {
        const double a = 2 * kPi * rng.uniform();
        const Vec3 radial = std::cos(a) * u + std::sin(a) * v;
        auto jitter = [&] {
            return Vec3{0.002 * rng.gaussian(), 0.002 * rng.gaussian(), 0.002 * rng.gaussian()};
        };
        hole.push_back(place(5 * std::cos(a), 5 * std::sin(a), 10 * rng.uniform()) + jitter());
        hole_n.push_back(-radial);
        bore.push_back(place(8 * std::cos(a), 8 * std::sin(a), 10 + 4 * rng.uniform()) + jitter());
        bore_n.push_back(-radial);
        const double rr = 5 + 3 * rng.uniform();
        ring.push_back(place(rr * std::cos(a), rr * std::sin(a), 10) + jitter());
        ring_n.push_back(axis);
    }
    const std::vector<FitInput> inputs = {
        {hole, hole_n, {}}, {bore, bore_n, {}}, {ring, ring_n, {}}};
    std::vector<FitResult> fits = {fit(FitKind::kCylinder, inputs[0]),
                                   fit(FitKind::kCylinder, inputs[1]),
                                   fit(FitKind::kPlane, inputs[2])};
    for (const FitResult& f : fits) ASSERT_TRUE(f.ok);
    // Fitted apart, the three axes differ by noise.
    EXPECT_NE(fits[0].surface.axis, fits[1].surface.axis);
    const double tol = 0.01;
    SnapOptions o;
    o.tolerance = tol;
    const std::vector<std::string> notes = snap_together(fits, inputs, o);
    ASSERT_EQ(notes.size(), 2u);
    EXPECT_EQ(notes[0], "3 axes made parallel");
    EXPECT_EQ(notes[1], "2 surfaces made coaxial");
    const Vec3 d0 = fits[0].surface.axis, d1 = fits[1].surface.axis, n2 = fits[2].surface.axis;
    EXPECT_EQ(std::fabs(dot(d0, d1)), 1.0);
    EXPECT_NEAR(std::fabs(dot(d0, n2)), 1.0, 1e-15);
    EXPECT_LE(line_distance(fits[1].surface.point, fits[0].surface.point, d0), 1e-12);
    EXPECT_LE(axis_angle_deg(d0, axis, false), 0.01);
    for (const FitResult& f : fits) EXPECT_LE(f.max, tol);
    // A tolerance the noise cannot meet: nothing is snapped.
    std::vector<FitResult> again = {fit(FitKind::kCylinder, inputs[0]),
                                    fit(FitKind::kCylinder, inputs[1]),
                                    fit(FitKind::kPlane, inputs[2])};
    o.tolerance = 0.001;
    EXPECT_TRUE(snap_together(again, inputs, o).empty());
}

// A hole (r 5) and its counterbore (r 8) along z through (3.14159, 2.71828), a place no round
// value reaches, with noise: snap_together() makes them coaxial along z, and snap(), holding
// what it fixed, rounds the radii without moving either off the shared line.
TEST(FitSnap, CoaxialLinesStaySharedThroughSnap) {
    test::Rng rng(52);
    const Vec3 axis{0, 0, 1};
    const Vec3 u = normalized(cross(axis, Vec3{1, 0, 0})), v = cross(axis, u);
    const Vec3 origin{3.14159, 2.71828, 0};
    std::vector<Vec3> hole, hole_n, bore, bore_n;
    for (int i = 0; i < 3000; ++i) {
        const double a = 2 * kPi * rng.uniform();
        const Vec3 radial = std::cos(a) * u + std::sin(a) * v;
        auto jitter = [&] {
            return Vec3{0.001 * rng.gaussian(), 0.001 * rng.gaussian(), 0.001 * rng.gaussian()};
        };
        hole.push_back(origin + 5 * radial + 10 * rng.uniform() * axis + jitter());
        hole_n.push_back(-radial);
        bore.push_back(origin + 8 * radial + (10 + 4 * rng.uniform()) * axis + jitter());
        bore_n.push_back(-radial);
    }
    const std::vector<FitInput> inputs = {{hole, hole_n, {}}, {bore, bore_n, {}}};
    std::vector<FitResult> fits = {fit(FitKind::kCylinder, inputs[0]),
                                   fit(FitKind::kCylinder, inputs[1])};
    ASSERT_TRUE(fits[0].ok && fits[1].ok);
    const std::vector<double> free_rms = {fits[0].rms, fits[1].rms};
    SnapOptions o;
    o.tolerance = 0.02;
    o.noise = 0.001;
    std::vector<SnapHold> holds;
    const std::vector<std::string> notes = snap_together(fits, inputs, o, free_rms, &holds);
    ASSERT_GE(notes.size(), 2u);
    ASSERT_TRUE(holds[0].direction && holds[0].line && holds[1].direction && holds[1].line);
    for (int i = 0; i < 2; ++i) {
        SnapOptions own = o;
        own.base_rms = free_rms[static_cast<std::size_t>(i)];
        own.hold = holds[static_cast<std::size_t>(i)];
        fits[static_cast<std::size_t>(i)] =
            snap(fits[static_cast<std::size_t>(i)], inputs[static_cast<std::size_t>(i)], own);
    }
    EXPECT_EQ(fits[0].surface.radius, 5.0);
    EXPECT_EQ(fits[1].surface.radius, 8.0);
    EXPECT_EQ(std::fabs(fits[0].surface.axis.z), 1.0);
    EXPECT_EQ(fits[0].surface.axis, fits[1].surface.axis);
    EXPECT_EQ(fits[0].surface.point.x, fits[1].surface.point.x);
    EXPECT_EQ(fits[0].surface.point.y, fits[1].surface.point.y);
    EXPECT_NEAR(fits[0].surface.point.x, 3.14159, 1e-3);
}

TEST(FitSnap, ConeAnglesAndTorusRadii) {
    test::Rng rng(22);
    Patch cone = cone_patch(rng, 10, 29.999, 180, 10, 4000);
    const FitResult fc = fit_patch(cone);
    ASSERT_TRUE(fc.ok);
    SnapOptions o;
    o.tolerance = 1e-3;
    o.axes = false;
    std::vector<std::string> applied;
    const FitResult sc = snap(fc, FitInput{cone.points, cone.normals, {}}, o, &applied);
    EXPECT_NEAR(sc.surface.angle, 30 * kDeg, 1e-12);
    EXPECT_EQ(applied.size(), 1u);
    Patch tor = torus_patch(rng, 20.0004, 3.0002, 90, 180, 4000);
    const FitResult ft = fit_patch(tor);
    applied.clear();
    const FitResult st = snap(ft, FitInput{tor.points, tor.normals, {}}, o, &applied);
    EXPECT_EQ(st.surface.radius, 20.0);
    EXPECT_EQ(st.surface.minor_radius, 3.0);
    EXPECT_EQ(applied.size(), 2u);
}

// A turned dome whose meridian arc is centered across the axis (a screw head: radius 54.87,
// 8.25 across) is the inner part of a spindle torus: a negative major radius. Its distances,
// closest points and normals hold as for any torus.
TEST(Fit, ATurnedDomeIsTheInnerPartOfASpindleTorus) {
    test::Rng rng(5);
    const double R = 8.25, r = 54.87;
    Surface local;
    local.kind = FitKind::kTorus;
    local.radius = -R;
    local.minor_radius = r;
    // Half the dome (a slot splits it), from 0.5 to 7.7 off the axis.
    // In the half-plane at azimuth a + pi: R + r cos b = -rho.
    const double b0 = std::acos((-0.5 - R) / r), b1 = std::acos((-7.7 - R) / r);
    const Patch p =
        make_patch("dome", local, 2000, rng, [=](double u, double v, Vec3& q, Vec3& nq) {
            const double a = kPi * u, b = b1 + (b0 - b1) * v;
            nq = {std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b)};
            q = Vec3{R * std::cos(a), R * std::sin(a), 0} + r * nq;
        });
    const FitResult f = fit_patch(p);
    ASSERT_TRUE(f.ok) << f.failure;
    EXPECT_NEAR(f.surface.radius, -R, 1e-6 * R);
    EXPECT_NEAR(f.surface.minor_radius, r, 1e-6 * r);
    EXPECT_LE(f.max, 1e-6 * p.size);
    // No sphere is near it.
    const FitResult sphere = fit(FitKind::kSphere, FitInput{p.points, p.normals, {}});
    EXPECT_GT(sphere.max, 1e-3 * p.size);
    for (std::size_t i = 0; i < p.points.size(); i += 97) {
        const Vec3 off = p.points[i] + 0.3 * p.normals[i];
        EXPECT_NEAR(distance(f.surface, off), 0.3, 1e-6);
        EXPECT_LE(norm(closest_point(f.surface, off) - p.points[i]), 1e-6);
        EXPECT_GT(std::fabs(dot(normal_at(f.surface, p.points[i]), p.normals[i])), 1 - 1e-9);
    }
    // A needle (|R| = 0.9 r: 2 wide, 8.7 long) is no turned dome: refused.
    Surface needle = local;
    needle.radius = -9;
    needle.minor_radius = 10;
    const double n0 = std::acos((-0.1 - 9) / 10.0), n1 = std::acos((-0.9 - 9) / 10.0);
    const Patch q =
        make_patch("needle", needle, 2000, rng, [=](double u, double v, Vec3& pt, Vec3& nq) {
            const double a = kPi * u, b = n1 + (n0 - n1) * v;
            nq = {std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b)};
            pt = Vec3{9 * std::cos(a), 9 * std::sin(a), 0} + 10 * nq;
        });
    const FitResult g = fit_patch(q);
    EXPECT_FALSE(g.ok) << "R " << g.surface.radius << " r " << g.surface.minor_radius;
}

// A caller that accepts fits within a tolerance t may pass refuse_rms (a few t): a fit of many
// points is first made on a strided sample of them and refused when that fit is off by more
// (docs/fitting.md; growing a 950k-facet part's tori). A patch of the kind is fitted as it is
// without, to the bit; a union with another surface's points is refused, and its whole fit
// would not have held it within t either; a fit of fewer points is never sampled.
TEST(Fit, ManyPointsOffTheirSampleFitAreRefusedWithoutTheWholeFit) {
    test::Rng rng(21);
    const auto same = [](const FitResult& a, const FitResult& b) {
        return a.ok == b.ok && a.rms == b.rms && a.max == b.max && a.iterations == b.iterations &&
               a.surface.point == b.surface.point && a.surface.axis == b.surface.axis &&
               a.surface.radius == b.surface.radius &&
               a.surface.minor_radius == b.surface.minor_radius &&
               a.surface.angle == b.surface.angle;
    };
    for (const Patch& p : target_patches(rng, 2 * kSampledFitPoints)) {
        if (p.truth.kind == FitKind::kPlane) continue;
        // Spheres also without normals (they need none) and with uneven weights.
        std::vector<double> weights(p.points.size());
        for (std::size_t i = 0; i < weights.size(); ++i) weights[i] = 0.5 + (i % 7) * 0.25;
        if (p.truth.kind == FitKind::kSphere) {
            for (const FitInput& bare :
                 {FitInput{p.points, {}, {}}, FitInput{p.points, {}, weights}}) {
                FitInput with = bare;
                with.refuse_rms = 1e-4 * p.size;
                EXPECT_TRUE(same(fit(FitKind::kSphere, with), fit(FitKind::kSphere, bare)))
                    << p.name;
            }
        }
        FitInput in{p.points, p.normals, {}};
        const FitResult whole = fit(p.truth.kind, in);
        in.refuse_rms = 1e-4 * p.size;
        const FitResult sampled = fit(p.truth.kind, in);
        ASSERT_TRUE(sampled.ok) << p.name << ": " << sampled.failure;
        EXPECT_TRUE(same(sampled, whole)) << p.name;
    }
    // A torus band beside a cylinder's patch (placed elsewhere): no torus holds both.
    const Patch band = torus_patch(rng, 30, 6, 90, 90, 2 * kSampledFitPoints);
    const Patch other = cylinder_patch(rng, 12, 90, 20, kSampledFitPoints / 4);
    std::vector<Vec3> points = band.points, normals = band.normals;
    points.insert(points.end(), other.points.begin(), other.points.end());
    normals.insert(normals.end(), other.normals.begin(), other.normals.end());
    const double t = 1e-4 * band.size;
    FitInput in{points, normals, {}};
    const FitResult whole = fit(FitKind::kTorus, in);
    EXPECT_FALSE(whole.ok && whole.max <= t);
    in.refuse_rms = 3 * t;
    const FitResult refused = fit(FitKind::kTorus, in);
    EXPECT_FALSE(refused.ok);
    EXPECT_NE(refused.failure.find("sample"), std::string::npos) << refused.failure;
    // Fewer points than kSampledFitPoints: fitted whole, as without refuse_rms.
    const std::size_t few = kSampledFitPoints / 2;
    std::vector<Vec3> few_points(band.points.begin(), band.points.begin() + few),
        few_normals(band.normals.begin(), band.normals.begin() + few);
    few_points.insert(few_points.end(), other.points.begin(), other.points.end());
    few_normals.insert(few_normals.end(), other.normals.begin(), other.normals.end());
    FitInput small{few_points, few_normals, {}};
    const FitResult small_whole = fit(FitKind::kTorus, small);
    small.refuse_rms = 3 * t;
    EXPECT_TRUE(same(fit(FitKind::kTorus, small), small_whole));
}

// refit(): from a surface near the fit (the fit moved by a thousandth of the patch's size, its
// radii by a thousandth of themselves, as a region's surface before its border moved) to the
// same least-squares minimum as fit(); a plane is fitted as by fit(); a start that is no finite
// surface fails cleanly.
// A plane's noisy points refitted from a cone flat to 1e-7 rad with its apex among them (what a
// 42-facet region of occt_TR12J's mesh, nudged by one float32 unit, became; its face fell back
// to facets): no cone, since the plane holds them as well. A shallow cone of 80 degrees is one.
TEST(Fit, AFlatConeIsNoCone) {
    test::Rng rng(31);
    Patch p = plane_patch(rng, 2000);
    add_noise(p, 0.05, rng);
    const FitInput in{p.points, p.normals, {}};
    Surface flat;
    flat.kind = FitKind::kCone;
    flat.axis = p.truth.axis;
    flat.angle = kPi / 2 - 1e-7;
    flat.radius = 20;
    flat.point = p.truth.point + (flat.radius / std::tan(flat.angle)) * flat.axis;
    const FitResult r = refit(flat, in);
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.failure.find("flat"), std::string::npos) << r.failure;
    EXPECT_TRUE(fit(FitKind::kPlane, in).ok);
    const Patch shallow = cone_patch(rng, 10, 80, 360, 2, 2000);
    const FitResult c = fit(FitKind::kCone, FitInput{shallow.points, shallow.normals, {}});
    ASSERT_TRUE(c.ok) << c.failure;
    EXPECT_NEAR(c.surface.angle, 80 * kDeg, 1e-9);
}

TEST(Fit, RefitFromANearbySurfaceReachesTheFit) {
    test::Rng rng(23);
    for (Patch p : target_patches(rng, 4000)) {
        add_noise(p, 0.001 * p.size, rng);
        const FitInput in{p.points, p.normals, {}};
        const FitResult whole = fit(p.truth.kind, in);
        ASSERT_TRUE(whole.ok) << p.name << ": " << whole.failure;
        Surface start = whole.surface;
        start.point += Vec3{0.6, -0.5, 0.6} * (1e-3 * p.size);
        start.axis = normalized(start.axis + Vec3{0.01, 0.0, -0.01});  // about 0.8 degrees
        start.radius *= 1.001;
        start.minor_radius *= 1.001;
        start.angle *= 1.001;
        const FitResult again = refit(start, in);
        ASSERT_TRUE(again.ok) << p.name << ": " << again.failure;
        EXPECT_EQ(again.surface.kind, whole.surface.kind);
        EXPECT_NEAR(again.rms, whole.rms, 1e-6 * whole.rms) << p.name;
        const ParamErrors e = compare(again.surface, p);
        EXPECT_LE(e.radius, 0.005) << p.name;
        EXPECT_LE(e.minor, 0.005) << p.name;
        if (p.truth.kind == FitKind::kPlane) {
            EXPECT_EQ(again.rms, whole.rms);
        } else if (p.truth.kind != FitKind::kSphere) {
            // No start of fit()'s: none from the normals, which an axis needs there.
            const FitInput bare{p.points, {}, {}};
            EXPECT_FALSE(fit(p.truth.kind, bare).ok) << p.name;
            const FitResult from = refit(start, bare);
            ASSERT_TRUE(from.ok) << p.name << ": " << from.failure;
            EXPECT_NEAR(from.rms, whole.rms, 1e-6 * whole.rms) << p.name;
        }
    }
    const Patch p = torus_patch(rng, 30, 6, 90, 90);
    Surface bad = p.truth;
    bad.radius = std::numeric_limits<double>::quiet_NaN();
    const FitResult r = refit(bad, FitInput{p.points, p.normals, {}});
    EXPECT_FALSE(r.ok);
    EXPECT_FALSE(r.failure.empty());
}

}  // namespace
}  // namespace ncrev
