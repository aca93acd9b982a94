// Tangent cylinders made exactly tangent before the B-rep is built (docs/brep.md, 1).
//
// A fillet and the arc it runs on from are tangent by design, but fitted to a float32 mesh each
// on its own they overlap or part by a rounding error. Where a third face cuts both (the floor
// of a pocket, in which a slot's arc runs on into a fillet's), its edges with them are two
// circles that cross twice beside the corner, at about sqrt(2 r e) from it for an overlap e
// (r the product of the radii over their sum): NIST FTC 06's arcs of radius 22.225 and 3.175
// overlapped by 1.3e-7 mm and crossed 8.5e-4 mm from the corner, far past its tolerance, and
// the floor's wire crossed itself. So the smaller of two adjacent cylinders with parallel axes
// that overlap within what their fits leave open is moved across its axis (its radius by a
// ten-thousandth as much, more only where no such move holds all its contacts) until the two
// are a hair apart (kHair): circles that neither cross nor touch, the corner within its
// tolerance of both.
#include <Eigen/Dense>
#include <Precision.hxx>
#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "brep/surfaces.h"

namespace ncrev::brep_detail {

namespace {

// How far apart two tangent surfaces are left: a hundredth of OpenCASCADE's smallest tolerance
// (Precision::Confusion(), 1e-7), so a corner between them is within its tolerance of both;
// and far above double rounding at a part's coordinates (2e-14 at 100, 2e-11 at 1e5), so the
// curves they leave on a third face stay apart after the solve rounds.
const double kHair = Precision::Confusion() / 100;
// Axes this close to parallel (sine of their angle) are made parallel with the contact: two
// fits of one direction differ by about 1e-7 from a float32 mesh (snapping makes them equal)
// and by 1e-6 from six-digit coordinates (NIST FTC 06's slot arcs, 2.5 mm high); the move,
// a turn about the axis point, is checked against the tolerance below.
constexpr double kParallel = 1e-4;
// Two unit directions this close (sine of their angle) are one to double rounding: a gap
// between cylinders along them changes by under 1e-11 over 1000 mm, a hundredth of kHair.
constexpr double kSameDirection = 1e-14;
// Coordinate rounding units (coordinate_rounding()) two exact fits may leave between tangent
// surfaces: each fit's vertices are off its surface by about one, either way.
constexpr double kRoundingUnits = 4;
// How much more a unit of radius costs than a unit of axis move in the solve (a least change
// in the weighted unknowns): the radius, a tool's and often a round value, takes 1/100^2 of a
// move where the axis can hold every contact (FTC 06: 5e-10 mm for 5e-6), and the rest only
// where it cannot (a fillet between three arcs).
constexpr double kRadiusWeight = 100;
// Gauss-Newton steps of the solve: its constraints are distances between axes, and it starts
// within the tolerance of the solution.
constexpr int kSolveSteps = 8;

// `v` without its part along unit `axis`.
Vec3 across(Vec3 v, Vec3 axis) { return v - dot(v, axis) * axis; }

// One contact of a moving cylinder with a larger one (axis point, radius; `inside` when the
// moving one lies within it).
struct Contact {
    Vec3 point;
    double radius = 0;
    bool inside = false;
};

// The gap of `c` from a cylinder of axis point p, radius r, unit axis a, less the hair; and its
// gradient in (p, r).
double residual(const Contact& c, Vec3 p, double r, Vec3 a, Vec3& grad_p, double& grad_r) {
    const Vec3 d = across(p - c.point, a);
    const double len = std::max(norm(d), 1e-300);
    grad_r = -1;
    if (c.inside) {  // the gap is (R - r) - |d|
        grad_p = -1 / len * d;
        return c.radius - r - len - kHair;
    }
    grad_p = 1 / len * d;
    return len - c.radius - r - kHair;
}

}  // namespace

std::size_t exact_tangencies(const Mesh& m, const FaceMap<std::int32_t>& region,
                             std::vector<RegionSurface>& regions, double tolerance) {
    const std::size_t nr = regions.size();
    const auto cylinder = [&](std::size_t r) {
        return r < nr && regions[r].has_surface && regions[r].surface.kind == FitKind::kCylinder;
    };
    std::set<std::pair<std::size_t, std::size_t>> pairs;
    for (std::uint32_t f = 0; f < m.num_faces(); ++f) {
        const auto a = static_cast<std::size_t>(region[FaceId(f)]);
        if (!cylinder(a)) continue;
        for (int i = 0; i < 3; ++i) {
            const HalfedgeId t = m.twin(Mesh::halfedge(FaceId(f), i));
            if (!t.is_valid()) continue;
            const auto b = static_cast<std::size_t>(region[Mesh::face(t)]);
            if (b > a && cylinder(b)) pairs.emplace(a, b);
        }
    }
    if (pairs.empty()) return 0;
    // Each region's vertices, and how far from its surface they lie: its fit's own error.
    std::vector<std::vector<std::uint32_t>> ids(nr);
    {
        std::vector<std::uint8_t> in_pair(nr, 0);
        for (const auto& [a, b] : pairs) in_pair[a] = in_pair[b] = 1;
        for (std::uint32_t f = 0; f < m.num_faces(); ++f) {
            const auto r = static_cast<std::size_t>(region[FaceId(f)]);
            if (r >= nr || !in_pair[r]) continue;
            for (int i = 0; i < 3; ++i) ids[r].push_back(m.vertex(FaceId(f), i).idx());
        }
    }
    std::vector<double> error(nr, 0);
    for (std::size_t r = 0; r < nr; ++r) {
        std::sort(ids[r].begin(), ids[r].end());
        ids[r].erase(std::unique(ids[r].begin(), ids[r].end()), ids[r].end());
        for (const std::uint32_t v : ids[r])
            error[r] = std::max(error[r], distance(regions[r].surface, m.position(VertexId(v))));
    }
    // Two cylinders are tangent when their gap is within what their fits leave open: each is
    // off its vertices by up to its error, an exact fit by the coordinates' rounding.
    const double rounding = kRoundingUnits * coordinate_rounding(m);
    // How far a region's vertices reach from its axis point along its axis, either way.
    const auto extent = [&](std::size_t r) {
        const Surface& s = regions[r].surface;
        double reach = 0;
        for (const std::uint32_t v : ids[r])
            reach = std::max(reach, std::abs(dot(m.position(VertexId(v)) - s.point, s.axis)));
        return reach;
    };
    std::vector<std::vector<std::size_t>> larger(nr);  // each one's tangent larger neighbours
    for (const auto& [a, b] : pairs) {
        const Surface& sa = regions[a].surface;
        const Surface& sb = regions[b].surface;
        if (std::abs(sa.radius - sb.radius) <= tolerance) continue;
        const double open = std::min(tolerance, error[a] + error[b] + rounding);
        // Parallel as far as the fits tell: turned onto the other's axis, the smaller one moves
        // by no more than they leave open at its ends.
        const std::size_t small = sa.radius < sb.radius ? a : b;
        const double sine = norm(cross(sa.axis, sb.axis));
        if (sine > kParallel || sine * extent(small) > open) continue;
        const double d = norm(across(sa.point - sb.point, sb.axis));
        const double outside = d - (sa.radius + sb.radius);
        const double inside = d - std::abs(sa.radius - sb.radius);
        const double gap = std::min(std::abs(outside), std::abs(inside));
        if (gap > open) continue;
        if (sa.radius < sb.radius) {
            larger[a].push_back(b);
        } else {
            larger[b].push_back(a);
        }
    }
    // The larger ones first: a fillet moves after the arcs it runs between.
    std::vector<std::size_t> order;
    for (std::size_t r = 0; r < nr; ++r)
        if (!larger[r].empty()) order.push_back(r);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return regions[a].surface.radius > regions[b].surface.radius;
    });
    std::size_t moved = 0;
    for (const std::size_t r : order) {
        Surface s = regions[r].surface;
        std::vector<Contact> contacts;
        for (const std::size_t n : larger[r]) {
            const Surface& o = regions[n].surface;
            const double d = norm(across(s.point - o.point, o.axis));
            contacts.push_back(
                {o.point, o.radius,
                 std::abs(d - (o.radius - s.radius)) < std::abs(d - (o.radius + s.radius))});
            // Along the larger one's axis exactly (within kParallel already).
            s.axis = dot(s.axis, o.axis) >= 0 ? o.axis : -o.axis;
        }
        // Turned by more than a hair at its ends.
        const bool turned = norm(cross(s.axis, regions[r].surface.axis)) * extent(r) > kHair / 2;
        // Every contact's axis the same to rounding: else the gap changes along the axis, and a
        // hair at the axis point is none where a third face cuts the two.
        if (std::any_of(larger[r].begin(), larger[r].end(), [&](std::size_t n) {
                return norm(cross(s.axis, regions[n].surface.axis)) > kSameDirection;
            }))
            continue;
        // Gauss-Newton in (the axis point across the axis, the radius weighted by
        // kRadiusWeight), each step the least change.
        const Vec3 u = any_perpendicular(s.axis);
        const Vec3 w = cross(s.axis, u);
        const auto k = static_cast<Eigen::Index>(contacts.size());
        bool solved = false, apart = true;
        for (int step = 0; step < kSolveSteps; ++step) {
            Eigen::MatrixXd J(k, 3);
            Eigen::VectorXd f(k);
            double worst = 0;
            for (Eigen::Index i = 0; i < k; ++i) {
                Vec3 gp;
                double gr;
                f(i) = residual(contacts[static_cast<std::size_t>(i)], s.point, s.radius, s.axis,
                                gp, gr);
                J(i, 0) = dot(gp, u);
                J(i, 1) = dot(gp, w);
                J(i, 2) = gr / kRadiusWeight;
                worst = std::max(worst, std::abs(f(i)));
                if (f(i) < -kHair / 2) apart = false;
            }
            // Cylinders apart already leave circles on a third face that do not cross: the
            // corner bridges their gap within its tolerance, and the part stays as fitted. Not
            // when its axis was turned to theirs: apart at its axis point now, it was not
            // along all its length (six-digit coordinates: axes 1e-6 apart over 10 mm, a gap
            // of 9e-6 mm).
            if (step == 0 && apart && !turned) break;
            if (worst <= kHair / 4) {
                solved = true;
                break;
            }
            const Eigen::VectorXd dx = J.completeOrthogonalDecomposition().solve(-f);
            s.point = s.point + dx(0) * u + dx(1) * w;
            s.radius += dx(2) / kRadiusWeight;
        }
        if (!solved || s.radius <= 0) continue;
        // Held within the tolerance of the region's vertices (or as loosely as it was).
        double after = 0;
        for (const std::uint32_t v : ids[r])
            after = std::max(after, distance(s, m.position(VertexId(v))));
        if (after > std::max(tolerance, error[r])) continue;
        regions[r].surface = s;
        ++moved;
    }
    return moved;
}

}  // namespace ncrev::brep_detail
