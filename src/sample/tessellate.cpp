// From an exact solid meshed by BRepMesh_IncrementalMesh to one watertight, outward-oriented,
// labelled mesh with shared vertices, and each face's surface in SRE form
// (../shared/docs/sre-format.md).
//
// Why a topological weld: BRepMesh discretises every edge once and every face adjacent to it
// reuses that discretisation, but each face's triangulation stores its own copy of the nodes.
// The copies are matched through the edge's polygon on each face's triangulation (node k of
// the polygon on one face is node k on the other), which does not depend on floating-point
// luck; the float32 coordinates of the matched copies are then compared as a check, and the
// mesh is written from one copy, so the STL welds exactly whatever the check says.
#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_OffsetSurface.hxx>
#include <Poly_PolygonOnTriangulation.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <array>
#include <bit>
#include <cmath>
#include <map>
#include <optional>
#include <unordered_map>

#include "detail/union_find.h"
#include "sample/sample_internal.h"

namespace ncrev::sample_detail {

namespace {

using Json = nlohmann::ordered_json;

Vec3 to_vec(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }
// "+ 0.0" turns -0.0 into 0.0: the same value, printed without a stray sign.
Json jvec(const gp_XYZ& p) { return Json::array({p.X() + 0.0, p.Y() + 0.0, p.Z() + 0.0}); }

std::array<std::uint32_t, 3> float_bits(const Vec3& p) {
    return {std::bit_cast<std::uint32_t>(static_cast<float>(p.x)),
            std::bit_cast<std::uint32_t>(static_cast<float>(p.y)),
            std::bit_cast<std::uint32_t>(static_cast<float>(p.z))};
}

struct FloatKeyHash {
    std::size_t operator()(const std::array<std::uint32_t, 3>& k) const {
        std::uint64_t h = k[0];
        h = h * 0x9E3779B97F4A7C15ull ^ k[1];
        h = h * 0x9E3779B97F4A7C15ull ^ k[2];
        return static_cast<std::size_t>(h ^ (h >> 29));
    }
};

/// One tool per surface kind: how a shop would have cut that kind of face.
struct ToolDef {
    const char* kind;  // face kind it stands for
    ToolRecord tool;
};
const std::array<ToolDef, 6>& tool_defs() {
    static const std::array<ToolDef, 6> defs{{
        {"plane", {0x4E79A7, ToolKind::kFlat, 10, 0, "flat end mill (planes)"}},
        {"cylinder", {0xF28E2B, ToolKind::kFlat, 8, 0, "end mill or drill (cylinders)"}},
        {"cone", {0xE15759, ToolKind::kDrill, 10, 0, "drill point or chamfer mill (cones)"}},
        {"sphere", {0x76B7B2, ToolKind::kBall, 10, 5, "ball end mill (spheres)"}},
        {"torus", {0x59A14F, ToolKind::kBullnose, 10, 2, "corner-radius mill (tori)"}},
        {"freeform", {0xEDC948, ToolKind::kBall, 6, 3, "ball end mill, 3-axis (free-form)"}},
    }};
    return defs;
}
std::size_t tool_slot(const std::string& kind) {
    for (std::size_t i = 0; i + 1 < tool_defs().size(); ++i) {
        if (kind == tool_defs()[i].kind) return i;
    }
    return tool_defs().size() - 1;
}

/// A face's surface: its kind, its SRE record when analytic, and the named parameters.
struct FaceSurface {
    std::string kind;
    std::optional<SurfaceRecord> sre;
    Json params = Json::object();
};

FaceSurface describe_analytic(const Adaptor3d_Surface& s, const TopoDS_Face& face) {
    FaceSurface out;
    // The outward normal at the middle of the face's parameter box, to say on which side of
    // the surface the material is.
    double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    gp_Pnt P;
    gp_Vec du, dv;
    s.D1(0.5 * (u0 + u1), 0.5 * (v0 + v1), P, du, dv);
    gp_Vec n = du.Crossed(dv);
    if (face.Orientation() == TopAbs_REVERSED) n.Reverse();
    SurfaceRecord rec;
    const auto set = [&rec](std::initializer_list<double> v) {
        std::size_t i = 0;
        for (const double x : v) rec.params[i++] = x + 0.0;
    };
    const auto away_from_axis = [&](const gp_Ax1& axis) {
        const gp_Vec w(axis.Location(), P);
        const gp_Vec radial = w - gp_Vec(axis.Direction()) * w.Dot(gp_Vec(axis.Direction()));
        return radial.Dot(n) > 0;
    };
    switch (s.GetType()) {
        case GeomAbs_Plane: {
            const gp_Pln pl = s.Plane();
            const gp_Dir nn = n.Magnitude() > 0 ? gp_Dir(n) : pl.Axis().Direction();
            const gp_XYZ p = pl.Location().XYZ();
            out.kind = "plane";
            rec.kind = SurfaceKind::kPlane;
            set({p.X(), p.Y(), p.Z(), nn.X(), nn.Y(), nn.Z()});
            out.params = {{"point", jvec(p)}, {"normal", jvec(nn.XYZ())}};
            break;
        }
        case GeomAbs_Cylinder: {
            const gp_Cylinder c = s.Cylinder();
            const gp_XYZ p = c.Location().XYZ(), a = c.Axis().Direction().XYZ();
            out.kind = "cylinder";
            rec.kind = SurfaceKind::kCylinder;
            set({p.X(), p.Y(), p.Z(), a.X(), a.Y(), a.Z(), c.Radius()});
            out.params = {{"axis_point", jvec(p)},
                          {"axis_dir", jvec(a)},
                          {"radius", c.Radius()},
                          {"convex", away_from_axis(c.Axis())}};
            break;
        }
        case GeomAbs_Cone: {
            // gp_Cone: radius RefRadius at Location, growing by sin(SemiAngle) per unit of the
            // generatrix along +Z; SemiAngle may be negative (then it grows along -Z). SRE: the
            // direction along which it grows and a half-angle in (0, pi/2).
            const gp_Cone c = s.Cone();
            const double a = c.SemiAngle();
            gp_XYZ dir = c.Axis().Direction().XYZ();
            if (a < 0) dir.Reverse();
            const gp_XYZ p = c.Location().XYZ();
            const double alpha = std::abs(a);
            out.kind = "cone";
            rec.kind = SurfaceKind::kCone;
            set({p.X(), p.Y(), p.Z(), dir.X(), dir.Y(), dir.Z(), c.RefRadius(), alpha});
            out.params = {{"apex", jvec(c.Apex().XYZ())},
                          {"axis_dir", jvec(dir)},
                          {"half_angle", alpha},
                          {"sre",
                           {{"point", jvec(p)},
                            {"axis_dir", jvec(dir)},
                            {"radius", c.RefRadius()},
                            {"half_angle", alpha}}},
                          {"convex", away_from_axis(c.Axis())}};
            break;
        }
        case GeomAbs_Sphere: {
            const gp_Sphere sp = s.Sphere();
            const gp_XYZ c = sp.Location().XYZ();
            out.kind = "sphere";
            rec.kind = SurfaceKind::kSphere;
            set({c.X(), c.Y(), c.Z(), sp.Radius()});
            out.params = {{"center", jvec(c)},
                          {"radius", sp.Radius()},
                          {"convex", gp_Vec(sp.Location(), P).Dot(n) > 0}};
            break;
        }
        case GeomAbs_Torus: {
            const gp_Torus t = s.Torus();
            const gp_XYZ c = t.Location().XYZ(), a = t.Axis().Direction().XYZ();
            // The tube centre nearest P: on the major circle, in P's meridian half-plane.
            const gp_Vec w(t.Location(), P);
            gp_Vec radial = w - gp_Vec(a) * w.Dot(gp_Vec(a));
            const bool ok = radial.Magnitude() > 0;
            if (ok) radial.Normalize();
            const gp_Pnt tube = t.Location().Translated(radial * t.MajorRadius());
            out.kind = "torus";
            rec.kind = SurfaceKind::kTorus;
            set({c.X(), c.Y(), c.Z(), a.X(), a.Y(), a.Z(), t.MajorRadius(), t.MinorRadius()});
            out.params = {{"center", jvec(c)},
                          {"axis_dir", jvec(a)},
                          {"major_radius", t.MajorRadius()},
                          {"minor_radius", t.MinorRadius()},
                          {"convex", ok && gp_Vec(tube, P).Dot(n) > 0}};
            break;
        }
        default:
            return out;
    }
    out.sre = rec;
    return out;
}

FaceSurface describe_surface(const TopoDS_Face& face) {
    const BRepAdaptor_Surface s(face, /*R=*/false);
    switch (s.GetType()) {
        case GeomAbs_Plane:
        case GeomAbs_Cylinder:
        case GeomAbs_Cone:
        case GeomAbs_Sphere:
        case GeomAbs_Torus:
            return describe_analytic(s, face);
        case GeomAbs_OffsetSurface: {
            // An offset of an analytic surface is analytic: ask OCCT for the canonical form.
            TopLoc_Location loc;
            const Handle(Geom_Surface) g = BRep_Tool::Surface(face, loc);
            const Handle(Geom_OffsetSurface) off = Handle(Geom_OffsetSurface)::DownCast(g);
            if (!off.IsNull()) {
                Handle(Geom_Surface) canon = off->Surface();
                if (!canon.IsNull()) {
                    if (!loc.IsIdentity()) {
                        canon = Handle(Geom_Surface)::DownCast(
                            canon->Transformed(loc.Transformation()));
                    }
                    const GeomAdaptor_Surface gs(canon);
                    FaceSurface f = describe_analytic(gs, face);
                    if (f.sre) return f;
                }
            }
            FaceSurface f;
            f.kind = "offset";
            return f;
        }
        case GeomAbs_BSplineSurface: {
            FaceSurface f;
            f.kind = "bspline";
            f.params = {{"u_degree", s.UDegree()},
                        {"v_degree", s.VDegree()},
                        {"u_poles", s.NbUPoles()},
                        {"v_poles", s.NbVPoles()}};
            return f;
        }
        case GeomAbs_BezierSurface:
            return {"bezier", std::nullopt, Json::object()};
        case GeomAbs_SurfaceOfRevolution:
            return {"revolution", std::nullopt, Json::object()};
        case GeomAbs_SurfaceOfExtrusion:
            return {"extrusion", std::nullopt, Json::object()};
        default:
            return {"other", std::nullopt, Json::object()};
    }
}

struct FaceMesh {
    Handle(Poly_Triangulation) tri;
    TopLoc_Location loc;
    std::uint32_t offset = 0;  // first raw node id
    bool flip = false;         // reverse triangle order to face outward
};

}  // namespace

void tessellate_solid(const TopoDS_Shape& solid, SamplePart& part, std::vector<Json>& face_params) {
    TopTools_IndexedMapOfShape faces, edges;
    TopExp::MapShapes(solid, TopAbs_FACE, faces);
    TopExp::MapShapes(solid, TopAbs_EDGE, edges);
    const int nf = faces.Extent();

    // Raw nodes: every face triangulation's nodes, in face order.
    std::vector<FaceMesh> fm(static_cast<std::size_t>(nf));
    std::vector<Vec3> raw;
    for (int f = 1; f <= nf; ++f) {
        const TopoDS_Face& face = TopoDS::Face(faces(f));
        FaceMesh& m = fm[static_cast<std::size_t>(f - 1)];
        m.tri = BRep_Tool::Triangulation(face, m.loc);
        if (m.tri.IsNull() || m.tri->NbTriangles() == 0) {
            throw ModelError("face " + std::to_string(f - 1) + " has no triangulation");
        }
        const gp_Trsf tr = m.loc.Transformation();
        // Triangles follow the surface's natural normal (du x dv); a reversed face, or a
        // mirroring placement, turns it inward.
        m.flip = (face.Orientation() == TopAbs_REVERSED) != tr.IsNegative();
        m.offset = static_cast<std::uint32_t>(raw.size());
        for (int i = 1; i <= m.tri->NbNodes(); ++i) {
            raw.push_back(to_vec(m.tri->Node(i).Transformed(tr).XYZ()));
        }
    }
    const std::size_t num_raw = raw.size();

    // Topological weld: node k of an edge's polygon is the same point on every face.
    detail::MinUnionFind uf(num_raw);
    struct Slots {
        std::uint32_t first = 0;
        int count = 0;
    };
    std::map<int, Slots> edge_slots;
    for (int f = 1; f <= nf; ++f) {
        const FaceMesh& m = fm[static_cast<std::size_t>(f - 1)];
        for (TopExp_Explorer ex(faces(f), TopAbs_EDGE); ex.More(); ex.Next()) {
            const TopoDS_Edge& e = TopoDS::Edge(ex.Current());
            const Handle(Poly_PolygonOnTriangulation)& poly =
                BRep_Tool::PolygonOnTriangulation(e, m.tri, m.loc);
            if (poly.IsNull()) continue;
            const int n = poly->NbNodes();
            const auto node = [&](int k) {
                return m.offset + static_cast<std::uint32_t>(poly->Node(k) - 1);
            };
            if (BRep_Tool::Degenerated(e)) {  // a pole or apex: one point
                for (int k = 2; k <= n; ++k) uf.unite(node(1), node(k));
                continue;
            }
            auto it = edge_slots.find(edges.FindIndex(e));
            if (it == edge_slots.end()) {
                Slots s{uf.add(), n};
                for (int k = 1; k < n; ++k) uf.add();
                it = edge_slots.emplace(edges.FindIndex(e), s).first;
            }
            if (it->second.count != n) continue;  // cannot happen with one BRepMesh run
            for (int k = 1; k <= n; ++k) {
                uf.unite(node(k), it->second.first + static_cast<std::uint32_t>(k - 1));
            }
        }
    }
    SampleWeld& weld = part.weld;
    weld = {};
    for (std::uint32_t i = 0; i < num_raw; ++i) {
        const std::uint32_t r = uf.find(i);
        if (r == i) continue;
        ++weld.merged_nodes;
        if (float_bits(raw[i]) != float_bits(raw[r])) ++weld.float32_mismatches;
        weld.max_gap = std::max(weld.max_gap, norm(raw[i] - raw[r]));
    }
    // Distinct nodes at the same float32 point would be welded by any STL reader: merge them
    // here too so the SRE and the STL have the same vertices.
    std::unordered_map<std::array<std::uint32_t, 3>, std::uint32_t, FloatKeyHash> by_bits;
    for (std::uint32_t i = 0; i < num_raw; ++i) {
        if (uf.find(i) != i) continue;
        const auto [it, inserted] = by_bits.emplace(float_bits(raw[i]), i);
        if (!inserted) {
            uf.unite(it->second, i);
            ++weld.coincident_merges;
        }
    }
    std::vector<std::uint32_t> vertex_of(num_raw, std::numeric_limits<std::uint32_t>::max());
    TriangleSoup& mesh = part.mesh;
    mesh = {};
    mesh.format = InputFormat::kSre;
    mesh.unit = Unit::kMillimetre;
    for (std::uint32_t i = 0; i < num_raw; ++i) {
        if (uf.find(i) != i) continue;
        vertex_of[i] = static_cast<std::uint32_t>(mesh.points.size());
        mesh.points.push_back(raw[i]);
    }

    // Faces: surfaces, tools, facets.
    part.faces.assign(static_cast<std::size_t>(nf), {});
    face_params.assign(static_cast<std::size_t>(nf), Json::object());
    std::vector<std::size_t> face_tool(static_cast<std::size_t>(nf));
    std::array<bool, 6> tool_used{};
    for (int f = 1; f <= nf; ++f) {
        const TopoDS_Face& face = TopoDS::Face(faces(f));
        const std::size_t fi = static_cast<std::size_t>(f - 1);
        FaceSurface desc = describe_surface(face);
        SampleFace& sf = part.faces[fi];
        sf.index = static_cast<std::uint32_t>(fi);
        sf.kind = desc.kind;
        if (desc.sre) {
            sf.surface = static_cast<std::int32_t>(mesh.surfaces.size());
            mesh.surfaces.push_back(*desc.sre);
        }
        GProp_GProps props;
        BRepGProp::SurfaceProperties(face, props);
        sf.area = props.Mass();
        face_params[fi] = std::move(desc.params);
        face_tool[fi] = tool_slot(desc.sre ? desc.kind : std::string("freeform"));
        tool_used[face_tool[fi]] = true;
    }
    // Tools block: the tools of the kinds present, in a fixed order.
    for (std::size_t t = 0; t < tool_defs().size(); ++t) {
        if (tool_used[t]) mesh.tools.push_back(tool_defs()[t].tool);
    }
    part.labels.clear();
    for (int f = 1; f <= nf; ++f) {
        const std::size_t fi = static_cast<std::size_t>(f - 1);
        const FaceMesh& m = fm[fi];
        for (int t = 1; t <= m.tri->NbTriangles(); ++t) {
            int n1 = 0, n2 = 0, n3 = 0;
            m.tri->Triangle(t).Get(n1, n2, n3);
            if (m.flip) std::swap(n2, n3);
            const auto v = [&](int n) {
                return vertex_of[uf.find(m.offset + static_cast<std::uint32_t>(n - 1))];
            };
            const std::array<std::uint32_t, 3> tri{v(n1), v(n2), v(n3)};
            if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
                ++weld.degenerate_facets_dropped;
                continue;
            }
            mesh.triangles.push_back(tri);
            mesh.color.push_back(tool_defs()[face_tool[fi]].tool.color);
            mesh.cut.push_back(static_cast<std::int64_t>(fi));
            mesh.surface.push_back(part.faces[fi].surface);
            part.labels.push_back(static_cast<std::int32_t>(fi));
            ++part.faces[fi].num_facets;
        }
    }
}

}  // namespace ncrev::sample_detail
