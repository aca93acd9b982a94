// Surface fitting (../shared/docs/method.md, Step 4).
//
// Starts: the plane by weighted principal components; the sphere by the algebraic fit of
// Kasa (|p|^2 + D.p + E = 0 in least squares); cylinders, cones and tori from their axis,
// found as the line that meets every normal line (each normal of a surface of revolution meets
// its axis), in Plücker coordinates (d, m): the line meets the normal line (p, n) when
// d.(p x n) + n.m = 0, a linear condition, minimised over unit d with m eliminated (H. Pottmann
// and J. Wallner, "Computational Line Geometry", 2001, ch. 6). The profile in the meridian
// plane then gives the radius (cylinder), the generator line (cone) or the tube circle (torus).
// Refinement: Levenberg-Marquardt on the geometric distances with analytic derivatives,
// directions perturbed in their tangent plane and renormalised each step.
#include "ncrev/fit.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Dense>
#include <Eigen/QR>
#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <queue>
#include <string>
#include <tuple>
#include <vector>

namespace ncrev {

const char* to_string(FitKind kind) {
    switch (kind) {
        case FitKind::kPlane:
            return "plane";
        case FitKind::kSphere:
            return "sphere";
        case FitKind::kCylinder:
            return "cylinder";
        case FitKind::kCone:
            return "cone";
        case FitKind::kTorus:
            return "torus";
        case FitKind::kShearCylinder:
            return "shear_cylinder";
        case FitKind::kSweptTorus:
            return "swept_torus";
        case FitKind::kBSpline:
            return "bspline";
    }
    return "unknown";
}

// ---------------------------------------------------------------------------------------
// B-spline surfaces (L. Piegl and W. Tiller, "The NURBS Book", 2nd ed., algorithms A2.1-A2.3).

namespace {

constexpr int kMaxDegree = 3;

/// Knot i of the clamped uniform vector of n poles and degree p.
double knot(int i, int p, int n) {
    return std::clamp(static_cast<double>(i - p) / (n - p), 0.0, 1.0);
}

/// The knot span of u and the p + 1 non-zero basis functions there, with their derivatives
/// (dN may be null). P > 0 fixes the degree at compile time (p is then P), so that the
/// loops unroll: the cubic profiles' projections call this millions of times. The same
/// operations in the same order either way.
/// `knots`, when given, holds knot(i, p, n) for i in [0, n + p] (the same values, looked up).
template <int P>
inline int basis_of_degree(int p, int n, double u, double* N, double* dN,
                           const double* knots = nullptr) {
    if constexpr (P > 0) p = P;
    const auto knot_at = [&](int i) { return knots ? knots[i] : knot(i, p, n); };
    u = std::clamp(u, 0.0, 1.0);
    const int span = std::min(n - 1, p + static_cast<int>(std::floor(u * (n - p))));
    // Triangular table of A2.2, with derivatives (A2.3, first order).
    double ndu[kMaxDegree + 1][kMaxDegree + 1];
    double left[kMaxDegree + 1], right[kMaxDegree + 1];
    ndu[0][0] = 1.0;
    for (int j = 1; j <= p; ++j) {
        left[j] = u - knot_at(span + 1 - j);
        right[j] = knot_at(span + j) - u;
        double saved = 0.0;
        for (int r = 0; r < j; ++r) {
            ndu[j][r] = right[r + 1] + left[j - r];
            const double temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for (int j = 0; j <= p; ++j) N[j] = ndu[j][p];
    if (dN) {
        for (int r = 0; r <= p; ++r) {
            double d = 0;
            if (r >= 1) d += ndu[r - 1][p - 1] / ndu[p][r - 1];
            if (r <= p - 1) d -= ndu[r][p - 1] / ndu[p][r];
            dN[r] = p * d;
        }
    }
    return span;
}

int basis(int p, int n, double u, double* N, double* dN) {
    return p == 3 ? basis_of_degree<3>(p, n, u, N, dN) : basis_of_degree<0>(p, n, u, N, dN);
}

/// basis() of degree 3, with the knots from cubic_knots(n) when given.
int cubic_basis(int n, double u, double* N, double* dN, const double* knots = nullptr) {
    return basis_of_degree<3>(3, n, u, N, dN, knots);
}

/// knot(i, 3, n) for i in [0, n + 3]: a profile's projections divide for them otherwise at
/// every evaluation.
std::vector<double> cubic_knots(int n) {
    std::vector<double> k(static_cast<std::size_t>(n + 4));
    for (int i = 0; i <= n + 3; ++i) k[static_cast<std::size_t>(i)] = knot(i, 3, n);
    return k;
}

}  // namespace

void BSplineSurface::evaluate(double u, double v, Vec3& p, Vec3& du, Vec3& dv) const {
    double Nu[kMaxDegree + 1], dNu[kMaxDegree + 1], Nv[kMaxDegree + 1], dNv[kMaxDegree + 1];
    const int su = basis(degree, num_u, u, Nu, dNu);
    const int sv = basis(degree, num_v, v, Nv, dNv);
    p = du = dv = Vec3{};
    for (int b = 0; b <= degree; ++b) {
        for (int a = 0; a <= degree; ++a) {
            const Vec3 P =
                poles[static_cast<std::size_t>((su - degree + a) + num_u * (sv - degree + b))];
            p += (Nu[a] * Nv[b]) * P;
            du += (dNu[a] * Nv[b]) * P;
            dv += (Nu[a] * dNv[b]) * P;
        }
    }
}

double BSplineSurface::Helix::turns(Vec3 p, double& angle) const {
    const Vec3 d = p - origin;
    angle = std::atan2(dot(d, cross(axis, x)), dot(d, x));
    return (dot(d, axis) - pitch * angle - h) / (2 * std::numbers::pi * pitch);
}

Vec3 BSplineSurface::evaluate(double u, double v) const {
    Vec3 p, du, dv;
    evaluate(u, v, p, du, dv);
    return p;
}

namespace {

constexpr double kPi = std::numbers::pi;
/// Points per task of the parallel sums: fixed, so that the summation order, and so the bits
/// of every result, do not depend on the thread count.
constexpr std::size_t kGrain = 4096;
/// Levenberg-Marquardt stops after this many iterations or when the cost decreases by less
/// than kRelativeDecrease of itself (double precision leaves nothing to gain below).
constexpr int kMaxIterations = 100;
constexpr double kRelativeDecrease = 1e-14;
/// A radius beyond this multiple of the points' extent has run away (a torus fitted to a
/// cylinder's points, a sphere to a plane's): stop refining and report no fit.
constexpr double kRunaway = 1000.0;
constexpr double kTorusRunaway = 100.0;
/// The inner (lemon) part of a spindle torus is taken when its tube circle's center lies
/// across the axis by less than this fraction of its radius: a turned dome's arc (the corpus
/// screw head: 8.25 for a radius of 54.87, 0.15). Nearer 1 the lemon is a needle far longer
/// than wide, which a thread flank's strip or a small patch near a fillet fits about any axis
/// (0.82-0.96 on the corpus parts) without being one.
constexpr double kLemonMaxAxisOffset = 0.5;
/// B-splines: the first net (poles along the shorter side), the largest per direction, the
/// weight of the smoothing term relative to the data (enough to bridge cells without points,
/// far below what would bend the surface away from them), the default tolerance of fit() as a
/// fraction of the points' extent, and the Gauss-Newton steps of a projection.
constexpr int kBSplineStartPoles = 4;
constexpr int kBSplineMaxPoles = 64;
/// Each net (or extrusion's profile) tried has this many times the poles along each direction
/// of the one before: finer steps than doubling, since poles are free parameters (a net of 272
/// where one of 156 would do passes the limit of merge_freeform(), which also weighs an
/// extrusion's poles against its pieces' parameters).
constexpr double kNetGrowth = 1.5;
constexpr double kBSplineSmoothing = 1e-6;
/// The weight of a guide (FitInput::guides) against a point's: a guide lies up to the mesh's
/// deflection inside the surface, and pulls the net a tenth of that off the points where both
/// hold it; where no point holds it, the guides alone do.
constexpr double kGuideWeight = 0.1;
constexpr double kBSplineDefaultTolerance = 1e-4;
constexpr int kProjectIterations = 20;
/// Samples per profile pole of an extrusion's start grid (coarse_start()).
constexpr int kProfileGrid = 4;
/// Shear cylinder start: the circle made slightly elliptic, so that the ellipse's turn has a
/// derivative to follow.
constexpr double kEllipseSeed = 1e-3;
/// A shear cylinder's sweep makes at most 80 degrees with the circle's normal (the SRE format
/// excludes a sweep in the circle's plane): a flatter ellipse is a plate, which straddles the
/// noise of a plane and would "fit" it better than the plane does.
constexpr double kMinShearCos = 0.17364817766693041;  // cos(80 degrees)
/// Swept torus start: tube radii tried, as fractions k / kSweptStarts of the smaller semi-axis.
constexpr int kSweptStarts = 16;
/// Points whose second principal variance is below this fraction of the first lie on a line
/// (to double precision): no surface is determined.
constexpr double kCollinear = 1e-20;
/// Kind selection: a simpler kind loses to a more complex one whose RMS residual is lower by
/// more than this factor (noise alone lowers it by about 1/(2n) per parameter, n points)...
constexpr double kSignificantRms = 1.1;
/// ...plus this fraction of the tolerance, so that on exact data (every RMS at rounding level)
/// the simplest kind wins.
constexpr double kRmsFloor = 0.02;

/// A unit vector orthogonal to unit d, and a third completing the frame.
void frame(Vec3 d, Vec3& u, Vec3& v) {
    const Vec3 a = std::fabs(d.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    u = normalized(cross(d, a));
    v = cross(d, u);
}

double weight(const FitInput& in, std::size_t i) {
    return in.weights.empty() ? 1.0 : in.weights[i];
}

bool finite(Vec3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

/// Weighted centroid and total weight.
Vec3 centroid(const FitInput& in, double* total = nullptr) {
    Vec3 c{};
    double w = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        c += weight(in, i) * in.points[i];
        w += weight(in, i);
    }
    if (total) *total = w;
    return w > 0 ? c / w : c;
}

/// A deterministic parallel sum over the points of f(i, acc).
template <class Acc, class F>
Acc sum_points(std::size_t n, F&& f) {
    if (n <= kGrain) {  // one task: the same sum without the scheduler's cost
        Acc acc{};
        for (std::size_t i = 0; i < n; ++i) f(i, acc);
        return acc;
    }
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, n, kGrain), Acc{},
        [&](const tbb::blocked_range<std::size_t>& r, Acc acc) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) f(i, acc);
            return acc;
        },
        [](Acc a, const Acc& b) {
            a += b;
            return a;
        });
}

// ---------------------------------------------------------------------------------------
// Models for Levenberg-Marquardt: residual(p, J) gives the signed distance of p and, when J
// is not null, its derivatives by the N parameters; stepped(delta) the model moved by delta.

struct SphereModel {
    static constexpr int N = 4;
    Vec3 c;
    double r;
    double residual(Vec3 p, double* J) const {
        const Vec3 q = p - c;
        const double len = norm(q);
        if (J) {
            const Vec3 e = len > 0 ? q / len : Vec3{1, 0, 0};
            J[0] = -e.x, J[1] = -e.y, J[2] = -e.z, J[3] = -1;
        }
        return len - r;
    }
    SphereModel stepped(const double* d) const { return {c + Vec3{d[0], d[1], d[2]}, r + d[3]}; }
    bool runaway(double extent) const { return std::fabs(r) > kRunaway * extent; }
    Surface surface() const {
        Surface s;
        s.kind = FitKind::kSphere;
        s.point = c;
        s.radius = r;
        return s;
    }
};

/// Axis through c along unit d; u, v complete the frame (parameters move c along u, v and tip
/// d towards u, v).
struct Axis {
    Vec3 c, d, u, v;
    static Axis make(Vec3 c, Vec3 d) {
        Axis a{c, normalized(d), {}, {}};
        frame(a.d, a.u, a.v);
        return a;
    }
    Axis stepped(double cu, double cv, double du, double dv) const {
        return make(c + cu * u + cv * v, d + du * u + dv * v);
    }
};

struct CylinderModel {
    static constexpr int N = 5;
    Axis a;
    double r;
    double residual(Vec3 p, double* J) const {
        const Vec3 q = p - a.c;
        const double h = dot(q, a.d);
        const Vec3 radial = q - h * a.d;
        const double rho = norm(radial);
        if (J) {
            const Vec3 e = rho > 0 ? radial / rho : a.u;
            const double eu = dot(e, a.u), ev = dot(e, a.v);
            J[0] = -eu, J[1] = -ev, J[2] = -h * eu, J[3] = -h * ev, J[4] = -1;
        }
        return rho - r;
    }
    CylinderModel stepped(const double* d) const {
        return {a.stepped(d[0], d[1], d[2], d[3]), r + d[4]};
    }
    bool runaway(double extent) const { return std::fabs(r) > kRunaway * extent; }
    Surface surface() const {
        Surface s;
        s.kind = FitKind::kCylinder;
        s.point = a.c;
        s.axis = a.d;
        s.radius = r;
        return s;
    }
};

/// Cone: radius r at the axis point c, growing along d with half-angle alpha. The residual is
/// the distance to the generator line in the meridian plane, rho cos(alpha) - r cos(alpha) -
/// h sin(alpha), which is well conditioned also for small angles (no apex in the parameters).
struct ConeModel {
    static constexpr int N = 6;
    Axis a;
    double r, alpha;
    double ca, sa;  ///< cos and sin of alpha, once per model rather than once per point
    static ConeModel make(const Axis& a, double r, double alpha) {
        return {a, r, alpha, std::cos(alpha), std::sin(alpha)};
    }
    double residual(Vec3 p, double* J) const {
        const Vec3 q = p - a.c;
        const double h = dot(q, a.d);
        const Vec3 radial = q - h * a.d;
        const double rho = norm(radial);
        if (J) {
            const Vec3 e = rho > 0 ? radial / rho : a.u;
            const double eu = dot(e, a.u), ev = dot(e, a.v);
            J[0] = -ca * eu;
            J[1] = -ca * ev;
            J[2] = -ca * h * eu - sa * dot(q, a.u);
            J[3] = -ca * h * ev - sa * dot(q, a.v);
            J[4] = -ca;
            J[5] = -rho * sa + r * sa - h * ca;
        }
        return (rho - r) * ca - h * sa;
    }
    ConeModel stepped(const double* d) const {
        return make(a.stepped(d[0], d[1], d[2], d[3]), r + d[4], alpha + d[5]);
    }
    bool runaway(double extent) const { return std::fabs(r) > kRunaway * extent; }
    Surface surface() const {
        Surface s;
        s.kind = FitKind::kCone;
        s.point = a.c;
        s.axis = a.d;
        s.radius = r;
        s.angle = alpha;
        return s;
    }
};

/// Torus: center c on the axis (moved along u, v and d), major R, minor r.
struct TorusModel {
    static constexpr int N = 7;
    Axis a;
    double R, r;
    double residual(Vec3 p, double* J) const {
        const Vec3 q = p - a.c;
        const double h = dot(q, a.d);
        const Vec3 radial = q - h * a.d;
        const double rho = norm(radial);
        const double dr = rho - R;
        const double s = std::sqrt(dr * dr + h * h);
        if (J) {
            const Vec3 e = rho > 0 ? radial / rho : a.u;
            const double eu = dot(e, a.u), ev = dot(e, a.v);
            const double sr = s > 0 ? dr / s : 1.0, sh = s > 0 ? h / s : 0.0;
            J[0] = -sr * eu;
            J[1] = -sr * ev;
            J[2] = -sr * h * eu + sh * dot(q, a.u);
            J[3] = -sr * h * ev + sh * dot(q, a.v);
            J[4] = -sh;  // the center moves along the axis
            J[5] = -sr;
            J[6] = -1;
        }
        return s - r;
    }
    TorusModel stepped(const double* d) const {
        Axis moved = a.stepped(d[0], d[1], d[2], d[3]);
        moved.c += d[4] * a.d;
        return {moved, R + d[5], r + d[6]};
    }
    // A torus degenerates into a cylinder or a plane through ever larger radii; a machined
    // torus (a fillet, a bull-nose corner) is never 100 times larger than the patch it covers.
    bool runaway(double extent) const {
        return std::fabs(R) > kTorusRunaway * extent || std::fabs(r) > kTorusRunaway * extent;
    }
    Surface surface() const {
        Surface s;
        s.kind = FitKind::kTorus;
        s.point = a.c;
        s.axis = a.d;
        s.radius = R;
        s.minor_radius = r;
        return s;
    }
};

/// The point of the ellipse x^2/A^2 + y^2/B^2 = 1 (A >= B > 0) nearest to (x, y), by a
/// monotone Newton iteration on the Lagrange parameter (after D. Eberly, "Distance from a
/// point to an ellipse", 2013): robust everywhere, also on the axes and at the center.
void nearest_on_ellipse(double A, double B, double x, double y, double& ex, double& ey) {
    const double sx = x < 0 ? -1.0 : 1.0, sy = y < 0 ? -1.0 : 1.0;
    x = std::fabs(x), y = std::fabs(y);
    if (y > 0) {
        if (x > 0) {
            // F(t) = (A x / (t + A^2))^2 + (B y / (t + B^2))^2 - 1 is convex and decreasing for
            // t > -B^2, and F(t0) >= 0 at t0 = -B^2 + B y: Newton from t0 climbs to the root
            // from below without overshooting (the tangent of a convex function lies below it).
            const double a2 = A * A, b2 = B * B;
            double t = -b2 + B * y;
            for (int it = 0; it < 100; ++it) {
                const double pa = A * x / (t + a2), pb = B * y / (t + b2);
                const double f = pa * pa + pb * pb - 1;
                if (!(f > 0)) break;
                const double df = -2 * (pa * pa / (t + a2) + pb * pb / (t + b2));
                const double step = -f / df;
                t += step;
                if (!(step > 1e-16 * (std::fabs(t) + b2))) break;
            }
            ex = a2 * x / (t + a2), ey = b2 * y / (t + b2);
        } else {
            ex = 0, ey = B;
        }
    } else {
        const double d = A * A - B * B;
        if (x * A < d) {
            ex = A * A * x / d;
            ey = B * std::sqrt(std::max(0.0, 1 - (ex / A) * (ex / A)));
        } else {
            ex = A, ey = 0;
        }
    }
    ex *= sx, ey *= sy;
}

/// An elliptic cylinder: axis through c along unit d, semi-axis A along the unit w (normal to
/// d) and B along m = d x w. The signed distance is positive outside.
struct EllipticCylinder {
    Vec3 c, d, w;
    double A, B;
    /// Signed distance of p, its local coordinates, the nearest ellipse point and the unit
    /// outward normal there (local).
    double signed_distance(Vec3 p, double& x, double& y, double& ex, double& ey, double& nx,
                           double& ny, double& h) const {
        const Vec3 q = p - c;
        h = dot(q, d);
        const Vec3 m = cross(d, w);
        x = dot(q, w), y = dot(q, m);
        const double a = std::max(std::fabs(A), std::fabs(B)),
                     b = std::min(std::fabs(A), std::fabs(B));
        // Work with the larger semi-axis along the first coordinate.
        const bool swap = std::fabs(B) > std::fabs(A);
        double lx = swap ? y : x, ly = swap ? x : y, lex, ley;
        nearest_on_ellipse(a, std::max(b, 1e-300), lx, ly, lex, ley);
        ex = swap ? ley : lex, ey = swap ? lex : ley;
        const double dx = x - ex, dy = y - ey;
        const double dist = std::sqrt(dx * dx + dy * dy);
        const bool outside = (x * x) / (A * A) + (y * y) / (B * B) > 1;
        if (dist > 0) {
            nx = dx / dist, ny = dy / dist;
            if (!outside) nx = -nx, ny = -ny;
        } else {
            const double gx = ex / (A * A), gy = ey / (B * B), gl = std::hypot(gx, gy);
            nx = gl > 0 ? gx / gl : 1, ny = gl > 0 ? gy / gl : 0;
        }
        return outside ? dist : -dist;
    }
    /// Derivatives of the signed distance by (cu, cv, du, dv, A, B, phi), u, v the frame of d.
    void gradient(Vec3 u, Vec3 v, double x, double y, double ex, double ey, double nx, double ny,
                  double h, double* J) const {
        const Vec3 m = cross(d, w);
        // The center moves across the axis: the point moves the other way in the section.
        J[0] = -(nx * dot(u, w) + ny * dot(u, m));
        J[1] = -(nx * dot(v, w) + ny * dot(v, m));
        // The axis tips: the section of p moves by -h times the tip.
        J[2] = -h * (nx * dot(u, w) + ny * dot(u, m));
        J[3] = -h * (nx * dot(v, w) + ny * dot(v, m));
        J[4] = -nx * (A != 0 ? ex / A : 0);
        J[5] = -ny * (B != 0 ? ey / B : 0);
        J[6] = nx * y - ny * x;  // turning w towards m turns the point the other way
    }
    EllipticCylinder stepped(const Axis& a, const double* s) const {
        const Axis moved = a.stepped(s[0], s[1], s[2], s[3]);
        const Vec3 m = cross(d, w);
        Vec3 nw = w + s[6] * m;                            // turned about d
        nw = normalized(nw - dot(nw, moved.d) * moved.d);  // and kept normal to the new axis
        return {moved.c, moved.d, nw, A + s[4], B + s[5]};
    }
};

struct ShearModel {
    static constexpr int N = 7;
    EllipticCylinder e;
    Axis frame() const { return Axis::make(e.c, e.d); }
    double residual(Vec3 p, double* J) const {
        double x, y, ex, ey, nx, ny, h;
        const double s = e.signed_distance(p, x, y, ex, ey, nx, ny, h);
        if (J) {
            const Axis a = frame();
            e.gradient(a.u, a.v, x, y, ex, ey, nx, ny, h, J);
        }
        return s;
    }
    ShearModel stepped(const double* d) const { return {e.stepped(frame(), d)}; }
    bool runaway(double extent) const {
        return std::fabs(e.A) > kRunaway * extent || std::fabs(e.B) > kRunaway * extent;
    }
    Surface surface() const;
};

/// The circle behind an elliptic cylinder: radius A (the larger semi-axis), in the plane that
/// cuts it in a circle. Of the two such planes, the one whose normal is nearer a coordinate
/// axis (tool axes are).
void circle_of(const EllipticCylinder& e, double& radius, Vec3& normal, Vec3& sweep) {
    Vec3 w = e.w;
    double A = std::fabs(e.A), B = std::fabs(e.B);
    if (B > A) {
        std::swap(A, B);
        w = cross(e.d, w);
    }
    const Vec3 m = cross(e.d, w);
    const double cg = A > 0 ? B / A : 1, sg = std::sqrt(std::max(0.0, 1 - cg * cg));
    const Vec3 n1 = cg * e.d + sg * m, n2 = cg * e.d - sg * m;
    auto axial = [](Vec3 n) { return std::max({std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)}); };
    normal = axial(n1) >= axial(n2) ? n1 : n2;
    radius = A;
    sweep = e.d;
}

Surface ShearModel::surface() const {
    Surface s;
    s.kind = FitKind::kShearCylinder;
    s.point = e.c;
    circle_of(e, s.radius, s.axis, s.sweep);
    return s;
}

/// The elliptic cylinder of a shear cylinder (c, a, r, d).
EllipticCylinder elliptic_of(Vec3 c, Vec3 a, double r, Vec3 d) {
    d = normalized(d);
    a = normalized(a);
    Vec3 w = cross(a, d);
    if (norm(w) < 1e-12) {
        Vec3 v;
        frame(d, w, v);  // a circular cylinder: any direction
    }
    w = normalized(w);
    return {c, d, w, r, r * std::fabs(dot(a, d))};
}

/// Swept torus: the elliptic cylinder of its tube centers and the tube radius. A fitted patch
/// lies on one sheet of the envelope: the residual is s - r, signed (r < 0 for the inner
/// sheet). Measuring |s| - r instead would let two sheets straddle the noise of any surface.
struct SweptModel {
    static constexpr int N = 8;
    EllipticCylinder e;
    double r;
    Axis frame() const { return Axis::make(e.c, e.d); }
    double residual(Vec3 p, double* J) const {
        double x, y, ex, ey, nx, ny, h;
        const double s = e.signed_distance(p, x, y, ex, ey, nx, ny, h);
        if (J) {
            const Axis a = frame();
            e.gradient(a.u, a.v, x, y, ex, ey, nx, ny, h, J);
            J[7] = -1;
        }
        return s - r;
    }
    SweptModel stepped(const double* d) const { return {e.stepped(frame(), d), r + d[7]}; }
    bool runaway(double extent) const {
        return std::fabs(e.A) > kRunaway * extent || std::fabs(r) > kRunaway * extent;
    }
    Surface surface() const {
        Surface s;
        s.kind = FitKind::kSweptTorus;
        s.point = e.c;
        circle_of(e, s.radius, s.axis, s.sweep);
        s.minor_radius = std::fabs(r);
        return s;
    }
};

template <int N>
struct NormalEquations {
    Eigen::Matrix<double, N, N> jtj = Eigen::Matrix<double, N, N>::Zero();
    Eigen::Matrix<double, N, 1> jtr = Eigen::Matrix<double, N, 1>::Zero();
    double cost = 0;
    NormalEquations& operator+=(const NormalEquations& o) {
        jtj += o.jtj;
        jtr += o.jtr;
        cost += o.cost;
        return *this;
    }
};

struct Cost {
    double value = 0;
    Cost& operator+=(const Cost& o) {
        value += o.value;
        return *this;
    }
};

template <class Model>
double cost_of(const Model& m, const FitInput& in) {
    return sum_points<Cost>(in.points.size(),
                            [&](std::size_t i, Cost& c) {
                                const double r = m.residual(in.points[i], nullptr);
                                c.value += weight(in, i) * r * r;
                            })
        .value;
}

/// Levenberg-Marquardt (Marquardt's scaling of the diagonal). Returns the iterations used, or
/// -2 when a radius ran away (the points are better described by a simpler kind).
template <class Model>
int refine(Model& model, const FitInput& in, unsigned frozen = 0) {
    constexpr int N = Model::N;
    Box3 box;
    for (const Vec3& p : in.points) box.add(p);
    const double extent = norm(box.max - box.min);
    double lambda = 1e-3;
    int it = 0;
    for (; it < kMaxIterations; ++it) {
        const auto ne = sum_points<NormalEquations<N>>(
            in.points.size(), [&](std::size_t i, NormalEquations<N>& acc) {
                double J[N];
                const double r = model.residual(in.points[i], J);
                for (int k = 0; k < N; ++k)
                    if (frozen & (1u << k)) J[k] = 0;  // held parameters do not move
                const double w = weight(in, i);
                // The lower triangle of w J J^T, in the order and rounding of Eigen's
                // rankUpdate(): its generic kernel for any size cost more than the model.
                for (int c = 0; c < N; ++c) {
                    const double f = w * J[c];
                    for (int k = c; k < N; ++k) acc.jtj(k, c) += f * J[k];
                }
                const Eigen::Map<const Eigen::Matrix<double, N, 1>> j(J);
                acc.jtr += (w * r) * j;
                acc.cost += w * r * r;
            });
        const Eigen::Matrix<double, N, N> jtj = ne.jtj.template selfadjointView<Eigen::Lower>();
        bool improved = false;
        for (int tries = 0; tries < 12 && !improved; ++tries) {
            Eigen::Matrix<double, N, N> a = jtj;
            for (int k = 0; k < N; ++k) a(k, k) += lambda * std::max(jtj(k, k), 1e-300);
            for (int k = 0; k < N; ++k)
                if (frozen & (1u << k)) a(k, k) = 1;  // and get a zero step
            const Eigen::Matrix<double, N, 1> delta = a.ldlt().solve(-ne.jtr);
            if (!delta.allFinite()) {
                lambda *= 10;
                continue;
            }
            const Model next = model.stepped(delta.data());
            const double c = cost_of(next, in);
            if (std::isfinite(c) && c <= ne.cost) {
                const double decrease = ne.cost - c;
                model = next;
                lambda = std::max(lambda / 3, 1e-12);
                improved = true;
                if (model.runaway(extent)) return -2;
                if (decrease <= kRelativeDecrease * ne.cost) return it + 1;
            } else {
                lambda *= 4;
            }
        }
        if (!improved) return it + 1;  // at a minimum to machine precision
    }
    return it;
}

template <class Model>
FitResult finish(const Model& model, int iterations, const FitInput& in) {
    FitResult res;
    res.surface = model.surface();
    res.iterations = iterations;
    struct Stats {
        double sum = 0, weight = 0, max = 0;
        Stats& operator+=(const Stats& o) {
            sum += o.sum;
            weight += o.weight;
            max = std::max(max, o.max);
            return *this;
        }
    };
    const Stats st = sum_points<Stats>(in.points.size(), [&](std::size_t i, Stats& s) {
        const double d = distance(res.surface, in.points[i]);
        const double w = weight(in, i);
        s.sum += w * d * d;
        s.weight += w;
        s.max = std::max(s.max, d);
    });
    res.rms = st.weight > 0 ? std::sqrt(st.sum / st.weight) : 0;
    res.max = st.max;
    const Surface& s = res.surface;
    res.ok = iterations >= 0 && finite(s.point) && finite(s.axis) && std::isfinite(s.radius) &&
             std::isfinite(s.angle) && std::isfinite(s.minor_radius) && std::isfinite(res.rms);
    if (!res.ok) {
        res.failure = iterations == -2 ? "a radius ran away: the points are nearly a simpler kind"
                                       : "the refinement diverged";
    }
    return res;
}

}  // namespace

FitResult residuals(const Surface& surface, const FitInput& in) {
    struct Fixed {
        Surface s;
        Surface surface() const { return s; }
    };
    return finish(Fixed{surface}, 0, in);
}

namespace {

FitResult failed(FitKind kind, std::string why) {
    FitResult r;
    r.surface.kind = kind;
    r.failure = std::move(why);
    return r;
}

/// The weighted principal axes of the points about g (eigenvalues ascending: column 0 is the
/// normal of their mean plane).
Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal_axes(const FitInput& in, Vec3 g) {
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - g;
        const Eigen::Vector3d e(q.x, q.y, q.z);
        cov += weight(in, i) * e * e.transpose();
    }
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov);
}

FitResult fit_plane(const FitInput& in) {
    double total = 0;
    const Vec3 c = centroid(in, &total);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es = principal_axes(in, c);
    if (es.info() != Eigen::Success || !(es.eigenvalues()(1) > 0)) {
        return failed(FitKind::kPlane, "the points are collinear or coincide");
    }
    const Eigen::Vector3d n = es.eigenvectors().col(0);
    Surface s;
    s.kind = FitKind::kPlane;
    s.point = c;
    s.axis = normalized(Vec3{n(0), n(1), n(2)});
    // Orient the normal with the given normals, when there are any.
    if (!in.normals.empty()) {
        double agree = 0;
        for (std::size_t i = 0; i < in.normals.size(); ++i)
            agree += weight(in, i) * dot(in.normals[i], s.axis);
        if (agree < 0) s.axis = -s.axis;
    }
    return residuals(s, in);
}

FitResult refine_cone(ConeModel& m, const FitInput& in);
FitResult refine_torus(TorusModel& m, const FitInput& in);

/// A model refined from where it stands, with its kind's checks: what fit() does after its
/// start, and refit() from a given surface.
FitResult refine_from(SphereModel m, const FitInput& in) {
    const int it = refine(m, in);
    if (m.r < 0) m.r = -m.r;
    return finish(m, it, in);
}
FitResult refine_from(CylinderModel m, const FitInput& in) {
    const int it = refine(m, in);
    return finish(m, it, in);
}
FitResult refine_from(ConeModel m, const FitInput& in) { return refine_cone(m, in); }
FitResult refine_from(TorusModel m, const FitInput& in) { return refine_torus(m, in); }

FitResult fit_sphere(const FitInput& in) {
    const Vec3 c0 = centroid(in);
    // Kasa: |q|^2 + D.q + E = 0 for q = p - c0, linear in (D, E).
    Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
    Eigen::Vector4d atb = Eigen::Vector4d::Zero();
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - c0;
        const Eigen::Vector4d row(q.x, q.y, q.z, 1.0);
        const double w = weight(in, i);
        ata += w * row * row.transpose();
        atb -= w * dot(q, q) * row;
    }
    const Eigen::Vector4d x = ata.ldlt().solve(atb);
    const Vec3 center{-0.5 * x(0), -0.5 * x(1), -0.5 * x(2)};
    const double r2 = dot(center, center) - x(3);
    if (!x.allFinite() || !(r2 > 0))
        return failed(FitKind::kSphere, "no sphere through the points");
    return refine_from(SphereModel{c0 + center, std::sqrt(r2)}, in);
}

/// A fit whose normals make more than 60 degrees on average with the given normals (mean |cos|
/// below this) went to another surface through the same points; the given normals (facet
/// normals averaged at the vertices) are off the true ones by half a facet's turn at most.
constexpr double kMinNormalAgreement = 0.5;

/// The line that best meets every normal line (see the top of the file): unit direction and
/// the point of the line nearest to `origin`. False when the normals leave it undetermined.
bool axis_from_normals(const FitInput& in, Vec3 origin, Vec3& point, Vec3& dir) {
    if (in.normals.size() != in.points.size()) return false;
    // Rows (p x n, n) with p relative to origin: minimise over unit d and free m.
    Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 p = in.points[i] - origin, n = in.normals[i];
        const Vec3 pn = cross(p, n);
        Eigen::Matrix<double, 6, 1> row;
        row << pn.x, pn.y, pn.z, n.x, n.y, n.z;
        M += weight(in, i) * row * row.transpose();
    }
    const Eigen::Matrix3d A = M.topLeftCorner<3, 3>(), B = M.topRightCorner<3, 3>(),
                          C = M.bottomRightCorner<3, 3>();
    // m = -C^+ B^T d (C is singular for a cylinder: the normals span a plane only).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ec(C);
    if (ec.info() != Eigen::Success) return false;
    const double cmax = ec.eigenvalues().maxCoeff();
    if (!(cmax > 0)) return false;
    Eigen::Matrix3d cinv = Eigen::Matrix3d::Zero();
    for (int k = 0; k < 3; ++k) {
        const double l = ec.eigenvalues()(k);
        if (l > 1e-9 * cmax)
            cinv += (1.0 / l) * ec.eigenvectors().col(k) * ec.eigenvectors().col(k).transpose();
    }
    const Eigen::Matrix3d schur = A - B * cinv * B.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(schur);
    if (es.info() != Eigen::Success) return false;
    const Eigen::Vector3d d = es.eigenvectors().col(0);
    // Undetermined when a second direction fits about as well (a sphere, a plane).
    const Eigen::Vector3d ev = es.eigenvalues();
    if (!(ev(1) > 1e-6 * std::max(ev(2), 1e-300))) return false;
    const Eigen::Vector3d m = -cinv * B.transpose() * d;
    dir = normalized(Vec3{d(0), d(1), d(2)});
    const Vec3 mm{m(0), m(1), m(2)};
    point = origin + cross(dir, mm);
    return finite(point) && finite(dir) && norm(dir) > 0;
}

/// Meridian coordinates of p about an axis: h along d from c, rho from the axis.
void meridian(Vec3 p, Vec3 c, Vec3 d, double& h, double& rho) {
    const Vec3 q = p - c;
    h = dot(q, d);
    rho = norm(q - h * d);
}

/// How well a fitted surface's normals agree with the given ones: the weighted mean |cos| of
/// the angle between them at the points (1 without normals).
double normal_agreement(const Surface& s, const FitInput& in) {
    if (in.normals.size() != in.points.size()) return 1;
    double sum = 0, total = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        sum += weight(in, i) * std::abs(dot(normal_at(s, in.points[i]), in.normals[i]));
        total += weight(in, i);
    }
    return total > 0 ? sum / total : 1;
}

/// The second start's fit replaces the first's, both agreeing with the normals (or neither),
/// only when its largest residual is below this part of the first's: the wrong surfaces miss
/// by far more (0.2-5 mm against 1e-4 on the strips of the test), while two fits of a noisy
/// patch from the two starts differ by the noise, and which of them is closer may depend on how
/// the part is turned.
constexpr double kClearlyCloser = 0.5;

/// Of the second start's fit a and the first's b: a is better when b failed, or when only a's
/// normals agree with the given ones (kMinNormalAgreement: b went to another surface through
/// the same points), or, both or neither agreeing, when a is clearly closer to the points.
bool better_fit(const FitResult& a, const FitResult& b, const FitInput& in) {
    if (!a.ok || !b.ok) return a.ok && !b.ok;
    const bool agree_a = normal_agreement(a.surface, in) >= kMinNormalAgreement;
    const bool agree_b = normal_agreement(b.surface, in) >= kMinNormalAgreement;
    if (agree_a != agree_b) return agree_a;
    return a.max < kClearlyCloser * b.max;
}

/// The direction the given normals are most nearly all normal to (the least eigenvector of
/// the sum of n n^T): a cylinder's axis, a cone's generator. False without normals.
/// `spread`: the middle eigenvalue over the trace, how widely the normals turn about e (about
/// Φ²/12 for normals over an arc of Φ radians, 0.5 all round); `lean`, when asked for: the least
/// over the trace, how far they lean along e (the mean squared cosine).
bool normals_normal(const FitInput& in, Vec3& e, double& spread, double* lean = nullptr) {
    if (in.normals.size() != in.points.size() || in.normals.empty()) return false;
    Eigen::Matrix3d nn = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < in.normals.size(); ++i) {
        const Eigen::Vector3d n(in.normals[i].x, in.normals[i].y, in.normals[i].z);
        nn += weight(in, i) * n * n.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(nn);
    if (es.info() != Eigen::Success) return false;
    const Eigen::Vector3d v = es.eigenvectors().col(0);
    e = normalized(Vec3{v(0), v(1), v(2)});
    const double trace = nn.trace();
    spread = trace > 0 ? es.eigenvalues()(1) / trace : 0;
    if (lean) *lean = trace > 0 ? es.eigenvalues()(0) / trace : 1;
    return finite(e);
}

/// Normals turning over a wide arc (spread from normals_normal()) determine the line they
/// meet: a first fit that agrees with them needs no second start. 0.2 is an arc of about 90
/// degrees; a strip of a few facet rows spans 10-40.
constexpr double kWideNormals = 0.2;
/// Nor does one within this part of the points' extent of every point: the wrong surfaces
/// through a strip miss some points by a good part of its width (0.07 and 0.14 of it on the
/// strips of the test), or pass through all of them with normals across the given ones.
constexpr double kCloseFit = 1e-3;

/// The points' extent as twice the farthest from their centroid: the same however they are
/// turned (a bounding box's diagonal is not).
double turning_extent(const FitInput& in) {
    const Vec3 g = centroid(in);
    double reach = 0;
    for (const Vec3& p : in.points) reach = std::max(reach, norm(p - g));
    return 2 * reach;
}

/// The first start's fit stands (no second start): it agrees with the normals, and they turn
/// widely or it passes within the caller's `accept` or kCloseFit of the extent of every point.
bool first_fit_stands(const FitResult& res, double spread, const FitInput& in) {
    if (!res.ok || normal_agreement(res.surface, in) < kMinNormalAgreement) return false;
    if (spread >= kWideNormals || res.max <= in.accept) return true;
    // The extent the same however the points are turned (a bounding box's is not, and the
    // choice must not be).
    return res.max <= kCloseFit * turning_extent(in);
}

/// The cylinder along unit d through the points: its radius and axis point from the circle
/// (Kasa) through the points projected along d. False when they are collinear.
bool cylinder_along(const FitInput& in, Vec3 d, CylinderModel& m) {
    Vec3 u, v;
    frame(d, u, v);
    const Vec3 g = centroid(in);
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - g;
        const double x = dot(q, u), y = dot(q, v);
        const Eigen::Vector3d row(x, y, 1.0);
        ata += weight(in, i) * row * row.transpose();
        atb -= weight(in, i) * (x * x + y * y) * row;
    }
    const Eigen::Vector3d k = ata.ldlt().solve(atb);
    const double x0 = -0.5 * k(0), y0 = -0.5 * k(1), r2 = x0 * x0 + y0 * y0 - k(2);
    if (!k.allFinite() || !(r2 > 0)) return false;
    m = CylinderModel{Axis::make(g + x0 * u + y0 * v, d), std::sqrt(r2)};
    return true;
}

/// The start of a second fit where the first does not stand (first_fit_stands()): e, the
/// direction the normals are all normal to, and the cylinder along it. False: keep the first.
bool second_start(const FitInput& in, const FitResult& first, Vec3& e, CylinderModel& m) {
    double spread = 0;
    if (!normals_normal(in, e, spread) || first_fit_stands(first, spread, in)) return false;
    return cylinder_along(in, e, m);
}

FitResult fit_cylinder(const FitInput& in) {
    Vec3 c, d;
    if (!axis_from_normals(in, centroid(in), c, d)) {
        return failed(FitKind::kCylinder, "the normals do not determine an axis");
    }
    double sum = 0, total = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        double h, rho;
        meridian(in.points[i], c, d, h, rho);
        sum += weight(in, i) * rho;
        total += weight(in, i);
    }
    // Put the axis point level with the centroid: parameters stay well conditioned.
    const Vec3 g = centroid(in);
    c += dot(g - c, d) * d;
    FitResult res = refine_from(CylinderModel{Axis::make(c, d), sum / total}, in);
    // A narrow strip (two rows of a coarse bore, their normals 20 degrees apart) leaves the
    // line that meets the normals ill-determined, and the points also lie on thin cylinders
    // across the strip, whose normals are far from the given ones: also from the direction
    // the normals are all normal to, and the better of the two.
    Vec3 e;
    CylinderModel m2{};
    if (!second_start(in, res, e, m2)) return res;
    FitResult other = refine_from(m2, in);
    return better_fit(other, res, in) ? other : res;
}

/// The cone about the axis through c along unit d: its generator line rho = r + t h by
/// weighted least squares in the meridian plane, then refined.
FitResult cone_about(const FitInput& in, Vec3 c, Vec3 d) {
    const Vec3 g = centroid(in);
    c += dot(g - c, d) * d;
    double sw = 0, sh = 0, sr = 0, shh = 0, shr = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        double h, rho;
        meridian(in.points[i], c, d, h, rho);
        const double w = weight(in, i);
        sw += w, sh += w * h, sr += w * rho, shh += w * h * h, shr += w * h * rho;
    }
    const double den = sw * shh - sh * sh;
    if (!(den > 0)) return failed(FitKind::kCone, "the points span no height along the axis");
    double t = (sw * shr - sh * sr) / den;
    const double r = (sr - t * sh) / sw;
    if (t < 0) {
        d = -d;  // the radius grows along the axis direction
        t = -t;
    }
    ConeModel m = ConeModel::make(Axis::make(c, d), r, std::atan(t));
    return refine_cone(m, in);
}

/// The cone refined from m, with its half-angle and radius checked.
FitResult refine_cone(ConeModel& m, const FitInput& in) {
    const int it = refine(m, in);
    if (m.alpha < 0) {  // crossed through a cylinder: turn the axis round
        m = ConeModel::make(Axis::make(m.a.c, -m.a.d), m.r, -m.alpha);
    }
    FitResult res = finish(m, it, in);
    if (res.ok && !(m.alpha > 0 && m.alpha < 0.5 * std::numbers::pi)) {
        res.ok = false;
        res.failure = "the half-angle left (0, pi/2)";
    }
    if (res.ok && m.r < 0) {
        res.ok = false;
        res.failure = "the points lie across the apex";
    }
    // A cone that leaves the plane through its apex by less, across the points, than its points
    // leave it is that plane as far as they tell: nothing a machinist would name a cone, and
    // its apex, which can lie among the points, makes a face on it degenerate (occt_TR12J's
    // mesh with its coordinates nudged by one float32 unit: a 42-facet region 0.26 mm off a cone
    // of half-angle pi/2 - 8e-8 with its apex in the middle of it: its face, one edge of 1.4 mm
    // running half round the apex, failed on its surface and on its mesh edges, and fell back
    // to facets).
    // Any two points' distance bounds the extent from below: most cones are decided by the
    // first and last without a pass over the points.
    const double flat_reach = res.max * std::tan(m.alpha);
    if (res.ok && !in.points.empty() && norm(in.points.back() - in.points.front()) <= flat_reach &&
        turning_extent(in) <= flat_reach) {
        res.ok = false;
        res.failure = "the cone is flat: a plane within its residual";
    }
    return res;
}

FitResult fit_cone(const FitInput& in) {
    Vec3 c, d;
    if (!axis_from_normals(in, centroid(in), c, d)) {
        return failed(FitKind::kCone, "the normals do not determine an axis");
    }
    FitResult res = cone_about(in, c, d);
    // As for the cylinder: a narrow strip of a cone of small half-angle (a drafted wall's
    // facets, each from rim to rim) leaves the normals' line ill-determined, and the fit can
    // settle on a flat cone 3 mm off. Its generators are what the normals are all normal to,
    // within the half-angle: a second start for the axis, and the better of the two.
    Vec3 e;
    CylinderModel m{};
    if (!second_start(in, res, e, m)) return res;
    FitResult other = cone_about(in, m.a.c, e);
    return better_fit(other, res, in) ? other : res;
}

/// spine_start() searches with at most this many of the points (evenly strided): it finds a
/// start, the refinement uses them all.
constexpr std::size_t kSpineSamples = 512;
/// The sample a fit of many points is refused on (FitInput::refuse_rms): every n-th point,
/// this many or more. Enough to fix a torus's seven parameters far better than a refusal
/// needs; each of its iterations goes over 2048 / n of the points (kSampledFitPoints keeps
/// that at most an eighth, the cost added to a fit that is not refused).
constexpr std::size_t kRefuseSamplePoints = 2048;
constexpr double kInf = std::numeric_limits<double>::infinity();
/// The tube radii spine_start() tries: +-4 x the points' reach x 2^(-k/2) for k < kSpineSteps,
/// down to about 1e-4 of the reach (finer than any tube a tessellation of the part resolves);
/// then golden-section steps between the best one's neighbours.
constexpr int kSpineSteps = 28;
constexpr int kSpineGoldenSteps = 40;

/// A torus from spine_start() stands only where the points run along its tube for at least
/// this many tube radii (a thin fillet ring, what it is for). Over a shorter run a bent tube
/// and a straight one (a cylinder) differ by a few hundredths of a millimetre, which a stray
/// facet or two of a neighbouring face provides: a cylinder band beside a ball end of its
/// radius fitted tubes bent at 2 to 4 radii.
constexpr double kSpineMinRun = 3;

/// How far the points run along the spine of m: its radius times the angle about its axis
/// that they cover (the full circle less the largest gap between them).
double spine_run(const FitInput& in, const TorusModel& m) {
    std::vector<double> angle;
    angle.reserve(in.points.size());
    for (const Vec3& p : in.points) {
        const Vec3 q = p - m.a.c;
        angle.push_back(std::atan2(dot(q, m.a.v), dot(q, m.a.u)));
    }
    if (angle.empty()) return 0;
    std::sort(angle.begin(), angle.end());
    double gap = angle.front() + 2 * std::numbers::pi - angle.back();
    for (std::size_t i = 1; i < angle.size(); ++i) gap = std::max(gap, angle[i] - angle[i - 1]);
    return std::fabs(m.R) * (2 * std::numbers::pi - gap);
}

/// The circle nearest the points: its plane by principal components, the circle in it by
/// Kasa's fit (cylinder_along() the plane's normal). Returns the weighted mean squared distance
/// of the points from it; infinite when there is none.
double circle_through(const FitInput& in, Vec3& c, Vec3& d, double& R) {
    double total = 0;
    const Vec3 g = centroid(in, &total);
    if (!(total > 0)) return kInf;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es = principal_axes(in, g);
    if (es.info() != Eigen::Success) return kInf;
    d = normalized(Vec3{es.eigenvectors()(0, 0), es.eigenvectors()(1, 0), es.eigenvectors()(2, 0)});
    CylinderModel m{};
    if (!cylinder_along(in, d, m)) return kInf;
    c = m.a.c;
    R = m.r;
    double sum = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - c;
        const double h = dot(q, d), e = norm(q - h * d) - R;
        sum += weight(in, i) * (h * h + e * e);
    }
    return sum / total;
}

/// Every step-th point (every point for a step of 0), normal (if any) and weight of an input,
/// as an input of its own (`input()`).
struct Strided {
    std::vector<Vec3> points, normals;
    std::vector<double> weights;
    Strided(const FitInput& in, std::size_t step) {
        step = std::max<std::size_t>(step, 1);
        for (std::size_t i = 0; i < in.points.size(); i += step) {
            points.push_back(in.points[i]);
            if (!in.normals.empty()) normals.push_back(in.normals[i]);
            weights.push_back(weight(in, i));
        }
    }
    FitInput input(const FitInput& like) const {
        FitInput f = like;
        f.points = points;
        f.normals = normals;
        f.weights = weights;
        return f;
    }
};

/// A second start for a torus, from its spine: the points moved along their normals by the
/// tube radius lie on one circle (the tube's center line), whose plane's normal is the axis
/// and whose radius is the major radius. The tube radius (either side: a fillet's tube is
/// outside the material, a round's inside) is the one that puts them closest to a circle.
/// Where the first start fails: a patch of a few rows of a thin fillet ring, whose normals
/// nearly all meet the tube's center line too, leaves the line that meets them all (the axis
/// of the first start) to the mesh normals' errors. `sample`: the points searched with (at most
/// kSpineSamples, with their normals); g: the centroid of all of them.
bool spine_start(const FitInput& sample, Vec3 g, TorusModel& m) {
    double reach = 0;
    for (const Vec3& p : sample.points) reach = std::max(reach, norm(p - g));
    if (!(reach > 0)) return false;
    std::vector<Vec3> moved(sample.points.size());
    FitInput spine = sample;
    spine.points = moved;
    Vec3 c, d;
    double R = 0;
    const auto spread = [&](double rho) {
        for (std::size_t k = 0; k < moved.size(); ++k)
            moved[k] = sample.points[k] - rho * sample.normals[k];
        return circle_through(spine, c, d, R);
    };
    // The grid: radii of both signs, largest first; the best and its neighbours bracket it.
    std::vector<double> grid;
    for (int k = 0; k < kSpineSteps; ++k) grid.push_back(4 * reach * std::pow(0.5, 0.5 * k));
    for (int k = kSpineSteps - 1; k >= 0; --k) grid.push_back(-grid[static_cast<std::size_t>(k)]);
    std::size_t best = 0;
    double best_spread = kInf;
    for (std::size_t k = 0; k < grid.size(); ++k) {
        const double e = spread(grid[k]);
        if (e < best_spread) best_spread = e, best = k;
    }
    if (!std::isfinite(best_spread)) return false;
    // Between the neighbours (of the same sign: a tube radius does not pass through zero).
    const std::size_t half = static_cast<std::size_t>(kSpineSteps);
    const bool first_half = best < half;
    const std::size_t lo_i = best > (first_half ? 0 : half) ? best - 1 : best;
    const std::size_t hi_i = best + 1 < (first_half ? half : grid.size()) ? best + 1 : best;
    double lo = grid[lo_i], hi = grid[hi_i];
    const double phi = 0.5 * (std::sqrt(5.0) - 1);
    double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
    double f1 = spread(x1), f2 = spread(x2);
    for (int it = 0; it < kSpineGoldenSteps; ++it) {
        if (f1 < f2) {
            hi = x2, x2 = x1, f2 = f1;
            x1 = hi - phi * (hi - lo);
            f1 = spread(x1);
        } else {
            lo = x1, x1 = x2, f1 = f2;
            x2 = lo + phi * (hi - lo);
            f2 = spread(x2);
        }
    }
    const double rho = 0.5 * (lo + hi);
    if (!std::isfinite(spread(rho))) return false;
    m = TorusModel{Axis::make(c, d), R, std::fabs(rho)};
    return finite(c) && finite(d) && R > 0 && std::fabs(rho) > 0;
}

/// The torus refined from m, with its radii checked.
FitResult refine_torus(TorusModel& m, const FitInput& in) {
    const int it = refine(m, in);
    FitResult res = finish(m, it, in);
    // A negative major radius is the inner part of a spindle torus (r > |R|): the lemon-shaped
    // dome of a screw head, whose meridian arc is centered across the axis (kLemonMaxAxisOffset).
    if (res.ok && !(m.r > 0 && (m.R > 0 || (-m.R > 0 && -m.R < kLemonMaxAxisOffset * m.r)))) {
        res.ok = false;
        res.failure = "the radii left their range";
    }
    return res;
}

FitResult fit_torus(const FitInput& in) {
    Vec3 c, d;
    if (!axis_from_normals(in, centroid(in), c, d)) {
        return failed(FitKind::kTorus, "the normals do not determine an axis");
    }
    // The tube circle in the meridian plane: Kasa fit of (rho, h).
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        double h, rho;
        meridian(in.points[i], c, d, h, rho);
        const Eigen::Vector3d row(rho, h, 1.0);
        const double w = weight(in, i);
        ata += w * row * row.transpose();
        atb -= w * (rho * rho + h * h) * row;
    }
    const Eigen::Vector3d x = ata.ldlt().solve(atb);
    const double R = -0.5 * x(0), h0 = -0.5 * x(1);
    const double r2 = R * R + h0 * h0 - x(2);
    if (!x.allFinite() || !(r2 > 0))
        return failed(FitKind::kTorus, "no tube circle through the profile");
    TorusModel m{Axis::make(c + h0 * d, d), R, std::sqrt(r2)};
    FitResult res = refine_torus(m, in);
    // A fit within what the caller accepts stands; otherwise also from the spine.
    if (res.ok && in.accept > 0 && res.max <= in.accept) return res;
    const std::size_t n = in.points.size();
    if (in.normals.size() != n || n < 8) return res;
    const std::size_t step = n / kSpineSamples;  // 0 or 1: every point
    const Strided strided(in, step);
    const FitInput sample = strided.input(in);
    TorusModel m2{};
    if (!spine_start(sample, centroid(in), m2)) return res;
    // Refined on the spine search's sample first: a torus that misses those points by more
    // than the caller accepts does not hold them all (most of the unions a segmentation tries
    // are no torus), and the sample is at most kSpineSamples points.
    if (step > 1 && in.accept > 0) {
        const FitResult first_look = refine_torus(m2, sample);
        if (!first_look.ok || first_look.max > in.accept) return res;
    }
    FitResult other = refine_torus(m2, in);
    if (!other.ok || spine_run(in, m2) < kSpineMinRun * m2.r) return res;
    return better_fit(other, res, in) ? other : res;
}

/// Gauss-Newton for the parameters (u, v) of the point of `b` nearest to p, from a start,
/// kept inside [0, 1]^2.
void project_bspline(const BSplineSurface& b, Vec3 p, double& u, double& v) {
    for (int it = 0; it < kProjectIterations; ++it) {
        Vec3 s, su, sv;
        b.evaluate(u, v, s, su, sv);
        const Vec3 r = s - p;
        const double a = dot(su, su), c = dot(sv, sv), d = dot(su, sv);
        const double g1 = dot(su, r), g2 = dot(sv, r);
        const double det = a * c - d * d;
        if (!(det > 0)) return;
        const double du = -(c * g1 - d * g2) / det, dv = -(a * g2 - d * g1) / det;
        const double nu = std::clamp(u + du, 0.0, 1.0), nv = std::clamp(v + dv, 0.0, 1.0);
        const bool done = std::fabs(nu - u) < 1e-13 && std::fabs(nv - v) < 1e-13;
        u = nu, v = nv;
        if (done) return;
    }
}

/// The grid of coarse_start(): gu + 1 by gv + 1 parameters (gv 0: the middle only). An
/// extrusion's profile folds (an S-shaped pocket wall): its grid follows the profile at
/// kProfileGrid samples per pole, along the middle only (the nearest point's place along the
/// profile does not depend on the height).
void start_grid(const BSplineSurface& b, int& gu, int& gv) {
    constexpr int kGrid = 16;
    gu = b.extruded || b.helical ? kProfileGrid * b.num_u : kGrid;
    gv = b.extruded ? 0 : b.helical ? std::max(kGrid, 2 * (b.num_v - 3)) : kGrid;
}

/// The parameters of the grid's point (i, j).
void start_params(int gu, int gv, int i, int j, double& u, double& v) {
    u = static_cast<double>(i) / gu;
    v = gv > 0 ? static_cast<double>(j) / gv : 0.5;
}

Vec3 start_point(const BSplineSurface& b, int gu, int gv, int i, int j) {
    double u = 0, v = 0;
    start_params(gu, gv, i, j, u, v);
    return b.evaluate(u, v);
}

/// Fills `starts` (see BSplineSurface).
void fill_starts(BSplineSurface& b) {
    int gu = 0, gv = 0;
    start_grid(b, gu, gv);
    b.starts.clear();
    b.starts.reserve(static_cast<std::size_t>((gu + 1) * (gv + 1)));
    for (int j = 0; j <= gv; ++j)
        for (int i = 0; i <= gu; ++i) b.starts.push_back(start_point(b, gu, gv, i, j));
}

/// The nearest of the grid of start_grid(): a start for project_bspline(). On a helical sweep
/// only the rows beside the point's own turn (its angle about the axis on the turn whose
/// height is nearest the profile's): the grid has two rows a knot span along a helix of
/// hundreds, and a scan of it all was most of the time of segmenting a finely meshed thread.
void coarse_start(const BSplineSurface& b, Vec3 p, double& u, double& v) {
    double best = std::numeric_limits<double>::infinity();
    int gu = 0, gv = 0;
    start_grid(b, gu, gv);
    const bool cached = b.starts.size() == static_cast<std::size_t>((gu + 1) * (gv + 1));
    int bi = 0, bj = 0;
    // Rows [j0, j1], and on a helix [k0, k1] too: the turns below and above the point's height
    // (one near half a pitch from the profile's is as near the one as the other).
    int j0 = 0, j1 = gv, k0 = 1, k1 = 0;
    const BSplineSurface::Helix& hx = b.helix;
    if (b.helical && hx.a1 > hx.a0 && hx.pitch != 0 && gv > 0) {
        double th = 0;
        const double turns = hx.turns(p, th);
        const auto row = [&](double turn) {
            const double at = std::clamp((th + 2 * kPi * turn - hx.a0) / (hx.a1 - hx.a0), 0.0, 1.0);
            return std::isfinite(at) ? static_cast<int>(std::lround(at * gv)) : -1;
        };
        const int below = row(std::floor(turns)), above = row(std::ceil(turns));
        if (below >= 0 && above >= 0) {
            j0 = std::max(0, below - 1), j1 = std::min(gv, below + 1);
            k0 = std::max(0, above - 1), k1 = std::min(gv, above + 1);
        }
    }
    const auto scan = [&](int j) {
        for (int i = 0; i <= gu; ++i) {
            const Vec3 q = (cached ? b.starts[static_cast<std::size_t>(i + (gu + 1) * j)]
                                   : start_point(b, gu, gv, i, j)) -
                           p;
            const double d2 = dot(q, q);
            if (d2 < best) best = d2, bi = i, bj = j;
        }
    };
    for (int j = j0; j <= j1; ++j) scan(j);
    for (int j = std::max(k0, j1 + 1); j <= k1; ++j) scan(j);  // rows not scanned above
    for (int j = k0; j <= std::min(k1, j0 - 1); ++j) scan(j);
    start_params(gu, gv, bi, bj, u, v);
}

/// A fitted B-spline: `point` and `axis` its mean plane's (a net's) or its centroid and
/// direction (an extrusion's); `iterations` its number of poles.
FitResult bspline_fit(std::shared_ptr<BSplineSurface> bs, Vec3 point, Vec3 axis, double rms,
                      double max, int iterations) {
    fill_starts(*bs);
    FitResult r;
    r.ok = true;
    r.surface.kind = FitKind::kBSpline;
    r.surface.point = point;
    r.surface.axis = axis;
    r.surface.bspline = std::move(bs);
    r.rms = rms;
    r.max = max;
    r.iterations = iterations;
    return r;
}

FitResult fit_bspline_impl(const FitInput& in, double tolerance) {
    FitResult fail;
    fail.surface.kind = FitKind::kBSpline;
    // The mean plane and the principal directions in it.
    double total = 0;
    const Vec3 c = centroid(in, &total);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - c;
        const Eigen::Vector3d e(q.x, q.y, q.z);
        cov += weight(in, i) * e * e.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const auto col = [&](int k) {
        const Eigen::Vector3d e = es.eigenvectors().col(k);
        return normalized(Vec3{e(0), e(1), e(2)});
    };
    const Vec3 nrm = col(0), e1 = col(2), e2 = cross(nrm, e1);
    // Parameters from the plane coordinates.
    const std::size_t n = in.points.size();
    std::vector<double> x(n), y(n), z(n);
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 q = in.points[i] - c;
        x[i] = dot(q, e1), y[i] = dot(q, e2), z[i] = dot(q, nrm);
        x0 = std::min(x0, x[i]), x1 = std::max(x1, x[i]);
        y0 = std::min(y0, y[i]), y1 = std::max(y1, y[i]);
    }
    if (!(x1 > x0 && y1 > y0)) {
        fail.failure = "the points span no area";
        return fail;
    }
    // The net's domain: the points' extent, and FitInput::margin of it beyond on each side.
    if (in.margin > 0) {
        const double ex = in.margin * (x1 - x0), ey = in.margin * (y1 - y0);
        x0 -= ex, x1 += ex, y0 -= ey, y1 += ey;
    }
    std::vector<double> u(n), v(n);
    for (std::size_t i = 0; i < n; ++i)
        u[i] = (x[i] - x0) / (x1 - x0), v[i] = (y[i] - y0) / (y1 - y0);
    // The guides (FitInput::guides) at their places over the mean plane (within the points'
    // extent: a guide is a middle of facets whose corners are points), and their weight.
    const std::size_t ng = in.guides.size();
    std::vector<double> guide_u(ng), guide_v(ng), guide_z(ng);
    for (std::size_t i = 0; i < ng; ++i) {
        const Vec3 q = in.guides[i] - c;
        guide_u[i] = std::clamp((dot(q, e1) - x0) / (x1 - x0), 0.0, 1.0);
        guide_v[i] = std::clamp((dot(q, e2) - y0) / (y1 - y0), 0.0, 1.0);
        guide_z[i] = dot(q, nrm);
    }
    const double guide_weight = kGuideWeight * total / static_cast<double>(n);
    // Net sizes: 4 along the shorter side to start (then kNetGrowth x as many), proportional to
    // the extents.
    const double aspect = (x1 - x0) / (y1 - y0);
    double base = kBSplineStartPoles;
    const auto max_poles =
        static_cast<int>(std::min<std::size_t>(n / 2, kBSplineMaxPoles * kBSplineMaxPoles));
    const int pole_limit = std::max(16, max_poles);  // the smallest net is always tried
    FitResult best = fail;
    int last_nu = 0, last_nv = 0;  // the net stops growing at kBSplineMaxPoles
    for (;;) {
        int nu = std::min(kBSplineMaxPoles,
                          std::max(4, static_cast<int>(std::lround(base * std::max(1.0, aspect)))));
        int nv = std::min(
            kBSplineMaxPoles,
            std::max(4, static_cast<int>(std::lround(base * std::max(1.0, 1.0 / aspect)))));
        // A long strip's first net: as many poles along it as the points allow (its 4 x 24
        // proportional net would have more poles than half its points and no net be tried).
        if (last_nu == 0 && nu * nv > pole_limit) {
            if (nu > nv) {
                nu = std::max(4, pole_limit / nv);
            } else {
                nv = std::max(4, pole_limit / nu);
            }
        }
        if (nu * nv > pole_limit || (nu == last_nu && nv == last_nv) ||
            (in.max_net_poles > 0 && nu * nv > in.max_net_poles))
            break;
        last_nu = nu, last_nv = nv;
        const int m = nu * nv;
        // Normal equations in band storage: pole (a, b) couples with (a + da, b + db), |da|,
        // |db| <= 3.
        constexpr int kW = 2 * kMaxDegree + 1;
        std::vector<double> band(static_cast<std::size_t>(m) * kW * kW, 0.0),
            rhs(static_cast<std::size_t>(m), 0.0);
        auto entry = [&](int row, int da, int db) -> double& {
            return band[(static_cast<std::size_t>(row) * kW +
                         static_cast<std::size_t>(da + kMaxDegree)) *
                            kW +
                        static_cast<std::size_t>(db + kMaxDegree)];
        };
        // A sample of height h at (uu, vv) over the mean plane, weighing w.
        const auto add_sample = [&](double uu, double vv, double w, double h) {
            double Nu[kMaxDegree + 1], Nv[kMaxDegree + 1];
            const int su = cubic_basis(nu, uu, Nu, nullptr) - 3,
                      sv = cubic_basis(nv, vv, Nv, nullptr) - 3;
            for (int b = 0; b <= 3; ++b) {
                for (int a = 0; a <= 3; ++a) {
                    const int row = (su + a) + nu * (sv + b);
                    const double fa = w * Nu[a] * Nv[b];
                    rhs[static_cast<std::size_t>(row)] += fa * h;
                    for (int bb = 0; bb <= 3; ++bb)
                        for (int aa = 0; aa <= 3; ++aa)
                            entry(row, aa - a, bb - b) += fa * Nu[aa] * Nv[bb];
                }
            }
        };
        for (std::size_t i = 0; i < n; ++i) add_sample(u[i], v[i], weight(in, i), z[i]);
        for (std::size_t i = 0; i < in.guides.size(); ++i)
            add_sample(guide_u[i], guide_v[i], guide_weight, guide_z[i]);
        // Smoothing: the squared second differences of the heights along both directions,
        // weighted so that it is felt only where there are no points.
        const double lambda = kBSplineSmoothing * total / m;
        auto smooth_row = [&](int a, int b, int sa, int sb) {
            // Difference h(a - sa) - 2 h(a) + h(a + sa) at interior poles.
            const int idx[3] = {(a - sa) + nu * (b - sb), a + nu * b, (a + sa) + nu * (b + sb)};
            const double coef[3] = {1, -2, 1};
            for (int r = 0; r < 3; ++r)
                for (int k = 0; k < 3; ++k) {
                    const int row = idx[r];
                    const int other = idx[k];
                    const int da = (other % nu) - (row % nu), db = (other / nu) - (row / nu);
                    entry(row, da, db) += lambda * coef[r] * coef[k];
                }
        };
        for (int b = 0; b < nv; ++b)
            for (int a = 1; a + 1 < nu; ++a) smooth_row(a, b, 1, 0);
        for (int b = 1; b + 1 < nv; ++b)
            for (int a = 0; a < nu; ++a) smooth_row(a, b, 0, 1);
        std::vector<Eigen::Triplet<double>> trip;
        trip.reserve(static_cast<std::size_t>(m) * kW * kW);
        for (int row = 0; row < m; ++row) {
            const int a = row % nu, b = row / nu;
            for (int db = -kMaxDegree; db <= kMaxDegree; ++db)
                for (int da = -kMaxDegree; da <= kMaxDegree; ++da) {
                    const double val = entry(row, da, db);
                    if (val == 0 || a + da < 0 || a + da >= nu || b + db < 0 || b + db >= nv)
                        continue;
                    trip.emplace_back(row, (a + da) + nu * (b + db), val);
                }
        }
        Eigen::SparseMatrix<double> A(m, m);
        A.setFromTriplets(trip.begin(), trip.end());
        Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
        if (solver.info() != Eigen::Success) break;
        const Eigen::VectorXd h = solver.solve(Eigen::Map<const Eigen::VectorXd>(rhs.data(), m));
        if (solver.info() != Eigen::Success || !h.allFinite()) break;
        auto bs = std::make_shared<BSplineSurface>();
        bs->num_u = nu, bs->num_v = nv;
        bs->poles.resize(static_cast<std::size_t>(m));
        for (int b = 0; b < nv; ++b) {
            // Greville abscissae: x(u) stays exactly linear, so only the heights are fitted.
            double gv = 0;
            for (int k = 1; k <= 3; ++k) gv += knot(b + k, 3, nv);
            gv /= 3;
            for (int a = 0; a < nu; ++a) {
                double gu = 0;
                for (int k = 1; k <= 3; ++k) gu += knot(a + k, 3, nu);
                gu /= 3;
                bs->poles[static_cast<std::size_t>(a + nu * b)] = c + (x0 + gu * (x1 - x0)) * e1 +
                                                                  (y0 + gv * (y1 - y0)) * e2 +
                                                                  h(a + nu * b) * nrm;
            }
        }
        // Residuals: true distances, projecting from each point's own parameters (on all
        // cores: most of the time of a large group's fit, docs/benchmarks.md), summed in order.
        std::vector<double> dist(n);
        const auto residuals = [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
                double uu = u[i], vv = v[i];
                project_bspline(*bs, in.points[i], uu, vv);
                dist[i] = norm(bs->evaluate(uu, vv) - in.points[i]);
            }
        };
        if (n <= kGrain) {  // one task: without the scheduler's cost
            residuals(tbb::blocked_range<std::size_t>(0, n));
        } else {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), residuals);
        }
        double sum = 0, mx = 0;
        for (std::size_t i = 0; i < n; ++i) {
            sum += weight(in, i) * dist[i] * dist[i];
            mx = std::max(mx, dist[i]);
        }
        FitResult r = bspline_fit(std::move(bs), c, nrm, std::sqrt(sum / total), mx, nu * nv);
        best = r;
        if (mx <= tolerance) return r;
        base *= kNetGrowth;
    }
    if (best.ok) {
        best.ok = false;
        best.failure =
            "no control net up to the size limit reaches the tolerance (not a height "
            "field over its mean plane, or too few points)";
        return best;
    }
    fail.failure = "the least-squares system is singular";
    return fail;
}

/// Normals this close to all normal to one direction e (their lean along it from
/// normals_normal(), the mean squared cosine, below this: about 2.5 degrees) make the points a
/// candidate for a linear extrusion along e (fit_extrusion()).
constexpr double kExtrusionNormals = 2e-3;
/// ...and the normals turn about e far more than they lean along it (the lean at most this part
/// of the spread): the normals of a shallow dome lean a little every way, and no direction is
/// the extrusion's.
constexpr double kExtrusionTurn = 1e-2;
/// Neighbours per point of the graph along the profile (fit_extrusion()).
constexpr std::size_t kProfileNeighbours = 6;
/// Pieces of the neighbour graph that fit_extrusion() joins at most (gaps in the sampling); more
/// are not one profile.
constexpr int kProfilePieces = 16;
/// Nodes of that graph at most (see profile_parameters()): joining its pieces costs up to
/// kProfilePieces x kProfileNodes^2 distance tests.
constexpr std::size_t kProfileNodes = 4096;
/// A profile whose ends are within this many of its longest step of each other, the chord
/// between them running along the curve, is closed.
constexpr double kClosedProfile = 2;
/// Two points are neighbours along a profile when the chord between them makes at most this
/// cosine with either's normal (60 degrees and more: a mesh's chords along a curve make 80 and
/// more, BRepMesh's angular deflection of 20 degrees at most turning them by half that).
constexpr double kChordAcross = 0.5;
/// Chord points across gaps in the profile's sampling (fit_extrusion()): spacing in the
/// parameter (a quarter of the finest net's knot span) and weight (of the points' mean).
constexpr double kFillStep = 1.0 / (4 * kBSplineMaxPoles);
constexpr double kFillWeight = 0.01;
/// Projections of the points onto the fitted profile: at most this many rounds of new
/// parameters and a new fit, while a round lowers the largest residual by kProfileGain.
constexpr int kProfileRounds = 10;
constexpr double kProfileGain = 0.05;
/// A net whose profile misses a point by more than kCoarseNetMiss x the tolerance after
/// kCoarseNetRounds rounds is given up for the next (finer) one.
constexpr int kCoarseNetRounds = 3;
constexpr double kCoarseNetMiss = 2;

/// Parameters along the profile of points projected into a plane (with their normals there):
/// the distance along the minimum spanning tree of their positions from one end, scaled to
/// [0, 1] (found by two searches: the point farthest from any is an end). A curve sampled
/// unevenly — a coarse mesh has points 0.05 mm apart on a bend and 3 mm apart on a flat — is a
/// path in its spanning tree, where a graph of nearest neighbours falls apart at the gaps. The
/// tree is built from the kProfileNeighbours nearest of each node (points merged in cells of
/// the tolerance's width; a grid finds them), its pieces joined by their closest pairs; only
/// pairs whose chord runs along the curve (kChordAcross) are linked. False when the points
/// span nothing, it would take more than kProfilePieces joins, or the profile is closed.
bool profile_parameters(const std::vector<double>& x, const std::vector<double>& y,
                        const std::vector<double>& ux, const std::vector<double>& uy,
                        double tolerance, std::vector<double>& s, std::vector<double>& s_turn) {
    const std::size_t n = x.size();
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
    for (std::size_t i = 0; i < n; ++i) {
        x0 = std::min(x0, x[i]), x1 = std::max(x1, x[i]);
        y0 = std::min(y0, y[i]), y1 = std::max(y1, y[i]);
    }
    const double span = std::max(x1 - x0, y1 - y0);
    if (!(span > 0)) return false;
    // Nodes: the points within one cell of a grid of the tolerance's width, at their mean (the
    // points of an extrusion's rims and rows coincide here, or nearly: a graph of their nearest
    // neighbours would link each cluster only within itself).
    // At most kProfileNodes nodes (the cells grow until so): they only order the points, and
    // joining the pieces of the graph tests pairs of them.
    std::vector<std::uint32_t> node(n);
    std::vector<double> nx, ny, count, mx, my;
    for (double snap = std::max(tolerance, span * 1e-6);; snap *= 2) {
        std::map<std::pair<long, long>, std::uint32_t> cells;
        nx.clear(), ny.clear(), count.clear(), mx.clear(), my.clear();
        for (std::size_t i = 0; i < n; ++i) {
            const std::pair<long, long> k{static_cast<long>(std::floor((x[i] - x0) / snap)),
                                          static_cast<long>(std::floor((y[i] - y0) / snap))};
            const auto [it, fresh] = cells.emplace(k, static_cast<std::uint32_t>(nx.size()));
            if (fresh)
                nx.push_back(0), ny.push_back(0), count.push_back(0), mx.push_back(0),
                    my.push_back(0);
            node[i] = it->second;
            nx[it->second] += x[i], ny[it->second] += y[i], count[it->second] += 1;
            mx[it->second] += ux[i], my[it->second] += uy[i];
        }
        if (nx.size() <= kProfileNodes) break;
    }
    const std::size_t m = nx.size();
    for (std::size_t k = 0; k < m; ++k) {
        nx[k] /= count[k], ny[k] /= count[k];
        const double l = std::hypot(mx[k], my[k]);
        if (l > 0) mx[k] /= l, my[k] /= l;
    }
    if (m < 2) return false;
    // Neighbours along the profile: the chord between them runs along the curve, across both
    // their normals. Across a fold of the profile (an S-shaped wall's two branches, nearer each
    // other than the next points along a sparse stretch) it runs along them.
    const auto along = [&](std::uint32_t a, std::uint32_t b) {
        const double cx = nx[b] - nx[a], cy = ny[b] - ny[a], l = std::hypot(cx, cy);
        if (!(l > 0)) return true;
        return std::fabs(cx * mx[a] + cy * my[a]) <= kChordAcross * l &&
               std::fabs(cx * mx[b] + cy * my[b]) <= kChordAcross * l;
    };
    const double cell = span / std::max(1.0, static_cast<double>(m) / 4);
    const auto key = [&](double a, double b) {
        return std::pair<long, long>{static_cast<long>(std::floor((a - x0) / cell)),
                                     static_cast<long>(std::floor((b - y0) / cell))};
    };
    std::map<std::pair<long, long>, std::vector<std::uint32_t>> grid;
    for (std::uint32_t i = 0; i < m; ++i) grid[key(nx[i], ny[i])].push_back(i);
    const auto dist = [&](std::uint32_t a, std::uint32_t b) {
        return std::hypot(nx[a] - nx[b], ny[a] - ny[b]);
    };
    using Edge = std::tuple<double, std::uint32_t, std::uint32_t>;
    std::vector<Edge> edges;
    for (std::uint32_t i = 0; i < m; ++i) {
        const auto [cx, cy] = key(nx[i], ny[i]);
        std::vector<std::pair<double, std::uint32_t>> near;
        for (long ring = 1; near.size() < kProfileNeighbours && ring <= 8; ring *= 2) {
            near.clear();
            for (long gx = cx - ring; gx <= cx + ring; ++gx)
                for (long gy = cy - ring; gy <= cy + ring; ++gy) {
                    const auto it = grid.find({gx, gy});
                    if (it == grid.end()) continue;
                    for (const std::uint32_t j : it->second)
                        if (j != i && along(i, j)) near.emplace_back(dist(i, j), j);
                }
        }
        const std::size_t k = std::min<std::size_t>(kProfileNeighbours, near.size());
        std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k), near.end());
        for (std::size_t a = 0; a < k; ++a)
            edges.emplace_back(near[a].first, std::min(i, near[a].second),
                               std::max(i, near[a].second));
    }
    std::sort(edges.begin(), edges.end());
    std::vector<std::uint32_t> parent(m);
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&](std::uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    std::vector<std::vector<std::pair<std::uint32_t, double>>> tree(m);
    std::size_t pieces = m;
    const auto join = [&](std::uint32_t a, std::uint32_t b, double w) {
        tree[a].emplace_back(b, w);
        tree[b].emplace_back(a, w);
        parent[find(a)] = find(b);
        --pieces;
    };
    for (const auto& [w, a, b] : edges)
        if (find(a) != find(b)) join(a, b, w);
    for (int joins = 0; pieces > 1; ++joins) {
        if (joins == kProfilePieces) return false;
        // The piece of node 0 to its closest other point.
        const std::uint32_t r0 = find(0);
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t ba = 0, bb = 0;
        for (std::uint32_t a = 0; a < m; ++a) {
            if (find(a) != r0) continue;
            for (std::uint32_t b = 0; b < m; ++b) {
                if (find(b) == r0 || !along(a, b)) continue;
                const double w = dist(a, b);
                if (w < best) best = w, ba = a, bb = b;
            }
        }
        if (!std::isfinite(best)) return false;
        join(ba, bb, best);
    }
    // Distances along the tree: its links' lengths, or the angles the normals turn by along them.
    std::vector<double> d(m), turn(m);
    const auto angle = [&](std::uint32_t a, std::uint32_t b) {
        return std::fabs(std::atan2(mx[a] * my[b] - my[a] * mx[b], mx[a] * mx[b] + my[a] * my[b]));
    };
    const auto farthest = [&](std::uint32_t from) {
        std::fill(d.begin(), d.end(), -1.0);
        std::vector<std::uint32_t> stack{from};
        d[from] = turn[from] = 0;
        std::uint32_t far = from;
        while (!stack.empty()) {
            const std::uint32_t v = stack.back();
            stack.pop_back();
            if (d[v] > d[far]) far = v;
            for (const auto& [w, len] : tree[v]) {
                if (d[w] >= 0) continue;
                d[w] = d[v] + len, turn[w] = turn[v] + angle(v, w);
                stack.push_back(w);
            }
        }
        return far;
    };
    const std::uint32_t end = farthest(0);
    const std::uint32_t other = farthest(end);
    if (!(d[other] > 0)) return false;
    // A closed profile (a whole bore, a ring wall) is a path too, its ends one step apart along
    // the curve: no open curve (nor a face without a seam) describes it.
    double longest = 0;
    for (const auto& links : tree)
        for (const auto& link : links) longest = std::max(longest, link.second);
    if (dist(end, other) <= kClosedProfile * longest && along(end, other)) return false;
    // The parameters: the length along the profile, and half that length and half the turning
    // of the normal (none for a profile that does not turn). Uniform knots in the second put
    // more poles where the profile bends sharply: a tight bend of a spline outline that a net
    // spread by length alone misses (trimesh_featuretype's wall, finely meshed).
    // Turning as a fraction of the most any point of the tree has turned, not of the path's to
    // `other`: points beside the path turn by their normals' noise, and a nearly straight
    // profile's path by almost nothing (a fillet's strip at 847k facets: 2e5 x the path's,
    // and with_chords() filled that parameter range with 57 million points, 13 s).
    double total_turn = 0;
    for (std::size_t v = 0; v < m; ++v) total_turn = std::max(total_turn, turn[v]);
    s.resize(n);
    for (std::size_t i = 0; i < n; ++i) s[i] = d[node[i]] / d[other];
    s_turn.clear();
    if (total_turn > 0) {
        s_turn.resize(n);
        for (std::size_t i = 0; i < n; ++i) s_turn[i] = 0.5 * (s[i] + turn[node[i]] / total_turn);
    }
    return true;
}

/// The point of a planar cubic profile (np poles (px[a], py[a]), `knots` from cubic_knots(np))
/// nearest (x, y), by Newton's method from the parameter u, kept in [0, 1]: u becomes its
/// parameter, (cx, cy) the point and (dx, dy) the profile's derivative there.
void nearest_on_profile(int np, const double* knots, const double* px, const double* py, double x,
                        double y, double& u, double& cx, double& cy, double& dx, double& dy) {
    const auto at = [&](double t) {
        double N[kMaxDegree + 1], dN[kMaxDegree + 1];
        const int sp = cubic_basis(np, t, N, dN, knots) - 3;
        cx = cy = dx = dy = 0;
        for (int a = 0; a <= 3; ++a) {
            cx += N[a] * px[sp + a], cy += N[a] * py[sp + a];
            dx += dN[a] * px[sp + a], dy += dN[a] * py[sp + a];
        }
    };
    for (int it = 0; it < kProjectIterations; ++it) {
        at(u);
        const double dd = dx * dx + dy * dy;
        if (!(dd > 0)) break;
        const double nu = std::clamp(u - ((cx - x) * dx + (cy - y) * dy) / dd, 0.0, 1.0);
        const bool done = std::fabs(nu - u) < 1e-13;
        u = nu;
        if (done) break;
    }
    at(u);
}

/// A planar profile swept along a rigid motion (fit_extrusion(), helical_sweep()): each point's
/// coordinates (x, y) in the profile's plane and its normal's components there (ux, uy), and
/// the B-spline surface of the profile whose poles are (px, py) in that plane, with `slack`
/// how far that surface may be from the exact sweep of the profile (added to every residual).
/// `point` and `axis` are the fit's (bspline_fit()).
struct ProfileSweep {
    std::vector<double> x, y, ux, uy;
    Vec3 point, axis;
    std::function<std::shared_ptr<BSplineSurface>(const Eigen::VectorXd& px,
                                                  const Eigen::VectorXd& py, double& slack)>
        make;
};

FitResult fit_profile_sweep(const FitInput& in, double tolerance, bool& capped,
                            const ProfileSweep& sweep, FitResult fail);

/// A linear extrusion: the points lie on lines along one direction e through a planar profile
/// curve — the wall of a pocket whose outline is a spline, as a flat end mill cuts it. Such a wall
/// folds back over its mean plane (no height field there), but its profile is a curve: a cubic
/// B-spline fitted in the plane normal to e (parameters from profile_parameters(), then the
/// points' projections), extruded over the points' span along e. The result is a B-spline
/// surface of degree 3 with 4 collinear, evenly spaced poles across (so exactly linear that
/// way). ok false when the normals are not all normal to one direction, the profile is not one
/// open curve, or no net up to kBSplineMaxPoles poles (or `max_profile_poles`: then `capped`)
/// along it reaches `tolerance`.
FitResult fit_extrusion(const FitInput& in, double tolerance, bool& capped) {
    capped = false;
    FitResult fail = failed(FitKind::kBSpline, "not a linear extrusion");
    const std::size_t n = in.points.size();
    if (in.normals.size() != n || n < 16) return fail;
    Vec3 e;
    double spread = 0, lean = 1;
    if (!normals_normal(in, e, spread, &lean) || !(lean <= kExtrusionNormals) ||
        !(lean <= kExtrusionTurn * spread))
        return fail;
    Vec3 e1, e2;
    frame(e, e1, e2);
    double total = 0;
    const Vec3 c = centroid(in, &total);
    std::vector<double> x(n), y(n), t(n), ux(n), uy(n);
    double t0 = std::numeric_limits<double>::infinity(), t1 = -t0;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 q = in.points[i] - c;
        x[i] = dot(q, e1), y[i] = dot(q, e2), t[i] = dot(q, e);
        ux[i] = dot(in.normals[i], e1), uy[i] = dot(in.normals[i], e2);
        t0 = std::min(t0, t[i]), t1 = std::max(t1, t[i]);
    }
    if (!(t1 > t0)) return fail;
    ProfileSweep sweep{std::move(x), std::move(y), std::move(ux), std::move(uy), c, e, {}};
    sweep.make = [c, e, e1, e2, t0, t1](const Eigen::VectorXd& px, const Eigen::VectorXd& py,
                                        double& slack) {
        const auto np = static_cast<int>(px.size());
        auto bs = std::make_shared<BSplineSurface>();
        bs->num_u = np, bs->num_v = 4;
        bs->extruded = true;
        bs->poles.resize(static_cast<std::size_t>(4 * np));
        for (int j = 0; j < 4; ++j)
            for (int a = 0; a < np; ++a)
                bs->poles[static_cast<std::size_t>(a + np * j)] =
                    c + px(a) * e1 + py(a) * e2 + (t0 + (t1 - t0) * j / 3.0) * e;
        slack = 0;  // exactly the extrusion of the profile
        return bs;
    };
    fail.failure = "the points along the extrusion are not one open profile";
    return fit_profile_sweep(in, tolerance, capped, sweep, std::move(fail));
}

FitResult fit_profile_sweep(const FitInput& in, double tolerance, bool& capped,
                            const ProfileSweep& sweep, FitResult fail) {
    capped = false;
    const std::size_t n = in.points.size();
    const std::vector<double>& x = sweep.x;
    const std::vector<double>& y = sweep.y;
    double total = 0;
    centroid(in, &total);
    std::vector<double> by_length, by_turn;
    if (!profile_parameters(x, y, sweep.ux, sweep.uy, tolerance, by_length, by_turn)) return fail;
    // An extrusion, but no net of the fewest poles is allowed: nothing to fit.
    if (in.max_profile_poles > 0 && in.max_profile_poles < kBSplineStartPoles) {
        capped = true;
        fail.failure = "the profile needs more poles than max_profile_poles";
        return fail;
    }
    // The points in the plane across e and their parameters, followed by chord points.
    struct Profile {
        std::vector<double> x, y, s;
    };
    // Chords across the gaps: a coarse mesh leaves steps of several millimetres along a flat
    // stretch of the profile, where a knot span may hold no point and the curve would bulge
    // between its neighbours (2 mm on trimesh_featuretype's wall). Points on the chord between
    // consecutive points (kFillStep apart in the parameter, weighted kFillWeight) hold it there:
    // the mesh's own facets are those chords, within its deflection of the surface.
    const auto with_chords = [&](std::vector<double> s) {
        Profile p{x, y, std::move(s)};
        std::vector<std::size_t> by_s(n);
        std::iota(by_s.begin(), by_s.end(), std::size_t{0});
        std::sort(by_s.begin(), by_s.end(), [&](std::size_t a, std::size_t b) {
            return p.s[a] != p.s[b] ? p.s[a] < p.s[b] : a < b;
        });
        for (std::size_t k = 1; k < n; ++k) {
            const std::size_t a = by_s[k - 1], b = by_s[k];
            const auto steps = static_cast<int>((p.s[b] - p.s[a]) / kFillStep);
            for (int j = 1; j < steps; ++j) {
                const double f = static_cast<double>(j) / steps;
                p.x.push_back(x[a] + f * (x[b] - x[a]));
                p.y.push_back(y[a] + f * (y[b] - y[a]));
                p.s.push_back(p.s[a] + f * (p.s[b] - p.s[a]));
            }
        }
        return p;
    };
    std::vector<Profile> starts{with_chords(std::move(by_length))};
    if (!by_turn.empty()) starts.push_back(with_chords(std::move(by_turn)));
    const double fill_weight = kFillWeight * total / static_cast<double>(n);
    const auto w_of = [&](std::size_t i) { return i < n ? weight(in, i) : fill_weight; };
    // The profile of np poles from a start; nothing when the least-squares system fails or the
    // net is given up for a finer one.
    const auto fit_profile = [&](int np, const Profile& start) -> std::optional<FitResult> {
        const std::vector<double>& xs = start.x;
        const std::vector<double>& ys = start.y;
        std::vector<double> s = start.s;  // each net from the profile's own parameters
        const std::size_t all = s.size();
        Eigen::VectorXd px, py;
        // The distance of each point from the curve in the plane across (its distance from
        // the extrusion: every point lies within the extrusion's span), from its projection.
        std::vector<double> off(n, 0.0);
        const std::vector<double> knots = cubic_knots(np);
        const auto project = [&]() {
            double far = 0;
            for (std::size_t i = 0; i < all; ++i) {
                double cx = 0, cy = 0, dx = 0, dy = 0;
                nearest_on_profile(np, knots.data(), px.data(), py.data(), xs[i], ys[i], s[i], cx,
                                   cy, dx, dy);
                if (i < n) {
                    off[i] = std::hypot(cx - xs[i], cy - ys[i]);
                    far = std::max(far, off[i]);
                }
            }
            return far;
        };
        double worst = std::numeric_limits<double>::infinity();
        bool last = false;
        for (int round = 0;; ++round) {
            // Least squares for the poles, with the smoothing of fit_bspline_impl().
            Eigen::MatrixXd A = Eigen::MatrixXd::Zero(np, np);
            Eigen::VectorXd bx = Eigen::VectorXd::Zero(np), by = Eigen::VectorXd::Zero(np);
            for (std::size_t i = 0; i < all; ++i) {
                double N[kMaxDegree + 1];
                const int sp = cubic_basis(np, s[i], N, nullptr, knots.data()) - 3;
                const double w = w_of(i);
                for (int a = 0; a <= 3; ++a) {
                    bx(sp + a) += w * N[a] * xs[i];
                    by(sp + a) += w * N[a] * ys[i];
                    for (int b = 0; b <= 3; ++b) A(sp + a, sp + b) += w * N[a] * N[b];
                }
            }
            const double lambda = kBSplineSmoothing * total / np;
            for (int a = 1; a + 1 < np; ++a) {
                const int idx[3] = {a - 1, a, a + 1};
                const double coef[3] = {1, -2, 1};
                for (int r = 0; r < 3; ++r)
                    for (int k = 0; k < 3; ++k) A(idx[r], idx[k]) += lambda * coef[r] * coef[k];
            }
            const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
            px = ldlt.solve(bx), py = ldlt.solve(by);
            if (ldlt.info() != Eigen::Success || !px.allFinite() || !py.allFinite())
                return std::nullopt;
            // New parameters: each point's projection onto the curve (Newton from its own).
            const double now = project();
            if (last) {
                worst = now;
                break;
            }
            // Another round only while it pays: one that gains less than kProfileGain ends it
            // (after one more fit). Not at the tolerance: the pieces' own residuals are the
            // measure merge_freeform() holds the extrusion to.
            last = round + 1 >= kProfileRounds || now > (1 - kProfileGain) * worst;
            worst = now;
            // A net still far off after a few rounds makes way for a finer one.
            if (round + 1 >= kCoarseNetRounds && now > kCoarseNetMiss * tolerance &&
                np < kBSplineMaxPoles)
                return std::nullopt;
        }
        double slack = 0;
        std::shared_ptr<BSplineSurface> bs = sweep.make(px, py, slack);
        if (!bs) return std::nullopt;
        double sum = 0, mx = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const double d = off[i] + slack;
            sum += weight(in, i) * d * d;
            mx = std::max(mx, d);
        }
        const int poles = bs->num_u * bs->num_v;
        return bspline_fit(std::move(bs), sweep.point, sweep.axis, std::sqrt(sum / total), mx,
                           poles);
    };
    // Nets of kNetGrowth x as many poles each time, the last of kBSplineMaxPoles; at each
    // size the start by length, then the one by turning. The first within the tolerance (and
    // the RMS goal) wins; failing the goal, the first within the tolerance.
    FitResult best = fail;
    std::optional<FitResult> within;
    for (int np = kBSplineStartPoles;;) {
        if (in.max_profile_poles > 0 && np > in.max_profile_poles) {
            capped = true;
            best.failure = "the profile needs more poles than max_profile_poles";
            break;
        }
        // The starts at once (each fit on its own; taken in order below, as one after the other
        // would be).
        std::array<std::optional<FitResult>, 2> fits;
        tbb::parallel_for(std::size_t{0}, starts.size(),
                          [&](std::size_t k) { fits[k] = fit_profile(np, starts[k]); });
        for (std::optional<FitResult>& r : fits) {
            if (!r) continue;
            if (r->max <= tolerance) {
                if (!(in.rms_goal > 0 && r->rms > in.rms_goal)) return *r;
                if (!within) within = std::move(r);
            } else if (np == kBSplineMaxPoles && (!best.surface.bspline || r->max < best.max)) {
                best = *r;
            }
        }
        if (np == kBSplineMaxPoles) break;
        np = std::min(kBSplineMaxPoles, static_cast<int>(std::ceil(np * kNetGrowth)));
    }
    if (within) return *within;
    best.ok = false;
    if (!capped) best.failure = "no profile of up to the size limit of poles reaches the tolerance";
    return best;
}

/// A helical sweep's normals: the mean squared sine of the angle between a point's normal and the
/// screw motion's velocity there, at most this (as kExtrusionNormals for an extrusion's lean:
/// about 2.5 degrees; the velocity lies in the surface's tangent plane exactly).
constexpr double kHelixNormals = 2e-3;
/// The motion turns: its angular part at least this share of the unit vector (omega, v) found at
/// the points' RMS radius from their centroid. Less is a translation (an extrusion's, which
/// fit_extrusion() takes) or no motion at all.
constexpr double kHelixMinTurn = 1e-2;
/// The profile's points leave at least this share of the pitch free along the axis (the gap that
/// says where one turn of the profile ends and the next begins): a sweep whose profile spans the
/// whole pitch (a thread's flanks, crest and root together) has no open profile in one turn.
constexpr double kHelixGap = 0.05;
/// The B-spline along the helix: knot spans of at most this angle to start with (a cubic then
/// follows the circle within about 1e-5 of its radius), halved while the surface strays more
/// than kHelixSlack x the tolerance from the exact sweep; at most kHelixMaxSpans spans.
constexpr double kHelixSpanAngle = kPi / 8;
constexpr double kHelixSlack = 1e-3;
constexpr int kHelixMaxSpans = 2048;

/// The screw motion of helical_sweep() refined on the points' distances: its normals' motion is
/// off by the mesh's normals' own error (a flank of an M6 thread meshed at 0.02 mm: an axis
/// 0.0003 rad and 0.002 mm off, a profile of 21 poles to reach the deflection, where the true
/// motion leaves a straight line within 1e-5 mm). Levenberg-Marquardt on the motion (the axis'
/// tilt and shift across itself, the pitch) and a profile of kRefinePoles poles together, each
/// point's residual its signed distance from the profile in the half-plane it turns back into;
/// the motion's columns by finite differences. At most kRefineRounds rounds, while a round
/// lowers the RMS by kRefineGain. `angle` the points' unwrapped angles about the axis in the
/// frame (e1, e2), kept as the branch each point's new angle is taken nearest to.
constexpr int kRefinePoles = 4;
constexpr int kRefineRounds = 30;
constexpr double kRefineGain = 1e-3;
void refine_screw(const FitInput& in, double tolerance, const std::vector<double>& angle, Vec3 e1,
                  Vec3 e2, double scale, Vec3& axis, Vec3& origin, double& pitch) {
    const std::size_t n = in.points.size();
    constexpr int kMotion = 5;
    const Vec3 a_in = axis, o_in = origin;
    const double p_in = pitch;
    // The point's place in the profile's half-plane under the motion changed by m.
    const auto place = [&](const std::array<double, kMotion>& m, std::size_t i, double& x,
                           double& y) {
        const Vec3 a = normalized(a_in + m[0] * e1 + m[1] * e2);
        const Vec3 o = o_in + m[2] * e1 + m[3] * e2;
        const Vec3 g1 = normalized(e1 - dot(e1, a) * a), g2 = cross(a, g1);
        const Vec3 d = in.points[i] - o;
        const double px = dot(d, g1), py = dot(d, g2);
        const double th = std::atan2(py, px);
        const double turned = angle[i] + std::remainder(th - angle[i], 2 * kPi);
        x = std::hypot(px, py);
        y = dot(d, a) - (p_in + m[4]) * turned;
    };
    std::array<double, kMotion> m{};
    std::vector<double> x(n), y(n), ux(n), uy(n);
    for (std::size_t i = 0; i < n; ++i) {
        place(m, i, x[i], y[i]);
        const Vec3 d = in.points[i] - origin;
        const Vec3 radial = normalized(d - dot(d, axis) * axis);
        ux[i] = dot(in.normals[i], radial), uy[i] = dot(in.normals[i], axis);
    }
    std::vector<double> s, s_turn;
    if (!profile_parameters(x, y, ux, uy, tolerance, s, s_turn)) return;
    double total = 0;
    centroid(in, &total);
    constexpr int np = kRefinePoles;
    const std::vector<double> knots = cubic_knots(np);
    // The profile's first poles: least squares at the parameters by length.
    Eigen::VectorXd poles(2 * np);
    {
        Eigen::MatrixXd A = Eigen::MatrixXd::Zero(np, np);
        Eigen::VectorXd bx = Eigen::VectorXd::Zero(np), by = Eigen::VectorXd::Zero(np);
        for (std::size_t i = 0; i < n; ++i) {
            double N[kMaxDegree + 1];
            const int sp = cubic_basis(np, s[i], N, nullptr, knots.data()) - 3;
            for (int a = 0; a <= 3; ++a) {
                bx(sp + a) += weight(in, i) * N[a] * x[i],
                    by(sp + a) += weight(in, i) * N[a] * y[i];
                for (int b = 0; b <= 3; ++b) A(sp + a, sp + b) += weight(in, i) * N[a] * N[b];
            }
        }
        A += kBSplineSmoothing * total * Eigen::MatrixXd::Identity(np, np);
        const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
        poles << ldlt.solve(bx), ldlt.solve(by);
        if (ldlt.info() != Eigen::Success || !poles.allFinite()) return;
    }
    // Each point's residual (signed, along the profile's normal at its projection) and the
    // profile's unit normal there; its parameter projected anew from the one before.
    std::vector<double> res(n), nx(n), ny(n);
    const auto residuals = [&](const std::array<double, kMotion>& mm, const Eigen::VectorXd& pl,
                               std::vector<double>& par) {
        double sum = 0;
        for (std::size_t i = 0; i < n; ++i) {
            double px = 0, py = 0;
            place(mm, i, px, py);
            double cx = 0, cy = 0, dx = 0, dy = 0;
            nearest_on_profile(np, knots.data(), pl.data(), pl.data() + np, px, py, par[i], cx, cy,
                               dx, dy);
            const double l = std::hypot(dx, dy);
            nx[i] = l > 0 ? -dy / l : 0, ny[i] = l > 0 ? dx / l : 0;
            res[i] = (px - cx) * nx[i] + (py - cy) * ny[i];
            sum += weight(in, i) * res[i] * res[i];
        }
        return std::sqrt(sum / total);
    };
    double rms = residuals(m, poles, s);
    const double rms_in = rms;
    const std::array<double, kMotion> step{1e-7, 1e-7, 1e-7 * scale, 1e-7 * scale, 1e-7 * scale};
    double damping = 1e-6;
    const int cols = 2 * np + kMotion;
    for (int round = 0; round < kRefineRounds && rms > 0; ++round) {
        Eigen::MatrixXd JtJ = Eigen::MatrixXd::Zero(cols, cols);
        Eigen::VectorXd Jtr = Eigen::VectorXd::Zero(cols);
        Eigen::VectorXd row(cols);
        for (std::size_t i = 0; i < n; ++i) {
            row.setZero();
            double N[kMaxDegree + 1];
            const int sp = cubic_basis(np, s[i], N, nullptr, knots.data()) - 3;
            for (int a = 0; a <= 3; ++a)
                row(sp + a) = -N[a] * nx[i], row(np + sp + a) = -N[a] * ny[i];
            double px = 0, py = 0;
            place(m, i, px, py);
            for (int k = 0; k < kMotion; ++k) {
                std::array<double, kMotion> mk = m;
                mk[static_cast<std::size_t>(k)] += step[static_cast<std::size_t>(k)];
                double qx = 0, qy = 0;
                place(mk, i, qx, qy);
                row(2 * np + k) =
                    ((qx - px) * nx[i] + (qy - py) * ny[i]) / step[static_cast<std::size_t>(k)];
            }
            JtJ += weight(in, i) * row * row.transpose();
            Jtr += weight(in, i) * res[i] * row;
        }
        bool better = false;
        for (int tries = 0; tries < 8 && !better; ++tries, damping *= 10) {
            Eigen::MatrixXd A = JtJ;
            for (int k = 0; k < cols; ++k) A(k, k) += damping * std::max(JtJ(k, k), 1e-30);
            const Eigen::VectorXd delta = A.ldlt().solve(-Jtr);
            if (!delta.allFinite()) continue;
            std::array<double, kMotion> mm = m;
            for (int k = 0; k < kMotion; ++k) mm[static_cast<std::size_t>(k)] += delta(2 * np + k);
            const Eigen::VectorXd pl = poles + delta.head(2 * np);
            // (res, nx and ny are the tried state's now; the next try or the accepted one
            // overwrites them, and a round with no better try ends the refinement.)
            std::vector<double> par = s;
            const double now = residuals(mm, pl, par);
            if (now < rms) {
                better = true;
                const bool small_gain = now > (1 - kRefineGain) * rms;
                m = mm, poles = pl, s = std::move(par), rms = now;
                damping = std::max(damping / 100, 1e-12);
                if (small_gain) round = kRefineRounds;
            }
        }
        if (!better) break;
    }
    if (!(rms < rms_in)) return;
    axis = normalized(a_in + m[0] * e1 + m[1] * e2);
    origin = o_in + m[2] * e1 + m[3] * e2;
    pitch = p_in + m[4];
}

/// A helical sweep: the points lie on helices about one axis, all of one pitch, through a planar
/// profile curve — a thread's flank, as a thread mill, a tap or a die cuts it (a linear
/// extrusion is the sweep without the turn, a surface of revolution the one without the
/// climb). The screw motion comes from the normals: a surface swept by the motion with velocity
/// field v(x) = omega x x + vbar has every normal normal to v, n . (omega x x) + n . vbar = 0,
/// linear in (omega, vbar): the eigenvector of the smallest eigenvalue of the 6 x 6 normal
/// equations (Pottmann and Randrup's kinematic surfaces). Its axis is omega's direction through
/// omega x vbar / |omega|^2, its pitch per radian omega . vbar / |omega|^2. Each point, turned
/// back along its helix into one half-plane through the axis (its angle about the axis and its
/// height less the pitch's share of that angle, wrapped into one pitch at the profile's gap),
/// is a point of the profile; the profile is fitted as an extrusion's is (fit_profile_sweep()),
/// and swept over the points' span of angle as a B-spline surface: the profile's poles across
/// (u), a cubic of uniform knot spans along the helix (v) that follows the circle within
/// kHelixSlack x the tolerance, so exactly helical across and within that along. ok false
/// when the normals fit no screw motion, the motion does not turn or climb, the profile is not
/// one open curve in one turn, or no profile of up to kBSplineMaxPoles poles (or
/// `max_profile_poles`) reaches `tolerance`. The points are finite (fit_helical() checks).
FitResult helical_sweep(const FitInput& in, double tolerance) {
    FitResult fail = failed(FitKind::kBSpline, "not a helical sweep");
    const std::size_t n = in.points.size();
    if (in.normals.size() != n || n < kMinBSplinePoints || !(tolerance > 0)) return fail;
    double total = 0;
    const Vec3 c = centroid(in, &total);
    double spread = 0;
    for (std::size_t i = 0; i < n; ++i)
        spread += weight(in, i) * dot(in.points[i] - c, in.points[i] - c);
    const double scale = std::sqrt(spread / total);
    if (!(scale > 0)) return fail;
    // The normal equations of n . (omega x q) + n . vbar = (q x n) . omega + n . vbar, with q the
    // points about their centroid in units of their RMS radius.
    Eigen::Matrix<double, 6, 6> normal_eq = Eigen::Matrix<double, 6, 6>::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 q = (in.points[i] - c) / scale;
        const Vec3 qn = cross(q, in.normals[i]);
        Eigen::Matrix<double, 6, 1> g;
        g << qn.x, qn.y, qn.z, in.normals[i].x, in.normals[i].y, in.normals[i].z;
        normal_eq += weight(in, i) * g * g.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(normal_eq);
    if (eigen.info() != Eigen::Success) return fail;
    const Eigen::Matrix<double, 6, 1> xi = eigen.eigenvectors().col(0);
    const Vec3 omega{xi(0), xi(1), xi(2)}, vbar{xi(3), xi(4), xi(5)};
    const double w2 = dot(omega, omega);
    if (!(w2 >= kHelixMinTurn)) return fail;
    double lean = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 v = cross(omega, (in.points[i] - c) / scale) + vbar;
        const double speed = norm(v);
        if (!(speed > 0)) return fail;
        const double sine = dot(in.normals[i], v) / speed;
        lean += weight(in, i) * sine * sine;
    }
    if (!(lean / total <= kHelixNormals)) return fail;
    Vec3 axis = omega / std::sqrt(w2);
    Vec3 origin = c + (scale / w2) * cross(omega, vbar);
    double pitch = scale * dot(omega, vbar) / w2;  // climb per radian
    const double period = 2 * kPi * std::fabs(pitch);
    if (!(period > tolerance)) {
        fail.failure = "the screw motion does not climb (a surface of revolution)";
        return fail;
    }
    Vec3 e1, e2;
    frame(axis, e1, e2);
    // Each point's angle about the axis and height less the pitch's share of it (its place in
    // the profile's half-plane once the motion is refined, below), the height wrapped into
    // one pitch.
    std::vector<double> h(n), angle(n), wrapped(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 d = in.points[i] - origin;
        angle[i] = std::atan2(dot(d, e2), dot(d, e1));
        h[i] = dot(d, axis) - pitch * angle[i];
        wrapped[i] = h[i] - period * std::floor(h[i] / period);
    }
    // The profile's turn starts after the widest gap of the heights wrapped into one pitch.
    std::vector<double> sorted = wrapped;
    std::sort(sorted.begin(), sorted.end());
    double gap = sorted.front() + period - sorted.back(), start = sorted.front();
    for (std::size_t k = 1; k < n; ++k) {
        if (sorted[k] - sorted[k - 1] > gap) gap = sorted[k] - sorted[k - 1], start = sorted[k];
    }
    if (!(gap >= kHelixGap * period)) {
        fail.failure = "the points span a whole pitch along the axis";
        return fail;
    }
    double a0 = std::numeric_limits<double>::infinity(), a1 = -a0;
    for (std::size_t i = 0; i < n; ++i) {
        const double hp = wrapped[i] >= start ? wrapped[i] : wrapped[i] + period;
        // z = h + pitch x angle = hp + pitch x (angle + 2 pi k)
        const double turns = std::round((h[i] - hp) / (2 * kPi * pitch));
        angle[i] += 2 * kPi * turns;
        h[i] = hp;
        a0 = std::min(a0, angle[i]), a1 = std::max(a1, angle[i]);
    }
    if (!(a1 > a0)) return fail;
    if (!((a1 - a0) / kHelixSpanAngle <= kHelixMaxSpans)) {
        fail.failure = "the helix turns too often for a B-spline of the size limit";
        return fail;
    }
    // The motion refined on the points' distances, and the points turned back along it.
    refine_screw(in, tolerance, angle, e1, e2, scale, axis, origin, pitch);
    e1 = normalized(e1 - dot(e1, axis) * axis), e2 = cross(axis, e1);
    std::vector<double> r(n), ux(n), uy(n);
    double r_max = 0;
    a0 = std::numeric_limits<double>::infinity(), a1 = -a0;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 d = in.points[i] - origin;
        const double px = dot(d, e1), py = dot(d, e2);
        r[i] = std::hypot(px, py);
        if (!(r[i] > 0)) return fail;
        angle[i] += std::remainder(std::atan2(py, px) - angle[i], 2 * kPi);
        h[i] = dot(d, axis) - pitch * angle[i];
        const Vec3 radial = (px * e1 + py * e2) / r[i];
        ux[i] = dot(in.normals[i], radial), uy[i] = dot(in.normals[i], axis);
        a0 = std::min(a0, angle[i]), a1 = std::max(a1, angle[i]);
        r_max = std::max(r_max, r[i]);
    }
    // The unit circle's direction d(phi) = cos phi e1 + sin phi e2 over [a0, a1] as a cubic
    // B-spline (least squares on samples along each span), its poles' angles for the climb at
    // the Greville abscissae (where a B-spline reproduces a linear function exactly).
    const double span_count = std::ceil((a1 - a0) / kHelixSpanAngle);
    if (!(span_count <= kHelixMaxSpans)) {
        fail.failure = "the helix turns too often for a B-spline of the size limit";
        return fail;
    }
    int spans = std::max(1, static_cast<int>(span_count));
    std::vector<double> dc, ds, phi;
    double circle_err = 0;
    for (;; spans *= 2) {
        const int nv = spans + 3;
        constexpr int kSamples = 8;  // per span, for the fit; twice as many for the check
        // Banded (each sample touches 4 poles): a sparse factorization, as a long thread has
        // thousands of poles along its helix.
        std::vector<Eigen::Triplet<double>> entries;
        entries.reserve(static_cast<std::size_t>(16 * (kSamples * spans + 1)));
        Eigen::VectorXd bc = Eigen::VectorXd::Zero(nv), bsn = Eigen::VectorXd::Zero(nv);
        for (int k = 0; k <= kSamples * spans; ++k) {
            const double v = static_cast<double>(k) / (kSamples * spans);
            const double f = a0 + v * (a1 - a0);
            double N[kMaxDegree + 1];
            const int sp = cubic_basis(nv, v, N, nullptr) - 3;
            for (int a = 0; a <= 3; ++a) {
                bc(sp + a) += N[a] * std::cos(f), bsn(sp + a) += N[a] * std::sin(f);
                for (int b = 0; b <= 3; ++b) entries.emplace_back(sp + a, sp + b, N[a] * N[b]);
            }
        }
        Eigen::SparseMatrix<double> A(nv, nv);
        A.setFromTriplets(entries.begin(), entries.end());
        const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(A);
        if (ldlt.info() != Eigen::Success) return fail;
        const Eigen::VectorXd pc = ldlt.solve(bc), ps = ldlt.solve(bsn);
        if (ldlt.info() != Eigen::Success || !pc.allFinite() || !ps.allFinite()) return fail;
        circle_err = 0;
        for (int k = 0; k <= 2 * kSamples * spans; ++k) {
            const double v = static_cast<double>(k) / (2 * kSamples * spans);
            const double f = a0 + v * (a1 - a0);
            double N[kMaxDegree + 1];
            const int sp = cubic_basis(nv, v, N, nullptr) - 3;
            double x = 0, y = 0;
            for (int a = 0; a <= 3; ++a) x += N[a] * pc(sp + a), y += N[a] * ps(sp + a);
            circle_err = std::max(circle_err, std::hypot(x - std::cos(f), y - std::sin(f)));
        }
        if (circle_err * r_max > kHelixSlack * tolerance) {
            if (spans * 2 > kHelixMaxSpans) {
                fail.failure = "the helix turns too often for a B-spline of the size limit";
                return fail;
            }
            continue;
        }
        dc.assign(pc.data(), pc.data() + nv);
        ds.assign(ps.data(), ps.data() + nv);
        const std::vector<double> knots = cubic_knots(nv);
        phi.resize(static_cast<std::size_t>(nv));
        for (int b = 0; b < nv; ++b) {
            const auto k = static_cast<std::size_t>(b);
            phi[k] = a0 + (a1 - a0) * (knots[k + 1] + knots[k + 2] + knots[k + 3]) / 3;
        }
        break;
    }
    double h_lo = std::numeric_limits<double>::infinity(), h_hi = -h_lo;
    for (const double hh : h) h_lo = std::min(h_lo, hh), h_hi = std::max(h_hi, hh);
    const double mid = 0.5 * (h_lo + h_hi);
    ProfileSweep sweep{std::move(r), std::move(h), std::move(ux), std::move(uy), origin, axis, {}};
    sweep.make = [origin, axis, e1, e2, pitch, dc, ds, phi, circle_err, mid](
                     const Eigen::VectorXd& px, const Eigen::VectorXd& py, double& slack) {
        const auto np = static_cast<int>(px.size());
        const auto nv = static_cast<int>(phi.size());
        auto bs = std::make_shared<BSplineSurface>();
        bs->num_u = np, bs->num_v = nv;
        bs->helical = true;
        bs->helix = {origin, axis, e1, pitch, phi.front(), phi.back(), mid};
        bs->poles.resize(static_cast<std::size_t>(np) * phi.size());
        double reach = 0;
        for (int b = 0; b < nv; ++b) {
            const auto k = static_cast<std::size_t>(b);
            const Vec3 dir = dc[k] * e1 + ds[k] * e2;
            for (int a = 0; a < np; ++a)
                bs->poles[static_cast<std::size_t>(a + np * b)] =
                    origin + px(a) * dir + (py(a) + pitch * phi[k]) * axis;
        }
        for (int a = 0; a < np; ++a) reach = std::max(reach, std::fabs(px(a)));
        // S(u, v) = sum_a N_a(u) (origin + px_a D(v) + (py_a + pitch phi(v)) axis): the exact
        // sweep but for D's miss of the circle, scaled by the profile's reach.
        slack = circle_err * reach;
        return bs;
    };
    fail.failure = "the points turned back along their helices are not one open profile";
    bool capped = false;  // a profile past max_profile_poles fails like any other here
    return fit_profile_sweep(in, tolerance, capped, sweep, std::move(fail));
}

FitResult fit_shear_cylinder(const FitInput& in) {
    // Start: the circular cylinder (its axis from the normals is the sweep direction: the
    // normals of any cylinder along d are normal to d), then let the section become an ellipse.
    const FitResult cyl = fit_cylinder(in);
    if (!cyl.ok) return failed(FitKind::kShearCylinder, cyl.failure);
    const Axis a = Axis::make(cyl.surface.point, cyl.surface.axis);
    ShearModel m{{a.c, a.d, a.u, cyl.surface.radius * (1 + kEllipseSeed), cyl.surface.radius}};
    const int it = refine(m, in);
    FitResult res = finish(m, it, in);
    const double ratio =
        std::min(std::fabs(m.e.A), std::fabs(m.e.B)) / std::max(std::fabs(m.e.A), std::fabs(m.e.B));
    if (res.ok && !(ratio >= kMinShearCos)) {
        res.ok = false;
        res.failure = "the sweep lies (almost) in the circle's plane: no shear cylinder";
    }
    return res;
}

/// How far the points q_i = p_i - r n_i (the tube centers, for the right r) are from lying on
/// one ellipse in the section normal to d: the relative residual of the algebraic conic
/// x^2 + b xy + c y^2 + d x + e y + f = 0 fitted by least squares.
double conic_misfit(const FitInput& in, Vec3 dir, double r) {
    Vec3 u, v;
    frame(dir, u, v);
    const Vec3 g = centroid(in);
    Eigen::Matrix<double, 5, 5> ata = Eigen::Matrix<double, 5, 5>::Zero();
    Eigen::Matrix<double, 5, 1> atb = Eigen::Matrix<double, 5, 1>::Zero();
    double scale = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - r * in.normals[i] - g;
        const double x = dot(q, u), y = dot(q, v);
        scale = std::max(scale, x * x + y * y);
    }
    if (!(scale > 0)) return std::numeric_limits<double>::infinity();
    double bb = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const Vec3 q = in.points[i] - r * in.normals[i] - g;
        const double x = dot(q, u) / std::sqrt(scale), y = dot(q, v) / std::sqrt(scale);
        Eigen::Matrix<double, 5, 1> row;
        row << x * y, y * y, x, y, 1.0;
        const double w = weight(in, i);
        ata += w * row * row.transpose();
        atb -= w * (x * x) * row;
        bb += w * x * x * x * x;
    }
    const Eigen::Matrix<double, 5, 1> sol = ata.ldlt().solve(atb);
    // Residual sum of squares of rows . sol = -x^2: b.b - sol . A^T b at the optimum, with
    // A^T b = atb.
    const double rss = bb - sol.dot(atb);
    return std::max(rss, 0.0) / std::max(bb, 1e-300);
}

FitResult fit_swept_torus(const FitInput& in) {
    // Start: the sweep direction from a shear-cylinder fit (the normals are normal to it),
    // then the tube radius r as the offset along the normals that brings the points onto one
    // ellipse (golden-section search on the conic misfit), then the ellipse of the tube
    // centers.
    if (in.normals.size() != in.points.size()) {
        return failed(FitKind::kSweptTorus, "the normals are needed for the tube radius");
    }
    const FitResult shear = fit_shear_cylinder(in);
    if (!shear.ok) return failed(FitKind::kSweptTorus, shear.failure);
    const Vec3 dir = shear.surface.sweep;
    const EllipticCylinder e0 = elliptic_of(shear.surface.point, shear.surface.axis,
                                            shear.surface.radius, shear.surface.sweep);
    const double bmin = std::min(std::fabs(e0.A), std::fabs(e0.B));
    // Coarse scan for the basin (the misfit need not be unimodal), then golden section.
    double best_r = 0, best = std::numeric_limits<double>::infinity();
    for (int k = 1; k < kSweptStarts; ++k) {
        const double r = bmin * k / kSweptStarts;
        const double f = conic_misfit(in, dir, r);
        if (f < best) best = f, best_r = r;
    }
    double lo = std::max(0.0, best_r - bmin / kSweptStarts), hi = best_r + bmin / kSweptStarts;
    constexpr double kGolden = 0.6180339887498949;
    for (int it = 0; it < 60; ++it) {
        const double a = hi - kGolden * (hi - lo), b = lo + kGolden * (hi - lo);
        if (conic_misfit(in, dir, a) < conic_misfit(in, dir, b)) {
            hi = b;
        } else {
            lo = a;
        }
    }
    const double r0 = 0.5 * (lo + hi);
    // The tube centers' elliptic cylinder, as a shear cylinder fit of the shifted points.
    std::vector<Vec3> centers(in.points.size());
    for (std::size_t i = 0; i < centers.size(); ++i) centers[i] = in.points[i] - r0 * in.normals[i];
    const FitResult core = fit_shear_cylinder(FitInput{centers, in.normals, in.weights});
    if (!core.ok) return failed(FitKind::kSweptTorus, core.failure);
    SweptModel m{
        elliptic_of(core.surface.point, core.surface.axis, core.surface.radius, core.surface.sweep),
        r0};
    const int it = refine(m, in);
    FitResult res = finish(m, it, in);
    const double ratio =
        std::min(std::fabs(m.e.A), std::fabs(m.e.B)) / std::max(std::fabs(m.e.A), std::fabs(m.e.B));
    if (res.ok && !(m.r != 0 && ratio >= kMinShearCos)) {
        res.ok = false;
        res.failure = "the radii left their range";
    }
    return res;
}

}  // namespace

bool fit_line(std::span<const Vec3> points, Vec3& point, Vec3& direction) {
    FitInput in;
    in.points = points;
    double total = 0;
    point = centroid(in, &total);
    if (!(total > 0)) return false;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es = principal_axes(in, point);
    if (es.info() != Eigen::Success || !(es.eigenvalues()(2) > 0)) return false;
    direction =
        normalized(Vec3{es.eigenvectors()(0, 2), es.eigenvectors()(1, 2), es.eigenvectors()(2, 2)});
    return true;
}

double fit_circle(std::span<const Vec3> points, Vec3& center, Vec3& normal, double& radius) {
    FitInput in;
    in.points = points;
    return circle_through(in, center, normal, radius);
}

double distance(const Surface& s, Vec3 p) { return norm(p - closest_point(s, p)); }

namespace {

// The foot of p on a sheared kind's elliptic cylinder (the shear cylinder itself, the swept
// torus's spine): the point, and the (unnormalised) normal of its ellipse there.
struct EllipticFoot {
    Vec3 on, normal, w;
};
EllipticFoot elliptic_foot(const Surface& s, Vec3 p) {
    const EllipticCylinder e = elliptic_of(s.point, s.axis, s.radius, s.sweep);
    double x, y, ex, ey, nx, ny, h;
    e.signed_distance(p, x, y, ex, ey, nx, ny, h);
    const Vec3 m = cross(e.d, e.w);
    return {e.c + h * e.d + ex * e.w + ey * m, nx * e.w + ny * m, e.w};
}

}  // namespace

Vec3 closest_point(const Surface& s, Vec3 p) {
    const Vec3 q = p - s.point;
    switch (s.kind) {
        case FitKind::kPlane:
            return p - dot(q, s.axis) * s.axis;
        case FitKind::kSphere: {
            const double len = norm(q);
            const Vec3 e = len > 0 ? q / len : Vec3{1, 0, 0};
            return s.point + s.radius * e;
        }
        case FitKind::kCylinder:
        case FitKind::kCone:
        case FitKind::kTorus: {
            const double h = dot(q, s.axis);
            const Vec3 radial = q - h * s.axis;
            const double rho = norm(radial);
            Vec3 e;
            if (rho > 0) {
                e = radial / rho;
            } else {
                Vec3 v;
                frame(s.axis, e, v);
            }
            if (s.kind == FitKind::kCylinder) return s.point + h * s.axis + s.radius * e;
            if (s.kind == FitKind::kTorus) {
                const Vec3 tube = s.point + s.radius * e;
                const Vec3 w = p - tube;
                const double lw = norm(w);
                return tube + s.minor_radius * (lw > 0 ? w / lw : s.axis);
            }
            // Cone: the nearest point of the half-line from the apex along the generator.
            const double ta = std::tan(s.angle);
            const double ha = ta > 0 ? -s.radius / ta : -std::numeric_limits<double>::infinity();
            const double ca = std::cos(s.angle), sa = std::sin(s.angle);
            const double t = (h - ha) * ca + rho * sa;
            const Vec3 apex = s.point + ha * s.axis;
            if (t <= 0) return apex;
            return apex + t * (ca * s.axis + sa * e);
        }
        case FitKind::kShearCylinder:
        case FitKind::kSweptTorus: {
            const EllipticFoot f = elliptic_foot(s, p);
            if (s.kind == FitKind::kShearCylinder) return f.on;
            const Vec3 out = p - f.on;
            const double lo = norm(out);
            return f.on + s.minor_radius * (lo > 0 ? out / lo : f.normal);
        }
        case FitKind::kBSpline: {
            if (!s.bspline) return p;
            double u = 0.5, v = 0.5;
            coarse_start(*s.bspline, p, u, v);
            project_bspline(*s.bspline, p, u, v);
            return s.bspline->evaluate(u, v);
        }
    }
    return p;
}

Vec3 normal_at(const Surface& s, Vec3 p) {
    const auto unit_or = [](Vec3 v, Vec3 fallback) {
        const double l = norm(v);
        return l > 0 ? v / l : fallback;
    };
    switch (s.kind) {
        case FitKind::kPlane:
            return s.axis;
        case FitKind::kSphere:
            return unit_or(closest_point(s, p) - s.point, s.axis);
        case FitKind::kCylinder:
        case FitKind::kCone:
        case FitKind::kTorus: {
            const Vec3 q = closest_point(s, p);
            const Vec3 w = q - s.point;
            Vec3 e = w - dot(w, s.axis) * s.axis;
            const double rho = norm(e);
            if (rho > 0) {
                e = e / rho;
            } else {
                Vec3 v;
                frame(s.axis, e, v);
            }
            if (s.kind == FitKind::kCylinder) return e;
            if (s.kind == FitKind::kCone) return std::cos(s.angle) * e - std::sin(s.angle) * s.axis;
            return unit_or(q - (s.point + s.radius * e), e);
        }
        case FitKind::kShearCylinder:
        case FitKind::kSweptTorus: {
            // The swept torus's closest point lies on the line from the elliptic cylinder's
            // foot to p, so that line is its normal.
            const EllipticFoot f = elliptic_foot(s, p);
            const Vec3 ellipse_normal = unit_or(f.normal, f.w);
            if (s.kind == FitKind::kShearCylinder) return ellipse_normal;
            return unit_or(p - f.on, ellipse_normal);
        }
        case FitKind::kBSpline: {
            if (!s.bspline) return s.axis;
            double u = 0.5, v = 0.5;
            coarse_start(*s.bspline, p, u, v);
            project_bspline(*s.bspline, p, u, v);
            Vec3 at, du, dv;
            s.bspline->evaluate(u, v, at, du, dv);
            return unit_or(cross(du, dv), s.axis);
        }
    }
    return s.axis;
}

CommonPoint common_point(std::span<const Surface> surfaces, Vec3 start) {
    constexpr int kMaxSteps = 50;
    CommonPoint out;
    out.point = start;
    const std::size_t k = surfaces.size();
    if (k == 0 || !finite(start)) return out;
    // Rounding level of the coordinates: the scale of the point and of the surfaces' anchors.
    double scale = norm(start);
    for (const Surface& s : surfaces) scale = std::max(scale, norm(s.point) + std::fabs(s.radius));
    const double eps = 1e-14 * std::max(1.0, scale);
    Eigen::MatrixXd J(static_cast<Eigen::Index>(k), 3);
    Eigen::VectorXd r(static_cast<Eigen::Index>(k));
    Vec3 p = start;
    for (int it = 0; it < kMaxSteps; ++it) {
        double worst = 0;
        for (std::size_t i = 0; i < k; ++i) {
            const Vec3 n = normal_at(surfaces[i], p);
            const double d = dot(p - closest_point(surfaces[i], p), n);
            J.row(static_cast<Eigen::Index>(i)) << n.x, n.y, n.z;
            r(static_cast<Eigen::Index>(i)) = d;
            worst = std::max(worst, std::abs(d));
        }
        out.iterations = it;
        if (worst <= eps) break;
        // Least-norm least squares: directions the normals do not fix are left alone
        // (parallel normals of tangent surfaces count as one, below a thousandth).
        Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(J);
        cod.setThreshold(1e-3);
        const Eigen::Vector3d step = -cod.solve(r);
        const Vec3 dp{step(0), step(1), step(2)};
        if (!finite(dp)) break;
        p = p + dp;
        if (norm(dp) <= eps) break;
    }
    out.point = p;
    out.residual = 0;
    for (const Surface& s : surfaces) out.residual = std::max(out.residual, distance(s, p));
    return out;
}

namespace {

/// Why `in` cannot be fitted as a B-spline at all (weights that do not match the points, too
/// few points, a point or weight not a finite number), or nothing.
std::optional<FitResult> unfit_for_bspline(const FitInput& in) {
    if (!in.weights.empty() && in.weights.size() != in.points.size()) {
        return failed(FitKind::kBSpline, "weights and points differ in number");
    }
    if (in.points.size() < kMinBSplinePoints) return failed(FitKind::kBSpline, "too few points");
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        if (!finite(in.points[i]) || (!in.weights.empty() && !(in.weights[i] >= 0))) {
            return failed(FitKind::kBSpline, "a point or weight is not a finite number");
        }
    }
    return std::nullopt;
}

}  // namespace

FitResult fit_helical(const FitInput& in, double tolerance) {
    if (std::optional<FitResult> bad = unfit_for_bspline(in)) return *bad;
    return helical_sweep(in, tolerance);
}

namespace {

/// x as a message shows it: six significant digits.
std::string number(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return buf;
}

/// FitInput::refuse_rms, for fit() and fit_bspline(): a fit of kSampledFitPoints points or more
/// made first on every n-th of them (kRefuseSamplePoints or more) by `look`, which gives the RMS
/// that may refuse them (none: it does not); the failure of `kind` when it exceeds refuse_rms,
/// nothing otherwise or when `in` is not sampled.
template <class Look>
std::optional<FitResult> refused_on_sample(FitKind kind, const FitInput& in, const char* fitted,
                                           Look&& look) {
    const std::size_t n = in.points.size();
    if (!(in.refuse_rms > 0 && n >= kSampledFitPoints)) return std::nullopt;
    const Strided strided(in, n / kRefuseSamplePoints);
    FitInput sample = strided.input(in);
    sample.refuse_rms = 0;
    const std::optional<double> rms = look(sample);
    if (!rms || !(*rms > in.refuse_rms)) return std::nullopt;
    return failed(kind, std::string("a sample of the points is off its ") + fitted + " by RMS " +
                            number(*rms));
}

/// What fit() and refit() ask of every input (matching sizes, finite points, non-negative
/// weights, points spanning a plane): a failure, or nothing.
std::optional<FitResult> invalid_input(FitKind kind, const FitInput& in) {
    const std::size_t n = in.points.size();
    if (!in.weights.empty() && in.weights.size() != n) {
        return failed(kind, "weights and points differ in number");
    }
    if (!in.normals.empty() && in.normals.size() != n) {
        return failed(kind, "normals and points differ in number");
    }
    constexpr std::size_t kMinPoints[kNumFitKinds] = {3, 4, 5, 6, 7, 8, 9, 16};
    if (n < kMinPoints[static_cast<int>(kind)]) return failed(kind, "too few points");
    for (std::size_t i = 0; i < n; ++i) {
        if (!finite(in.points[i]) || (!in.weights.empty() && !(in.weights[i] >= 0))) {
            return failed(kind, "a point or weight is not a finite number");
        }
    }
    // Every kind needs points that span a plane at least.
    const Vec3 c = centroid(in);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 q = in.points[i] - c;
        const Eigen::Vector3d e(q.x, q.y, q.z);
        cov += weight(in, i) * e * e.transpose();
    }
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
    if (!(ev(1) > kCollinear * ev(2))) return failed(kind, "the points are collinear or coincide");
    return std::nullopt;
}

/// The kinds fitted by refining from a start (Levenberg-Marquardt): the ones refit() starts
/// from a given surface and FitInput::refuse_rms samples first.
bool refined_kind(FitKind kind) {
    return kind == FitKind::kSphere || kind == FitKind::kCylinder || kind == FitKind::kCone ||
           kind == FitKind::kTorus;
}

/// `f` called with the model a sphere, cylinder, cone or torus `s` is refined as; an empty
/// result for the other kinds.
template <class F>
FitResult with_model(const Surface& s, F&& f) {
    switch (s.kind) {
        case FitKind::kSphere:
            return f(SphereModel{s.point, s.radius});
        case FitKind::kCylinder:
            return f(CylinderModel{Axis::make(s.point, s.axis), s.radius});
        case FitKind::kCone:
            return f(ConeModel::make(Axis::make(s.point, s.axis), s.radius, s.angle));
        case FitKind::kTorus:
            return f(TorusModel{Axis::make(s.point, s.axis), s.radius, s.minor_radius});
        default:
            return {};
    }
}

}  // namespace

FitResult fit_bspline(const FitInput& in, double tolerance) {
    if (std::optional<FitResult> bad = unfit_for_bspline(in)) return *bad;
    // A wall extruded along one direction first: its net is a profile's, not a grid's.
    bool capped = false;
    FitResult extrusion = fit_extrusion(in, tolerance, capped);
    if (extrusion.ok) return extrusion;
    // An extrusion whose profile would need more poles than the caller takes is still one: no
    // net over its mean plane either.
    if (capped) return extrusion;
    // The nets on a sample first (FitInput::refuse_rms): a group of pieces half a part's size,
    // far from any height field, took a second of nets over all its points to find none. Not
    // the extrusion: a sample's normals and profile nodes are not the whole's, and a folded
    // wall that only the whole's profile holds is no height field. The sample's nets are not
    // held to the caller's largest: its principal axes, and so its nets' proportions, differ a
    // little from the whole's, and it should try every net the whole would (more poles only
    // bring its RMS down).
    const auto nets = [&](FitInput sample) -> std::optional<double> {
        sample.max_net_poles = 0;
        return fit_bspline_impl(sample, tolerance).rms;  // the largest net's when all fail
    };
    if (auto refused = refused_on_sample(FitKind::kBSpline, in, "nets", nets)) return *refused;
    return fit_bspline_impl(in, tolerance);
}

FitResult refit(const Surface& start, const FitInput& in) {
    const FitKind kind = start.kind;
    if (!refined_kind(kind)) return fit(kind, in);
    if (auto bad = invalid_input(kind, in)) return *bad;
    if (!finite(start.point) || !finite(start.axis) || !std::isfinite(start.radius) ||
        !std::isfinite(start.angle) || !std::isfinite(start.minor_radius) ||
        (kind != FitKind::kSphere && !(norm(start.axis) > 0))) {
        return failed(kind, "the start is not a finite surface");
    }
    return with_model(start, [&](auto m) { return refine_from(m, in); });
}

FitResult fit(FitKind kind, const FitInput& in) {
    if (auto bad = invalid_input(kind, in)) return *bad;
    if (refined_kind(kind)) {
        const auto one_fit = [&](const FitInput& sample) -> std::optional<double> {
            const FitResult look = fit(kind, sample);
            return look.ok ? std::optional<double>(look.rms) : std::nullopt;
        };
        if (auto refused = refused_on_sample(kind, in, "fit", one_fit)) return *refused;
    }
    switch (kind) {
        case FitKind::kPlane:
            return fit_plane(in);
        case FitKind::kSphere:
            return fit_sphere(in);
        case FitKind::kCylinder:
            return fit_cylinder(in);
        case FitKind::kCone:
            return fit_cone(in);
        case FitKind::kTorus:
            return fit_torus(in);
        case FitKind::kShearCylinder:
            return fit_shear_cylinder(in);
        case FitKind::kSweptTorus:
            return fit_swept_torus(in);
        case FitKind::kBSpline: {
            Box3 box;
            for (const Vec3& p : in.points) box.add(p);
            return fit_bspline_impl(in, kBSplineDefaultTolerance * norm(box.max - box.min));
        }
    }
    return failed(kind, "unknown kind");
}

KindSelection fit_simplest(const FitInput& input, double tolerance, FitKindSet kinds) {
    KindSelection sel;
    // Rounds of kinds: the surfaces of revolution first; the sheared kinds only when none of
    // those fits; the B-spline last. Within a round, the simplest passing kind wins unless a
    // richer one of the round fits clearly better.
    constexpr int kRounds[][2] = {{0, 5}, {5, 7}, {7, 8}};
    for (const auto& round : kRounds) {
        double best_rms = std::numeric_limits<double>::infinity();
        for (int k = round[0]; k < round[1]; ++k) {
            const auto kind = static_cast<FitKind>(k);
            if ((kinds & fit_kind_bit(kind)) == 0) continue;
            sel.tried[static_cast<std::size_t>(k)] =
                kind == FitKind::kBSpline ? fit_bspline(input, tolerance) : fit(kind, input);
            const FitResult& r = sel.tried[static_cast<std::size_t>(k)];
            if (r.ok) best_rms = std::min(best_rms, r.rms);
        }
        for (int k = round[0]; k < round[1]; ++k) {
            const FitResult& r = sel.tried[static_cast<std::size_t>(k)];
            if (!r.ok || r.max > tolerance) continue;
            // A kind with more parameters that fits clearly better reveals a biased simpler one
            // (a narrow strip of a cone fits a cylinder within a loose tolerance, but worse).
            if (r.rms > kSignificantRms * best_rms + kRmsFloor * tolerance) continue;
            sel.best = r;
            return sel;
        }
    }
    sel.best.failure = "no kind fits within the tolerance";
    return sel;
}

namespace {

/// Parameter bits of the models (see their residual()).
constexpr unsigned kDirBits = (1u << 2) | (1u << 3);
/// The axis position across the axis (cylinders, cones, tori).
constexpr unsigned kPositionBits = (1u << 0) | (1u << 1);
/// Axes closer than this are made parallel when the tolerance allows.
constexpr double kParallelDegrees = 0.5;
constexpr double kAxisSnapDegrees = 2.0;
/// Round values are multiples of 1 / n model units for these n (steps 1, 0.5, 0.1, 0.05, 0.01):
/// round(x n) / n is the double nearest to the decimal (6.35), which round(x / 0.05) x 0.05 is
/// not.
constexpr double kRoundDivisions[] = {1, 2, 10, 20, 100};
constexpr double kAngleStepsDegrees[] = {5.0, 1.0, 0.5};

template <class Model>
FitResult refine_held(Model m, unsigned frozen, const FitInput& in) {
    const int it = refine(m, in, frozen);
    return finish(m, it, in);
}

/// Refits `s` with the parameters in `frozen` held at their values in `s`.
FitResult refit_surface(const Surface& s, unsigned frozen, const FitInput& in) {
    switch (s.kind) {
        case FitKind::kPlane: {
            // A held normal: the best plane passes through the weighted centroid.
            Surface p = s;
            p.point = centroid(in);
            return residuals(p, in);
        }
        case FitKind::kSphere:
        case FitKind::kCylinder:
        case FitKind::kCone:
        case FitKind::kTorus:
            return with_model(s, [&](auto m) { return refine_held(m, frozen, in); });
        case FitKind::kShearCylinder:
        case FitKind::kSweptTorus:
        case FitKind::kBSpline:
            break;  // not snapped (yet)
    }
    return {};
}

/// Bits of a torus's center along its axis and of a sphere's center (see their residual()).
constexpr unsigned kTorusAlongBit = 1u << 4;
constexpr unsigned kSphereCenterBits = (1u << 0) | (1u << 1) | (1u << 2);

/// Whether `r`, refitted with values held, explains the points of `in` as well as a fit of
/// RMS `base_rms` does, within chance (SnapOptions::noise).
bool explains(const FitResult& r, double base_rms, const FitInput& in, const SnapOptions& o) {
    if (o.noise < 0) return true;
    double sum = 0, sum2 = 0;
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const double w = weight(in, i);
        sum += w;
        sum2 += w * w;
    }
    const double n = sum2 > 0 ? sum * sum / sum2 : 1.0;
    // A fit whose own residuals show less than the noise (an exact face of a CAD mesh among
    // approximate ones) is held to them: their variance estimate, RMS^2 n / (n - p).
    const double p = fit_parameters(r.surface.kind);
    double noise = o.noise;
    if (n > p + 1) noise = std::min(noise, base_rms * std::sqrt(n / (n - p)));
    return r.rms * r.rms <=
           base_rms * base_rms + kSnapChi2 * noise * noise / n + o.rms_floor * o.rms_floor;
}

/// The coordinate axis `d` is exactly (+-), or -1.
int coordinate_axis(Vec3 d) {
    for (int k = 0; k < 3; ++k)
        if (std::fabs(d[k]) == 1.0 && d[(k + 1) % 3] == 0 && d[(k + 2) % 3] == 0) return k;
    return -1;
}

}  // namespace

int fit_parameters(FitKind kind) {
    switch (kind) {
        case FitKind::kPlane:
            return 3;
        case FitKind::kSphere:
            return 4;
        case FitKind::kCylinder:
            return CylinderModel::N;
        case FitKind::kCone:
            return ConeModel::N;
        case FitKind::kTorus:
            return TorusModel::N;
        case FitKind::kShearCylinder:
            return ShearModel::N;
        case FitKind::kSweptTorus:
            return SweptModel::N;
        case FitKind::kBSpline:
            break;
    }
    return 0;
}

FitResult snap(const FitResult& fit0, const FitInput& in, const SnapOptions& o,
               std::vector<std::string>* applied) {
    if (!fit0.ok || fit0.surface.kind == FitKind::kBSpline ||
        fit0.surface.kind == FitKind::kShearCylinder || fit0.surface.kind == FitKind::kSweptTorus) {
        return fit0;
    }
    FitResult cur = fit0;
    unsigned frozen = 0;
    const double base_rms = o.base_rms >= 0 ? o.base_rms : fit0.rms;
    auto accept = [&](const FitResult& r) {
        return r.ok && r.max <= o.tolerance && explains(r, base_rms, in, o);
    };
    auto note = [&](const std::string& what) {
        if (applied) applied->push_back(what);
    };
    const FitKind kind = cur.surface.kind;
    static const char* kNames[3] = {"x", "y", "z"};
    // What snap_together() fixed stays as it is.
    if (kind != FitKind::kSphere && o.hold.direction) frozen |= kDirBits;
    if (kind != FitKind::kSphere && kind != FitKind::kPlane && o.hold.line) frozen |= kPositionBits;
    // 1. The axis (or a plane's normal) to a coordinate axis.
    if (o.axes && kind != FitKind::kSphere && !o.hold.direction) {
        for (int k = 0; k < 3; ++k) {
            Vec3 e{};
            e[k] = 1;
            const double c = dot(cur.surface.axis, e);
            if (std::fabs(c) < std::cos(kAxisSnapDegrees * kPi / 180)) continue;
            if (coordinate_axis(cur.surface.axis) == k) {  // already: held as it is
                frozen |= kDirBits;
                break;
            }
            Surface s = cur.surface;
            s.axis = c > 0 ? e : -e;
            const FitResult r = refit_surface(s, frozen | kDirBits, in);
            if (accept(r)) {
                cur = r;
                frozen |= kDirBits;
                note(std::string("axis to ") + (c > 0 ? "+" : "-") + kNames[k]);
            }
            break;
        }
    }
    // 2. Positions to round values, coarsest step first: `coords` of the surface's point
    // together (held by `bits`); a plane has nothing left to fit once its offset is held.
    if (o.positions) {
        auto round_point = [&](std::initializer_list<int> coords, unsigned bits, const char* what) {
            for (const double n : kRoundDivisions) {
                Surface s = cur.surface;
                bool moved = false;
                for (const int k : coords) {
                    const double rounded = std::round(s.point[k] * n) / n;
                    moved = moved || rounded != s.point[k];
                    s.point[k] = rounded;
                }
                if (!moved) {  // already round at this step, so at every finer one: held
                    frozen |= bits;
                    return;
                }
                const FitResult r = kind == FitKind::kPlane ? residuals(s, in)
                                                            : refit_surface(s, frozen | bits, in);
                if (accept(r)) {
                    std::string at = what;
                    for (const int k : coords)
                        at += std::string(" ") + kNames[k] + " " + number(r.surface.point[k]);
                    note(at);
                    cur = r;
                    frozen |= bits;
                    return;
                }
            }
        };
        const int k = coordinate_axis(cur.surface.axis);
        if (k >= 0 && kind != FitKind::kSphere) frozen |= kDirBits;  // exact: it stays
        if (kind == FitKind::kSphere) {
            round_point({0, 1, 2}, kSphereCenterBits, "center");
        } else if (k >= 0 && kind == FitKind::kPlane) {
            round_point({k}, 0, "offset");
        } else if (k >= 0) {
            if (!o.hold.line) round_point({(k + 1) % 3, (k + 2) % 3}, kPositionBits, "axis at");
            if (kind == FitKind::kTorus) round_point({k}, kTorusAlongBit, "center at");
        }
    }
    // 3. Radii: tool radii first, then round values. Bit of each radius in its model.
    struct RadiusSlot {
        double Surface::*field;
        unsigned bit;
        const char* name;
    };
    std::vector<RadiusSlot> slots;
    if (kind == FitKind::kSphere) slots.push_back({&Surface::radius, 1u << 3, "radius"});
    if (kind == FitKind::kCylinder) slots.push_back({&Surface::radius, 1u << 4, "radius"});
    if (kind == FitKind::kTorus) {
        slots.push_back({&Surface::minor_radius, 1u << 6, "minor radius"});
        slots.push_back({&Surface::radius, 1u << 5, "major radius"});
    }
    for (const RadiusSlot& slot : slots) {
        // A spindle torus's inner part has a negative major radius: its size is snapped.
        const double signed_value = cur.surface.*(slot.field);
        const double sign = signed_value < 0 ? -1.0 : 1.0, value = std::fabs(signed_value);
        std::vector<double> candidates;
        std::vector<double> tools = o.tool_radii;
        std::sort(tools.begin(), tools.end(),
                  [&](double a, double b) { return std::fabs(a - value) < std::fabs(b - value); });
        for (double t : tools)
            if (t > 0) candidates.push_back(t);
        if (o.round_values) {
            for (const double n : kRoundDivisions) {
                const double rounded = std::round(value * n) / n;
                if (rounded > 0) candidates.push_back(rounded);
            }
        }
        for (double cand : candidates) {
            if (cand == value) {  // already round: held
                frozen |= slot.bit;
                break;
            }
            Surface s = cur.surface;
            s.*(slot.field) = sign * cand;
            const FitResult r = refit_surface(s, frozen | slot.bit, in);
            if (accept(r)) {
                note(std::string(slot.name) + " " + number(signed_value) + " -> " +
                     number(sign * cand));
                cur = r;
                frozen |= slot.bit;
                break;
            }
        }
    }
    // 4. A cone's half-angle to round degrees.
    if (kind == FitKind::kCone && o.round_values) {
        const double deg = cur.surface.angle * 180 / kPi;
        for (double step : kAngleStepsDegrees) {
            const double rounded = std::round(deg / step) * step;
            if (rounded <= 0 || rounded >= 90) continue;
            if (rounded == deg) break;
            Surface s = cur.surface;
            s.angle = rounded * kPi / 180;
            const FitResult r = refit_surface(s, frozen | (1u << 5), in);
            if (accept(r)) {
                note("half-angle " + number(deg) + " -> " + number(rounded) + " deg");
                cur = r;
                break;
            }
        }
    }
    return cur;
}

std::vector<std::string> snap_together(std::span<FitResult> fits, std::span<const FitInput> inputs,
                                       const SnapOptions& o, std::span<const double> base_rms,
                                       std::vector<SnapHold>* holds) {
    std::vector<std::string> notes;
    if (holds) holds->assign(fits.size(), SnapHold{});
    if (fits.size() != inputs.size() || (!base_rms.empty() && base_rms.size() != fits.size()))
        return notes;
    std::vector<double> from(fits.size());
    for (std::size_t i = 0; i < fits.size(); ++i)
        from[i] = base_rms.empty() ? fits[i].rms : base_rms[i];
    auto has_axis = [&](std::size_t i) {
        const FitKind k = fits[i].surface.kind;
        return fits[i].ok && (k == FitKind::kPlane || k == FitKind::kCylinder ||
                              k == FitKind::kCone || k == FitKind::kTorus);
    };
    auto is_revolution = [&](std::size_t i) {
        return has_axis(i) && fits[i].surface.kind != FitKind::kPlane;
    };
    // Refits every member with `frozen` held at the surface `make(group)` gives for it (none:
    // left as it is), and commits when all keep the tolerance (and the RMS). Otherwise, unless
    // `all`, leaves out the members that do not and tries the rest again. Returns the members
    // committed (none, or at least two).
    auto try_group = [&](std::vector<std::size_t> group, unsigned frozen, const auto& make,
                         bool all) {
        while (group.size() >= 2) {
            std::vector<std::optional<Surface>> wanted = make(group);
            std::vector<FitResult> out(group.size());
            std::vector<std::uint8_t> bad(group.size(), 0);
            tbb::parallel_for(std::size_t{0}, group.size(), [&](std::size_t k) {
                const std::size_t i = group[k];
                if (!wanted[k]) {
                    out[k] = fits[i];
                    return;
                }
                out[k] = refit_surface(*wanted[k], frozen, inputs[i]);
                bad[k] = !out[k].ok || out[k].max > o.tolerance ||
                         !explains(out[k], from[i], inputs[i], o);
            });
            if (std::find(bad.begin(), bad.end(), 1) == bad.end()) {
                for (std::size_t k = 0; k < group.size(); ++k) fits[group[k]] = std::move(out[k]);
                return group;
            }
            if (all) break;
            std::vector<std::size_t> kept;
            for (std::size_t k = 0; k < group.size(); ++k)
                if (!bad[k]) kept.push_back(group[k]);
            group = std::move(kept);
        }
        return std::vector<std::size_t>{};
    };
    auto axis_dir = [&](std::size_t i, Vec3 like) {
        const Vec3 a = fits[i].surface.axis;
        return dot(a, like) < 0 ? -a : a;
    };
    const double cos_parallel = std::cos(kParallelDegrees * kPi / 180);
    // 1. Parallel directions: greedy groups around each unassigned axis, in order.
    std::vector<int> group_of(fits.size(), -1);
    std::vector<std::vector<std::size_t>> groups;
    for (std::size_t i = 0; i < fits.size(); ++i) {
        if (!has_axis(i) || group_of[i] >= 0) continue;
        std::vector<std::size_t> g{i};
        for (std::size_t j = i + 1; j < fits.size(); ++j) {
            if (has_axis(j) && group_of[j] < 0 &&
                std::fabs(dot(fits[i].surface.axis, fits[j].surface.axis)) >= cos_parallel) {
                g.push_back(j);
            }
        }
        for (const std::size_t k : g) group_of[k] = static_cast<int>(groups.size());
        groups.push_back(g);
    }
    for (const auto& g : groups) {
        if (g.size() < 2) continue;
        const Vec3 a0 = fits[g[0]].surface.axis;
        std::vector<std::size_t> done = g;
        if (!std::all_of(g.begin(), g.end(), [&](std::size_t i) {
                return fits[i].surface.axis == a0 || fits[i].surface.axis == -a0;
            })) {
            // The common direction: the point-count-weighted mean, signs aligned with the first.
            const auto parallel = [&](const std::vector<std::size_t>& group) {
                Vec3 mean{};
                for (const std::size_t i : group)
                    mean += static_cast<double>(inputs[i].points.size()) *
                            axis_dir(i, fits[group[0]].surface.axis);
                const Vec3 dir = normalized(mean);
                std::vector<std::optional<Surface>> out;
                for (const std::size_t i : group) {
                    Surface s = fits[i].surface;
                    s.axis = axis_dir(i, dir) == fits[i].surface.axis ? dir : -dir;
                    if (s.axis == fits[i].surface.axis) {
                        out.emplace_back();
                    } else {
                        out.emplace_back(s);
                    }
                }
                return out;
            };
            done = try_group(g, kDirBits, parallel, false);
            if (done.empty()) continue;
            notes.push_back(std::to_string(done.size()) + " axes made parallel");
        }
        // The group's direction to a coordinate axis, for all or none.
        const Vec3 d = fits[done[0]].surface.axis;
        for (int k = 0; k < 3 && o.axes; ++k) {
            if (std::fabs(d[k]) < std::cos(kAxisSnapDegrees * kPi / 180)) continue;
            if (coordinate_axis(d) == k) break;
            Vec3 e{};
            e[k] = 1;
            const auto to_axis = [&](const std::vector<std::size_t>& group) {
                std::vector<std::optional<Surface>> out;
                for (const std::size_t i : group) {
                    Surface s = fits[i].surface;
                    s.axis = dot(s.axis, e) < 0 ? -e : e;
                    out.emplace_back(s);
                }
                return out;
            };
            if (!try_group(done, kDirBits, to_axis, true).empty()) {
                static const char* kNames[3] = {"x", "y", "z"};
                notes.push_back(std::to_string(done.size()) + " parallel axes to " + kNames[k]);
            }
            break;
        }
        if (holds)
            for (const std::size_t i : done) (*holds)[i].direction = true;
    }
    // 2. Coaxial: surfaces of revolution whose axis lines (now parallel) nearly coincide.
    std::vector<bool> used(fits.size(), false);
    for (std::size_t i = 0; i < fits.size(); ++i) {
        if (!is_revolution(i) || used[i]) continue;
        const Vec3 d = fits[i].surface.axis;
        std::vector<std::size_t> g{i};
        for (std::size_t j = i + 1; j < fits.size(); ++j) {
            if (!is_revolution(j) || used[j]) continue;
            if (std::fabs(dot(d, fits[j].surface.axis)) < 1 - 1e-12) continue;
            const Vec3 w = fits[j].surface.point - fits[i].surface.point;
            if (norm(w - dot(w, d) * d) <= o.tolerance) g.push_back(j);
        }
        if (g.size() < 2) continue;
        std::vector<std::size_t> done = g;
        if (!std::all_of(g.begin(), g.end(), [&](std::size_t k) {
                const Vec3 w = fits[k].surface.point - fits[i].surface.point;
                return w - dot(w, d) * d == Vec3{};
            })) {
            // The common line: through the mean of the members' axis points, projected.
            const auto coaxial = [&](const std::vector<std::size_t>& group) {
                Vec3 mean{};
                double total = 0;
                const Vec3 p0 = fits[group[0]].surface.point;
                for (const std::size_t k : group) {
                    const double wgt = static_cast<double>(inputs[k].points.size());
                    const Vec3 w = fits[k].surface.point - p0;
                    mean += wgt * (w - dot(w, d) * d);
                    total += wgt;
                }
                const Vec3 base = p0 + mean / total;
                std::vector<std::optional<Surface>> out;
                for (const std::size_t k : group) {
                    Surface s = fits[k].surface;
                    // Keep the member's own place along the axis.
                    s.point = base + dot(s.point - base, d) * d;
                    out.emplace_back(s);
                }
                return out;
            };
            done = try_group(g, kDirBits | kPositionBits, coaxial, false);
            if (done.empty()) continue;
            notes.push_back(std::to_string(done.size()) + " surfaces made coaxial");
        }
        for (const std::size_t k : done) used[k] = true;
        // The line across a coordinate axis to round values, coarsest step first, all or none.
        const int k = coordinate_axis(fits[done[0]].surface.axis);
        if (o.positions && k >= 0) {
            const int c1 = (k + 1) % 3, c2 = (k + 2) % 3;
            const Vec3 p0 = fits[done[0]].surface.point;
            for (const double n : kRoundDivisions) {
                const double x1 = std::round(p0[c1] * n) / n, x2 = std::round(p0[c2] * n) / n;
                if (x1 == p0[c1] && x2 == p0[c2]) break;
                const auto rounded = [&](const std::vector<std::size_t>& group) {
                    std::vector<std::optional<Surface>> out;
                    for (const std::size_t m : group) {
                        Surface s = fits[m].surface;
                        s.point[c1] = x1;
                        s.point[c2] = x2;
                        out.emplace_back(s);
                    }
                    return out;
                };
                if (!try_group(done, kDirBits | kPositionBits, rounded, true).empty()) {
                    notes.push_back(std::to_string(done.size()) + " coaxial lines at " +
                                    number(x1) + " " + number(x2));
                    break;
                }
            }
        }
        if (holds)
            for (const std::size_t m : done) (*holds)[m] = {true, true};
    }
    return notes;
}

}  // namespace ncrev
