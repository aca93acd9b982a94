// The sample parts: each a few lines of OpenCASCADE modelling from named dimensions, the way a
// machinist would describe the part (stock, then the features cut into it). All lengths in mm.
// Features are selected by where their edges lie, never by OpenCASCADE's edge order, so a
// different seed (other dimensions) selects the same features.
#include <BRepAdaptor_Curve.hxx>
#include <BRepAlgoAPI_Common.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepFilletAPI_MakeChamfer.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepOffsetAPI_MakeThickSolid.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRep_Tool.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <GeomAPI_PointsToBSplineSurface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <ShapeUpgrade_UnifySameDomain.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <array>
#include <cmath>
#include <gp_Circ.hxx>
#include <numbers>

#include "sample/sample_internal.h"

namespace ncrev::sample_detail {

// ---------------------------------------------------------------------------------------------
// Dimensions

namespace {

std::uint64_t fnv1a(std::string_view s) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const char c : s) {
        h ^= static_cast<unsigned char>(c);
        h *= 0x100000001b3ull;
    }
    return h;
}

double round_to(double v, double step) { return std::round(v / step) * step; }

}  // namespace

Dims::Dims(std::string_view part, std::uint64_t seed)
    : rng_(seed ^ fnv1a(part)), vary_(seed != 0) {}

double Dims::vary(double nominal, double rel) {
    if (!vary_ || rel <= 0) return nominal;
    return nominal * (1.0 + rel * (2.0 * rng_.uniform() - 1.0));
}

double Dims::length(const char* name, double nominal, double rel) {
    const double v = round_to(vary(nominal, rel), 0.01);
    dims_.push_back({name, v});
    return v;
}

double Dims::angle_deg(const char* name, double nominal, double rel) {
    const double v = round_to(vary(nominal, rel), 0.01);
    dims_.push_back({name, v});
    return v;
}

int Dims::count(const char* name, int nominal, int lo, int hi) {
    int v = nominal;
    if (vary_) v = lo + static_cast<int>(rng_.next() % static_cast<std::uint64_t>(hi - lo + 1));
    dims_.push_back({name, static_cast<double>(v)});
    return v;
}

double Dims::derived(const char* name, double value) {
    dims_.push_back({name, value});
    return value;
}

// ---------------------------------------------------------------------------------------------
// Modelling helpers

namespace {

constexpr double kPi = std::numbers::pi;
// Edges are selected by position: modelling noise is ~1e-7 mm, distinct features are at least
// tenths of a millimetre apart, so 1e-4 mm separates the two by three orders of magnitude.
constexpr double kSelectTol = 1e-4;
// Tools stick out of the stock by this much so that no tool face is coplanar with a stock
// face (coplanar faces make booleans fragile).
constexpr double kOverrun = 2.0;
// Half of a 118 degree drill point: the standard twist drill.
constexpr double kDrillHalfAngleDeg = 59.0;

bool near(double a, double b) { return std::abs(a - b) < kSelectTol; }
double deg(double degrees) { return degrees * kPi / 180.0; }

TopoDS_Shape box(double x0, double y0, double z0, double x1, double y1, double z1) {
    BRepPrimAPI_MakeBox mk(gp_Pnt(x0, y0, z0), gp_Pnt(x1, y1, z1));
    return mk.Shape();
}

TopoDS_Shape unify(const TopoDS_Shape& s) {
    ShapeUpgrade_UnifySameDomain u(s, /*UnifyEdges=*/true, /*UnifyFaces=*/true,
                                   /*ConcatBSplines=*/false);
    u.Build();
    return u.Shape();
}

TopoDS_Shape cut(const TopoDS_Shape& a, const TopoDS_Shape& b, const char* what) {
    BRepAlgoAPI_Cut op(a, b);
    if (!op.IsDone() || op.HasErrors()) throw ModelError(std::string("cut failed: ") + what);
    return unify(op.Shape());
}

TopoDS_Shape fuse(const TopoDS_Shape& a, const TopoDS_Shape& b, const char* what) {
    BRepAlgoAPI_Fuse op(a, b);
    if (!op.IsDone() || op.HasErrors()) throw ModelError(std::string("fuse failed: ") + what);
    return unify(op.Shape());
}

TopoDS_Shape common(const TopoDS_Shape& a, const TopoDS_Shape& b, const char* what) {
    BRepAlgoAPI_Common op(a, b);
    if (!op.IsDone() || op.HasErrors()) throw ModelError(std::string("common failed: ") + what);
    return unify(op.Shape());
}

/// Where an edge lies: its curve type, its first, middle and last points, and for a circle
/// its radius.
struct EdgeGeom {
    GeomAbs_CurveType type = GeomAbs_OtherCurve;
    gp_Pnt a, m, b;
    double radius = 0;

    bool all_z(double z) const { return near(a.Z(), z) && near(m.Z(), z) && near(b.Z(), z); }
    bool all_x(double x) const { return near(a.X(), x) && near(m.X(), x) && near(b.X(), x); }
    bool is_line() const { return type == GeomAbs_Line; }
    bool is_circle() const { return type == GeomAbs_Circle; }
    /// A line parallel to Z.
    bool is_vertical() const { return is_line() && near(a.X(), b.X()) && near(a.Y(), b.Y()); }
    /// A line parallel to Y.
    bool along_y() const { return is_line() && near(a.X(), b.X()) && near(a.Z(), b.Z()); }
};

EdgeGeom edge_geom(const TopoDS_Edge& e) {
    BRepAdaptor_Curve c(e);
    EdgeGeom g;
    g.type = c.GetType();
    const double t0 = c.FirstParameter(), t1 = c.LastParameter();
    g.a = c.Value(t0);
    g.m = c.Value(0.5 * (t0 + t1));
    g.b = c.Value(t1);
    if (g.type == GeomAbs_Circle) g.radius = c.Circle().Radius();
    return g;
}

/// The non-degenerate edges of `s` whose geometry satisfies `pred`.
template <class Pred>
std::vector<TopoDS_Edge> select_edges(const TopoDS_Shape& s, Pred pred) {
    TopTools_IndexedMapOfShape edges;
    TopExp::MapShapes(s, TopAbs_EDGE, edges);
    std::vector<TopoDS_Edge> out;
    for (int i = 1; i <= edges.Extent(); ++i) {
        const TopoDS_Edge& e = TopoDS::Edge(edges(i));
        if (BRep_Tool::Degenerated(e)) continue;
        if (pred(edge_geom(e))) out.push_back(e);
    }
    return out;
}

TopoDS_Shape fillet(const TopoDS_Shape& s, double r, const std::vector<TopoDS_Edge>& edges,
                    const char* what) {
    if (edges.empty()) throw ModelError(std::string("no edge to fillet: ") + what);
    BRepFilletAPI_MakeFillet mk(s);
    for (const TopoDS_Edge& e : edges) mk.Add(r, e);
    mk.Build();
    if (!mk.IsDone()) throw ModelError(std::string("fillet failed: ") + what);
    return mk.Shape();
}

TopoDS_Shape chamfer(const TopoDS_Shape& s, double d, const std::vector<TopoDS_Edge>& edges,
                     const char* what) {
    if (edges.empty()) throw ModelError(std::string("no edge to chamfer: ") + what);
    BRepFilletAPI_MakeChamfer mk(s);
    for (const TopoDS_Edge& e : edges) mk.Add(d, e);
    mk.Build();
    if (!mk.IsDone()) throw ModelError(std::string("chamfer failed: ") + what);
    return mk.Shape();
}

gp_Pnt at(const gp_Ax2& frame, double rho, double h) {
    return gp_Pnt(frame.Location().XYZ() + rho * frame.XDirection().XYZ() +
                  h * frame.Direction().XYZ());
}

/// A closed profile in the (radius, height) half-plane of `frame` made of straight segments,
/// revolved a full turn about the frame's axis: lines parallel to the axis become cylinders,
/// oblique ones cones, perpendicular ones planes.
TopoDS_Shape revolve_polygon(const gp_Ax2& frame, std::span<const std::array<double, 2>> rh) {
    BRepBuilderAPI_MakeWire wire;
    for (std::size_t i = 0; i < rh.size(); ++i) {
        const auto& p = rh[i];
        const auto& q = rh[(i + 1) % rh.size()];
        wire.Add(BRepBuilderAPI_MakeEdge(at(frame, p[0], p[1]), at(frame, q[0], q[1])).Edge());
    }
    BRepBuilderAPI_MakeFace face(wire.Wire(), /*OnlyPlane=*/true);
    if (!face.IsDone()) throw ModelError("profile face failed");
    BRepPrimAPI_MakeRevol rev(face.Face(), gp_Ax1(frame.Location(), frame.Direction()), 2 * kPi);
    if (!rev.IsDone()) throw ModelError("revolve failed");
    return rev.Shape();
}

/// The arc of the circle (centre and plane normal from `frame`, radius r) from p1 to p2 that
/// passes through `mid`. Built on the exact circle, not through three points, so that a
/// revolved arc is recognised as a torus or sphere.
TopoDS_Edge arc_edge(const gp_Ax2& frame, double r, const gp_Pnt& p1, const gp_Pnt& mid,
                     const gp_Pnt& p2) {
    for (const bool flip : {false, true}) {
        gp_Ax2 ax = frame;
        if (flip) ax = gp_Ax2(frame.Location(), frame.Direction().Reversed(), frame.XDirection());
        GC_MakeArcOfCircle arc(gp_Circ(ax, r), p1, p2, /*Sense=*/true);
        if (!arc.IsDone()) continue;
        const Handle(Geom_TrimmedCurve)& c = arc.Value();
        const gp_Pnt m = c->Value(0.5 * (c->FirstParameter() + c->LastParameter()));
        if (m.Distance(mid) < 1e-6 * (1 + r)) return BRepBuilderAPI_MakeEdge(c).Edge();
    }
    throw ModelError("arc construction failed");
}

/// A twist drill's hole: diameter `d`, full-diameter depth `depth` below the entry point
/// `top` along -Z, and a 118 degree cone tip; the tool rises kOverrun above the entry.
TopoDS_Shape drill_tool(double x, double y, double top, double d, double depth) {
    const double r = 0.5 * d;
    const double tip = r / std::tan(deg(kDrillHalfAngleDeg));
    const gp_Ax2 frame(gp_Pnt(x, y, top), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
    const std::array<std::array<double, 2>, 4> rh{
        {{0, kOverrun}, {r, kOverrun}, {r, -depth}, {0, -depth - tip}}};
    return revolve_polygon(frame, rh);
}

/// A countersunk through hole entering at (x, y, top) along -Z: the cone from radius rk at the
/// entry (its radius shrinks by `t` per unit depth) straight into the bore of radius rs, through
/// a plate of thickness `depth`; the tool rises kOverrun above the entry.
TopoDS_Shape countersink_tool(double x, double y, double top, double rk, double rs, double t,
                              double depth) {
    const gp_Ax2 frame(gp_Pnt(x, y, top), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
    const double cone_depth = (rk - rs) / t;
    const std::array<std::array<double, 2>, 5> rh{{{0, kOverrun},
                                                   {rk + kOverrun * t, kOverrun},
                                                   {rs, -cone_depth},
                                                   {rs, -depth - kOverrun},
                                                   {0, -depth - kOverrun}}};
    return revolve_polygon(frame, rh);
}

/// A straight through hole along Z from below z0 to above z1.
TopoDS_Shape through_tool(double x, double y, double z0, double z1, double d) {
    BRepPrimAPI_MakeCylinder mk(gp_Ax2(gp_Pnt(x, y, z0 - kOverrun), gp_Dir(0, 0, 1)), 0.5 * d,
                                z1 - z0 + 2 * kOverrun);
    return mk.Shape();
}

/// A stadium (slot outline: two half circles of radius r joined by straight sides) centred
/// at (cx, cy) with its centres 2a apart along X, in the plane z = z0, extruded by h along Z.
TopoDS_Shape stadium_prism(double cx, double cy, double a, double r, double z0, double h) {
    const gp_Pnt p0(cx - a, cy - r, z0), p1(cx + a, cy - r, z0);
    const gp_Pnt p2(cx + a, cy + r, z0), p3(cx - a, cy + r, z0);
    const gp_Pnt e1(cx + a + r, cy, z0), e0(cx - a - r, cy, z0);
    BRepBuilderAPI_MakeWire wire;
    wire.Add(BRepBuilderAPI_MakeEdge(p0, p1).Edge());
    wire.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(p1, e1, p2).Value()).Edge());
    wire.Add(BRepBuilderAPI_MakeEdge(p2, p3).Edge());
    wire.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(p3, e0, p0).Value()).Edge());
    BRepBuilderAPI_MakeFace face(wire.Wire(), /*OnlyPlane=*/true);
    if (!face.IsDone()) throw ModelError("slot outline failed");
    BRepPrimAPI_MakePrism prism(face.Face(), gp_Vec(0, 0, h));
    return prism.Shape();
}

// ---------------------------------------------------------------------------------------------
// The parts

TopoDS_Shape build_pocket_block(Dims& d) {
    const double L = d.length("block_length", 100), W = d.length("block_width", 70);
    const double H = d.length("block_height", 30);
    const double pl = d.length("pocket_length", 60), pw = d.length("pocket_width", 40);
    const double depth = d.length("pocket_depth", 12);
    const double rc = d.length("pocket_corner_radius", 8);
    const double rf = d.length("pocket_floor_fillet", 3);
    const double ch = d.length("top_edge_chamfer", 1.5);

    TopoDS_Shape block = box(0, 0, 0, L, W, H);
    block = chamfer(block, ch, select_edges(block, [&](const EdgeGeom& g) { return g.all_z(H); }),
                    "block top edges");

    // The pocket as the volume an end mill of radius rc with corner radius rf sweeps.
    const double x0 = 0.5 * (L - pl), y0 = 0.5 * (W - pw), z0 = H - depth;
    TopoDS_Shape tool = box(x0, y0, z0, x0 + pl, y0 + pw, H + kOverrun);
    tool = fillet(tool, rc, select_edges(tool, [](const EdgeGeom& g) { return g.is_vertical(); }),
                  "pocket corners");
    tool = fillet(tool, rf, select_edges(tool, [&](const EdgeGeom& g) { return g.all_z(z0); }),
                  "pocket floor");
    return cut(block, tool, "pocket");
}

TopoDS_Shape build_drilled_plate(Dims& d) {
    const double L = d.length("plate_length", 120), W = d.length("plate_width", 80);
    const double T = d.length("plate_thickness", 20);
    const double dt = d.length("through_hole_diameter", 10);
    const double inset = d.length("through_hole_inset", 15);
    const double db = d.length("blind_hole_diameter", 8.5);
    const double depth = d.length("blind_hole_depth", 12);
    d.angle_deg("drill_point_angle_deg", 2 * kDrillHalfAngleDeg);

    TopoDS_Shape part = box(0, 0, 0, L, W, T);
    const std::array<std::array<double, 2>, 4> corners{
        {{inset, inset}, {L - inset, inset}, {inset, W - inset}, {L - inset, W - inset}}};
    for (const auto& c : corners) part = cut(part, through_tool(c[0], c[1], 0, T, dt), "hole");
    for (int i = 1; i <= 3; ++i) {
        part = cut(part, drill_tool(L * i / 4.0, 0.5 * W, T, db, depth), "blind hole");
    }
    return part;
}

TopoDS_Shape build_counterbore_countersink(Dims& d) {
    const double L = d.length("plate_length", 100), W = d.length("plate_width", 60);
    const double T = d.length("plate_thickness", 25);
    const double rcorner = d.length("corner_radius", 5);
    const double hole = d.length("counterbore_hole_diameter", 11);
    const double cb = d.length("counterbore_diameter", 18);
    const double cb_depth = d.length("counterbore_depth", 11);
    const double csk_hole = d.length("countersink_hole_diameter", 9);
    const double csk = d.length("countersink_diameter", 18);
    const double csk_angle = d.angle_deg("countersink_angle_deg", 90);

    TopoDS_Shape part = box(0, 0, 0, L, W, T);
    part =
        fillet(part, rcorner, select_edges(part, [](const EdgeGeom& g) { return g.is_vertical(); }),
               "plate corners");
    const double rh = 0.5 * hole, rb = 0.5 * cb;
    const double rs = 0.5 * csk_hole, rk = 0.5 * csk;
    const double t = std::tan(deg(0.5 * csk_angle));  // radius change per unit depth
    for (const double y : {0.3 * W, 0.7 * W}) {
        const gp_Ax2 f1(gp_Pnt(0.25 * L, y, T), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
        const std::array<std::array<double, 2>, 6> bore{{{0, kOverrun},
                                                         {rb, kOverrun},
                                                         {rb, -cb_depth},
                                                         {rh, -cb_depth},
                                                         {rh, -T - kOverrun},
                                                         {0, -T - kOverrun}}};
        part = cut(part, revolve_polygon(f1, bore), "counterbore");
        part = cut(part, countersink_tool(0.75 * L, y, T, rk, rs, t, T), "countersink");
    }
    return part;
}

TopoDS_Shape build_slot_plate(Dims& d) {
    const double L = d.length("plate_length", 120), W = d.length("plate_width", 60);
    const double T = d.length("plate_thickness", 15);
    const double w1 = d.length("through_slot_width", 12);
    const double l1 = d.length("through_slot_length", 62);
    const double w2 = d.length("blind_slot_width", 10);
    const double l2 = d.length("blind_slot_length", 50);
    const double depth2 = d.length("blind_slot_depth", 6);

    TopoDS_Shape part = box(0, 0, 0, L, W, T);
    part =
        cut(part,
            stadium_prism(0.5 * L, 0.3 * W, 0.5 * (l1 - w1), 0.5 * w1, -kOverrun, T + 2 * kOverrun),
            "through slot");
    part = cut(
        part,
        stadium_prism(0.5 * L, 0.72 * W, 0.5 * (l2 - w2), 0.5 * w2, T - depth2, depth2 + kOverrun),
        "blind slot");
    return part;
}

TopoDS_Shape build_fillet_chamfer_block(Dims& d) {
    const double L = d.length("block_length", 80), W = d.length("block_width", 60);
    const double H = d.length("block_height", 40);
    const double rv = d.length("vertical_edge_fillet", 10);
    const double rt = d.length("top_edge_fillet", 4);
    const double cb = d.length("bottom_edge_chamfer", 2);

    TopoDS_Shape part = box(0, 0, 0, L, W, H);
    part = fillet(part, rv, select_edges(part, [](const EdgeGeom& g) { return g.is_vertical(); }),
                  "vertical edges");
    part = fillet(part, rt, select_edges(part, [&](const EdgeGeom& g) { return g.all_z(H); }),
                  "top edges");
    part = chamfer(part, cb, select_edges(part, [](const EdgeGeom& g) { return g.all_z(0); }),
                   "bottom edges");
    return part;
}

TopoDS_Shape build_boss_plate(Dims& d) {
    const double L = d.length("plate_length", 100), W = d.length("plate_width", 80);
    const double T = d.length("plate_thickness", 12);
    const double rcorner = d.length("corner_radius", 6);
    const double bd = d.length("boss_diameter", 30), bh = d.length("boss_height", 25);
    const double rf = d.length("boss_base_fillet", 3);
    const double ch = d.length("boss_top_chamfer", 1.5);
    const double bore = d.length("bore_diameter", 12);
    const double bore_depth = d.length("bore_depth", 20);
    d.angle_deg("drill_point_angle_deg", 2 * kDrillHalfAngleDeg);

    TopoDS_Shape part = box(0, 0, 0, L, W, T);
    part =
        fillet(part, rcorner, select_edges(part, [](const EdgeGeom& g) { return g.is_vertical(); }),
               "plate corners");
    const double cx = 0.5 * L, cy = 0.5 * W, rb = 0.5 * bd;
    BRepPrimAPI_MakeCylinder boss(gp_Ax2(gp_Pnt(cx, cy, 0.5 * T), gp_Dir(0, 0, 1)), rb,
                                  bh + 0.5 * T);
    part = fuse(part, boss.Shape(), "boss");
    const auto circle_at = [&](double z) {
        return [=](const EdgeGeom& g) { return g.is_circle() && g.all_z(z) && near(g.radius, rb); };
    };
    part = fillet(part, rf, select_edges(part, circle_at(T)), "boss base");
    part = chamfer(part, ch, select_edges(part, circle_at(T + bh)), "boss top");
    return cut(part, drill_tool(cx, cy, T + bh, bore, bore_depth), "bore");
}

TopoDS_Shape build_l_bracket(Dims& d) {
    const double L = d.length("base_length", 80), Hh = d.length("height", 60);
    const double t = d.length("thickness", 10), W = d.length("width", 50);
    const double ri = d.length("inner_fillet", 6), ro = d.length("outer_fillet", 12);
    const double hole = d.length("hole_diameter", 9);
    const double hole_x = d.length("base_hole_x", 52), hole_z = d.length("leg_hole_z", 40);

    // The L profile in the XZ plane, extruded along +Y.
    const std::array<gp_Pnt, 6> p{gp_Pnt(0, 0, 0), gp_Pnt(L, 0, 0),  gp_Pnt(L, 0, t),
                                  gp_Pnt(t, 0, t), gp_Pnt(t, 0, Hh), gp_Pnt(0, 0, Hh)};
    BRepBuilderAPI_MakeWire wire;
    for (std::size_t i = 0; i < p.size(); ++i) {
        wire.Add(BRepBuilderAPI_MakeEdge(p[i], p[(i + 1) % p.size()]).Edge());
    }
    BRepBuilderAPI_MakeFace face(wire.Wire(), /*OnlyPlane=*/true);
    TopoDS_Shape part = BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0, W, 0)).Shape();
    const auto along_y_at = [](double x, double z) {
        return
            [=](const EdgeGeom& g) { return g.along_y() && near(g.a.X(), x) && near(g.a.Z(), z); };
    };
    part = fillet(part, ri, select_edges(part, along_y_at(t, t)), "inner corner");
    part = fillet(part, ro, select_edges(part, along_y_at(0, 0)), "outer corner");
    for (const double y : {0.27 * W, 0.73 * W}) {
        part = cut(part, through_tool(hole_x, y, 0, t, hole), "base hole");
        BRepPrimAPI_MakeCylinder leg(gp_Ax2(gp_Pnt(-kOverrun, y, hole_z), gp_Dir(1, 0, 0)),
                                     0.5 * hole, t + 2 * kOverrun);
        part = cut(part, leg.Shape(), "leg hole");
    }
    return part;
}

TopoDS_Shape build_turned_shaft(Dims& d) {
    const double r1 = 0.5 * d.length("journal_diameter", 30), l1 = d.length("journal_length", 40);
    const double c1 = d.length("end_chamfer", 1.5);
    const double r2 = 0.5 * d.length("collar_diameter", 40), l2 = d.length("collar_length", 50);
    const double gw = d.length("groove_width", 3), gd = d.length("groove_depth", 1.5);
    const double lt = d.length("taper_length", 20);
    const double r3 = 0.5 * d.length("tip_diameter", 24), l3 = d.length("tip_length", 30);
    const double rs = d.length("shoulder_fillet", 1.5);

    // Profile (radius, height) along +Z, from the chamfered end to the spherical end.
    const double z1 = l1, z2 = l1 + l2, z3 = z2 + lt, z4 = z3 + l3;
    const double g1 = z1 + 0.5 * l2, g2 = z3 + 0.5 * l3;
    const double hw = 0.5 * gw;
    const std::vector<std::array<double, 2>> rh{
        {0, 0},        {r1 - c1, 0},       {r1, c1},           {r1, z1},           {r2, z1},
        {r2, g1 - hw}, {r2 - gd, g1 - hw}, {r2 - gd, g1 + hw}, {r2, g1 + hw},      {r2, z2},
        {r3, z3},      {r3, g2 - hw},      {r3 - gd, g2 - hw}, {r3 - gd, g2 + hw}, {r3, g2 + hw},
        {r3, z4}};
    const gp_Ax2 frame(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
    BRepBuilderAPI_MakeWire wire;
    for (std::size_t i = 0; i + 1 < rh.size(); ++i) {
        wire.Add(BRepBuilderAPI_MakeEdge(at(frame, rh[i][0], rh[i][1]),
                                         at(frame, rh[i + 1][0], rh[i + 1][1]))
                     .Edge());
    }
    // The spherical end: a quarter circle centred on the axis, radius r3.
    const double s = std::sqrt(0.5);
    wire.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(at(frame, r3, z4),
                                                        at(frame, r3 * s, z4 + r3 * s),
                                                        at(frame, 0, z4 + r3))
                                         .Value())
                 .Edge());
    wire.Add(BRepBuilderAPI_MakeEdge(at(frame, 0, z4 + r3), at(frame, 0, 0)).Edge());
    BRepBuilderAPI_MakeFace face(wire.Wire(), /*OnlyPlane=*/true);
    if (!face.IsDone()) throw ModelError("shaft profile failed");
    BRepPrimAPI_MakeRevol rev(face.Face(), gp_Ax1(frame.Location(), frame.Direction()), 2 * kPi);
    if (!rev.IsDone()) throw ModelError("shaft revolve failed");
    TopoDS_Shape part = rev.Shape();
    return fillet(part, rs,
                  select_edges(part,
                               [&](const EdgeGeom& g) {
                                   return g.is_circle() && g.all_z(z1) && near(g.radius, r1);
                               }),
                  "shoulder");
}

TopoDS_Shape build_spherical_pocket(Dims& d) {
    const double L = d.length("block_length", 90), W = d.length("block_width", 70);
    const double H = d.length("block_height", 35);
    const double rs = d.length("pocket_sphere_radius", 25);
    const double depth = d.length("pocket_depth", 10);
    const double rim = d.length("pocket_rim_fillet", 2);
    const double rb = 0.5 * d.length("ball_mill_diameter", 10);
    const double gdepth = d.length("groove_depth", 4);
    const double glen = d.length("groove_length", 22);

    TopoDS_Shape part = box(0, 0, 0, L, W, H);
    const double cx = 0.33 * L, cy = 0.5 * W;
    // The pocket and its rim fillet as one revolved tool, so that the fillet is the exact
    // torus rolling between the top plane and the sphere (a fillet made by
    // BRepFilletAPI_MakeFillet there would be a B-spline approximation).
    const double zc = H + rs - depth;  // sphere centre height
    const double fz = H - rim;         // fillet circle centre height
    const double frho = std::sqrt((rs + rim) * (rs + rim) - (zc - fz) * (zc - fz));
    const double dr = frho, dz = fz - zc, dl = std::hypot(dr, dz);
    const std::array<double, 2> T{rim * -dr / dl + frho, rim * -dz / dl + fz};  // tangency
    const auto arc_mid = [](std::array<double, 2> c, double r, std::array<double, 2> u,
                            std::array<double, 2> v) {
        const double mx = u[0] + v[0], my = u[1] + v[1], ml = std::hypot(mx, my);
        return std::array<double, 2>{c[0] + r * mx / ml, c[1] + r * my / ml};
    };
    const gp_Ax2 frame(gp_Pnt(cx, cy, 0), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
    const auto P = [&](std::array<double, 2> q) { return at(frame, q[0], q[1]); };
    const std::array<double, 2> fm = arc_mid({frho, fz}, rim, {0, 1}, {-dr / dl, -dz / dl});
    const std::array<double, 2> sm = arc_mid({0, zc}, rs, {dr / dl, dz / dl}, {0, -1});
    BRepBuilderAPI_MakeWire wire;
    wire.Add(BRepBuilderAPI_MakeEdge(P({0, H + kOverrun}), P({frho, H + kOverrun})).Edge());
    wire.Add(BRepBuilderAPI_MakeEdge(P({frho, H + kOverrun}), P({frho, H})).Edge());
    wire.Add(arc_edge(gp_Ax2(P({frho, fz}), frame.YDirection(), frame.XDirection()), rim,
                      P({frho, H}), P(fm), P(T)));
    wire.Add(arc_edge(gp_Ax2(P({0, zc}), frame.YDirection(), frame.XDirection()), rs, P(T), P(sm),
                      P({0, zc - rs})));
    wire.Add(BRepBuilderAPI_MakeEdge(P({0, zc - rs}), P({0, H + kOverrun})).Edge());
    BRepBuilderAPI_MakeFace face(wire.Wire(), /*OnlyPlane=*/true);
    if (!face.IsDone()) throw ModelError("pocket profile failed");
    BRepPrimAPI_MakeRevol rev(face.Face(), gp_Ax1(frame.Location(), frame.Direction()), 2 * kPi);
    part = cut(part, rev.Shape(), "spherical pocket");
    // A groove a ball end mill leaves: a cylinder with a sphere at either end. Each sphere's
    // seam (the meridian along its frame's x direction) lies inside the cylinder, as a ball end
    // mill leaves each end one spherical face: with the seam outside, the end ball came as two
    // faces of one sphere, which no mesh can tell apart.
    const double gx0 = 0.66 * L, gz = H + rb - gdepth;
    TopoDS_Shape groove =
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(gx0, cy, gz), gp_Dir(1, 0, 0)), rb, glen).Shape();
    const auto ball = [&](double x, double inward) {
        return BRepPrimAPI_MakeSphere(
                   gp_Ax2(gp_Pnt(x, cy, gz), gp_Dir(0, 0, 1), gp_Dir(inward, 0, 0)), rb)
            .Shape();
    };
    groove = fuse(groove, ball(gx0, 1), "ball start");
    groove = fuse(groove, ball(gx0 + glen, -1), "ball end");
    return cut(part, groove, "ball groove");
}

TopoDS_Shape build_freeform_die(Dims& d) {
    const double L = d.length("block_length", 100), W = d.length("block_width", 80);
    const double H = d.length("base_height", 30);
    const double A = d.length("dome_amplitude", 8);
    const double B = d.length("wave_amplitude", 2.5);

    // Heights of a smooth die surface on a grid that overhangs the block by 15 %, interpolated
    // by a bicubic B-spline; the block is then trimmed by it.
    constexpr int kNu = 11, kNv = 9;
    TColgp_Array2OfPnt pts(1, kNu, 1, kNv);
    for (int i = 1; i <= kNu; ++i) {
        for (int j = 1; j <= kNv; ++j) {
            const double u = -0.15 + 1.3 * (i - 1) / (kNu - 1);
            const double v = -0.15 + 1.3 * (j - 1) / (kNv - 1);
            const double z = H + A * std::cos(kPi * (u - 0.5)) * std::cos(kPi * (v - 0.5)) +
                             B * std::sin(2 * kPi * u + 0.4) * std::cos(1.5 * kPi * v);
            pts.SetValue(i, j, gp_Pnt(u * L, v * W, z));
        }
    }
    GeomAPI_PointsToBSplineSurface approx;
    approx.Interpolate(pts);
    if (!approx.IsDone()) throw ModelError("die surface interpolation failed");
    const Handle(Geom_BSplineSurface) surf = approx.Surface();
    BRepBuilderAPI_MakeFace top(surf, 1e-6);
    if (!top.IsDone()) throw ModelError("die face failed");
    const double drop = H + 2 * (A + B) + 10;  // deeper than the surface's lowest point
    const TopoDS_Shape slab = BRepPrimAPI_MakePrism(top.Face(), gp_Vec(0, 0, -drop)).Shape();
    return common(box(0, 0, 0, L, W, H + 2 * (A + B) + 5), slab, "die");
}

TopoDS_Shape build_flange(Dims& d) {
    const double ro = 0.5 * d.length("outer_diameter", 160);
    const double t = d.length("disc_thickness", 18);
    const double rh = 0.5 * d.length("hub_diameter", 70);
    const double hh = d.length("hub_height", 30);
    const double rb = 0.5 * d.length("bore_diameter", 40);
    const double co = d.length("outer_chamfer", 2), cb = d.length("bore_chamfer", 1.5);
    const double ch = d.length("hub_chamfer", 1.5);
    const double rf = d.length("hub_fillet", 4);
    const int n = d.count("bolt_holes", 6, 4, 8);
    const double hole = d.length("bolt_hole_diameter", 14);
    const double pcd = d.derived("bolt_circle_diameter", round_to(rh + rf + ro - co, 0.01));

    const double H = t + hh;
    const std::array<std::array<double, 2>, 9> rzs{{{rb, 0},
                                                    {ro, 0},
                                                    {ro, t - co},
                                                    {ro - co, t},
                                                    {rh, t},
                                                    {rh, H - ch},
                                                    {rh - ch, H},
                                                    {rb + cb, H},
                                                    {rb, H - cb}}};
    const gp_Ax2 frame(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
    TopoDS_Shape part = revolve_polygon(frame, rzs);
    part = fillet(part, rf,
                  select_edges(part,
                               [&](const EdgeGeom& g) {
                                   return g.is_circle() && g.all_z(t) && near(g.radius, rh);
                               }),
                  "hub base");
    for (int i = 0; i < n; ++i) {
        const double a = 2 * kPi * (i + 0.5) / n;
        part = cut(part, through_tool(0.5 * pcd * std::cos(a), 0.5 * pcd * std::sin(a), 0, t, hole),
                   "bolt hole");
    }
    return part;
}

TopoDS_Shape build_keyway_shaft(Dims& d) {
    const double r = 0.5 * d.length("shaft_diameter", 40), len = d.length("shaft_length", 120);
    const double c = d.length("end_chamfer", 1.5);
    const double kw = d.length("key_width", 12), kl = d.length("key_length", 50);
    const double kd = d.length("key_depth", 5);

    // Axis along +X; the profile's radial direction is +Z.
    const gp_Ax2 frame(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0), gp_Dir(0, 0, 1));
    const std::array<std::array<double, 2>, 6> rh{
        {{0, 0}, {r - c, 0}, {r, c}, {r, len - c}, {r - c, len}, {0, len}}};
    TopoDS_Shape part = revolve_polygon(frame, rh);
    return cut(part, stadium_prism(0.5 * len, 0, 0.5 * (kl - kw), 0.5 * kw, r - kd, kd + kOverrun),
               "keyway");
}

TopoDS_Shape build_enclosure(Dims& d) {
    const double L = d.length("length", 100), W = d.length("width", 70);
    const double H = d.length("height", 40);
    const double rv = d.length("corner_radius", 8), wall = d.length("wall_thickness", 2.5);

    TopoDS_Shape part = box(0, 0, 0, L, W, H);
    part = fillet(part, rv, select_edges(part, [](const EdgeGeom& g) { return g.is_vertical(); }),
                  "corners");
    TopTools_ListOfShape open;
    for (TopExp_Explorer ex(part, TopAbs_FACE); ex.More(); ex.Next()) {
        const TopoDS_Face& f = TopoDS::Face(ex.Current());
        bool top = true;
        for (TopExp_Explorer ev(f, TopAbs_VERTEX); ev.More(); ev.Next()) {
            top = top && near(BRep_Tool::Pnt(TopoDS::Vertex(ev.Current())).Z(), H);
        }
        if (top) open.Append(f);
    }
    if (open.Extent() != 1) throw ModelError("enclosure: top face not found");
    BRepOffsetAPI_MakeThickSolid shell;
    shell.MakeThickSolidByJoin(part, open, -wall, 1e-5);
    shell.Build();
    if (!shell.IsDone()) throw ModelError("enclosure: shelling failed");
    return shell.Shape();
}

// Parts that stress segmentation (issue 7): a gentle fillet only a facet or two wide between two
// planes, countersinks meeting their bores with no plane between, a shallow free-form face
// next to a plane it almost continues, thin slots whose walls are one facet strip each.

TopoDS_Shape build_fillet_wedge(Dims& d) {
    const double L = d.length("block_length", 80), W = d.length("block_width", 50);
    const double H = d.length("block_height", 30);
    const double ridge = d.length("ridge_x", 45);
    const double slope = d.angle_deg("roof_slope_deg", 25);
    const double rr = d.length("ridge_fillet", 12);
    const double rv = d.length("corner_fillet", 2);
    // The profile in the XZ plane: a flat top up to the ridge, then a roof sloping down.
    const double drop = (L - ridge) * std::tan(deg(slope));
    BRepBuilderAPI_MakePolygon poly;
    poly.Add(gp_Pnt(0, 0, 0));
    poly.Add(gp_Pnt(L, 0, 0));
    poly.Add(gp_Pnt(L, 0, H - drop));
    poly.Add(gp_Pnt(ridge, 0, H));
    poly.Add(gp_Pnt(0, 0, H));
    poly.Close();
    BRepBuilderAPI_MakeFace face(poly.Wire(), /*OnlyPlane=*/true);
    if (!face.IsDone()) throw ModelError("wedge profile failed");
    TopoDS_Shape part = BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0, W, 0)).Shape();
    part = fillet(part, rv, select_edges(part, [](const EdgeGeom& g) { return g.is_vertical(); }),
                  "vertical corners");
    return fillet(part, rr,
                  select_edges(part,
                               [&](const EdgeGeom& g) {
                                   return g.along_y() && near(g.a.X(), ridge) && near(g.a.Z(), H);
                               }),
                  "ridge");
}

TopoDS_Shape build_countersink_bore(Dims& d) {
    const double L = d.length("plate_length", 90), W = d.length("plate_width", 40);
    const double T = d.length("plate_thickness", 12);
    const double bore = d.length("bore_diameter", 8);
    const double csk = d.length("countersink_diameter", 16);
    TopoDS_Shape part = box(0, 0, 0, L, W, T);
    // Three countersinks of 90, 82 and 120 degrees, each meeting its bore directly.
    const double angles[3] = {d.angle_deg("countersink_a_deg", 90),
                              d.angle_deg("countersink_b_deg", 82),
                              d.angle_deg("countersink_c_deg", 120)};
    for (int i = 0; i < 3; ++i) {
        const double t = std::tan(deg(0.5 * angles[i]));
        part =
            cut(part, countersink_tool(L * (i + 1) / 4.0, 0.5 * W, T, 0.5 * csk, 0.5 * bore, t, T),
                "countersunk bore");
    }
    return part;
}

TopoDS_Shape build_shallow_freeform(Dims& d) {
    const double L = d.length("block_length", 100), W = d.length("block_width", 60);
    const double H = d.length("block_height", 25);
    const double x0 = d.length("flat_length", 45);
    const double A = d.length("rise", 3);
    // A surface that leaves the flat top at x0 with zero height and (nearly) zero slope and
    // rises gently, with a slight wave across: a free-form face almost continuing the plane.
    constexpr int kNu = 9, kNv = 7;
    TColgp_Array2OfPnt pts(1, kNu, 1, kNv);
    const double span = 1.2 * (L - x0);
    for (int i = 1; i <= kNu; ++i) {
        for (int j = 1; j <= kNv; ++j) {
            const double u = (i - 1.0) / (kNu - 1), v = -0.15 + 1.3 * (j - 1.0) / (kNv - 1);
            const double z = H + A * u * u * (1 + 0.3 * std::sin(kPi * v));
            pts.SetValue(i, j, gp_Pnt(x0 + u * span, v * W, z));
        }
    }
    GeomAPI_PointsToBSplineSurface approx;
    approx.Interpolate(pts);
    if (!approx.IsDone()) throw ModelError("shallow surface interpolation failed");
    BRepBuilderAPI_MakeFace top(approx.Surface(), 1e-6);
    if (!top.IsDone()) throw ModelError("shallow face failed");
    const TopoDS_Shape slab =
        BRepPrimAPI_MakePrism(top.Face(), gp_Vec(0, 0, -(H + 2 * A + 10))).Shape();
    const TopoDS_Shape rising = common(box(x0, 0, 0, L, W, H + 2 * A + 5), slab, "rising part");
    return unify(fuse(box(0, 0, 0, x0, W, H), rising, "shallow block"));
}

TopoDS_Shape build_thin_slot(Dims& d) {
    const double L = d.length("plate_length", 80), W = d.length("plate_width", 40);
    const double T = d.length("plate_thickness", 12);
    const double sw = d.length("slot_width", 1.2), sd = d.length("slot_depth", 6);
    const double sl = d.length("slot_length", 50);
    const double tw = d.length("through_slot_width", 2.5), tl = d.length("through_slot_length", 30);
    TopoDS_Shape part = box(0, 0, 0, L, W, T);
    // A saw cut: square ends, flat bottom, walls one facet strip each.
    const double x0 = 0.5 * (L - sl), y0 = 0.3 * W;
    part =
        cut(part, box(x0, y0 - 0.5 * sw, T - sd, x0 + sl, y0 + 0.5 * sw, T + kOverrun), "saw cut");
    // A narrow through slot with round ends.
    part = cut(
        part,
        stadium_prism(0.5 * L, 0.72 * W, 0.5 * (tl - tw), 0.5 * tw, -kOverrun, T + 2 * kOverrun),
        "narrow slot");
    return part;
}

constexpr PartEntry kParts[] = {
    {{"pocket_block",
      "block with a rectangular pocket: corner radii, floor fillets (tori at the corners), "
      "chamfered top edges"},
     build_pocket_block},
    {{"drilled_plate",
      "plate with four through holes and three blind drilled holes (118 deg tips)"},
     build_drilled_plate},
    {{"counterbore_countersink", "plate with two counterbored and two countersunk (90 deg) holes"},
     build_counterbore_countersink},
    {{"slot_plate", "plate with a through slot and a flat-bottomed blind slot"}, build_slot_plate},
    {{"fillet_chamfer_block",
      "block with filleted vertical and top edges (tori at the corners) and a chamfered base"},
     build_fillet_chamfer_block},
    {{"boss_plate", "plate with a cylindrical boss: base fillet, top chamfer, drilled blind bore"},
     build_boss_plate},
    {{"l_bracket", "L-bracket with inner and outer corner fillets and four holes"},
     build_l_bracket},
    {{"turned_shaft",
      "turned shaft: chamfer, shoulder fillet, two grooves, a taper and a spherical end"},
     build_turned_shaft},
    {{"spherical_pocket",
      "block with a ball-end-milled spherical pocket (filleted rim) and a ball-nose groove"},
     build_spherical_pocket},
    {{"freeform_die", "die block whose top is a free-form bicubic B-spline surface"},
     build_freeform_die},
    {{"flange", "flange with a hub, chamfers, a fillet, a bore and a bolt circle"}, build_flange},
    {{"keyway_shaft", "shaft with chamfered ends and a milled keyway"}, build_keyway_shaft},
    {{"enclosure", "shelled box (open top) with rounded vertical corners"}, build_enclosure},
    {{"fillet_wedge",
      "block with a flat top and a sloping roof joined by a gentle fillet a facet or two wide, "
      "filleted vertical corners"},
     build_fillet_wedge},
    {{"countersink_bore", "plate with three countersinks (90, 82, 120 deg) meeting their bores"},
     build_countersink_bore},
    {{"shallow_freeform", "block whose flat top continues into a shallow free-form B-spline face"},
     build_shallow_freeform},
    {{"thin_slot", "plate with a 1.2 mm saw cut and a narrow round-ended through slot"},
     build_thin_slot},
};

}  // namespace

std::span<const PartEntry> part_entries() { return kParts; }

}  // namespace ncrev::sample_detail
