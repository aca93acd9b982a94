// The exact B-rep from regions and their surfaces (method.md, Step 2b).
//
// 1. Borders: region_borders() gives the chains of mesh edges between two regions, corner to
//    corner (or closed loops), and the corners where three or more regions meet.
// 2. Vertices: every corner solved onto the surfaces of the regions around it (common_point:
//    exact where three surfaces cross); a closed loop gets one vertex, solved onto its two.
// 3. Edges, one per chain, shared by the two faces: the surfaces' intersection (OpenCASCADE's
//    GeomAPI_IntSS, analytic for elementary pairs) — the branch that runs along the chain,
//    trimmed at the chain's vertices — where the surfaces cross at a clear angle; where they
//    are tangent (a fillet and its neighbours: the intersection is ill-conditioned) or the
//    intersection misses the chain, a curve interpolated through the chain's vertices solved
//    onto both surfaces. Beside a region built from its facets, the chain's own segments.
// 4. Faces: each region's surface (its natural normal turned to the solid's outside by the
//    face orientation, the seam of a periodic surface put opposite the region), bounded by
//    the loops of its border walked on the mesh; ShapeFix_Face adds the curves on the surface,
//    missing seams and degenerate edges at poles, within the chordal deflection.
// 5. Shell and solid, checked with BRepCheck_Analyzer. A region whose face fails (cannot be
//    built, fails the check, no surface) is built again from its facets — planar triangles
//    sewn to its neighbours by sharing the chain's segments — and the B-rep is rebuilt.
#include "brep/surfaces.h"

#include <tbb/parallel_for.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepBuilderAPI_Copy.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepGProp.hxx>
#include <BRepLib.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <ElSLib.hxx>
#include <GCPnts_AbscissaPoint.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Line.hxx>
#include <GeomAPI_IntSS.hxx>
#include <GeomAPI_Interpolate.hxx>
#include <GeomAPI_PointsToBSpline.hxx>
#include <GeomAPI_ProjectPointOnCurve.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Circle.hxx>
#include <Geom_ConicalSurface.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_ElementarySurface.hxx>
#include <Geom_Ellipse.hxx>
#include <Geom_Line.hxx>
#include <Geom_OffsetSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_SurfaceOfLinearExtrusion.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <IntAna_QuadQuadGeo.hxx>
#include <Precision.hxx>
#include <ShapeBuild_ReShape.hxx>
#include <ShapeFix_Edge.hxx>
#include <ShapeFix_Face.hxx>
#include <ShapeFix_Wire.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TColgp_HArray1OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "brep/check.h"
#include "brep/deviation.h"
#include "detail/union_find.h"
#include "ncrev/segment.h"

namespace ncrev::brep_detail {

namespace {

// Smallest tolerance of vertices, edges and faces: OpenCASCADE's Precision::Confusion().
constexpr double kMinTolerance = 1e-7;
// Two surfaces meeting at less than this angle (rad, 10 degrees) are treated as tangent: their
// intersection moves by (surface error) / sin(angle) — 6x at 10 degrees — and OpenCASCADE's
// intersection of nearly tangent surfaces is unreliable, so the edge is fitted instead.
constexpr double kTangentAngle = 0.17453292519943295;
// How far from a corner's mesh vertex, in tube radii, the junction of two tubes of one radius
// is looked for (spine_junction()): a corner further than that along a fillet from where the
// segmentation put it would be another blend's.
constexpr double kJunctionSpan = 2;
// The share of a tangency chain's steps, and of its length along the spine, that may go back
// for the chain to count as running along the contact (in_spine_order()). The turned shaft's
// shoulder fillet at 386k facets went back 6 steps of 585, by 0.3 % of its turn; NIST FTC 07's
// chains that are not along a contact go back 1 step of 3 or more.
constexpr double kBacktrackShare = 0.05;
// Of two tubes tangent along a chain, the one whose spine points travel along the chain less
// than this share of as far as the other's is not taken as the tube (tangency_points()): a bore
// and the torus rounding its end touch along a circle round the bore's axis, where the bore's
// spine points are one point (0 against the chain's length), and the feet of that point pile up
// (NIST FTC 10 at 0.02 mm: within 1e-11 mm, a temporary print). Any share between the two
// would do.
constexpr double kStillSpine = 0.5;
// A curve through tangency feet is taken when it is within this many tolerances of both
// surfaces (build_surface_brep()): surfaces that each hold the chain's vertices within the
// tolerance are within twice it of each other where they touch. A curve farther off runs
// through feet of surfaces that do not touch there, and the curve through points solved onto
// both is nearer (a B-spline beside a torus on NIST FTC 10 at 0.02 mm: feet 0.17 mm, 10
// tolerances, off, and the B-spline's wire crossed itself; 0.03 mm through solved points).
constexpr double kTouchTolerances = 2;
// A line or circle is taken for a tangent junction's curve when it passes within this share of
// the tolerance of every contact point (build_surface_brep()): then it is where the surfaces
// touch as nearly as the cubic through the points, which passes through them. The contact
// points of a cylinder fillet on a plane, or of a torus on a plane square to its axis, lie on
// a line or circle to rounding (the spine's projection onto the plane); a tenth of the
// tolerance keeps the surfaces' fitting error out of the edge.
constexpr double kConicFeet = 0.1;
// Points of a chain used to choose and trim an intersection branch (all when fewer).
constexpr std::size_t kChainSamples = 24;
// Facet centroids used to find which way a surface's natural normal points.
constexpr std::size_t kOrientationSamples = 16;
// Chains of more points than this get an approximating edge curve (fitted_curve()): fewer
// take no more poles interpolated.
constexpr std::size_t kApproximateFrom = 8;
// Build rounds: each round turns (the smallest of) the regions whose faces failed into facets;
// a failure spreads at most to neighbours, so a few rounds settle.
constexpr int kMaxRounds = 12;
/// A fallback region's B-spline (spline_fallback) is fitted to this many points per facet
/// edge (and the triangle grid they span): 15 a facet, enough for the smallest cubic net.
constexpr int kSplineSamples = 4;
// Why a face BRepMesh leaves without triangles fails (its boundary crosses itself at the
// mesher's resolution: like a self-intersecting wire, it first gets piecewise-linear edges
// along its tangent junctions).
constexpr const char* kUntriangulated = "BRepMesh cannot triangulate its face";

gp_Pnt pnt(Vec3 v) { return {v.x, v.y, v.z}; }
Vec3 vec(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }
Vec3 vec(const gp_Vec& p) { return {p.X(), p.Y(), p.Z()}; }

// Why a face with an edge from a vertex back to it, no longer than that vertex's tolerance
// ball is across, fails. It passes BRepCheck, but a STEP file gives an edge only its curve and its
// two ends: one whose ends are the same vertex on a closed curve is read as the whole curve. The
// face fix puts such a piece on a band's loop where it splits the loop at the seam it adds and the
// loop's own vertex is already there (NIST CTC 04's countersunk holes, their mesh's vertices
// moved by one float32 unit: each loop's vertex elsewhere round the hole, and two faces read
// back with two whole circles for one). It fails as a face that crossed itself does: a
// band first takes a seam of its own (seamed_band()), which splits no loop.
constexpr const char* kNoLengthLoop = "an edge of its face closes on its vertex with no length";
// A face that is no band (a sphere's cap round its pole: the fix's seam from the loop to the
// pole splits the loop where it starts) gets its surface's seam turned about the axis instead,
// by the golden angle, so that later turns never come back near one tried before; at most
// kSeamTurns times.
constexpr double kSeamTurn = 2 * std::numbers::pi * (1 - 1 / std::numbers::phi);
constexpr int kSeamTurns = 2;

// `g` turned about its own axis by `turns` seam turns (an elementary surface of revolution: the
// same surface, its seam elsewhere); others as they are.
Handle(Geom_Surface) seam_turned(const Handle(Geom_Surface) & g, int turns) {
    const Handle(Geom_ElementarySurface) e = Handle(Geom_ElementarySurface)::DownCast(g);
    if (turns == 0 || e.IsNull() || e->IsKind(STANDARD_TYPE(Geom_Plane))) return g;
    return Handle(Geom_Surface)::DownCast(e->Rotated(e->Position().Axis(), turns * kSeamTurn));
}

// Whether `face` has such an edge.
bool has_no_length_loop(const TopoDS_Face& face) {
    for (TopExp_Explorer x(face, TopAbs_EDGE); x.More(); x.Next()) {
        const TopoDS_Edge e = TopoDS::Edge(x.Current());
        if (BRep_Tool::Degenerated(e)) continue;
        TopoDS_Vertex a, b;
        TopExp::Vertices(e, a, b);
        if (a.IsNull() || !a.IsSame(b)) continue;
        BRepAdaptor_Curve c(e);
        if (GCPnts_AbscissaPoint::Length(c) <= 2 * BRep_Tool::Tolerance(a)) return true;
    }
    return false;
}

// The unit part of `v` perpendicular to the unit `axis`, or any perpendicular when too small.
Vec3 perpendicular_part(Vec3 v, Vec3 axis) {
    const Vec3 p = v - dot(v, axis) * axis;
    const double n = norm(p);
    return n > 1e-9 * (norm(v) + 1e-300) && n > 0 ? (1.0 / n) * p : any_perpendicular(axis);
}

// An axis system at `origin`, main direction `z`, x direction from `x_hint` (made
// perpendicular).
gp_Ax3 frame(Vec3 origin, Vec3 z, Vec3 x_hint) {
    const Vec3 x = perpendicular_part(x_hint, z);
    return gp_Ax3(pnt(origin), gp_Dir(z.x, z.y, z.z), gp_Dir(x.x, x.y, x.z));
}

// What a region looks like from its facets: area-weighted centroid and outward normal.
struct RegionShape {
    Vec3 centroid;
    Vec3 normal;
    double area = 0;
    std::vector<FaceId> samples;  ///< facets spread over the region
};

// The knots of fit's B-splines (BSplineSurface), along a direction of `poles` poles: uniform
// on [0, 1], clamped (the ends repeated degree + 1 times).
void uniform_knots(int poles, int degree, TColStd_Array1OfReal& knots,
                   TColStd_Array1OfInteger& mults) {
    const int spans = poles - degree;
    knots.Resize(1, spans + 1, false);
    mults.Resize(1, spans + 1, false);
    for (int i = 0; i <= spans; ++i) {
        knots.SetValue(i + 1, static_cast<double>(i) / spans);
        mults.SetValue(i + 1, (i == 0 || i == spans) ? degree + 1 : 1);
    }
}

// The OpenCASCADE surface of `s`, its seam (or pole) put away from the region: the seam of a
// cylinder, cone or torus opposite the region's centroid, a sphere's pole at the middle of the
// region. Null (with `why`) when there is none.
Handle(Geom_Surface) geom_surface(const Surface& s, const RegionShape& r, std::string& why) {
    const Vec3 axis = normalized(s.axis);
    switch (s.kind) {
        case FitKind::kPlane: {
            const Vec3 n = dot(axis, r.normal) >= 0 ? axis : -axis;
            return new Geom_Plane(frame(s.point, n, any_perpendicular(n)));
        }
        case FitKind::kCylinder:
            return new Geom_CylindricalSurface(frame(s.point, axis, s.point - r.centroid),
                                               s.radius);
        case FitKind::kCone:
            return new Geom_ConicalSurface(frame(s.point, axis, s.point - r.centroid), s.angle,
                                           s.radius);
        case FitKind::kSphere: {
            Vec3 pole = r.centroid - s.point;
            pole = norm(pole) > 1e-9 * s.radius ? normalized(pole) : Vec3{0, 0, 1};
            return new Geom_SphericalSurface(frame(s.point, pole, any_perpendicular(pole)),
                                             s.radius);
        }
        case FitKind::kTorus: {
            // The inner part of a spindle torus (R < 0) is OpenCASCADE's torus (|R|, r) where
            // R + r cos v < 0: a point of parameter u lies at azimuth u + pi, so the seam's
            // x direction points at the centroid to fall opposite it.
            const Vec3 away = s.radius < 0 ? r.centroid - s.point : s.point - r.centroid;
            return new Geom_ToroidalSurface(frame(s.point, axis, away), std::fabs(s.radius),
                                            s.minor_radius);
        }
        case FitKind::kShearCylinder:
        case FitKind::kSweptTorus: {
            const gp_Ax2 ax = frame(s.point, axis, any_perpendicular(axis)).Ax2();
            Handle(Geom_Surface) base = new Geom_SurfaceOfLinearExtrusion(
                new Geom_Circle(ax, s.radius), gp_Dir(s.sweep.x, s.sweep.y, s.sweep.z));
            if (s.kind == FitKind::kShearCylinder) return base;
            // The tube at distance r from the sheared cylinder: the offset side on which the
            // region's centroid lies.
            Handle(Geom_Surface) out = new Geom_OffsetSurface(base, s.minor_radius);
            Handle(Geom_Surface) in = new Geom_OffsetSurface(base, -s.minor_radius);
            GeomAPI_ProjectPointOnSurf po(pnt(r.centroid), out), pi(pnt(r.centroid), in);
            const double dout = po.NbPoints() ? po.LowerDistance() : 1e300;
            const double din = pi.NbPoints() ? pi.LowerDistance() : 1e300;
            return dout <= din ? out : in;
        }
        case FitKind::kBSpline: {
            if (!s.bspline || s.bspline->num_u < 2 || s.bspline->num_v < 2) {
                why = "the B-spline surface has no control net";
                return {};
            }
            const BSplineSurface& b = *s.bspline;
            TColgp_Array2OfPnt poles(1, b.num_u, 1, b.num_v);
            for (int j = 0; j < b.num_v; ++j) {
                for (int i = 0; i < b.num_u; ++i) {
                    poles.SetValue(i + 1, j + 1,
                                   pnt(b.poles[static_cast<std::size_t>(i + b.num_u * j)]));
                }
            }
            TColStd_Array1OfReal ku(1, 1), kv(1, 1);
            TColStd_Array1OfInteger mu(1, 1), mv(1, 1);
            uniform_knots(b.num_u, b.degree, ku, mu);
            uniform_knots(b.num_v, b.degree, kv, mv);
            return new Geom_BSplineSurface(poles, ku, kv, mu, mv, b.degree, b.degree);
        }
    }
    why = "unknown surface kind";
    return {};
}

// +1 when the surface's natural normal points out of the solid over the region, -1 when in.
int natural_sense(const Handle(Geom_Surface) & s, const Mesh& m, const RegionShape& r) {
    double score = 0;
    for (FaceId f : r.samples) {
        const Vec3 n = m.face_normal_area2(f);
        const Vec3 c = (1.0 / 3) * (m.position(m.vertex(f, 0)) + m.position(m.vertex(f, 1)) +
                                    m.position(m.vertex(f, 2)));
        GeomAPI_ProjectPointOnSurf proj(pnt(c), s);
        if (!proj.NbPoints()) continue;
        double u = 0, v = 0;
        proj.LowerDistanceParameters(u, v);
        gp_Pnt p;
        gp_Vec du, dv;
        s->D1(u, v, p, du, dv);
        score += dot(normalized(vec(du.Crossed(dv))), n);
    }
    return score >= 0 ? 1 : -1;
}

// A chain's curve, oriented along the chain, between parameters first < last.
struct ChainCurve {
    Handle(Geom_Curve) curve;
    double first = 0, last = 0;
    double deviation = 0;  ///< largest distance of the chain's points from it
};

// Parameters of `points` on `c`, unwrapped along the chain, or false when a point does not
// project. The curve is reversed when the chain runs against it.
bool trim_along(Handle(Geom_Curve) c, const std::vector<gp_Pnt>& points, bool closed,
                ChainCurve& out) {
    // A trimmed curve (the general intersection's circles come so) is its basis curve.
    for (Handle(Geom_TrimmedCurve) t = Handle(Geom_TrimmedCurve)::DownCast(c); !t.IsNull();
         t = Handle(Geom_TrimmedCurve)::DownCast(c)) {
        c = t->BasisCurve();
    }
    // A closed B-spline (what the intersection gives for a loop such as a cone meeting a
    // cylinder) made periodic, so that a chain may run across its start.
    if (!c->IsPeriodic() && c->IsClosed()) {
        const Handle(Geom_BSplineCurve) bs = Handle(Geom_BSplineCurve)::DownCast(c);
        if (bs.IsNull()) return false;
        const Handle(Geom_BSplineCurve) copy = Handle(Geom_BSplineCurve)::DownCast(bs->Copy());
        copy->SetPeriodic();
        if (!copy->IsPeriodic()) return false;
        c = copy;
    }
    const bool periodic = c->IsPeriodic();
    const double period = periodic ? c->Period() : 0;
    std::vector<double> u;
    u.reserve(points.size());
    double dev = 0;
    // A bounded curve's ends are candidates too: a point past an end has no normal projection
    // there, and its nearest one may be far along (a solved corner just past the end of a
    // fitted extrusion's profile would project mid-way and the curve look doubled back).
    const double c0 = c->FirstParameter(), c1 = c->LastParameter();
    const bool bounded = !periodic && !Precision::IsInfinite(c0) && !Precision::IsInfinite(c1);
    const gp_Pnt end0 = bounded ? c->Value(c0) : gp_Pnt(), end1 = bounded ? c->Value(c1) : gp_Pnt();
    for (const gp_Pnt& p : points) {
        GeomAPI_ProjectPointOnCurve proj(p, c);
        double t = 0, d = std::numeric_limits<double>::infinity();
        if (proj.NbPoints() > 0) t = proj.LowerDistanceParameter(), d = proj.LowerDistance();
        if (bounded) {
            if (const double d0 = p.Distance(end0); d0 < d) t = c0, d = d0;
            if (const double d1 = p.Distance(end1); d1 < d) t = c1, d = d1;
        }
        if (!std::isfinite(d)) return false;
        dev = std::max(dev, d);
        if (periodic && !u.empty()) {
            while (t - u.back() > 0.5 * period) t -= period;
            while (u.back() - t > 0.5 * period) t += period;
        }
        u.push_back(t);
    }
    double a = u.front(), b = u.back();
    if (closed) {
        if (!periodic) return false;
        // Unwrapped around once: the last point is the first one a period on.
        if (std::abs(std::abs(b - a) - period) > 0.25 * period) return false;
        b = a + (b > a ? period : -period);
        // A closed edge's range starts at a knot: OpenCASCADE's integrals over a face
        // (BRepGProp's volume, the NURBS conversion) lose part of a periodic B-spline whose
        // range [a, a + period] begins between knots (a domed head's flat top bounded by one:
        // 4.3 mm3, 0.6 % of the solid).
        if (const Handle(Geom_BSplineCurve) bs = Handle(Geom_BSplineCurve)::DownCast(c);
            !bs.IsNull()) {
            const Handle(Geom_BSplineCurve) copy = Handle(Geom_BSplineCurve)::DownCast(bs->Copy());
            copy->SetOrigin(std::min(a, b), Precision::PConfusion());
            c = copy;
        }
    }
    if (a == b) return false;
    // Monotone along the chain (a curve that doubles back is the wrong branch).
    const double sgn = b > a ? 1 : -1;
    for (std::size_t i = 1; i < u.size(); ++i) {
        if (sgn * (u[i] - u[i - 1]) < -1e-9 * (std::abs(b - a) + 1)) return false;
    }
    if (b < a) {
        c = c->Reversed();
        a = c->ReversedParameter(a);
        b = c->ReversedParameter(b);
    }
    out.curve = c;
    out.first = a;
    out.last = b;
    out.deviation = dev;
    return true;
}

// Chain points used for choosing and trimming: ends (the solved vertices) and up to
// kChainSamples spread between.
std::vector<gp_Pnt> chain_samples(const std::vector<gp_Pnt>& points) {
    if (points.size() <= kChainSamples) return points;
    std::vector<gp_Pnt> out;
    for (std::size_t k = 0; k < kChainSamples; ++k) {
        out.push_back(points[k * (points.size() - 1) / (kChainSamples - 1)]);
    }
    return out;
}

// The exact intersection of two elementary surfaces (planes, cylinders, cones, spheres, tori)
// as lines, circles and ellipses (IntAna_QuadQuadGeo); empty when the pair is not elementary
// or the answer is another kind of curve.
std::vector<Handle(Geom_Curve)> analytic_intersection(const Handle(Geom_Surface) & a,
                                                      const Handle(Geom_Surface) & b) {
    GeomAdaptor_Surface sa(a), sb(b);
    // Order: plane, cylinder, sphere, cone, torus (the order IntAna's constructors take).
    const auto rank = [](GeomAbs_SurfaceType t) {
        switch (t) {
            case GeomAbs_Plane:
                return 0;
            case GeomAbs_Cylinder:
                return 1;
            case GeomAbs_Sphere:
                return 2;
            case GeomAbs_Cone:
                return 3;
            case GeomAbs_Torus:
                return 4;
            default:
                return -1;
        }
    };
    int ra = rank(sa.GetType()), rb = rank(sb.GetType());
    if (ra < 0 || rb < 0) return {};
    const GeomAdaptor_Surface& lo = ra <= rb ? sa : sb;
    const GeomAdaptor_Surface& hi = ra <= rb ? sb : sa;
    if (ra > rb) std::swap(ra, rb);
    const double tol = Precision::Confusion(), ang = Precision::Angular();
    IntAna_QuadQuadGeo q;
    switch (ra * 5 + rb) {
        case 0:
            q = IntAna_QuadQuadGeo(lo.Plane(), hi.Plane(), ang, tol);
            break;
        case 1:
            q = IntAna_QuadQuadGeo(lo.Plane(), hi.Cylinder(), ang, tol);
            break;
        case 2:
            q = IntAna_QuadQuadGeo(lo.Plane(), hi.Sphere());
            break;
        case 3:
            q = IntAna_QuadQuadGeo(lo.Plane(), hi.Cone(), ang, tol);
            break;
        case 4:
            q = IntAna_QuadQuadGeo(lo.Plane(), hi.Torus(), tol);
            break;
        case 6:
            q = IntAna_QuadQuadGeo(lo.Cylinder(), hi.Cylinder(), tol);
            break;
        case 7:
            q = IntAna_QuadQuadGeo(lo.Cylinder(), hi.Sphere(), tol);
            break;
        case 8:
            q = IntAna_QuadQuadGeo(lo.Cylinder(), hi.Cone(), tol);
            break;
        case 9:
            q = IntAna_QuadQuadGeo(lo.Cylinder(), hi.Torus(), tol);
            break;
        case 12:
            q = IntAna_QuadQuadGeo(lo.Sphere(), hi.Sphere(), tol);
            break;
        case 13:
            q = IntAna_QuadQuadGeo(lo.Sphere(), hi.Cone(), tol);
            break;
        case 14:
            q = IntAna_QuadQuadGeo(lo.Sphere(), hi.Torus(), tol);
            break;
        case 18:
            q = IntAna_QuadQuadGeo(lo.Cone(), hi.Cone(), tol);
            break;
        case 19:
            q = IntAna_QuadQuadGeo(lo.Cone(), hi.Torus(), tol);
            break;
        case 24:
            q = IntAna_QuadQuadGeo(lo.Torus(), hi.Torus(), tol);
            break;
        default:
            return {};
    }
    std::vector<Handle(Geom_Curve)> out;
    if (!q.IsDone()) return out;
    for (int i = 1; i <= q.NbSolutions(); ++i) {
        switch (q.TypeInter()) {
            case IntAna_Line:
                out.push_back(new Geom_Line(q.Line(i)));
                break;
            case IntAna_Circle:
                out.push_back(new Geom_Circle(q.Circle(i)));
                break;
            case IntAna_Ellipse:
                out.push_back(new Geom_Ellipse(q.Ellipse(i)));
                break;
            default:
                return {};
        }
    }
    return out;
}

// The spine of a tube surface nearest `p` and the tube's radius: a cylinder's axis, a torus's
// center circle, a sphere's center. False for other kinds (and on a torus's axis).
bool spine_point(const Surface& s, Vec3 p, Vec3& c, double& radius) {
    const Vec3 axis = normalized(s.axis);
    switch (s.kind) {
        case FitKind::kCylinder:
            c = s.point + dot(p - s.point, axis) * axis;
            radius = s.radius;
            return true;
        case FitKind::kTorus: {
            const Vec3 radial = perpendicular_part(p - s.point, axis);
            if (norm(radial) <= 1e-12 * std::fabs(s.radius)) return false;
            c = s.point + s.radius * normalized(radial);
            radius = s.minor_radius;
            return true;
        }
        case FitKind::kSphere:
            c = s.point;
            radius = s.radius;
            return true;
        default:
            return false;
    }
}

// Where `tube` touches the tangent surface `other` nearest `p`: the foot on `other` of the
// tube's spine point `c` nearest p. Two tubes whose spines meet (a corner torus running into
// the edge fillet of the same radius) touch along a whole section: every point of it is a foot,
// and p says which. False where p has no spine point (a torus's axis) or lies on the spine.
bool contact_point(const Surface& tube, const Surface& other, Vec3 p, double tolerance, Vec3& c,
                   double& radius, Vec3& out) {
    if (!spine_point(tube, p, c, radius)) return false;
    Vec3 c2;
    double r2 = 0;
    if (spine_point(other, c, c2, r2) && norm(c2 - c) <= tolerance) {
        if (norm(p - c) <= 0) return false;
        out = c + radius * normalized(p - c);
    } else {
        out = closest_point(other, c);
    }
    return true;
}

// The direction of the spine of `s` (a cylinder or torus) at its point nearest `c`.
Vec3 spine_direction(const Surface& s, Vec3 c) {
    const Vec3 axis = normalized(s.axis);
    if (s.kind == FitKind::kCylinder) return axis;
    return normalized(cross(axis, perpendicular_part(c - s.point, axis)));
}

// Two tubes of one radius whose spines touch: an edge fillet running into the corner torus of
// the same radius (a rolling-ball corner), a torus into a torus or into a ball. They meet along
// the tube's section through the point `s0` where their spines touch, which is returned. Found
// as the point of a's spine nearest b's spine, searched `span` either way of p's spine point:
// well conditioned although the spines are tangent there (their gap grows with the square of
// the step along them, and a tilt of a fitted axis by e moves it by e times the spine's
// radius), unlike any point solved onto the surfaces themselves, which slides along the
// contact. False when a and b are not such a pair (both cylinders, radii or spines apart by
// more than `tolerance`).
bool spine_junction(const Surface& a, const Surface& b, Vec3 p, double tolerance, double span,
                    Vec3& s0) {
    Vec3 ca, cb;
    double ra = 0, rb = 0;
    if (!spine_point(a, p, ca, ra) || !spine_point(b, p, cb, rb)) return false;
    if (std::abs(ra - rb) > tolerance) return false;
    if (a.kind == FitKind::kCylinder && b.kind == FitKind::kCylinder) return false;
    if (a.kind == FitKind::kSphere || b.kind == FitKind::kSphere) {
        // A ball's spine is its center: the junction when the other's spine passes through it.
        const Surface& ball = a.kind == FitKind::kSphere ? a : b;
        const Surface& other = a.kind == FitKind::kSphere ? b : a;
        Vec3 c;
        double r = 0;
        if (other.kind == FitKind::kSphere || !spine_point(other, ball.point, c, r) ||
            norm(c - ball.point) > tolerance) {
            return false;
        }
        s0 = ball.point;
        return true;
    }
    // Along the spine of the one that is not a cylinder's axis when one is: a torus's circle
    // walked by steps along its tangent, each put back on the circle.
    const Surface& walk = a.kind == FitKind::kCylinder ? b : a;
    const Surface& to = a.kind == FitKind::kCylinder ? a : b;
    Vec3 c0;
    double r = 0;
    if (!spine_point(walk, p, c0, r)) return false;
    const Vec3 t = spine_direction(walk, c0);
    const auto at = [&](double step, Vec3& x) {
        double rr = 0;
        return spine_point(walk, c0 + step * t, x, rr);
    };
    const auto gap = [&](double step) {
        Vec3 x, y;
        double rr = 0;
        if (!at(step, x) || !spine_point(to, x, y, rr)) return 1e300;
        return norm(x - y);
    };
    // Golden-section search: the gap is unimodal along a spine tangent to the other.
    constexpr double kGolden = 0.6180339887498949;
    constexpr int kIterations = 80;
    double lo = -span, hi = span;
    double x1 = hi - kGolden * (hi - lo), x2 = lo + kGolden * (hi - lo);
    double f1 = gap(x1), f2 = gap(x2);
    for (int i = 0; i < kIterations; ++i) {
        if (f1 <= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - kGolden * (hi - lo);
            f1 = gap(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + kGolden * (hi - lo);
            f2 = gap(x2);
        }
    }
    const double best = 0.5 * (lo + hi);
    // At the end of the span: the gap still falling, the junction is further than that. Within
    // the tolerance at either end: the spines run together (one fillet's torus in two regions),
    // and no point of them is the junction.
    if (gap(best) > tolerance || std::abs(best) >= 0.99 * span || !(gap(-span) > tolerance) ||
        !(gap(span) > tolerance))
        return false;
    return at(best, s0);
}

// Whether the spines of the tubes `a` and `b` (radius r) run together at their junction s0:
// their directions there, `t` (a's), are close enough that the plane their tubes meet in (the
// bisector of the two) is within `tolerance` of a's section across the tube. Two fillets whose
// spines cross at a few degrees (NIST CTC 05's tilted and level tori of 6.35 mm) meet in a
// mitre instead, and their section put the curve 1.9 mm off the mesh.
bool spines_tangent(const Surface& a, const Surface& b, Vec3 s0, double r, double tolerance,
                    Vec3& t) {
    t = spine_direction(a, s0);
    Vec3 tb = spine_direction(b, s0);
    if (dot(t, tb) < 0) tb = -1.0 * tb;
    const double sin_half = 0.5 * norm(t - tb);
    return r * sin_half <= tolerance;
}

// Where the spine point `c` of the tube `s` (a cylinder or torus) is along its spine: the
// position along a cylinder's axis, the angle about a torus's axis (in (-pi, pi]).
double spine_parameter(const Surface& s, Vec3 c) {
    const Vec3 axis = normalized(s.axis);
    if (s.kind == FitKind::kCylinder) return dot(c - s.point, axis);
    const Vec3 x = any_perpendicular(axis), y = cross(axis, x);
    const Vec3 r = c - s.point;
    return std::atan2(dot(r, y), dot(r, x));
}

// The contact feet `feet` of a tube along a chain, whose spine points are at `along`
// (spine_parameter()), put in the order of their spine points between the chain's two ends;
// feet that repeat one before or lie beyond an end are dropped. The contact curve runs with
// the spine, but the chain's vertices zigzag across it: where the mesh's border turns back,
// its feet backtrack, and the periodic cubic through them loops (the turned shaft's shoulder
// fillet at 386k facets: 6 of its 585 steps went back or repeated, and its plane's wire
// crossed itself). Left as they are for a ball (its spine is a point), and for a loop that
// does not go once round a torus's axis.
void in_spine_order(const Surface& tube, const std::vector<double>& along,
                    std::vector<gp_Pnt>& feet) {
    const std::size_t n = feet.size();
    if (n < 3 || (tube.kind != FitKind::kCylinder && tube.kind != FitKind::kTorus)) return;
    // Unwrapped: each step of a torus's angle taken the short way round.
    std::vector<double> u(n, 0.0);
    for (std::size_t k = 1; k < n; ++k) {
        double d = along[k] - along[k - 1];
        if (tube.kind == FitKind::kTorus) d = std::remainder(d, 2 * std::numbers::pi);
        u[k] = u[k - 1] + d;
    }
    const double span = u[n - 1] - u[0];
    if (!(std::abs(span) > 0)) return;
    const bool loop = feet.front().IsEqual(feet.back(), 0);
    if (loop && (tube.kind != FitKind::kTorus ||
                 std::abs(std::abs(span) - 2 * std::numbers::pi) > std::numbers::pi))
        return;
    // A chain along the contact goes back a few steps by little; one that is not along it (a
    // contact across the spine, a chain that leaves the junction) by a third of its steps or
    // more, and is left in its order.
    std::size_t back_steps = 0;
    double back = 0;
    for (std::size_t k = 1; k < n; ++k) {
        const double d = (u[k] - u[k - 1]) * (span > 0 ? 1 : -1);
        if (d <= 0) {
            ++back_steps;
            back -= d;
        }
    }
    if (back_steps == 0 || static_cast<double>(back_steps) > kBacktrackShare * (n - 1) ||
        back > kBacktrackShare * std::abs(span))
        return;
    std::vector<std::size_t> inner;
    for (std::size_t k = 1; k + 1 < n; ++k) {
        const double f = (u[k] - u[0]) / span;
        if (f > 0 && f < 1) inner.push_back(k);
    }
    std::stable_sort(inner.begin(), inner.end(),
                     [&](std::size_t i, std::size_t j) { return (u[i] - u[j]) * span < 0; });
    std::vector<gp_Pnt> sorted{feet.front()};
    double last = u[0];
    for (std::size_t k : inner) {
        if (!((u[k] - last) * span > 0)) continue;
        sorted.push_back(feet[k]);
        last = u[k];
    }
    sorted.push_back(feet.back());
    feet = std::move(sorted);
}

// Where two tangent surfaces touch along a chain: one of them a tube (the one of smaller radius
// when both are, unless its spine stands still: kStillSpine), the foot on the other of the
// tube's spine point nearest each chain vertex.
// False when neither is a tube, or a foot is not at the tube's radius from its spine within
// `tolerance` (the surfaces do not touch there).
bool tangency_points(const Surface& a, const Surface& b, const Mesh& m,
                     const std::vector<VertexId>& chain, double tolerance,
                     double junction_tolerance, std::vector<gp_Pnt>& out) {
    Vec3 c;
    double ra = 0, rb = 0;
    const Vec3 p0 = m.position(chain[chain.size() / 2]);
    const bool ta = spine_point(a, p0, c, ra), tb = spine_point(b, p0, c, rb);
    if (!ta && !tb) return false;
    // The length of the path of a surface's spine points along the chain (0 for a ball).
    const auto travel = [&](const Surface& s) {
        double length = 0;
        Vec3 prev, at;
        double r = 0;
        for (std::size_t k = 0; k < chain.size(); ++k) {
            if (!spine_point(s, m.position(chain[k]), at, r)) return 0.0;
            if (k > 0) length += norm(at - prev);
            prev = at;
        }
        return length;
    };
    // The tube of smaller radius, unless its spine stands still along the chain while the
    // other's runs with it (kStillSpine).
    bool a_tube = ta && (!tb || ra <= rb);
    if (ta && tb) {
        const double along_a = travel(a), along_b = travel(b);
        if (a_tube && along_a < kStillSpine * along_b) {
            a_tube = false;
        } else if (!a_tube && along_b < kStillSpine * along_a) {
            a_tube = true;
        }
    }
    const Surface& tube = a_tube ? a : b;
    const Surface& other = a_tube ? b : a;
    out.clear();
    // Two tubes whose spines touch (spine_junction()): the section through the junction.
    // The foot of each chain point on the spine touches the other's spine anywhere in the
    // band where their gap is within the tolerance (0.7 mm either way on the fillet block's
    // 4 mm fillets at 345k facets), and the curve would follow the chain across it.
    const double r0 = a_tube ? ra : rb;
    Vec3 s0;
    const auto in_band = [&](VertexId v) {
        Vec3 c1, c2;
        double r1 = 0, r2 = 0;
        return spine_point(tube, m.position(v), c1, r1) && spine_point(other, c1, c2, r2) &&
               norm(c2 - c1) <= tolerance;
    };
    Vec3 t;
    if (tube.kind != FitKind::kSphere && other.kind != FitKind::kSphere &&
        std::all_of(chain.begin(), chain.end(), in_band) &&
        spine_junction(tube, other, p0, junction_tolerance, kJunctionSpan * r0, s0) &&
        spines_tangent(tube, other, s0, r0, junction_tolerance, t)) {
        for (VertexId v : chain) {
            const Vec3 d = perpendicular_part(m.position(v) - s0, t);
            if (norm(d) <= 0) return false;
            out.push_back(pnt(s0 + r0 * normalized(d)));
        }
        return true;
    }
    std::vector<double> along;
    along.reserve(chain.size());
    for (VertexId v : chain) {
        double radius = 0;
        Vec3 q;
        if (!contact_point(tube, other, m.position(v), tolerance, c, radius, q)) return false;
        if (std::abs(norm(q - c) - radius) > tolerance) return false;
        out.push_back(pnt(q));
        along.push_back(spine_parameter(tube, c));
    }
    in_spine_order(tube, along, out);
    return true;
}

// A corner where two of its surfaces are tangent, one of them a tube (a fillet running into
// its plane or into another fillet): common_point() leaves it about where the mesh vertex was,
// anywhere in the band where the two are within the tolerance of each other (sqrt(2 r tol)
// across: 1.9 mm for a 30 mm radius at 0.06 mm), which cuts the fillet's face short or long by
// that much. The corner is where their contact curve meets the other surfaces: alternately the
// contact point nearest (contact_point(), as tangency_points()) and the step along
// the spine's direction that puts it on the others. False (and `p` unchanged) when no such
// pair is there, or the other surfaces do not fix the point along the contact.
bool tangent_corner(std::span<const Surface> on, double tolerance, Vec3& p, double& tube_radius,
                    bool& junction) {
    constexpr int kSteps = 20;
    const double sin_tangent = std::sin(kTangentAngle);
    junction = false;
    for (std::size_t i = 0; i < on.size(); ++i) {
        for (std::size_t j = i + 1; j < on.size(); ++j) {
            if (norm(cross(normal_at(on[i], p), normal_at(on[j], p))) > sin_tangent) continue;
            Vec3 c;
            double ri = 0, rj = 0;
            const bool ti = spine_point(on[i], p, c, ri), tj = spine_point(on[j], p, c, rj);
            if (!ti && !tj) continue;
            // Two tubes meeting at a section (spine_junction()), every other surface tangent to
            // them there (the face both fillets run along): the corner is that surface's foot
            // from the junction, searched within two tube radii of p. Stepping along the
            // contact below finds nothing there: the other surface is tangent to it too. Held to
            // the tolerance: a fillet fitted thinner than that (the fillet block's 4 mm one came
            // 0.02 mm thin at 345k facets) keeps its plain corner; allowing 10 x the tolerance
            // moved corners of CTC 04 and FTC 07 off the mesh (mesh->solid 0.25 -> 0.69 delta).
            Vec3 s0;
            if (ti && tj && on.size() == 3 &&
                spine_junction(on[i], on[j], p, tolerance, kJunctionSpan * ri, s0)) {
                const Surface& third = on[3 - i - j];
                const Vec3 q = closest_point(third, s0);
                double residual = 0;
                for (const Surface& s : on) residual = std::max(residual, distance(s, q));
                if (residual <= tolerance) {
                    p = q;
                    tube_radius = ri;
                    junction = true;
                    return true;
                }
            }
            const bool i_tube = ti && (!tj || ri <= rj);
            const Surface& tube = i_tube ? on[i] : on[j];
            const Surface& other = i_tube ? on[j] : on[i];
            if (tube.kind == FitKind::kSphere) continue;  // a sphere's contact has no direction
            Vec3 q = p;
            bool fixed = true;
            for (int step = 0; step < kSteps; ++step) {
                double radius = 0;
                if (!contact_point(tube, other, q, tolerance, c, radius, q)) return false;
                const Vec3 t = spine_direction(tube, c);
                // Least squares along t onto the remaining surfaces (linearised).
                double num = 0, den = 0;
                for (std::size_t k = 0; k < on.size(); ++k) {
                    if (k == i || k == j) continue;
                    const Vec3 n = normal_at(on[k], q);
                    const double f = dot(q - closest_point(on[k], q), n);
                    const double g = dot(n, t);
                    num += f * g;
                    den += g * g;
                }
                if (den <= sin_tangent * sin_tangent) {
                    fixed = false;
                    break;
                }
                const double move = -num / den;
                q = q + move * t;
                if (std::abs(move) <= 1e-12 * (1 + norm(q))) break;
            }
            if (!fixed) continue;
            p = q;
            tube_radius = i_tube ? ri : rj;
            return true;
        }
    }
    return false;
}

// Whether `c` leaves the polyline through `points` by more than `accept` between them: the
// chain's points lie on a branch that bulges away between them (an ellipse arc between two
// close corners of a steep plane on a cylinder), or only the ends were there to check.
bool strays_from(const ChainCurve& c, const std::vector<gp_Pnt>& points, double accept) {
    const int n = 4 * static_cast<int>(std::min(points.size(), kChainSamples)) + 8;
    for (int k = 1; k < n; ++k) {
        const gp_Pnt q = c.curve->Value(c.first + (c.last - c.first) * k / n);
        double best = 1e300;
        for (std::size_t i = 0; i + 1 < points.size() && best > accept; ++i) {
            const gp_Vec ab(points[i], points[i + 1]), aq(points[i], q);
            const double len2 = ab.SquareMagnitude();
            const double t = len2 > 0 ? std::clamp(aq.Dot(ab) / len2, 0.0, 1.0) : 0.0;
            best = std::min(best, q.Distance(points[i].Translated(t * ab)));
        }
        if (best > accept) return true;
    }
    return false;
}

// The intersection branch of `a` and `b` along `points`, within `accept` of all of them:
// analytic for elementary pairs, else OpenCASCADE's general surface intersection.
// Where a plane crosses a linear extrusion of a B-spline profile (fit_bspline()'s extrusions:
// num_v 4, each row the profile moved along one line): exactly the profile moved along the
// extrusion onto the plane — the same knots, each pole projected along the direction — since
// the extrusion is P(u) + t e and the plane's equation fixes t as an affine function of P(u).
// Null unless one surface is a plane and the other such an extrusion, crossing at more than
// kTangentAngle (nearer parallel, the projection blows up).
Handle(Geom_Curve) plane_extrusion_curve(const Surface& a, const Surface& b) {
    const Surface* plane = a.kind == FitKind::kPlane   ? &a
                           : b.kind == FitKind::kPlane ? &b
                                                       : nullptr;
    const Surface* ext = plane == &a ? &b : &a;
    if (!plane || ext->kind != FitKind::kBSpline || !ext->bspline || !ext->bspline->extruded)
        return {};
    const BSplineSurface& bs = *ext->bspline;
    if (bs.num_v < 2 || bs.num_u <= bs.degree) return {};
    const Vec3 along = bs.poles[static_cast<std::size_t>(bs.num_u * (bs.num_v - 1))] - bs.poles[0];
    if (!(norm(along) > 0)) return {};
    const Vec3 e = normalized(along), n = plane->axis;
    const double ne = dot(n, e);
    if (!(std::abs(ne) > std::sin(kTangentAngle))) return {};
    TColgp_Array1OfPnt poles(1, bs.num_u);
    for (int i = 0; i < bs.num_u; ++i) {
        const Vec3 p = bs.poles[static_cast<std::size_t>(i)];
        poles.SetValue(i + 1, pnt(p + (dot(n, plane->point - p) / ne) * e));
    }
    TColStd_Array1OfReal knots(1, 1);
    TColStd_Array1OfInteger mults(1, 1);
    uniform_knots(bs.num_u, bs.degree, knots, mults);
    return new Geom_BSplineCurve(poles, knots, mults, bs.degree);
}

// The meridian of a surface of revolution in the half-plane (rho >= 0, h) of an axis through
// `o` along unit `d`: a line through (rho, h) along (drho, dh), or a circle of center (rho, h)
// and `radius`. A torus's is its tube circle on the region's side (center at R, which is
// negative for a lemon); a cone's the line of its nappe.
struct Meridian {
    bool circle = false;
    double rho = 0, h = 0, drho = 0, dh = 0, radius = 0;
};

// Whether `s` is a surface of revolution about the axis (o, d), and its meridian. Axes fitted
// separately differ by their noise; the circles are kept only where the chain's points lie
// within the edge tolerance of them (intersection_curve), so this only spares the work.
bool meridian_about(const Surface& s, Vec3 o, Vec3 d, double scale, Meridian& m) {
    constexpr double kCoaxial = 1e-4;
    const Vec3 axis = normalized(s.axis);
    const bool parallel = norm(cross(axis, d)) <= kCoaxial;
    const auto on_axis = [&](Vec3 p) {
        const Vec3 w = p - o;
        return norm(w - dot(w, d) * d) <= kCoaxial * scale;
    };
    const double h = dot(s.point - o, d);
    switch (s.kind) {
        case FitKind::kPlane:
            if (!parallel) return false;
            m = {false, 0, h, 1, 0, 0};
            return true;
        case FitKind::kCylinder:
            if (!parallel || !on_axis(s.point)) return false;
            m = {false, s.radius, 0, 0, 1, 0};
            return true;
        case FitKind::kCone: {
            if (!parallel || !on_axis(s.point)) return false;
            const double grow = dot(axis, d) > 0 ? std::tan(s.angle) : -std::tan(s.angle);
            m = {false, s.radius, h, grow, 1, 0};
            return true;
        }
        case FitKind::kSphere:
            if (!on_axis(s.point)) return false;
            m = {true, 0, h, 0, 0, s.radius};
            return true;
        case FitKind::kTorus:
            if (!parallel || !on_axis(s.point)) return false;
            m = {true, s.radius, h, 0, 0, s.minor_radius};
            return true;
        default:
            return false;
    }
}

// Where two coaxial surfaces of revolution meet: circles about their axis, one per crossing
// of their meridians off the axis. IntAna's answers assume a torus's tube circle on the
// surface's side of the axis and give none on the inner part of a spindle torus (a domed
// head meeting its flat top or its side); empty when the pair is not coaxial or its meridians
// do not cross.
std::vector<Handle(Geom_Curve)> coaxial_circles(const Surface& a, const Surface& b) {
    const Surface* ref =
        a.kind == FitKind::kCylinder || a.kind == FitKind::kCone || a.kind == FitKind::kTorus ? &a
                                                                                              : &b;
    if (ref->kind != FitKind::kCylinder && ref->kind != FitKind::kCone &&
        ref->kind != FitKind::kTorus)
        return {};
    const Vec3 o = ref->point, d = normalized(ref->axis);
    const double scale = std::max({norm(a.point - o), norm(b.point - o), std::fabs(a.radius),
                                   std::fabs(b.radius), a.minor_radius, b.minor_radius, 1.0});
    Meridian ma, mb;
    if (!meridian_about(a, o, d, scale, ma) || !meridian_about(b, o, d, scale, mb)) {
        return {};
    }
    if (ma.circle && !mb.circle) std::swap(ma, mb);
    std::vector<std::array<double, 2>> hits;  // (rho, h)
    if (!ma.circle && !mb.circle) {
        // Lines: p_a + s u_a = p_b + t u_b.
        const double det = ma.drho * (-mb.dh) - ma.dh * (-mb.drho);
        if (std::fabs(det) <= 1e-12 * std::hypot(ma.drho, ma.dh) * std::hypot(mb.drho, mb.dh))
            return {};
        const double rx = mb.rho - ma.rho, ry = mb.h - ma.h;
        const double t = (rx * (-mb.dh) - ry * (-mb.drho)) / det;
        hits.push_back({ma.rho + t * ma.drho, ma.h + t * ma.dh});
    } else if (!ma.circle) {
        // Line and circle: |p + t u - c|^2 = r^2.
        const double ul = std::hypot(ma.drho, ma.dh);
        const double ux = ma.drho / ul, uy = ma.dh / ul;
        const double wx = ma.rho - mb.rho, wy = ma.h - mb.h;
        const double bq = wx * ux + wy * uy, cq = wx * wx + wy * wy - mb.radius * mb.radius;
        const double disc = bq * bq - cq;
        if (disc < 0) return {};
        for (const double t : {-bq - std::sqrt(disc), -bq + std::sqrt(disc)})
            hits.push_back({ma.rho + t * ux, ma.h + t * uy});
    } else {
        // Circles: the radical line, then the chord's half-length.
        const double dx = mb.rho - ma.rho, dy = mb.h - ma.h, dist = std::hypot(dx, dy);
        if (!(dist > 0)) return {};
        const double along =
            (dist * dist + ma.radius * ma.radius - mb.radius * mb.radius) / (2 * dist);
        const double half2 = ma.radius * ma.radius - along * along;
        if (half2 < 0) return {};
        const double half = std::sqrt(half2), ex = dx / dist, ey = dy / dist;
        const double mx = ma.rho + along * ex, my = ma.h + along * ey;
        hits.push_back({mx - half * ey, my + half * ex});
        hits.push_back({mx + half * ey, my - half * ex});
    }
    std::vector<Handle(Geom_Curve)> out;
    for (const auto& [rho, h] : hits) {
        if (!(rho > kMinTolerance) || !std::isfinite(h)) continue;
        const Vec3 c = o + h * d;
        out.push_back(new Geom_Circle(gp_Ax2(pnt(c), gp_Dir(d.x, d.y, d.z)), rho));
    }
    return out;
}

bool intersection_curve(const Handle(Geom_Surface) & a, const Handle(Geom_Surface) & b,
                        const Surface& sa, const Surface& sb, const std::vector<gp_Pnt>& points,
                        bool closed, double accept, ChainCurve& out, bool& analytic) {
    const std::vector<gp_Pnt> samples = chain_samples(points);
    const auto best_of = [&](const std::vector<Handle(Geom_Curve)>& lines) {
        bool found = false;
        for (const Handle(Geom_Curve) & line : lines) {
            ChainCurve c;
            if (!trim_along(line, samples, closed, c) || c.deviation > accept ||
                strays_from(c, points, accept)) {
                continue;
            }
            if (!found || c.deviation < out.deviation) {
                out = c;
                found = true;
            }
        }
        return found;
    };
    analytic = true;
    if (best_of(analytic_intersection(a, b))) return true;
    if (const Handle(Geom_Curve) c = plane_extrusion_curve(sa, sb); !c.IsNull() && best_of({c}))
        return true;
    if (best_of(coaxial_circles(sa, sb))) return true;
    analytic = false;
    GeomAPI_IntSS inter(a, b, Precision::Confusion());
    if (!inter.IsDone()) return false;
    std::vector<Handle(Geom_Curve)> lines;
    for (int i = 1; i <= inter.NbLines(); ++i) lines.push_back(inter.Line(i));
    return best_of(lines);
}

// The line and the circle nearest `points` (fit_line(), fit_circle()), for a chain whose curve
// may be one: empty for fewer than three points or points all in one place; no circle for
// three (it would pass through them whatever they are).
std::vector<Handle(Geom_Curve)> line_and_circle(const std::vector<gp_Pnt>& points) {
    if (points.size() < 3) return {};
    std::vector<Vec3> p;
    p.reserve(points.size());
    for (const gp_Pnt& q : points) p.push_back(vec(q));
    std::vector<Handle(Geom_Curve)> out;
    Vec3 at, along;
    if (!fit_line(p, at, along)) return out;
    out.push_back(new Geom_Line(pnt(at), gp_Dir(along.x, along.y, along.z)));
    Vec3 center, normal;
    double radius = 0;
    if (p.size() >= 4 && std::isfinite(fit_circle(p, center, normal, radius)) && radius > 0) {
        out.push_back(
            new Geom_Circle(gp_Ax2(pnt(center), gp_Dir(normal.x, normal.y, normal.z)), radius));
    }
    return out;
}

// `points` without those behind their neighbours, where the polyline through them would turn
// back by more than a right angle; the first point is always kept, the last may replace the
// points before it.
std::vector<gp_Pnt> forward_points(const std::vector<gp_Pnt>& points) {
    std::vector<gp_Pnt> kept;
    kept.reserve(points.size());
    for (const gp_Pnt& q : points) {
        while (kept.size() >= 2 &&
               gp_Vec(kept[kept.size() - 2], kept.back()).Dot(gp_Vec(kept.back(), q)) < 0) {
            kept.pop_back();
        }
        kept.push_back(q);
    }
    return kept;
}

// A curve through `points` (already on both surfaces): a cubic interpolation, periodic when
// the chain is closed, or (`linear`) the degree-1 B-spline through them, chord-length knots;
// or, when `approximate` is positive and the chain open, a C2 B-spline of degree 3 to 8 within
// `approximate` of them (through the ends), with as few poles as that takes: a fine mesh's
// chain has hundreds of points, and an interpolation as many poles, each written to the STEP
// with the curve's two curves on the surfaces.
bool fitted_curve(const std::vector<gp_Pnt>& points, bool closed, bool linear, ChainCurve& out,
                  double approximate = 0) {
    std::vector<gp_Pnt> p;
    for (const gp_Pnt& q : points) {
        if (p.empty() || p.back().Distance(q) > 10 * kMinTolerance) p.push_back(q);
    }
    if (closed && p.size() > 1 && p.back().Distance(p.front()) <= 10 * kMinTolerance) p.pop_back();
    // A chain point behind its neighbours is dropped: a corner solved a little past the chain's
    // first interior vertex, or an interior point that slid along a tangent junction, would
    // otherwise fold the curve back on itself (a self-intersecting wire on the surface).
    if (!closed) p = forward_points(p);
    if (p.size() < (closed ? 3u : 2u)) return false;
    // OpenCASCADE throws where it finds the points unfit for a curve (tangency feet heaped on
    // one another, as kStillSpine's were): no curve from these points then, and the caller
    // tries its other points rather than give up the chain.
    try {
        if (linear) {
            if (closed) p.push_back(p.front());
            const int n = static_cast<int>(p.size());
            TColgp_Array1OfPnt poles(1, n);
            TColStd_Array1OfReal knots(1, n);
            TColStd_Array1OfInteger mults(1, n);
            double len = 0;
            for (int i = 0; i < n; ++i) {
                const auto k = static_cast<std::size_t>(i);
                if (i > 0) len += p[k].Distance(p[k - 1]);
                poles.SetValue(i + 1, p[k]);
                knots.SetValue(i + 1, len);
                mults.SetValue(i + 1, (i == 0 || i == n - 1) ? 2 : 1);
            }
            out.curve = new Geom_BSplineCurve(poles, knots, mults, 1);
            out.first = 0;
            out.last = len;
            out.deviation = 0;
            return true;
        }
        Handle(TColgp_HArray1OfPnt) arr = new TColgp_HArray1OfPnt(1, static_cast<int>(p.size()));
        for (std::size_t i = 0; i < p.size(); ++i) arr->SetValue(static_cast<int>(i) + 1, p[i]);
        // The whole curve.
        const auto whole = [&out](const Handle(Geom_Curve) & c) {
            out.curve = c;
            out.first = c->FirstParameter();
            out.last = c->LastParameter();
            out.deviation = 0;
            return true;
        };
        if (approximate > 0) {
            if (closed || p.size() <= kApproximateFrom) return false;
            GeomAPI_PointsToBSpline fit(arr->Array1(), 3, 8, GeomAbs_C2, approximate);
            return fit.IsDone() && whole(fit.Curve());
        }
        // Two points: the segment between them, as a line (the cubic through them is that
        // segment too, written with four poles and as many on each surface).
        if (!closed && p.size() == 2) {
            out.curve = new Geom_Line(p[0], gp_Dir(gp_Vec(p[0], p[1])));
            out.first = 0;
            out.last = p[0].Distance(p[1]);
            out.deviation = 0;
            return true;
        }
        GeomAPI_Interpolate interp(arr, closed, kMinTolerance);
        interp.Perform();
        return interp.IsDone() && whole(interp.Curve());
    } catch (const Standard_Failure&) {
        return false;
    }
}

// `pts` with points inserted between each two by bisection: the middle of a span goes where
// `onto(p, q)` puts it (std::nullopt: the span stays straight) while that moves it by more than
// a quarter of `tolerance`, up to `depth` levels (2^depth - 1 points a span). A coarse mesh has
// few vertices along a curved junction (a free-form face meeting a plane).
template <class Onto>
std::vector<gp_Pnt> bisected(const std::vector<Vec3>& pts, const Onto& onto, double tolerance,
                             int depth) {
    std::vector<gp_Pnt> out;
    const auto split = [&](const auto& self, Vec3 p, Vec3 q, int level) -> void {
        if (level == 0) return;
        const std::optional<Vec3> w = onto(p, q);
        if (!w || !(norm(*w - 0.5 * (p + q)) > 0.25 * tolerance)) return;
        self(self, p, *w, level - 1);
        out.push_back(pnt(*w));
        self(self, *w, q, level - 1);
    };
    for (std::size_t i = 0; i < pts.size(); ++i) {
        if (i > 0) split(split, pts[i - 1], pts[i], depth);
        out.push_back(pnt(pts[i]));
    }
    return out;
}

// The chain's points with points solved onto both surfaces inserted between them wherever
// the straight segment strays from the surfaces by more than a quarter of `tolerance`
// (bisected(), up to 31 points a span).
std::vector<gp_Pnt> densified(const std::vector<gp_Pnt>& pts, std::span<const Surface> pair,
                              double tolerance) {
    std::vector<Vec3> v;
    v.reserve(pts.size());
    for (const gp_Pnt& p : pts) v.push_back(vec(p));
    const auto onto = [&](Vec3 p, Vec3 q) -> std::optional<Vec3> {
        const Vec3 mid = 0.5 * (p + q);
        const CommonPoint m = common_point(pair, mid);
        // A sagitta beyond a quarter of the chord means the solve left the junction (tangent
        // surfaces give it no grip along their common line): the chord stays.
        if (!(norm(m.point - mid) < 0.25 * norm(q - p)) || !(m.residual <= tolerance))
            return std::nullopt;
        return m.point;
    };
    return bisected(v, onto, tolerance, 5);
}

// A point of a tangent junction: `p` moved along the two surfaces' mean normal to midway
// between them. Solving onto both (common_point()) is ill-conditioned where they are tangent:
// the solution slides across the band where they are within the tolerance of each other, by
// (gap) / sin(angle); along the normal it moves only by the gap, and stays at the mesh vertex
// along the junction. Within half their gap of each surface there. Also the last resort where
// two surfaces meet at a shallow angle but do not cross on the chain (make_curve()).
Vec3 midway_point(const Surface& a, const Surface& b, Vec3 p) {
    constexpr int kSteps = 4;  // each step closes the gap to second order in the angle
    for (int k = 0; k < kSteps; ++k) {
        const Vec3 na = normal_at(a, p);
        Vec3 nb = normal_at(b, p);
        if (dot(na, nb) < 0) nb = -1.0 * nb;
        const Vec3 n = normalized(na + nb);
        const double da = dot(closest_point(a, p) - p, n), db = dot(closest_point(b, p) - p, n);
        p = p + 0.5 * (da + db) * n;
    }
    return p;
}

// The chain's points moved midway between two surfaces (midway_point()), with the
// middle of each span between two points also moved there while it is off them by more than a
// quarter of `tolerance` (bisected(), up to 15 points a span: a chain of one mesh edge between
// two corners, on curved surfaces).
std::vector<gp_Pnt> midway_points(const Surface& a, const Surface& b, const Mesh& m,
                                  const std::vector<VertexId>& chain, gp_Pnt p0, gp_Pnt p1,
                                  double tolerance) {
    std::vector<Vec3> pts;
    pts.reserve(chain.size());
    for (std::size_t k = 0; k < chain.size(); ++k) {
        pts.push_back(k == 0                  ? vec(p0)
                      : k + 1 == chain.size() ? vec(p1)
                                              : midway_point(a, b, m.position(chain[k])));
    }
    const auto onto = [&](Vec3 p, Vec3 q) -> std::optional<Vec3> {
        return midway_point(a, b, 0.5 * (p + q));
    };
    return bisected(pts, onto, tolerance, 4);
}

// The largest distance from the curve to the surfaces, at the midpoints of its spans between
// the chain's points and at the points themselves.
double curve_off_surfaces(const ChainCurve& c, const Surface& a, const Surface& b, int samples) {
    double worst = 0;
    for (int k = 0; k <= 2 * samples; ++k) {
        const double t = c.first + (c.last - c.first) * k / (2.0 * samples);
        const Vec3 p = vec(c.curve->Value(t));
        worst = std::max({worst, distance(a, p), distance(b, p)});
    }
    return worst;
}

struct Builder {
    const Mesh& m;
    const FaceMap<std::int32_t>& region;
    std::span<const RegionSurface> surfaces;
    RegionBorders borders;
    std::vector<RegionShape> shapes;
    std::vector<std::size_t> facets;  ///< per region
    // Per half-edge: the chain it lies on (-1 inside a region), and whether it runs along it.
    std::vector<std::int32_t> he_chain;
    std::vector<std::uint8_t> he_forward;
    // Per region: loops of (chain, runs along it).
    std::vector<std::vector<std::vector<std::pair<std::int32_t, bool>>>> loops;

    Builder(const Mesh& mesh, const FaceMap<std::int32_t>& r, std::span<const RegionSurface> s)
        : m(mesh), region(r), surfaces(s) {}

    void prepare() {
        borders = region_borders(m, region);
        const std::size_t nr = surfaces.size();
        shapes.assign(nr, {});
        std::vector<std::vector<FaceId>> faces(nr);
        for (std::uint32_t f = 0; f < m.num_faces(); ++f) {
            const FaceId id(f);
            const auto r = static_cast<std::size_t>(region[id]);
            const Vec3 n2 = m.face_normal_area2(id);
            const double a = 0.5 * norm(n2);
            const Vec3 c = (1.0 / 3) * (m.position(m.vertex(id, 0)) + m.position(m.vertex(id, 1)) +
                                        m.position(m.vertex(id, 2)));
            shapes[r].centroid = shapes[r].centroid + a * c;
            shapes[r].normal = shapes[r].normal + 0.5 * n2;
            shapes[r].area += a;
            faces[r].push_back(id);
        }
        facets.resize(nr);
        for (std::size_t r = 0; r < nr; ++r) facets[r] = faces[r].size();
        for (std::size_t r = 0; r < nr; ++r) {
            RegionShape& s = shapes[r];
            if (s.area > 0) s.centroid = (1.0 / s.area) * s.centroid;
            if (norm(s.normal) > 0) s.normal = normalized(s.normal);
            const std::size_t n = faces[r].size();
            const std::size_t k = std::min(n, kOrientationSamples);
            for (std::size_t i = 0; i < k; ++i) s.samples.push_back(faces[r][i * n / k]);
        }
        he_chain.assign(m.num_halfedges(), -1);
        he_forward.assign(m.num_halfedges(), 0);
        for (std::size_t c = 0; c < borders.chains.size(); ++c) {
            const auto& vs = borders.chains[c].vertices;
            for (std::size_t k = 0; k + 1 < vs.size(); ++k) {
                m.for_each_outgoing(vs[k], [&](HalfedgeId h) {
                    if (m.target(h) != vs[k + 1]) return;
                    he_chain[h.idx()] = static_cast<std::int32_t>(c);
                    he_forward[h.idx()] = 1;
                    const HalfedgeId t = m.twin(h);
                    if (t.is_valid()) he_chain[t.idx()] = static_cast<std::int32_t>(c);
                });
            }
        }
        // Loops: each region's border half-edges walked with the region on the left.
        loops.assign(nr, {});
        std::vector<std::uint8_t> seen(m.num_halfedges(), 0);
        for (std::uint32_t hi = 0; hi < m.num_halfedges(); ++hi) {
            if (seen[hi] || he_chain[hi] < 0) continue;
            const HalfedgeId h0(hi);
            const std::int32_t r = region[Mesh::face(h0)];
            std::vector<std::uint32_t> walk;
            HalfedgeId h = h0;
            do {
                seen[h.idx()] = 1;
                walk.push_back(h.idx());
                // The next border half-edge of r around the target vertex.
                HalfedgeId n = Mesh::next(h);
                while (he_chain[n.idx()] < 0) n = Mesh::next(m.twin(n));
                h = n;
            } while (h != h0 && walk.size() <= m.num_halfedges());
            // Start the loop where a chain starts: after a change of chain (a single closed
            // chain has none).
            std::size_t start = 0;
            for (std::size_t i = 0; i < walk.size(); ++i) {
                const std::size_t p = (i + walk.size() - 1) % walk.size();
                if (he_chain[walk[i]] != he_chain[walk[p]]) {
                    start = i;
                    break;
                }
            }
            std::vector<std::pair<std::int32_t, bool>> loop;
            for (std::size_t i = 0; i < walk.size(); ++i) {
                const std::uint32_t w = walk[(start + i) % walk.size()];
                if (loop.empty() || loop.back().first != he_chain[w]) {
                    loop.emplace_back(he_chain[w], he_forward[w] != 0);
                }
            }
            loops[static_cast<std::size_t>(r)].push_back(std::move(loop));
        }
    }
};

// How a chain's edge was made (the report's edges by curve).
enum class ChainKind : std::uint8_t { kIntersection, kTangency, kFitted };

// A chain's curve to make (build_surface_brep()): its regions' states and end points (what
// GeometryCache::Chain keys on), and the result.
struct CurveJob {
    std::size_t chain = 0;
    std::array<std::uint8_t, 4> state{};
    gp_Pnt p0, p1;
    ChainCurve cc;
    bool ok = false, intersected = false, touched = false, analytic = false;
};

// A face's loop on a cylinder, cone or torus, sampled in wire order: the points' surface
// parameters (u, the angle, unwrapped to run on continuously; a torus's v too), where each
// edge's samples start, and how many turns about the axis the loop makes.
struct UnwrappedLoop {
    std::vector<gp_Pnt2d> uv;
    std::vector<std::size_t> edge_start;
    int winding = 0;
    int tube_winding = 0;  // a torus's: turns round its tube (v)
};

// The (u, v) of a point on a cylinder, cone or torus, each periodic parameter taken within
// half a turn of `near`'s.
gp_Pnt2d revolution_uv(const GeomAdaptor_Surface& s, const gp_Pnt& p, const gp_Pnt2d& near) {
    constexpr double kTurn = 2 * std::numbers::pi;
    double u = 0, v = 0;
    if (s.GetType() == GeomAbs_Cylinder) {
        ElSLib::Parameters(s.Cylinder(), p, u, v);
    } else if (s.GetType() == GeomAbs_Cone) {
        ElSLib::Parameters(s.Cone(), p, u, v);
    } else if (s.GetType() == GeomAbs_Sphere) {
        ElSLib::Parameters(s.Sphere(), p, u, v);
    } else {
        ElSLib::Parameters(s.Torus(), p, u, v);
        v += kTurn * std::round((near.Y() - v) / kTurn);
    }
    u += kTurn * std::round((near.X() - u) / kTurn);
    return {u, v};
}

// The two isolines of `s` (a cylinder, cone, sphere or torus) at `points`' mean parameters:
// its generator and circle (a cylinder's, a cone's), its meridian and parallel (a sphere's, a
// torus's). Empty for other surfaces. A contact curve that is one of them lies on `s`
// exactly, and its curve on `s` is a line of (u, v), which the STEP then carries as such.
std::vector<Handle(Geom_Curve)> isolines_through(const Handle(Geom_Surface) & s,
                                                 const std::vector<gp_Pnt>& points) {
    const GeomAdaptor_Surface a(s);
    const GeomAbs_SurfaceType type = a.GetType();
    if (points.empty() || (type != GeomAbs_Cylinder && type != GeomAbs_Cone &&
                           type != GeomAbs_Sphere && type != GeomAbs_Torus)) {
        return {};
    }
    double su = 0, sv = 0;
    gp_Pnt2d near(0, 0);
    for (const gp_Pnt& p : points) {
        const gp_Pnt2d uv = revolution_uv(a, p, near);
        near = uv;
        su += uv.X();
        sv += uv.Y();
    }
    const double n = static_cast<double>(points.size());
    try {
        return {s->UIso(su / n), s->VIso(sv / n)};
    } catch (const Standard_Failure&) {
        return {};
    }
}

// The distance from `p` to the piece [first, last] of the line or circle `t`: to its nearest
// normal projection within the piece, or to the nearer end.
double distance_to_piece(const ChainCurve& t, const gp_Pnt& p) {
    double d = std::min(p.Distance(t.curve->Value(t.first)), p.Distance(t.curve->Value(t.last)));
    GeomAPI_ProjectPointOnCurve proj(p, t.curve);
    for (int i = 1; i <= proj.NbPoints(); ++i) {
        double u = proj.Parameter(i);
        if (t.curve->IsPeriodic()) {
            const double period = t.curve->Period();
            u += period * std::ceil((t.first - u) / period);  // the first turn at or past `first`
        }
        if (u >= t.first && u <= t.last) d = std::min(d, proj.Distance(i));
    }
    return d;
}

// The first of the isolines of `ga` and of `gb` through `points` (isolines_through()), then
// their least-squares line and circle (line_and_circle()), that passes within `feet` of every
// point, within `off` of both surfaces (curve_off_surfaces(), its deviation in `out`) and
// never farther than `stray` from the points' polyline; false when none does.
bool conic_through(const std::vector<gp_Pnt>& points, bool closed, const Handle(Geom_Surface) & ga,
                   const Handle(Geom_Surface) & gb, const Surface& sa, const Surface& sb,
                   double feet, double off, double stray, int samples, ChainCurve& out) {
    std::vector<Handle(Geom_Curve)> conics = isolines_through(ga, points);
    for (const Handle(Geom_Curve) & c : isolines_through(gb, points)) conics.push_back(c);
    for (const Handle(Geom_Curve) & c : line_and_circle(points)) conics.push_back(c);
    // Trimmed at an open chain's points with those that go back dropped (forward_points()): a
    // fine mesh's border zigzags across the contact, and its feet, along a line or circle,
    // step back and forth on it (the fillet block at 950k facets). Within `feet` of them all,
    // measured to the trimmed piece (distance_to_piece()).
    const std::vector<gp_Pnt> ahead = closed ? points : forward_points(points);
    for (const Handle(Geom_Curve) & c : conics) {
        ChainCurve t;
        if (!trim_along(c, ahead, closed, t) || t.deviation > feet) continue;
        if (ahead.size() < points.size() &&
            !std::all_of(points.begin(), points.end(),
                         [&](const gp_Pnt& p) { return distance_to_piece(t, p) <= feet; })) {
            continue;
        }
        t.deviation = curve_off_surfaces(t, sa, sb, samples);
        if (t.deviation <= off && !strays_from(t, points, stray)) {
            out = t;
            return true;
        }
    }
    return false;
}

// `start`: where the first point's periodic parameters are taken near (a torus's loops all
// near one, so that a band's two are on the same turn of the tube).
UnwrappedLoop unwrap_loop(const GeomAdaptor_Surface& s, const std::vector<TopoDS_Edge>& loop,
                          const gp_Pnt2d& start) {
    // Samples per edge: enough to follow a helical edge of a quarter turn within a few
    // percent of the radius, which is all the crossing test below needs.
    constexpr int kSamples = 12;
    UnwrappedLoop out;
    gp_Pnt first;
    for (const TopoDS_Edge& e : loop) {
        BRepAdaptor_Curve c(e);
        const bool reversed = e.Orientation() == TopAbs_REVERSED;
        out.edge_start.push_back(out.uv.size());
        for (int i = 0; i < kSamples; ++i) {
            const double t = static_cast<double>(i) / kSamples;
            const double w = reversed ? 1 - t : t;
            const gp_Pnt p =
                c.Value(c.FirstParameter() + w * (c.LastParameter() - c.FirstParameter()));
            if (out.uv.empty()) first = p;
            out.uv.push_back(revolution_uv(s, p, out.uv.empty() ? start : out.uv.back()));
        }
    }
    if (out.uv.empty()) return out;
    // Back at the start: the unwrapped angle has gone round `winding` whole turns.
    const gp_Pnt2d back = revolution_uv(s, first, out.uv.back());
    out.uv.push_back(back);
    out.winding =
        static_cast<int>(std::lround((back.X() - out.uv.front().X()) / (2 * std::numbers::pi)));
    out.tube_winding =
        static_cast<int>(std::lround((back.Y() - out.uv.front().Y()) / (2 * std::numbers::pi)));
    return out;
}

// Whether segment a-b crosses segment c-d away from a and b.
bool crosses(const gp_Pnt2d& a, const gp_Pnt2d& b, const gp_Pnt2d& c, const gp_Pnt2d& d) {
    const gp_XY r = b.XY() - a.XY(), q = d.XY() - c.XY();
    const double den = r ^ q;
    if (std::abs(den) <= 1e-300) return false;
    const gp_XY ac = c.XY() - a.XY();
    const double t = (ac ^ q) / den, w = (ac ^ r) / den;
    // The ends of a-b are on the loops: touching there is not crossing.
    constexpr double kEnd = 1e-6;
    return t > kEnd && t < 1 - kEnd && w >= 0 && w <= 1;
}

// Whether segment a-b crosses none of `loops`, each repeated `copies` turns either way.
bool clear_of_loops(const gp_Pnt2d& a, const gp_Pnt2d& b, const std::vector<UnwrappedLoop>& loops,
                    int copies) {
    constexpr double kTurn = 2 * std::numbers::pi;
    for (const UnwrappedLoop& l : loops) {
        for (int k = -copies; k <= copies; ++k) {
            const gp_Vec2d shift(k * kTurn, 0);
            for (std::size_t j = 0; j + 1 < l.uv.size(); ++j) {
                if (crosses(a, b, l.uv[j].Translated(shift), l.uv[j + 1].Translated(shift))) {
                    return false;
                }
            }
        }
    }
    return true;
}

// A seam edge of `face` from vertex `v0` at `p0` to `v1` at `p1` (surface parameters), straight
// in (u, v): used forward along that segment, reversed along it shifted `shift` in u (a turn,
// where the loop beside it has brought the wire). A null edge when it cannot be made.
TopoDS_Edge seam_edge(const TopoDS_Face& face, const TopoDS_Vertex& v0, const gp_Pnt2d& p0,
                      const TopoDS_Vertex& v1, const gp_Pnt2d& p1, double shift, double tolerance) {
    const double span = p0.Distance(p1);
    if (span <= Precision::PConfusion()) return {};
    Handle(Geom2d_Line) forward = new Geom2d_Line(p0, gp_Dir2d(p1.XY() - p0.XY()));
    Handle(Geom2d_Curve) backward =
        Handle(Geom2d_Curve)::DownCast(forward->Translated(gp_Vec2d(shift, 0)));
    BRep_Builder B;
    TopoDS_Edge seam;
    B.MakeEdge(seam);
    B.UpdateEdge(seam, forward, face, tolerance);
    B.Range(seam, 0, span);
    B.Add(seam, v0.Oriented(TopAbs_FORWARD));
    B.Add(seam, v1.Oriented(TopAbs_REVERSED));
    if (!BRepLib::BuildCurve3d(seam, tolerance)) return {};
    B.UpdateEdge(seam, forward, backward, face, tolerance);
    B.Range(seam, 0, span);
    return seam;
}

// The wires of a face on a cone with one loop that goes once round the axis (the face is a cap
// round the apex: CTC 01's and CTC 05's drill points, cut across by a slot), with that loop
// closed by a seam along the ruling from one of its vertices to the apex and a degenerated
// edge there, which is how OpenCASCADE bounds a face at a cone's apex; ShapeFix_Face left such
// wires open (BRepCheck_NotClosed). A spindle torus (minor radius over major, FTC 07's corner
// blends) has two such points on its axis, where R + r cos v = 0; a cap there is closed the same
// way, the seam along a meridian. The seam from the nearest vertex to the point whose ruling
// crosses no loop; an empty result when the loops are not such a cap or no ruling is clear.
std::vector<std::vector<TopoDS_Edge>> seamed_cap(const TopoDS_Face& face,
                                                 const std::vector<std::vector<TopoDS_Edge>>& wires,
                                                 const std::vector<UnwrappedLoop>& loops,
                                                 std::size_t ia, double tolerance) {
    constexpr double kTurn = 2 * std::numbers::pi;
    const GeomAdaptor_Surface s(BRep_Tool::Surface(face));
    double v_apex = 0;
    if (s.GetType() == GeomAbs_Cone) {
        double u_apex = 0;
        ElSLib::Parameters(s.Cone(), s.Cone().Apex(), u_apex, v_apex);
    } else {
        const gp_Torus t = s.Torus();
        if (t.MinorRadius() <= t.MajorRadius()) return {};
        // Of the two points, the one nearer the loop (v unwrapped as the loop's).
        const double v0 = std::acos(-t.MajorRadius() / t.MinorRadius());
        const double v_loop = loops[ia].uv.front().Y();
        double best_gap = 1e300;
        for (const double c : {v0, -v0}) {
            const double v = c + kTurn * std::round((v_loop - c) / kTurn);
            if (std::abs(v - v_loop) < best_gap) {
                best_gap = std::abs(v - v_loop);
                v_apex = v;
            }
        }
    }
    double u_lo = 1e300, u_hi = -1e300;
    for (const gp_Pnt2d& p : loops[ia].uv) {
        u_lo = std::min(u_lo, p.X());
        u_hi = std::max(u_hi, p.X());
    }
    const int copies = static_cast<int>(std::ceil((u_hi - u_lo) / kTurn)) + 1;
    double best = 1e300;
    std::size_t best_a = 0;
    for (std::size_t ea = 0; ea < wires[ia].size(); ++ea) {
        const gp_Pnt2d pa = loops[ia].uv[loops[ia].edge_start[ea]];
        const double len = std::abs(pa.Y() - v_apex);
        if (len >= best || !clear_of_loops(gp_Pnt2d(pa.X(), v_apex), pa, loops, copies)) continue;
        best = len;
        best_a = ea;
    }
    if (best == 1e300) return {};
    const int w = loops[ia].winding;
    const TopoDS_Vertex va = TopExp::FirstVertex(wires[ia][best_a], true);
    const gp_Pnt2d pa =
        revolution_uv(s, BRep_Tool::Pnt(va), loops[ia].uv[loops[ia].edge_start[best_a]]);
    BRep_Builder B;
    TopoDS_Vertex tip;
    B.MakeVertex(tip, s.Value(pa.X(), v_apex), tolerance);
    // The seam from the apex up the ruling to the vertex: forward from the apex, and reversed
    // a turn along, where the loop has brought the wire.
    const TopoDS_Edge seam =
        seam_edge(face, tip, gp_Pnt2d(pa.X(), v_apex), va, pa, w * kTurn, tolerance);
    if (seam.IsNull()) return {};
    // The apex, a turn back from where the reversed seam arrives to where the seam leaves.
    TopoDS_Edge degenerate;
    B.MakeEdge(degenerate);
    Handle(Geom2d_Line) round =
        new Geom2d_Line(gp_Pnt2d(pa.X() + w * kTurn, v_apex), gp_Dir2d(w > 0 ? -1 : 1, 0));
    B.UpdateEdge(degenerate, round, face, tolerance);
    B.Range(degenerate, 0, kTurn);
    B.Degenerated(degenerate, true);
    B.Add(degenerate, tip.Oriented(TopAbs_FORWARD));
    B.Add(degenerate, tip.Oriented(TopAbs_REVERSED));

    std::vector<TopoDS_Edge> cap;
    for (std::size_t i = 0; i < wires[ia].size(); ++i) {
        cap.push_back(wires[ia][(best_a + i) % wires[ia].size()]);
    }
    cap.push_back(TopoDS::Edge(seam.Reversed()));
    cap.push_back(degenerate);
    cap.push_back(seam);
    std::vector<std::vector<TopoDS_Edge>> out{std::move(cap)};
    for (std::size_t i = 0; i < wires.size(); ++i) {
        if (i != ia) out.push_back(wires[i]);
    }
    return out;
}

// The wires of a face on a cylinder, cone or torus whose loops include two that each go once
// round the axis (the face is a band round it), with those two joined into one wire by a seam edge
// between a vertex of each. OpenCASCADE's face fix adds such a seam itself along one ruling,
// but only right when each loop crosses that ruling once: the M6 screw's thread root, a
// cylinder band whose outer loop winds down the thread, crossed the ruling at every turn and
// the fix kept a sliver of the face; the occt_screw's countersunk cone, its top loop down and
// across the slot, lost 6 of 9 edges though each loop crossed the ruling once. Here the seam
// runs straight in (u, v) between the two vertices with the shortest such segment that crosses
// no loop: for bands whose loops cross the ruling more than once, and for any band whose face
// failed with the fix's seam (`always`). Other bands keep the fix's seam, on a ruling: made
// the default for every band, it took CTC 02's two fallbacks away but the largest deviations
// of CTC 03, FTC 09 and the M6 screw grew 0.1 -> 0.6, 0.05 -> 0.33 and 0.8 -> 3.3 deflections
// (not examined further). `is_band` tells whether the loops make such a band; an empty result
// when they do not, when the fix's seam serves, or when no segment is clear.
std::vector<std::vector<TopoDS_Edge>> seamed_band(
    const TopoDS_Face& face, const std::vector<std::vector<TopoDS_Edge>>& wires, double tolerance,
    bool always, bool& is_band) {
    constexpr double kTurn = 2 * std::numbers::pi;
    is_band = false;
    const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
    const GeomAdaptor_Surface s(surface);
    if (s.GetType() != GeomAbs_Cylinder && s.GetType() != GeomAbs_Cone &&
        s.GetType() != GeomAbs_Torus) {
        return {};
    }
    std::vector<UnwrappedLoop> loops;
    std::vector<std::size_t> winding;
    for (std::size_t i = 0; i < wires.size(); ++i) {
        loops.push_back(unwrap_loop(
            s, wires[i], loops.empty() ? gp_Pnt2d() : gp_Pnt2d(0, loops.front().uv.front().Y())));
        if (loops.back().tube_winding != 0) return {};  // round a torus's tube: not a band
        if (loops.back().winding != 0) winding.push_back(i);
    }
    if (winding.size() == 1 && std::abs(loops[winding[0]].winding) == 1 &&
        s.GetType() != GeomAbs_Cylinder) {
        // A cap round the apex, with its own seam only after the fix's failed.
        is_band = true;
        return always ? seamed_cap(face, wires, loops, winding[0], tolerance)
                      : std::vector<std::vector<TopoDS_Edge>>{};
    }
    if (winding.size() != 2) return {};
    const std::size_t ia = winding[0], ib = winding[1];
    const int w = loops[ia].winding;
    if (std::abs(w) != 1 || loops[ib].winding != -w) return {};
    is_band = true;
    // The fix's own seam, on the ruling u = 0, serves when each loop crosses it once; it is
    // kept there unless the face failed with it (`always`).
    const auto ruling_crossings = [&](const UnwrappedLoop& l) {
        std::int64_t n = 0;
        for (std::size_t j = 0; j + 1 < l.uv.size(); ++j) {
            n += std::abs(static_cast<std::int64_t>(std::floor(l.uv[j + 1].X() / kTurn)) -
                          static_cast<std::int64_t>(std::floor(l.uv[j].X() / kTurn)));
        }
        return n;
    };
    if (!always && ruling_crossings(loops[ia]) <= 1 && ruling_crossings(loops[ib]) <= 1) {
        return {};
    }

    // Every loop's samples, repeated a turn either way as far as the two loops reach.
    double u_lo = 1e300, u_hi = -1e300;
    for (const std::size_t i : {ia, ib}) {
        for (const gp_Pnt2d& p : loops[i].uv) {
            u_lo = std::min(u_lo, p.X());
            u_hi = std::max(u_hi, p.X());
        }
    }
    const int copies = static_cast<int>(std::ceil((u_hi - u_lo) / kTurn)) + 1;
    // The segment's length on the surface, from a few points along it.
    const auto length = [&](const gp_Pnt2d& a, const gp_Pnt2d& b) {
        constexpr int kSteps = 8;
        double len = 0;
        gp_Pnt prev = s.Value(a.X(), a.Y());
        for (int i = 1; i <= kSteps; ++i) {
            const gp_XY q = a.XY() + (b.XY() - a.XY()) * (static_cast<double>(i) / kSteps);
            const gp_Pnt p = s.Value(q.X(), q.Y());
            len += p.Distance(prev);
            prev = p;
        }
        return len;
    };
    // Every pair of vertices (b's a turn either way), shortest first; the first clear one is
    // taken. Testing a pair against every loop costs as much as the loops' samples, so only as
    // many are tested as it takes (a band beside a fallback has a loop of hundreds of mesh-edge
    // segments: every pair tested would be cubic in them).
    struct Candidate {
        double length;
        std::size_t a, b;
        gp_Pnt2d pa, pb;
    };
    std::vector<Candidate> candidates;
    for (std::size_t ea = 0; ea < wires[ia].size(); ++ea) {
        const gp_Pnt2d pa = loops[ia].uv[loops[ia].edge_start[ea]];
        for (std::size_t eb = 0; eb < wires[ib].size(); ++eb) {
            const gp_Pnt2d b0 = loops[ib].uv[loops[ib].edge_start[eb]];
            for (int k = -1; k <= 1; ++k) {
                // b's point taken the nearest turn to a's, then a turn either way.
                const double shift = kTurn * (std::round((pa.X() - b0.X()) / kTurn) + k);
                const gp_Pnt2d pb(b0.X() + shift, b0.Y());
                candidates.push_back({length(pa, pb), ea, eb, pa, pb});
            }
        }
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& x, const Candidate& y) { return x.length < y.length; });
    const auto best = std::find_if(candidates.begin(), candidates.end(), [&](const Candidate& c) {
        return clear_of_loops(c.pa, c.pb, loops, copies);
    });
    if (best == candidates.end()) return {};
    const std::size_t best_a = best->a, best_b = best->b;
    const gp_Pnt2d best_pa = best->pa, best_pb = best->pb;

    // The seam from b's vertex to a's; used forward (b to a) on the pcurve through those
    // points, and reversed (a to b) a turn along, where loop a has brought the wire.
    const TopoDS_Vertex va = TopExp::FirstVertex(wires[ia][best_a], true);
    const TopoDS_Vertex vb = TopExp::FirstVertex(wires[ib][best_b], true);
    const gp_Pnt2d pa = revolution_uv(s, BRep_Tool::Pnt(va), best_pa);
    const gp_Pnt2d pb = revolution_uv(s, BRep_Tool::Pnt(vb), best_pb);
    const TopoDS_Edge seam = seam_edge(face, vb, pb, va, pa, w * kTurn, tolerance);
    if (seam.IsNull()) return {};

    // Loop a from its vertex round to it, the seam back to b, loop b round, the seam to a.
    std::vector<TopoDS_Edge> band;
    for (std::size_t i = 0; i < wires[ia].size(); ++i) {
        band.push_back(wires[ia][(best_a + i) % wires[ia].size()]);
    }
    band.push_back(TopoDS::Edge(seam.Reversed()));
    for (std::size_t i = 0; i < wires[ib].size(); ++i) {
        band.push_back(wires[ib][(best_b + i) % wires[ib].size()]);
    }
    band.push_back(seam);
    std::vector<std::vector<TopoDS_Edge>> out{std::move(band)};
    for (std::size_t i = 0; i < wires.size(); ++i) {
        if (i != ia && i != ib) out.push_back(wires[i]);
    }
    return out;
}

// A closed wire of `edges`, in their order, added to `face`.
void add_wire(const BRep_Builder& B, TopoDS_Face& face, const std::vector<TopoDS_Edge>& edges) {
    TopoDS_Wire W;
    B.MakeWire(W);
    for (const TopoDS_Edge& e : edges) B.Add(W, e);
    W.Closed(true);
    B.Add(face, W);
}

// A face's wire as it walks: OpenCASCADE's ShapeBuild_ReShape::Apply puts the pieces an
// earlier face's fix split a shared edge into in that edge's own order, each reversed, where
// this face uses the edge reversed, so the wire runs back along them. Our fix does not reorder
// (it would reorder seams), and BRepCheck finds the wire NotClosed: a 12-sided faceted cross
// bore's band, whose closed edge round the vertical bore that bore's face had split in three.
// Each such run is put back in the order the wire walks it; true when `edges` changed (not
// where the wire walks already, or breaks somewhere no reversed run mends).
bool in_walk_order(std::vector<TopoDS_Edge>& edges) {
    const std::size_t n = edges.size();
    const auto joins = [](const TopoDS_Edge& a, const TopoDS_Edge& b) {
        return TopExp::LastVertex(a, true).IsSame(TopExp::FirstVertex(b, true));
    };
    std::vector<TopoDS_Edge> es = edges;
    for (std::size_t pass = 0; pass < n; ++pass) {
        std::size_t broken = n;
        for (std::size_t i = 0; i < n; ++i) {
            if (!joins(es[i], es[(i + 1) % n])) {
                broken = i;
                break;
            }
        }
        if (broken == n) {
            if (pass == 0) return false;
            edges = std::move(es);
            return true;
        }
        // The edge before the break last: the run to reverse starts the list.
        std::rotate(es.begin(), es.begin() + static_cast<std::ptrdiff_t>((broken + 1) % n),
                    es.end());
        bool mended = false;
        for (std::size_t len = 2; len < n && !mended; ++len) {
            bool walks = joins(es[n - 1], es[len - 1]) && joins(es[0], es[len]);
            for (std::size_t k = 0; walks && k + 1 < len; ++k) walks = joins(es[k + 1], es[k]);
            if (walks) {
                std::reverse(es.begin(), es.begin() + static_cast<std::ptrdiff_t>(len));
                mended = true;
            }
        }
        if (!mended) return false;
    }
    return false;
}

// The geometry one build round computed, which the next reuses while what it was computed
// from is unchanged (build_surface_brep): a round differs from the one before only around the
// regions that failed, and solving every corner and intersecting every pair of surfaces again
// cost most of a finely meshed part's B-rep. Topology (vertices, edges, faces) is built afresh
// every round: the faces' fixes replace edges and vertices, which a kept edge would carry into
// the next round's faces.
struct GeometryCache {
    // A corner: what it is solved from (the regions with a surface around it, whether it may
    // go onto a contact curve) and the result.
    struct Corner {
        bool valid = false;
        std::vector<std::int32_t> on;
        bool contact_allowed = false;
        bool at_vertex = false;  // kept at its mesh vertex (moved_at)
        Vec3 point{};
        double tolerance = 0;
        bool solved = false;  // had surfaces to be solved onto
        bool on_contact = false;
        double residual = 0;
    };
    // A chain's curve between two surfaces: what it is made from (its regions' states:
    // fallback, piecewise-linear tangent edges; its end points) and the curve.
    struct Chain {
        bool valid = false;
        std::array<std::uint8_t, 4> state{};
        gp_Pnt p0, p1;
        ChainCurve curve;
        ChainKind kind = ChainKind::kFitted;
        bool analytic = false;
        // What its edges are made from: `id` names the curve, `polyline_id` the segments
        // between the end points `q0`, `q1` (new ids when they change).
        std::uint64_t id = 0, polyline_id = 0;
        gp_Pnt q0, q1;
    };
    // A face that passed the checks (OpenCASCADE's, BRepMesh's), made from: its surface and
    // orientation, whether it was a fallback's face bounded by mesh edges, and the ids of the
    // chains around it. The same face again needs no checks.
    struct Face {
        bool valid = false;
        Handle(Geom_Surface) surface;
        int sense = 1;
        bool fallback = false;
        bool own_seam = false;
        std::vector<std::uint64_t> chains;
    };
    std::unordered_map<std::uint32_t, Corner> corners;
    std::vector<Chain> chains;
    std::vector<Face> faces;
    std::uint64_t next_id = 1;
};

/// The closed shell `shell` as solids, one per connected piece (faces joined by shared edges):
/// a mesh of several components (parts side by side) gives several, in a compound; one gives
/// the solid of `shell` itself. A piece that bounds a negative volume is a cavity's shell
/// (healing faces it into the cavity): it goes into the smallest solid that holds one of its
/// vertices, as a void. Each face keeps its orientation in the shell.
TopoDS_Shape solids_of(const TopoDS_Shell& shell) {
    BRep_Builder B;
    std::vector<TopoDS_Shape> members;
    for (TopoDS_Iterator it(shell); it.More(); it.Next()) members.push_back(it.Value());
    TopTools_IndexedMapOfShape index;  // faces, orientation aside (1-based)
    for (const TopoDS_Shape& f : members) index.Add(f);
    detail::MinUnionFind pieces_of(static_cast<std::size_t>(index.Extent()) + 1);
    TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
    TopExp::MapShapesAndUniqueAncestors(shell, TopAbs_EDGE, TopAbs_FACE, edge_faces);
    for (int i = 1; i <= edge_faces.Extent(); ++i) {
        const auto first =
            static_cast<std::uint32_t>(index.FindIndex(edge_faces.FindFromIndex(i).First()));
        for (const TopoDS_Shape& f : edge_faces.FindFromIndex(i))
            pieces_of.unite(first, static_cast<std::uint32_t>(index.FindIndex(f)));
    }
    std::map<std::uint32_t, TopoDS_Shell> pieces;  // by root: the smallest index of its faces
    for (const TopoDS_Shape& f : members) {
        auto [it, fresh] =
            pieces.try_emplace(pieces_of.find(static_cast<std::uint32_t>(index.FindIndex(f))));
        if (fresh) B.MakeShell(it->second);
        B.Add(it->second, f);
    }
    const auto solid_of = [&](TopoDS_Shell sh) {
        sh.Closed(true);
        TopoDS_Solid solid;
        B.MakeSolid(solid);
        B.Add(solid, sh);
        return solid;
    };
    if (pieces.size() <= 1) return solid_of(shell);
    struct Piece {
        TopoDS_Shell shell;
        TopoDS_Solid solid;
        double volume = 0;
        std::vector<TopoDS_Shell> voids;
    };
    std::vector<Piece> all_pieces;
    for (const auto& [r, sh] : pieces) {
        Piece p{sh, solid_of(sh), 0, {}};
        GProp_GProps props;
        BRepGProp::VolumeProperties(p.solid, props);
        p.volume = props.Mass();
        all_pieces.push_back(std::move(p));
    }
    std::vector<std::uint8_t> placed(all_pieces.size(), 0);
    for (std::size_t v = 0; v < all_pieces.size(); ++v) {
        if (all_pieces[v].volume >= 0) continue;
        TopExp_Explorer vertex(all_pieces[v].shell, TopAbs_VERTEX);
        if (!vertex.More()) continue;
        const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(vertex.Current()));
        std::size_t around = all_pieces.size();
        for (std::size_t o = 0; o < all_pieces.size(); ++o) {
            if (all_pieces[o].volume <= 0) continue;
            if (around < all_pieces.size() && all_pieces[o].volume >= all_pieces[around].volume)
                continue;
            BRepClass3d_SolidClassifier in(all_pieces[o].solid, p, Precision::Confusion());
            if (in.State() == TopAbs_IN) around = o;
        }
        if (around == all_pieces.size()) continue;  // not inside a piece: a solid of its own
        all_pieces[around].voids.push_back(all_pieces[v].shell);
        placed[v] = 1;
    }
    TopoDS_Compound all;
    B.MakeCompound(all);
    std::size_t solids = 0;
    TopoDS_Shape last;
    for (std::size_t k = 0; k < all_pieces.size(); ++k) {
        if (placed[k]) continue;
        Piece& p = all_pieces[k];
        if (!p.voids.empty()) {
            B.MakeSolid(p.solid);
            B.Add(p.solid, p.shell);
            for (TopoDS_Shell& hole : p.voids) {
                hole.Closed(true);
                B.Add(p.solid, hole);
            }
        }
        B.Add(all, p.solid);
        last = p.solid;
        ++solids;
    }
    return solids == 1 ? last : TopoDS_Shape(all);
}

}  // namespace

SurfaceBrep build_surface_brep(const Mesh& m, const FaceMap<std::int32_t>& region,
                               std::span<const RegionSurface> regions,
                               const SurfaceBrepOptions& opt) {
    SurfaceBrep out;
    const std::size_t nr = regions.size();
    out.regions.assign(nr, {});
    // The labels, changed where a failing region is absorbed by a neighbour.
    FaceMap<std::int32_t> labels = region;
    Builder bd(m, labels, regions);
    bd.prepare();
    const RegionBorders& borders = bd.borders;
    const double max_tol = std::max(opt.chordal_deflection, 10 * opt.tolerance);

    // Geometry of every region; a region without one is built from its facets.
    std::vector<Handle(Geom_Surface)> geom(nr);
    std::vector<int> sense(nr, 1);
    std::vector<std::uint8_t> fallback(nr, 0);
    const auto fall_back = [&](std::size_t r, std::string why) {
        if (fallback[r]) return;
        fallback[r] = 1;
        out.regions[r].fallback = true;
        out.regions[r].reason = std::move(why);
    };
    std::vector<std::int32_t> absorbed(nr, -1);
    // Regions whose tangent junctions take piecewise-linear edges (after a self-crossing wire).
    std::vector<std::uint8_t> linear(nr, 0);
    // Regions whose face is a band round a cylinder's, cone's or torus's axis, or a cap round
    // a cone's apex or a spindle torus's axis point (seamed_band), and those of them whose face
    // takes its own seam after it failed with the fix's.
    std::vector<std::uint8_t> is_band_face(nr, 0), own_seam(nr, 0), seam_turns(nr, 0);
    // Corners (mesh vertex ids) solved without it after a face or chain at them failed with it
    // (a corner moved along a coarse mesh's contact band can pass its chain's next point).
    std::unordered_set<std::uint32_t> plain_at;
    // Corners kept at their mesh vertex after a face at them crossed itself with every other
    // remedy tried (moved_at): surfaces nearly tangent to one another leave their common point
    // ill-conditioned. Two fillets and their corner torus on NIST FTC 07 at 88k facets: solved
    // 0.12 mm from the mesh vertex, past the tangent line of one fillet with the top plane and
    // 0.09 mm above that plane, so the fillet's end edge crossed its tangent-line edge.
    std::unordered_set<std::uint32_t> vertex_at;
    // Regions whose facets changed since their geometry was made (all, at first; a region
    // absorbed and its absorber after try_absorb()).
    std::vector<std::uint8_t> reshaped(nr, 1);
    const auto compute_geometry = [&] {
        for (std::size_t r = 0; r < nr; ++r) {
            if (absorbed[r] >= 0 || fallback[r] || !reshaped[r]) continue;
            if (r < opt.facets_only.size() && !opt.facets_only[r].empty()) {
                fall_back(r, opt.facets_only[r]);
                continue;
            }
            if (!regions[r].has_surface) {
                fall_back(r, regions[r].no_surface_reason.empty() ? "no surface fits the region"
                                                                  : regions[r].no_surface_reason);
                continue;
            }
            std::string why;
            try {
                geom[r] =
                    seam_turned(geom_surface(regions[r].surface, bd.shapes[r], why), seam_turns[r]);
                if (!geom[r].IsNull()) sense[r] = natural_sense(geom[r], m, bd.shapes[r]);
            } catch (const Standard_Failure& f) {
                geom[r].Nullify();
                why = std::string("OpenCASCADE cannot make the surface: ") + f.GetMessageString();
            }
            if (geom[r].IsNull()) fall_back(r, "no OpenCASCADE surface: " + why);
            if (!fallback[r] && bd.loops[r].empty() &&
                regions[r].surface.kind != FitKind::kSphere &&
                regions[r].surface.kind != FitKind::kTorus) {
                fall_back(r, "a region without a border on an open surface");
            }
        }
    };
    compute_geometry();
    std::fill(reshaped.begin(), reshaped.end(), 0);
    // A failing region whose facets are all chords of a neighbour's surface (vertices within
    // twice the tolerance, middles within the chordal deflection, normals agreeing): a sliver
    // segmentation cut off a face (a strip along a fillet's tangent line, an island). It joins
    // that neighbour instead of coming back as facets.
    const double cos_normal = std::cos(kSegmentNormalAngle);
    const auto try_absorb = [&](std::size_t r) -> bool {
        if (!opt.allow_fallback || absorbed[r] >= 0) return false;
        std::vector<std::int32_t> neighbours;
        for (const BorderChain& ch : bd.borders.chains) {
            if (ch.left == static_cast<std::int32_t>(r) && ch.right >= 0) {
                neighbours.push_back(ch.right);
            }
            if (ch.right == static_cast<std::int32_t>(r)) neighbours.push_back(ch.left);
        }
        std::sort(neighbours.begin(), neighbours.end());
        neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
        std::int32_t best = -1;
        double best_worst = 1e300;
        for (std::int32_t n : neighbours) {
            const auto k = static_cast<std::size_t>(n);
            if (fallback[k] || absorbed[k] >= 0 || !regions[k].has_surface) continue;
            const Surface& su = regions[k].surface;
            double worst = 0;
            bool chords = true;
            for (std::uint32_t f = 0; f < m.num_faces() && chords; ++f) {
                const FaceId id(f);
                if (labels[id] != static_cast<std::int32_t>(r)) continue;
                Vec3 c{};
                for (int i = 0; i < 3; ++i) {
                    const Vec3 p = m.position(m.vertex(id, i));
                    worst = std::max(worst, distance(su, p));
                    c = c + (1.0 / 3) * p;
                }
                chords = worst <= 2 * opt.tolerance &&
                         distance(su, c) <= opt.chordal_deflection + opt.tolerance &&
                         std::abs(dot(normal_at(su, c), m.face_normal(id))) >= cos_normal;
            }
            if (chords && worst < best_worst) {
                best = n;
                best_worst = worst;
            }
        }
        if (best < 0) return false;
        for (std::uint32_t f = 0; f < m.num_faces(); ++f) {
            if (labels[FaceId(f)] == static_cast<std::int32_t>(r)) labels[FaceId(f)] = best;
        }
        absorbed[r] = best;
        reshaped[r] = reshaped[static_cast<std::size_t>(best)] = 1;
        return true;
    };
    // A fallback region that is not built from its facets: one face on its surface bounded by
    // the polyline edges of its border (every chain around it is its mesh edges). Its surface,
    // when it fell back before it had one made.
    std::vector<std::uint8_t> as_facets(nr, 0);
    for (std::size_t r = 0; r < nr && r < opt.as_facets.size(); ++r)
        as_facets[r] = opt.as_facets[r];
    const auto fallback_surface = [&](std::size_t r) {
        if (!geom[r].IsNull()) return true;
        if (!regions[r].has_surface || bd.loops[r].empty()) return false;
        std::string why;
        try {
            geom[r] = geom_surface(regions[r].surface, bd.shapes[r], why);
            if (!geom[r].IsNull()) sense[r] = natural_sense(geom[r], m, bd.shapes[r]);
        } catch (const Standard_Failure&) {
            geom[r].Nullify();
        }
        return !geom[r].IsNull();
    };
    // A fallback region whose face bounded by its mesh edges fails on its own surface (a cap
    // over a torus's tip, which no face on the torus can hold; a strip whose polyline wires
    // take no seam) gets one more try on a B-spline fitted to points of its facets projected
    // on its surface: a height field over its mean plane, which needs no seam, within the
    // segmentation's tolerance. Only then does it come back as its facets (FTC 07's five were
    // 123 facet faces).
    std::vector<std::uint8_t> spline(nr, 0);
    const auto spline_fallback = [&](std::size_t r) -> bool {
        if (spline[r]) return false;
        spline[r] = 1;
        std::vector<FaceId> own;
        for (std::uint32_t f = 0; f < m.num_faces(); ++f) {
            if (labels[FaceId(f)] == static_cast<std::int32_t>(r)) own.push_back(FaceId(f));
        }
        // Points of its facets (kSplineSamples per edge and across), on its own surface where
        // it has one: a small region's vertices are fewer than the smallest net's poles.
        std::vector<Vec3> points, normals;
        const bool on_surface = regions[r].has_surface;
        for (const FaceId id : own) {
            const Vec3 a = m.position(m.vertex(id, 0)), b = m.position(m.vertex(id, 1)),
                       c = m.position(m.vertex(id, 2));
            const Vec3 n = m.face_normal(id);
            for (int i = 0; i <= kSplineSamples; ++i) {
                for (int j = 0; i + j <= kSplineSamples; ++j) {
                    const double u = double(i) / kSplineSamples, v = double(j) / kSplineSamples;
                    Vec3 p = a + u * (b - a) + v * (c - a);
                    Vec3 q = n;
                    if (on_surface) {
                        p = closest_point(regions[r].surface, p);
                        q = normal_at(regions[r].surface, p);
                        if (dot(q, n) < 0) q = -q;
                    }
                    points.push_back(p);
                    normals.push_back(q);
                }
            }
        }
        const FitResult fit = fit_bspline(FitInput{points, normals, {}}, opt.tolerance);
        if (!fit.ok || !(fit.max <= opt.tolerance)) return false;
        // Within twice the tolerance of the region's own vertices (its surface's points were
        // fitted; those are within the tolerance of them).
        for (const FaceId id : own) {
            for (int i = 0; i < 3; ++i) {
                if (!(distance(fit.surface, m.position(m.vertex(id, i))) <= 2 * opt.tolerance))
                    return false;
            }
        }
        std::string why;
        Handle(Geom_Surface) g;
        try {
            g = geom_surface(fit.surface, bd.shapes[r], why);
        } catch (const Standard_Failure&) {
            return false;
        }
        if (g.IsNull()) return false;
        geom[r] = g;
        sense[r] = natural_sense(g, m, bd.shapes[r]);
        out.regions[r].spline = true;
        return true;
    };
    GeometryCache cache;
    // After absorbing: borders and loops again, and the geometry of the regions whose facets
    // changed (a surface's seam is put away from its region's centroid). The cache keeps the
    // chains that are still there, between regions that did not change, under their new
    // indices; faces and corners are keyed by what they are made from, so only those
    // around the change are made again.
    const auto relabelled = [&] {
        std::vector<BorderChain> before = std::move(bd.borders.chains);
        bd.prepare();
        compute_geometry();
        if (!opt.reuse_geometry) {
            cache = GeometryCache{};
            std::fill(reshaped.begin(), reshaped.end(), 0);
            return;
        }
        std::map<std::tuple<std::int32_t, std::int32_t, std::uint32_t, std::uint32_t>,
                 std::vector<std::size_t>>
            old_chain;
        for (std::size_t c = 0; c < before.size() && c < cache.chains.size(); ++c) {
            const BorderChain& ch = before[c];
            if (reshaped[static_cast<std::size_t>(ch.left)] ||
                (ch.right >= 0 && reshaped[static_cast<std::size_t>(ch.right)]))
                continue;
            old_chain[{ch.left, ch.right, ch.vertices.front().idx(), ch.vertices.back().idx()}]
                .push_back(c);
        }
        std::vector<GeometryCache::Chain> chains(bd.borders.chains.size());
        for (std::size_t c = 0; c < chains.size(); ++c) {
            const BorderChain& ch = bd.borders.chains[c];
            const auto it = old_chain.find(
                {ch.left, ch.right, ch.vertices.front().idx(), ch.vertices.back().idx()});
            if (it == old_chain.end()) continue;
            for (const std::size_t o : it->second) {
                if (before[o].closed == ch.closed && before[o].vertices == ch.vertices) {
                    chains[c] = std::move(cache.chains[o]);
                    break;
                }
            }
        }
        cache.chains = std::move(chains);
        std::fill(reshaped.begin(), reshaped.end(), 0);
    };
    if (!opt.allow_fallback) {
        for (std::size_t r = 0; r < nr; ++r) {
            if (fallback[r]) {
                out.problem = "region " + std::to_string(r) + ": " + out.regions[r].reason;
                return out;
            }
        }
    }

    // Regions around every mesh vertex that is a corner or a loop's start.
    const auto regions_at = [&](VertexId v) {
        std::vector<std::int32_t> rs;
        m.for_each_outgoing(v, [&](HalfedgeId h) { rs.push_back(labels[Mesh::face(h)]); });
        std::sort(rs.begin(), rs.end());
        rs.erase(std::unique(rs.begin(), rs.end()), rs.end());
        return rs;
    };

    BRep_Builder B;
    // Corner v solved onto the surfaces of the regions `on`.
    const auto solve_corner = [&](VertexId v, const std::vector<std::int32_t>& on_ids,
                                  bool contact_allowed, bool at_vertex) {
        GeometryCache::Corner c;
        c.valid = true;
        c.on = on_ids;
        c.contact_allowed = contact_allowed;
        c.at_vertex = at_vertex;
        std::vector<Surface> on;
        for (std::int32_t r : on_ids) on.push_back(regions[static_cast<std::size_t>(r)].surface);
        Vec3 p = m.position(v);
        double tol = kMinTolerance;
        if (!on.empty()) {
            c.solved = true;
            bool placed = false;  // at a point the surfaces hold
            if (!at_vertex) {
                CommonPoint cp = common_point(on, p);
                // Two tangent surfaces leave the solve free along their contact band: the
                // corner goes onto their contact curve when that is within the tolerance of
                // every surface and within the band (its half-width sqrt(2 r tol), r the tube's
                // radius). A junction of two tubes (spine_junction()) is unique within the span
                // it was searched in: the mesh vertex may be far from it along the contact
                // (1.35 mm at a 4 mm fillet's corner torus at a tolerance of 0.011 mm, the
                // fillet block at 345k facets, where a line and a circle of contact are tangent
                // on the top face).
                Vec3 q = cp.point;
                double radius = 0;
                bool junction = false;
                if (contact_allowed && on.size() >= 3 &&
                    tangent_corner(on, opt.tolerance, q, radius, junction)) {
                    double residual = 0;
                    for (const Surface& s : on) residual = std::max(residual, distance(s, q));
                    const double band = std::sqrt(2 * radius * opt.tolerance);
                    const double reach = junction ? kJunctionSpan * radius : max_tol + 2 * band;
                    if (residual <= opt.tolerance && norm(q - p) <= reach) {
                        cp.point = q;
                        cp.residual = residual;
                        c.on_contact = true;
                    }
                }
                if (cp.residual <= opt.tolerance &&
                    (c.on_contact || norm(cp.point - p) <= max_tol)) {
                    p = cp.point;
                    tol = std::max(tol, 1.01 * cp.residual);
                    c.residual = cp.residual;
                    placed = true;
                }
            }
            if (!placed) {
                // The mesh vertex, with the tolerance that reaches every surface: unsolved
                // (surfaces nearly tangent, or a bad fit), or kept there (vertex_at).
                double d = 0;
                for (const Surface& s : on) d = std::max(d, distance(s, p));
                tol = std::max(tol, 1.01 * d);
                c.residual = d;
            }
        }
        c.point = p;
        c.tolerance = tol;
        return c;
    };
    for (int round = 1; round <= kMaxRounds; ++round) {
        out.rounds = round;
        out.intersection_edges = out.tangency_edges = out.fitted_edges = out.polyline_edges = 0;
        out.analytic_edges = 0;
        out.corners = out.tangent_corners = 0;
        out.max_corner_residual = 0;
        // 2. Vertices: solved corners (and loop starts); other mesh vertices at their place.
        std::unordered_map<std::uint32_t, TopoDS_Vertex> vertex;
        // Per region, its corners put on a contact curve this round.
        std::vector<std::vector<std::uint32_t>> contact_at(nr);
        // Per region, its corners solved plainly this round more than the tolerance from their
        // mesh vertex (which the tessellation put on the part): moved there by the solve.
        std::vector<std::vector<std::uint32_t>> moved_at(nr);
        const auto contact_corner = [&](std::size_t r) { return !contact_at[r].empty(); };
        // Back to plain for the next round: the corners of region r that were on a contact
        // curve (false when it had none).
        const auto make_plain = [&](std::size_t r) {
            for (std::uint32_t v : contact_at[r]) plain_at.insert(v);
            return contact_corner(r);
        };
        const auto solved_vertex = [&](VertexId v) -> TopoDS_Vertex {
            auto it = vertex.find(v.idx());
            if (it != vertex.end()) return it->second;
            std::vector<std::int32_t> on;
            const std::vector<std::int32_t> around = regions_at(v);
            // Not on a contact curve where that failed here before, or around a region whose
            // face came back wrong from a STEP written with one (opt.plain_corners).
            bool contact_allowed = plain_at.count(v.idx()) == 0;
            for (std::int32_t r : around) {
                const auto k = static_cast<std::size_t>(r);
                if (!fallback[k]) on.push_back(r);
                if (k < opt.plain_corners.size() && opt.plain_corners[k]) contact_allowed = false;
            }
            const bool at_vertex = vertex_at.count(v.idx()) != 0;
            GeometryCache::Corner& c = cache.corners[v.idx()];
            if (!opt.reuse_geometry || !c.valid || c.on != on ||
                c.contact_allowed != contact_allowed || c.at_vertex != at_vertex) {
                c = solve_corner(v, on, contact_allowed, at_vertex);
                ++out.corners_solved;
            }
            if (c.solved && !c.on_contact && norm(c.point - m.position(v)) > opt.tolerance) {
                for (std::int32_t r : around)
                    moved_at[static_cast<std::size_t>(r)].push_back(v.idx());
            }
            if (c.solved) {
                ++out.corners;
                out.max_corner_residual = std::max(out.max_corner_residual, c.residual);
            }
            if (c.on_contact) {
                ++out.tangent_corners;
                for (std::int32_t r : around)
                    contact_at[static_cast<std::size_t>(r)].push_back(v.idx());
            }
            TopoDS_Vertex V;
            B.MakeVertex(V, pnt(c.point), c.tolerance);
            vertex.emplace(v.idx(), V);
            return V;
        };
        const auto plain_vertex = [&](VertexId v) -> TopoDS_Vertex {
            auto it = vertex.find(v.idx());
            if (it != vertex.end()) return it->second;
            TopoDS_Vertex V;
            B.MakeVertex(V, pnt(m.position(v)), kMinTolerance);
            vertex.emplace(v.idx(), V);
            return V;
        };
        for (VertexId c : borders.corners) solved_vertex(c);
        // 2b. A chain between two surfaces whose solved ends are within the surfaces' own
        // tolerance of each other has no length to speak of: its two corners are one (four
        // surfaces meeting where segmentation made two corners of three), and the edge between
        // them, 0.0001-0.04 mm on CTC 04 at a deflection of 0.94 mm (tolerance 0.094), made the
        // wires of both its faces cross themselves. Its corners become one vertex and the chain no
        // edge — only a chain of one mesh edge (a longer one could run round a hole between two
        // close corners), and only while every loop it is in keeps two other chains.
        std::vector<std::uint8_t> collapsed(borders.chains.size(), 0);
        {
            // Per loop (numbered over all regions), the chains it still has; per chain, its loops.
            std::vector<std::size_t> loop_left;
            std::vector<std::vector<std::size_t>> loops_of(borders.chains.size());
            for (std::size_t r = 0; r < nr; ++r) {
                for (const auto& loop : bd.loops[r]) {
                    for (const auto& lc : loop) {
                        loops_of[static_cast<std::size_t>(lc.first)].push_back(loop_left.size());
                    }
                    loop_left.push_back(loop.size());
                }
            }
            for (std::size_t c = 0; c < borders.chains.size(); ++c) {
                const BorderChain& ch = borders.chains[c];
                if (ch.closed || ch.right < 0 || fallback[static_cast<std::size_t>(ch.left)] ||
                    fallback[static_cast<std::size_t>(ch.right)] ||
                    std::any_of(loops_of[c].begin(), loops_of[c].end(),
                                [&](std::size_t l) { return loop_left[l] < 3; })) {
                    continue;
                }
                const TopoDS_Vertex V0 = solved_vertex(ch.vertices.front());
                const TopoDS_Vertex V1 = solved_vertex(ch.vertices.back());
                if (V0.IsSame(V1)) continue;
                const gp_Pnt P0 = BRep_Tool::Pnt(V0), P1 = BRep_Tool::Pnt(V1);
                const double d = P0.Distance(P1);
                if (d > opt.tolerance) continue;
                // A longer chain only when all of it is as near the corner as the mesh's own
                // corners are (0.13 mm at the fillet block's 345k facets, where a side plane,
                // its vertical fillet, the top fillet and their corner torus are all tangent
                // at one point): one that runs round a hole between the two goes further.
                if (ch.vertices.size() > 2) {
                    const double reach =
                        max_tol + std::max(P0.Distance(pnt(m.position(ch.vertices.front()))),
                                           P1.Distance(pnt(m.position(ch.vertices.back()))));
                    if (std::any_of(ch.vertices.begin(), ch.vertices.end(), [&](VertexId v) {
                            return P0.Distance(pnt(m.position(v))) > reach;
                        }))
                        continue;
                }
                B.UpdateVertex(
                    V0, std::max(BRep_Tool::Tolerance(V0), 1.01 * (d + BRep_Tool::Tolerance(V1))));
                // Every mesh vertex that stood for V1 stands for V0 now.
                for (auto& [id, v] : vertex) {
                    if (v.IsSame(V1)) v = V0;
                }
                for (const std::size_t l : loops_of[c]) --loop_left[l];
                collapsed[c] = 1;
            }
        }
        // Straight segment edges between mesh vertices, shared (key: the two vertex ids).
        std::unordered_map<std::uint64_t, TopoDS_Edge> segment;
        const auto segment_edge = [&](VertexId a, VertexId b, bool& forward) -> TopoDS_Edge {
            const std::uint32_t lo = std::min(a.idx(), b.idx()), hi = std::max(a.idx(), b.idx());
            forward = a.idx() == lo;
            const std::uint64_t key = (std::uint64_t{lo} << 32) | hi;
            auto it = segment.find(key);
            if (it != segment.end()) return it->second;
            const TopoDS_Vertex va = plain_vertex(VertexId(lo)), vb = plain_vertex(VertexId(hi));
            BRepBuilderAPI_MakeEdge me(va, vb);
            TopoDS_Edge e = me.IsDone() ? me.Edge() : TopoDS_Edge();
            segment.emplace(key, e);
            return e;
        };

        // 3. Edges: per chain, its edges in chain order, each running along the chain.
        std::vector<std::vector<TopoDS_Edge>> chain_edges(borders.chains.size());
        cache.chains.resize(borders.chains.size());
        // Per chain, what its edges are made from this round (GeometryCache::Chain).
        std::vector<std::uint64_t> chain_id(borders.chains.size(), 0);
        // A chain's curve between its two surfaces, from its solved end points (job.p0, p1):
        // the intersection where they cross, else a curve fitted through the chain's points
        // solved onto both. Reads only the surfaces and the mesh: chains are made in parallel.
        const auto make_curve = [&](CurveJob& job) {
            const BorderChain& ch = borders.chains[job.chain];
            const auto ra = static_cast<std::size_t>(ch.left);
            const auto rb = static_cast<std::size_t>(ch.right);
            ChainCurve& cc = job.cc;
            bool& ok = job.ok;
            bool& intersected = job.intersected;
            bool& touched = job.touched;
            const Surface& sa = regions[ra].surface;
            const Surface& sb = regions[rb].surface;
            // The chain's points: the solved ends, the interior vertices solved onto both.
            std::vector<gp_Pnt> pts;
            pts.reserve(ch.vertices.size());
            const std::array<Surface, 2> pair{sa, sb};
            double min_sin = 1;
            for (std::size_t k = 0; k < ch.vertices.size(); ++k) {
                const bool end = k == 0 || k + 1 == ch.vertices.size();
                if (end) {
                    pts.push_back(k == 0 ? job.p0 : job.p1);
                } else {
                    pts.push_back(pnt(common_point(pair, m.position(ch.vertices[k])).point));
                }
                const Vec3 p = vec(pts.back());
                min_sin = std::min(min_sin, norm(cross(normal_at(sa, p), normal_at(sb, p))));
            }
            const bool tangent = min_sin <= std::sin(kTangentAngle);
            // A tangent junction with a fillet (a cylinder, torus or sphere: a tube about a
            // spine): where they touch is exact, the foot on the other surface of the
            // spine point nearest each chain point. Solving onto both surfaces instead is
            // ill-conditioned there: any point of the band where they are within the
            // tolerance of each other is a solution, and the curve wanders across it.
            // Taken when the curve through those points is within kTouchTolerances of both
            // surfaces (two cylinders crossing at a shallow angle are not tangent along a
            // curve, and the feet are not where they meet).
            std::vector<gp_Pnt> touch;
            if (tangent && pts.size() > 2 &&
                tangency_points(sa, sb, m, ch.vertices, max_tol, opt.tolerance, touch)) {
                touch.front() = pts.front();
                touch.back() = pts.back();
            } else {
                touch.clear();
            }
            try {
                if (!tangent) {
                    bool analytic = false;
                    ok = intersection_curve(geom[ra], geom[rb], sa, sb, pts, ch.closed,
                                            opt.chordal_deflection + opt.tolerance, cc, analytic);
                    intersected = ok;
                    // A general intersection (a B-spline of many poles) that is a line or
                    // circle to a tenth of the tolerance, and as near both surfaces: that line
                    // or circle (a plane across a torus square to its axis but for the fits'
                    // error, two cylinders whose axes all but meet).
                    ChainCurve simple;
                    if (ok && !analytic &&
                        conic_through(pts, ch.closed, geom[ra], geom[rb], sa, sb,
                                      kConicFeet * opt.tolerance, kConicFeet * opt.tolerance,
                                      opt.chordal_deflection + opt.tolerance,
                                      4 * static_cast<int>(pts.size()), simple)) {
                        cc = simple;
                        analytic = true;
                    }
                    job.analytic = ok && analytic;
                }
                if (!ok) {
                    // The curve through the exact contact points where there are some and
                    // it stays within the tolerance of both surfaces; otherwise the
                    // closest to the surfaces of: the cubic through the chain's points,
                    // the cubic through them densified, the piecewise-linear one (where a
                    // cubic swings off the surfaces: points unevenly spaced, a kink where
                    // the chain leaves the junction). Densified only where the surfaces
                    // cross: along a tangent junction every point of a band about the
                    // tangency line is on both to the tolerance, and solved points would
                    // wander across it. The curve's distance from the two surfaces is its
                    // tolerance.
                    const std::vector<gp_Pnt> dense =
                        tangent ? pts : densified(pts, pair, opt.tolerance);
                    const int samples = 4 * static_cast<int>(dense.size());
                    // A curve on both surfaces may still leave the chain: two surfaces tangent
                    // along a whole circle (a cone and the torus rounding its end) take one
                    // through jittery tangency points the long way round (NIST FTC 07: a
                    // 271-degree arc for a junction of 89, 2.5 mm off it, and a face that did
                    // not close; the volume was 0.07 % off). The curve through the tangency
                    // points, and the one through the midway points, are held to twice max_tol
                    // of the polyline through those points (strays_from()).
                    const double stray = 2 * max_tol;
                    ChainCurve best;
                    best.deviation = -1;
                    Handle(Geom_Curve) conic;
                    // A line or circle where one runs through the contact points: where the
                    // tube's spine is a line or circle and the other surface a plane, a tube
                    // along it or a surface about the same axis (a fillet's edges on a pocket's
                    // walls and floor), or across the section where two tubes meet. Within
                    // kConicFeet tolerances of every point; otherwise the cubic through them.
                    // Not for a region whose wire crossed itself: it gets the piecewise-linear
                    // curve (below), the retry that the exact curve would leave the same.
                    if (!touch.empty() && !linear[ra] && !linear[rb] &&
                        conic_through(touch, ch.closed, geom[ra], geom[rb], sa, sb,
                                      kConicFeet * opt.tolerance, kTouchTolerances * opt.tolerance,
                                      stray, samples, best)) {
                        touched = true;
                        conic = best.curve;
                    }
                    if (!touched && !touch.empty() &&
                        fitted_curve(touch, ch.closed, linear[ra] || linear[rb], best)) {
                        best.deviation = curve_off_surfaces(best, sa, sb, samples);
                        touched = best.deviation <= kTouchTolerances * opt.tolerance &&
                                  !strays_from(best, touch, stray);
                        if (!touched) best.deviation = -1;
                    }
                    // First the approximation within half the tolerance, taken when it
                    // is within the tolerance of both surfaces (not where a wire crossed
                    // itself: see below).
                    bool approximated = false;
                    if (!touched && !linear[ra] && !linear[rb]) {
                        ChainCurve t;
                        if (fitted_curve(pts, ch.closed, false, t, 0.5 * opt.tolerance)) {
                            t.deviation = curve_off_surfaces(t, sa, sb, samples);
                            approximated = t.deviation <= opt.tolerance;
                            if (approximated) best = t;
                        }
                    }
                    for (int variant = 0; variant < 3 && !touched && !approximated; ++variant) {
                        ChainCurve t;
                        if (!fitted_curve(variant == 0 ? pts : dense, ch.closed, variant == 2, t)) {
                            continue;
                        }
                        t.deviation = curve_off_surfaces(t, sa, sb, samples);
                        // A region whose wire crossed itself gets the piecewise-linear
                        // curve along its tangent junctions: a cubic through many close
                        // points wiggles across the tangency band, and its curve on the
                        // flat neighbour can cross the next edge's near their vertex.
                        if (variant == 2 && (linear[ra] || linear[rb]) && tangent &&
                            t.deviation <= max_tol) {
                            best = t;
                            break;
                        }
                        if (best.deviation < 0 || t.deviation < best.deviation) best = t;
                    }
                    ok = best.deviation >= 0 && best.deviation <= max_tol;
                    // Last, the curve through the points midway between the two surfaces
                    // (midway_points()): along a tangent junction, where the solved points
                    // slid across the tangency band (two fitted pieces of one free-form
                    // face, a fillet on a slightly tilted wall); and where two surfaces meet
                    // at a shallow angle without crossing on the chain (two B-splines at
                    // 15-18 degrees on NIST CTC 02, each within the deflection of its
                    // points: apart by up to that along the chain, they cross off it or
                    // nowhere near, and no intersection or solved point is on the chain).
                    // Piecewise-linear first for a region whose wire crossed itself, as above.
                    // Also along a tangent junction whose best curve so far is farther from
                    // the surfaces than the mesh's chordal deflection (and the tolerance),
                    // taken where nearer: two surfaces fitted a little apart, so that no
                    // point is on both. Such an edge's tolerance is looser than the mesh's
                    // own error, and BRepMesh, which follows its curves on the surfaces,
                    // left the face's triangles twice that off the mesh (NIST FTC 07 at 88k
                    // facets: a torus and the cylinder it rounds fitted 0.07 mm apart, the
                    // curve through the solved points 0.17 mm = 1.7 delta off them, midway
                    // 0.015 mm; the torus's triangles 0.36 mm off the mesh). Not for every
                    // curve beyond the tolerance: the link rods' B-spline patches, whose
                    // midway curves are nearer both surfaces, then ended 2.7 delta off the
                    // mesh (1.06 before).
                    const bool loose =
                        ok && tangent &&
                        best.deviation > std::max(opt.tolerance, opt.chordal_deflection);
                    if (!ok || loose) {
                        const std::vector<gp_Pnt> mid =
                            midway_points(sa, sb, m, ch.vertices, job.p0, job.p1, opt.tolerance);
                        const bool linear_first = linear[ra] || linear[rb];
                        bool taken = false;
                        for (int variant = 0; variant < 2 && !taken; ++variant) {
                            ChainCurve t;
                            if (!fitted_curve(mid, ch.closed, (variant == 0) == linear_first, t))
                                continue;
                            t.deviation =
                                curve_off_surfaces(t, sa, sb, 4 * static_cast<int>(mid.size()));
                            taken = t.deviation <= max_tol && !strays_from(t, mid, stray) &&
                                    (!ok || t.deviation < best.deviation);
                            if (taken) best = t;
                        }
                        ok = ok || taken;
                    }
                    if (ok) cc = best;
                    // Exact, unless the curve through the midway points replaced it.
                    job.analytic = ok && !conic.IsNull() && best.curve == conic;
                }
            } catch (const Standard_Failure&) {
                ok = false;
            }
        };
        // The curves to make this round (the chains between two surfaces whose curve is not kept
        // from the round before), made in parallel; their corners solved first.
        std::vector<CurveJob> jobs;
        for (std::size_t c = 0; c < borders.chains.size(); ++c) {
            const BorderChain& ch = borders.chains[c];
            if (ch.right < 0) continue;
            const auto ra = static_cast<std::size_t>(ch.left),
                       rb = static_cast<std::size_t>(ch.right);
            if (fallback[ra] || fallback[rb] || collapsed[c]) continue;
            const TopoDS_Vertex V0 = solved_vertex(ch.vertices.front());
            const TopoDS_Vertex V1 = ch.closed ? V0 : solved_vertex(ch.vertices.back());
            const gp_Pnt p0 = BRep_Tool::Pnt(V0), p1 = BRep_Tool::Pnt(V1);
            const GeometryCache::Chain& kept = cache.chains[c];
            const std::array<std::uint8_t, 4> state{fallback[ra], fallback[rb], linear[ra],
                                                    linear[rb]};
            if (opt.reuse_geometry && kept.valid && kept.state == state && kept.p0.IsEqual(p0, 0) &&
                kept.p1.IsEqual(p1, 0)) {
                continue;
            }
            CurveJob job;
            job.chain = c;
            job.state = state;
            job.p0 = p0;
            job.p1 = p1;
            jobs.push_back(std::move(job));
        }
        tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t j) { make_curve(jobs[j]); });
        // Kept for the next round: every chain between two surfaces now has this round's curve
        // (or its failure) in the cache.
        for (CurveJob& job : jobs) {
            GeometryCache::Chain& kept = cache.chains[job.chain];
            kept = GeometryCache::Chain{};
            ++out.curves_made;
            kept.state = job.state;
            kept.p0 = job.p0;
            kept.p1 = job.p1;
            if (!job.ok) continue;
            kept.valid = true;
            kept.id = cache.next_id++;
            kept.curve = std::move(job.cc);
            kept.kind = job.intersected ? ChainKind::kIntersection
                        : job.touched   ? ChainKind::kTangency
                                        : ChainKind::kFitted;
            kept.analytic = job.analytic;
        }
        std::vector<std::int32_t> failed_chain;
        for (std::size_t c = 0; c < borders.chains.size(); ++c) {
            const BorderChain& ch = borders.chains[c];
            const auto ra = static_cast<std::size_t>(ch.left);
            const bool boundary = ch.right < 0;
            const auto rb = boundary ? ra : static_cast<std::size_t>(ch.right);
            const VertexId v0 = ch.vertices.front(), v1 = ch.vertices.back();
            const bool polyline = boundary || fallback[ra] || fallback[rb];
            if (collapsed[c]) continue;  // no edge; chain_id 0
            if (!polyline) {
                const TopoDS_Vertex V0 = solved_vertex(v0);
                const TopoDS_Vertex V1 = ch.closed ? V0 : solved_vertex(v1);
                // The curve made above, or kept from the round before: a copy (this round's
                // fixes may change its edge's).
                const GeometryCache::Chain& kept = cache.chains[c];
                bool ok = kept.valid;
                ChainCurve cc;
                if (ok) {
                    cc = kept.curve;
                    cc.curve = Handle(Geom_Curve)::DownCast(kept.curve.curve->Copy());
                    if (kept.analytic) ++out.analytic_edges;
                }
                try {
                    if (ok) {
                        // The vertices reach the curve's ends.
                        const gp_Pnt e0 = cc.curve->Value(cc.first), e1 = cc.curve->Value(cc.last);
                        B.UpdateVertex(V0, std::max(BRep_Tool::Tolerance(V0),
                                                    1.01 * e0.Distance(BRep_Tool::Pnt(V0))));
                        B.UpdateVertex(V1, std::max(BRep_Tool::Tolerance(V1),
                                                    1.01 * e1.Distance(BRep_Tool::Pnt(V1))));
                        BRepBuilderAPI_MakeEdge me(cc.curve, V0, V1, cc.first, cc.last);
                        ok = me.IsDone();
                        if (ok) {
                            TopoDS_Edge e = me.Edge();
                            B.UpdateEdge(e, std::max(kMinTolerance, 1.01 * cc.deviation));
                            chain_edges[c].push_back(e);
                            ++(kept.kind == ChainKind::kIntersection ? out.intersection_edges
                               : kept.kind == ChainKind::kTangency   ? out.tangency_edges
                                                                     : out.fitted_edges);
                        }
                    }
                } catch (const Standard_Failure&) {
                    ok = false;
                }
                if (ok) {
                    chain_id[c] = kept.id;
                    continue;
                }
                failed_chain.push_back(static_cast<std::int32_t>(c));
            }
            // The chain's own segments.
            {
                GeometryCache::Chain& kept = cache.chains[c];
                const gp_Pnt q0 = BRep_Tool::Pnt(plain_vertex(v0));
                const gp_Pnt q1 = BRep_Tool::Pnt(plain_vertex(v1));
                if (kept.polyline_id == 0 || !kept.q0.IsEqual(q0, 0) || !kept.q1.IsEqual(q1, 0)) {
                    kept.polyline_id = cache.next_id++;
                    kept.q0 = q0;
                    kept.q1 = q1;
                }
                chain_id[c] = kept.polyline_id;
            }
            for (std::size_t k = 0; k + 1 < ch.vertices.size(); ++k) {
                bool fwd = true;
                TopoDS_Edge e = segment_edge(ch.vertices[k], ch.vertices[k + 1], fwd);
                chain_edges[c].push_back(
                    TopoDS::Edge(e.Oriented(fwd ? TopAbs_FORWARD : TopAbs_REVERSED)));
            }
            ++out.polyline_edges;
        }
        // A chain without a curve between two surfaces: a region on either side whose facets are
        // chords of its neighbour's surface joins it; otherwise one side becomes facets (below).
        bool changed = false;
        bool chain_absorbed = false;
        for (std::int32_t c : failed_chain) {
            const BorderChain& ch = borders.chains[static_cast<std::size_t>(c)];
            for (std::int32_t r : {ch.left, ch.right}) {
                if (r >= 0 && absorbed[static_cast<std::size_t>(ch.left)] < 0 &&
                    (ch.right < 0 || absorbed[static_cast<std::size_t>(ch.right)] < 0) &&
                    try_absorb(static_cast<std::size_t>(r))) {
                    chain_absorbed = true;
                }
            }
        }
        if (chain_absorbed) {
            relabelled();
            continue;
        }
        // A chain whose end moved onto a contact curve: first again with plain corners.
        bool chain_plain_retry = false;
        for (std::int32_t c : failed_chain) {
            const BorderChain& ch = borders.chains[static_cast<std::size_t>(c)];
            for (const VertexId end : {ch.vertices.front(), ch.vertices.back()}) {
                const auto& at = contact_at[static_cast<std::size_t>(ch.left)];
                if (std::find(at.begin(), at.end(), end.idx()) != at.end() &&
                    plain_at.insert(end.idx()).second) {
                    chain_plain_retry = true;
                }
            }
        }
        if (chain_plain_retry && round < kMaxRounds) continue;
        // Only the smaller of the two becomes facets: the chain is then its polyline of mesh
        // edges, chords of the larger region's surface like every edge between a surface face
        // and fallback facets (a 215-facet plane went to facets for a 30-facet fillet's sake).
        for (std::int32_t c : failed_chain) {
            const BorderChain& ch = borders.chains[static_cast<std::size_t>(c)];
            if (ch.right < 0) continue;
            const auto l = static_cast<std::size_t>(ch.left),
                       r = static_cast<std::size_t>(ch.right);
            if (fallback[l] || fallback[r]) continue;
            const bool left_smaller =
                bd.facets[l] < bd.facets[r] ||
                (bd.facets[l] == bd.facets[r] && regions[r].surface.kind == FitKind::kPlane);
            const std::size_t drop = left_smaller ? l : r;
            fall_back(drop, "no edge curve with region " + std::to_string(left_smaller ? r : l));
            changed = true;
        }
        if (changed) {
            if (!opt.allow_fallback) break;
            continue;
        }

        // 4. Faces.
        Handle(ShapeBuild_ReShape) context = new ShapeBuild_ReShape;
        std::vector<std::vector<TopoDS_Face>> faces(nr);
        cache.faces.resize(nr);
        std::vector<std::pair<std::size_t, std::string>> failed_region;
        // A new face to check: its region, a copy of it as built, what it is made from.
        struct FaceCheck {
            std::size_t region = 0;
            TopoDS_Face copy;
            GeometryCache::Face made;
            std::string failure;
        };
        std::vector<FaceCheck> to_check;
        // A surface face that fails is retried or falls back (below); a fallback region's face
        // bounded by its mesh edges that fails leaves the region as its facets.
        // The fallback regions' faces bounded by mesh edges, but not in the last two rounds:
        // facets always close the shell, so the last round cannot fail on such a face.
        const auto makes_mesh_edge_faces = [&](int k) {
            return opt.allow_fallback && k < kMaxRounds - 1;
        };
        const bool mesh_edge_faces = makes_mesh_edge_faces(round);
        // A fallback region whose mesh-edge face failed: on a B-spline next round, if that
        // round still makes such faces and the fit succeeds.
        const auto on_spline_next = [&](std::size_t r) {
            return makes_mesh_edge_faces(round + 1) && spline_fallback(r);
        };
        bool spline_retry = false;
        const auto face_failed = [&](std::size_t r, std::string why) {
            if (fallback[r]) {
                if (on_spline_next(r)) {
                    spline_retry = true;
                } else {
                    as_facets[r] = 1;
                }
            } else {
                failed_region.emplace_back(r, std::move(why));
            }
        };
        for (std::size_t r = 0; r < nr; ++r) {
            if (bd.facets[r] == 0) continue;
            if (fallback[r] && (!mesh_edge_faces || as_facets[r] || !fallback_surface(r))) {
                as_facets[r] = 1;
                continue;
            }
            // Made from the same as a face that passed the checks before: no checks.
            GeometryCache::Face made;
            made.surface = geom[r];
            made.sense = sense[r];
            made.fallback = fallback[r] != 0;
            made.own_seam = own_seam[r] != 0;
            for (const auto& loop : bd.loops[r]) {
                for (const auto& lc : loop) {
                    made.chains.push_back(chain_id[static_cast<std::size_t>(lc.first)]);
                }
            }
            const GeometryCache::Face& passed = cache.faces[r];
            const bool checked = opt.reuse_geometry && passed.valid &&
                                 passed.surface == made.surface && passed.sense == made.sense &&
                                 passed.fallback == made.fallback &&
                                 passed.own_seam == made.own_seam && passed.chains == made.chains;
            try {
                TopoDS_Face F;
                if (bd.loops[r].empty()) {
                    BRepBuilderAPI_MakeFace mf(geom[r], Precision::Confusion());
                    if (!mf.IsDone()) throw Standard_Failure("natural bounds");
                    F = mf.Face();
                } else {
                    B.MakeFace(F, geom[r], kMinTolerance);
                    std::size_t wire_edges_in = 0;
                    std::vector<std::vector<TopoDS_Edge>> wires;
                    for (const auto& loop : bd.loops[r]) {
                        // The loop, in the surface's own orientation.
                        std::vector<TopoDS_Edge> wire_edges;
                        for (const auto& [c, fwd] : loop) {
                            const auto& es = chain_edges[static_cast<std::size_t>(c)];
                            if (fwd) {
                                for (const TopoDS_Edge& e : es) wire_edges.push_back(e);
                            } else {
                                for (auto it = es.rbegin(); it != es.rend(); ++it) {
                                    wire_edges.push_back(TopoDS::Edge(it->Reversed()));
                                }
                            }
                        }
                        if (sense[r] < 0) {
                            std::reverse(wire_edges.begin(), wire_edges.end());
                            for (TopoDS_Edge& e : wire_edges) e.Reverse();
                        }
                        wire_edges_in += wire_edges.size();
                        wires.push_back(std::move(wire_edges));
                    }
                    bool is_band = false;
                    if (auto seamed = seamed_band(F, wires, max_tol, own_seam[r] != 0, is_band);
                        !seamed.empty()) {
                        wires = std::move(seamed);
                        // With the seam (and the apex's degenerated edge).
                        TopTools_IndexedMapOfShape distinct;
                        for (const auto& we : wires) {
                            for (const TopoDS_Edge& e : we) distinct.Add(e);
                        }
                        wire_edges_in = static_cast<std::size_t>(distinct.Extent());
                    }
                    is_band_face[r] = is_band ? 1 : 0;
                    for (const auto& wire_edges : wires) add_wire(B, F, wire_edges);
                    // The edges earlier faces' fixes replaced, replaced here too: a shared
                    // edge fixed twice from its original would otherwise become two edges.
                    F = TopoDS::Face(context->Apply(F));
                    {
                        bool reordered = false;
                        std::vector<std::vector<TopoDS_Edge>> walked;
                        for (TopoDS_Iterator w(F); w.More(); w.Next()) {
                            std::vector<TopoDS_Edge> es;
                            for (TopoDS_Iterator e(w.Value()); e.More(); e.Next()) {
                                es.push_back(TopoDS::Edge(e.Value()));
                            }
                            reordered = in_walk_order(es) || reordered;
                            walked.push_back(std::move(es));
                        }
                        if (reordered) {
                            TopoDS_Face G;
                            B.MakeFace(G, geom[r], kMinTolerance);
                            for (const auto& es : walked) add_wire(B, G, es);
                            F = G;
                        }
                    }
                    ShapeFix_Face fix(F);
                    fix.SetContext(context);
                    fix.SetPrecision(kMinTolerance);
                    fix.SetMinTolerance(kMinTolerance);
                    fix.SetMaxTolerance(max_tol);
                    // Only the fixes that keep the edges shared with the neighbours: curves on
                    // the surface, seams, poles, orientation. Those that drop, merge, split or
                    // add edges or wires (small edges and wires, self-intersections, lacking
                    // edges, loops) would leave a neighbour's edge without its twin.
                    fix.FixSmallAreaWireMode() = 0;
                    fix.FixIntersectingWiresMode() = 0;
                    fix.FixLoopWiresMode() = 0;
                    fix.FixSplitFaceMode() = 0;
                    // Nor the wires' orientation, but on spheres and tori (surfaces closed both
                    // ways): each loop is walked in the surface's own orientation (above), and
                    // on a plane, cylinder, cone or B-spline a wire the wrong way round fails
                    // the check below (BRepCheck_Analyzer refuses a plane's square bounded
                    // clockwise). On a sphere or torus a loop the wrong way round would instead
                    // get the surface's natural bounds added around it (FixAddNaturalBound) and
                    // pass as the rest of the surface: there the orientation fix stays. Telling
                    // outer from inner (IsOuterBound) was two fifths of the fix, which runs on
                    // every face, serially, in every round (docs/benchmarks.md, thirty-fourth
                    // session).
                    const bool closed_both_ways = geom[r]->IsUClosed() && geom[r]->IsVClosed();
                    if (!closed_both_ways &&
                        !geom[r]->IsKind(STANDARD_TYPE(Geom_SphericalSurface))) {
                        fix.FixOrientationMode() = 0;
                    }
                    const Handle(ShapeFix_Wire)& wire_fix = fix.FixWireTool();
                    wire_fix->FixReorderMode() = 0;
                    wire_fix->FixSmallMode() = 0;
                    wire_fix->FixConnectedMode() = 0;
                    wire_fix->FixSelfIntersectionMode() = 0;
                    wire_fix->FixLackingMode() = 0;
                    wire_fix->FixNotchedEdgesMode() = 0;
                    wire_fix->FixTailMode() = 0;
                    fix.Perform();
                    F = fix.Face();
                    // Edges the fix added or changed (seams, split edges) get their parameter
                    // ranges and tolerances made consistent with their curves on the surface.
                    for (TopExp_Explorer x(F, TopAbs_EDGE); x.More(); x.Next()) {
                        ShapeFix_Edge().FixSameParameter(TopoDS::Edge(x.Current()));
                    }
                    // The fix may still drop a whole wire (one it finds outside the surface's
                    // bounds): the face then passes its check and leaves its neighbours' edges
                    // unpaired (the M6 screw's threaded cone kept 11 of its 158 edges, and the
                    // part went planar). It adds seams and splits edges, but never has fewer.
                    TopTools_IndexedMapOfShape kept_edges;
                    TopExp::MapShapes(F, TopAbs_EDGE, kept_edges);
                    if (static_cast<std::size_t>(kept_edges.Extent()) < wire_edges_in) {
                        face_failed(r, "its face's fix dropped edges (" +
                                           std::to_string(kept_edges.Extent()) + " of " +
                                           std::to_string(wire_edges_in) + " left)");
                        continue;
                    }
                }
                if (sense[r] < 0) F.Reverse();
                faces[r].push_back(F);
                made.valid = true;
                if (checked) {
                    cache.faces[r] = std::move(made);
                    continue;
                }
                // Checked below, as it is now: later faces' fixes change shared edges in place.
                ++out.faces_checked;
                to_check.push_back(
                    {r, TopoDS::Face(BRepBuilderAPI_Copy(F).Shape()), std::move(made), {}});
            } catch (const Standard_Failure& f) {
                face_failed(
                    r, std::string("OpenCASCADE fails building its face: ") + f.GetMessageString());
            }
        }
        // The new faces' checks (OpenCASCADE's; BRepMesh can triangulate it), each on its own
        // copy, in parallel; failures taken in region order, as one after the other would be.
        tbb::parallel_for(std::size_t{0}, to_check.size(), [&](std::size_t i) {
            FaceCheck& fc = to_check[i];
            try {
                if (std::string why = check_failure(fc.copy); !why.empty()) {
                    fc.failure = "its face fails OpenCASCADE's check (" + why + ")";
                    return;
                }
                if (has_no_length_loop(TopoDS::Face(fc.copy))) {
                    fc.failure = kNoLengthLoop;
                    return;
                }
                if (opt.mesh_deflection > 0) {
                    triangulate(fc.copy, opt.mesh_deflection, false);
                    TopLoc_Location loc;
                    if (BRep_Tool::Triangulation(fc.copy, loc).IsNull()) {
                        fc.failure = kUntriangulated;
                    }
                }
            } catch (const Standard_Failure& f) {
                fc.failure =
                    std::string("OpenCASCADE fails building its face: ") + f.GetMessageString();
            }
        });
        for (FaceCheck& fc : to_check) {
            if (fc.failure.empty()) {
                cache.faces[fc.region] = std::move(fc.made);
                continue;
            }
            faces[fc.region].pop_back();
            face_failed(fc.region, std::move(fc.failure));
        }
        std::stable_sort(failed_region.begin(), failed_region.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        // Facet faces of the fallback regions without a face of their own.
        for (std::uint32_t fi = 0; fi < m.num_faces(); ++fi) {
            const FaceId f(fi);
            const auto r = static_cast<std::size_t>(labels[f]);
            if (!fallback[r] || !as_facets[r]) continue;
            TopoDS_Wire W;
            B.MakeWire(W);
            for (int i = 0; i < 3; ++i) {
                const HalfedgeId h = m.halfedge(f, i);
                bool fwd = true;
                TopoDS_Edge e = segment_edge(m.origin(h), m.target(h), fwd);
                B.Add(W, e.Oriented(fwd ? TopAbs_FORWARD : TopAbs_REVERSED));
            }
            W.Closed(true);
            const gp_Pnt p0 = BRep_Tool::Pnt(plain_vertex(m.vertex(f, 0)));
            const gp_Pnt p1 = BRep_Tool::Pnt(plain_vertex(m.vertex(f, 1)));
            const gp_Pnt p2 = BRep_Tool::Pnt(plain_vertex(m.vertex(f, 2)));
            const gp_Vec n = gp_Vec(p0, p1).Crossed(gp_Vec(p0, p2));
            // Healing leaves no zero-area facet; one whose corner was solved onto another's
            // place leaves its neighbours' edges unpaired, which the closed-shell check
            // below turns into further fallbacks.
            if (n.Magnitude() <= 0) continue;
            TopoDS_Face F;
            B.MakeFace(F, new Geom_Plane(p0, gp_Dir(n)), kMinTolerance);
            B.Add(F, W);
            faces[r].push_back(F);
        }
        if (spline_retry && failed_region.empty()) continue;
        if (!failed_region.empty()) {
            if (!opt.allow_fallback) {
                out.problem = "region " + std::to_string(failed_region.front().first) + ": " +
                              failed_region.front().second;
                return out;
            }
            // Smallest first: a sliver region's failing face often takes a large neighbour's
            // with it (their shared edges zigzag); once the sliver is facets, the neighbour's
            // face usually builds. Regions more than 4x larger than the smallest failing one
            // get another round (all of them in the last).
            bool retry = false;
            for (const auto& [r, why] : failed_region) {
                bool tried = false;
                if (is_band_face[r] && !own_seam[r]) {
                    own_seam[r] = 1;
                    tried = true;
                } else if (why == kNoLengthLoop && seam_turns[r] < kSeamTurns) {
                    ++seam_turns[r];
                    geom[r] = seam_turned(geom[r], 1);
                    tried = true;
                }
                if (make_plain(r)) tried = true;
                const bool crossed = why.find("SelfIntersectingWire") != std::string::npos;
                if (!linear[r] && (crossed || why == kUntriangulated)) {
                    linear[r] = 1;
                    tried = true;
                }
                // Last, its plainly solved corners that moved back to their mesh vertices.
                if (!tried && crossed) {
                    for (std::uint32_t v : moved_at[r]) tried = vertex_at.insert(v).second || tried;
                }
                retry = retry || tried;
            }
            if (retry && round < kMaxRounds) continue;
            bool absorbed_any = false;
            for (const auto& [r, why] : failed_region) absorbed_any = try_absorb(r) || absorbed_any;
            if (absorbed_any) {
                relabelled();
                continue;
            }
            std::size_t smallest = SIZE_MAX;
            for (const auto& [r, why] : failed_region) {
                smallest = std::min(smallest, bd.facets[r]);
            }
            for (auto& [r, why] : failed_region) {
                if (round == kMaxRounds || bd.facets[r] <= 4 * smallest) {
                    fall_back(r, std::move(why));
                }
            }
            continue;
        }

        // 5. Shell and solid.
        TopoDS_Shell shell;
        B.MakeShell(shell);
        for (std::size_t r = 0; r < nr; ++r) {
            for (const TopoDS_Face& f : faces[r]) B.Add(shell, f);
        }
        const TopoDS_Shape fixed = context->Apply(shell);
        TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
        TopExp::MapShapesAndUniqueAncestors(fixed, TopAbs_EDGE, TopAbs_FACE, edge_faces);
        bool closed = true;
        std::vector<TopoDS_Shape> open_faces;  // faces along an edge that has no other face
        for (int i = 1; i <= edge_faces.Extent(); ++i) {
            const TopoDS_Edge& e = TopoDS::Edge(edge_faces.FindKey(i));
            if (BRep_Tool::Degenerated(e)) continue;
            const int n = edge_faces.FindFromIndex(i).Extent();
            if (n == 2) continue;
            if (n == 1 && BRep_Tool::IsClosed(e, TopoDS::Face(edge_faces.FindFromIndex(i).First())))
                continue;
            closed = false;
            for (const TopoDS_Shape& f : edge_faces.FindFromIndex(i)) open_faces.push_back(f);
        }
        // Faces that run along a shared edge in the same direction (one of them turned
        // inside out, e.g. by a wire the fix reversed): the shell cannot be oriented there.
        {
            std::map<const void*, std::pair<int, std::vector<TopoDS_Shape>>> use;
            for (TopExp_Explorer fx(fixed, TopAbs_FACE); fx.More(); fx.Next()) {
                for (TopExp_Explorer ex(fx.Current(), TopAbs_EDGE); ex.More(); ex.Next()) {
                    const TopoDS_Edge& e = TopoDS::Edge(ex.Current());
                    if (BRep_Tool::Degenerated(e) ||
                        BRep_Tool::IsClosed(e, TopoDS::Face(fx.Current()))) {
                        continue;
                    }
                    auto& [balance, fs] = use[e.TShape().get()];
                    balance += e.Orientation() == TopAbs_FORWARD ? 1 : -1;
                    fs.push_back(fx.Current());
                }
            }
            for (const auto& [key, u] : use) {
                if (u.first == 0 || u.second.size() != 2) continue;
                closed = false;
                for (const TopoDS_Shape& f : u.second) open_faces.push_back(f);
            }
        }
        for (std::size_t r = 0; r < nr; ++r) {
            out.regions[r].contact_corners = contact_corner(r);
            out.regions[r].faces.clear();
            for (const TopoDS_Face& f : faces[r]) {
                out.regions[r].faces.push_back(TopoDS::Face(context->Value(f)));
            }
        }
        // Every edge now has its curves on both faces: make them agree (same range, same
        // parameter), with the tolerance that takes.
        for (TopExp_Explorer x(fixed, TopAbs_EDGE); x.More(); x.Next()) {
            ShapeFix_Edge().FixSameParameter(TopoDS::Edge(x.Current()));
        }
        TopoDS_Shape result = fixed;
        if (closed) result = solids_of(TopoDS::Shell(fixed));
        out.shape = result;
        out.solid = closed;
        std::vector<TopoDS_Shape> bad = open_faces;
        const std::string why = closed ? check_failure(result, &bad, true)
                                       : std::string("the shell is not closed, or not orientable");
        out.valid = why.empty() && closed;
        if (!why.empty()) out.problem = closed ? "BRepCheck_Analyzer: " + why : why;
        if (out.valid || !opt.allow_fallback) break;
        // The regions whose faces hold what the check finds wrong become facets.
        TopTools_IndexedMapOfShape bad_faces;
        for (const TopoDS_Shape& b : bad) {
            if (b.ShapeType() == TopAbs_FACE) {
                bad_faces.Add(b);
                continue;
            }
            TopTools_IndexedDataMapOfShapeListOfShape anc;
            TopExp::MapShapesAndUniqueAncestors(result, b.ShapeType(), TopAbs_FACE, anc);
            const int i = anc.FindIndex(b);
            if (i == 0) continue;
            for (const TopoDS_Shape& f : anc.FindFromIndex(i)) bad_faces.Add(f);
        }
        std::vector<std::size_t> bad_regions;
        bool to_facets = false;
        for (std::size_t r = 0; r < nr; ++r) {
            if (fallback[r] && as_facets[r]) continue;
            for (const TopoDS_Face& f : out.regions[r].faces) {
                if (bad_faces.Contains(f) || bad_faces.Contains(f.Reversed())) {
                    // A fallback's face bounded by mesh edges: its facets next round.
                    if (fallback[r]) {
                        if (!on_spline_next(r)) as_facets[r] = 1;
                        to_facets = true;
                    } else {
                        bad_regions.push_back(r);
                    }
                    break;
                }
            }
        }
        if (bad_regions.empty()) {
            if (to_facets) continue;
            break;
        }
        bool plain_retry = false;
        for (std::size_t r : bad_regions) {
            plain_retry = make_plain(r) || plain_retry;
            if (is_band_face[r] && !own_seam[r]) {
                own_seam[r] = 1;
                plain_retry = true;
            }
        }
        if (plain_retry && round < kMaxRounds) continue;
        bool solid_absorbed = false;
        for (std::size_t r : bad_regions) {
            if (bd.facets[r] > 0) solid_absorbed = try_absorb(r) || solid_absorbed;
        }
        if (solid_absorbed) {
            relabelled();
            continue;
        }
        for (std::size_t r : bad_regions) {
            fall_back(r, "the solid fails OpenCASCADE's check at its face (" + why + ")");
        }
    }
    for (std::size_t r = 0; r < nr; ++r) {
        out.regions[r].absorbed_into = absorbed[r];
        out.regions[r].mesh_edges = fallback[r] && !as_facets[r];
        out.regions[r].facets = bd.facets[r];
    }
    // Largest tolerance.
    if (!out.shape.IsNull()) {
        for (TopExp_Explorer x(out.shape, TopAbs_VERTEX); x.More(); x.Next()) {
            out.max_tolerance =
                std::max(out.max_tolerance, BRep_Tool::Tolerance(TopoDS::Vertex(x.Current())));
        }
        for (TopExp_Explorer x(out.shape, TopAbs_EDGE); x.More(); x.Next()) {
            out.max_tolerance =
                std::max(out.max_tolerance, BRep_Tool::Tolerance(TopoDS::Edge(x.Current())));
        }
    }
    return out;
}

}  // namespace ncrev::brep_detail
