// Planar B-rep from a half-edge mesh (../shared/docs/method.md, Step 2a, and "Beyond the paper":
// coplanar merging). One code path serves both methods: `facets` is planar merging with every
// facet its own region.
//
// 1. Regions: facets grown breadth-first from a seed while every vertex of the candidate lies
//    within the tolerance of the seed's plane (facets: one region per facet).
// 2. Borders: mesh edges between two regions, or on the mesh boundary. Corners: vertices where
//    borders branch, where the pair of regions changes, or where the border turns. Each border
//    chain between corners is then split wherever a straight segment would leave the
//    tolerance, so that its segments are the B-rep's edges — computed once per chain, so the
//    two faces on either side share exactly the same edges and vertices.
// 3. Faces: each region's border half-edges walked into loops, compressed to oriented segment
//    edges; the loop of largest signed area is the outer wire, the others are holes.
// Everything is made with BRep_Builder: shared vertices and edges, no sewing.
#include "brep/planar.h"

#include <BRepLib.hxx>
#include <BRep_Builder.hxx>
#include <Geom_Line.hxx>
#include <Geom_Plane.hxx>
#include <Precision.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <cmath>

#include "detail/union_find.h"

namespace ncrev::brep_detail {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;
// Smallest tolerance given to vertices, edges and faces: OpenCASCADE's Precision::Confusion()
// (1e-7 model units), below which its checks treat lengths as zero.
constexpr double kMinTolerance = 1e-7;

gp_Pnt pnt(Vec3 v) { return {v.x, v.y, v.z}; }

double distance_to_segment(Vec3 p, Vec3 a, Vec3 b) {
    const Vec3 ab = b - a;
    const double len2 = dot(ab, ab);
    if (len2 == 0) return norm(p - a);
    const double t = std::clamp(dot(p - a, ab) / len2, 0.0, 1.0);
    return norm(p - (a + t * ab));
}

/// Fills topo.body and topo.bodies: faces that share a segment are one body; and
/// topo.void_of from the mesh's components' nesting, when given.
void number_bodies(PlanarTopology& topo, const Mesh& m, const ComponentNesting* nesting) {
    const auto nf = static_cast<std::uint32_t>(topo.faces.size());
    detail::MinUnionFind bodies(nf);
    std::vector<std::uint32_t> face_of_segment(topo.segments.size(), kNone);
    for (std::uint32_t f = 0; f < nf; ++f) {
        for (const PlanarTopology::Loop& loop : topo.faces[f].loops) {
            for (const auto& [seg, forward] : loop.edges) {
                std::uint32_t& other = face_of_segment[seg];
                if (other == kNone) {
                    other = f;
                } else {
                    bodies.unite(other, f);
                }
            }
        }
    }
    topo.body.assign(nf, kNone);
    std::vector<std::uint32_t> number(nf, kNone);
    topo.bodies = 0;
    for (std::uint32_t f = 0; f < nf; ++f) {
        std::uint32_t& n = number[bodies.find(f)];
        if (n == kNone) n = topo.bodies++;
        topo.body[f] = n;
    }
    topo.void_of.assign(topo.bodies, PlanarTopology::kNoBody);
    topo.voids = 0;
    if (!nesting || !topo.closed || topo.bodies < 2) return;
    // A body is one mesh component (faces share segments where facets share edges); a vertex
    // of its first face tells which.
    std::vector<std::uint32_t> component(topo.bodies, kNone);
    std::vector<std::uint32_t> body_of(nesting->parent.size(), kNone);
    for (std::uint32_t f = 0; f < nf; ++f) {
        const std::uint32_t b = topo.body[f];
        if (component[b] != kNone) continue;
        const std::uint32_t seg = topo.faces[f].loops.front().edges.front().first;
        const HalfedgeId h = m.outgoing(VertexId(topo.segments[seg][0]));
        component[b] = nesting->components.of_face[h.idx() / 3];
        body_of[component[b]] = b;
    }
    for (std::uint32_t b = 0; b < topo.bodies; ++b) {
        const std::uint32_t c = component[b];
        if (nesting->depth[c] % 2 == 0) continue;
        topo.void_of[b] = body_of[nesting->parent[c]];
        ++topo.voids;
    }
}

}  // namespace

PlanarTopology planar_topology(const Mesh& m, bool merge, double tol,
                               const ComponentNesting* nesting) {
    const std::size_t nf = m.num_faces(), nh = m.num_halfedges(), nv = m.num_vertices();
    PlanarTopology out;

    // 1. Regions.
    std::vector<std::uint32_t> region(nf, kNone);
    std::vector<std::uint32_t> queue;
    std::uint32_t num_regions = 0;
    for (std::size_t seed = 0; seed < nf; ++seed) {
        if (region[seed] != kNone) continue;
        const std::uint32_t r = num_regions++;
        region[seed] = r;
        if (!merge) continue;
        const FaceId sf(static_cast<std::uint32_t>(seed));
        const Vec3 n = m.face_normal(sf);
        const Vec3 p0 = m.position(m.vertex(sf, 0));
        queue.assign(1, static_cast<std::uint32_t>(seed));
        for (std::size_t q = 0; q < queue.size(); ++q) {
            const std::uint32_t f = queue[q];
            for (int k = 0; k < 3; ++k) {
                const HalfedgeId t = m.twin(Mesh::halfedge(FaceId(f), k));
                if (!t.is_valid()) continue;
                const FaceId g = Mesh::face(t);
                if (region[g.idx()] != kNone) continue;
                if (dot(m.face_normal_area2(g), n) <= 0) continue;
                bool on_plane = true;
                for (int j = 0; j < 3 && on_plane; ++j) {
                    on_plane = std::abs(dot(m.position(m.vertex(g, j)) - p0, n)) <= tol;
                }
                if (!on_plane) continue;
                region[g.idx()] = r;
                queue.push_back(g.idx());
            }
        }
    }

    // Region planes: area-weighted normal through the area-weighted centroid.
    std::vector<Vec3> rn(num_regions), rc(num_regions);
    std::vector<double> ra(num_regions, 0.0);
    for (std::size_t f = 0; f < nf; ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const Vec3 n2 = m.face_normal_area2(ff);
        const double a = 0.5 * norm(n2);
        const Vec3 c = (m.position(m.vertex(ff, 0)) + m.position(m.vertex(ff, 1)) +
                        m.position(m.vertex(ff, 2))) /
                       3.0;
        rn[region[f]] += n2;
        rc[region[f]] += a * c;
        ra[region[f]] += a;
    }
    double deviation = 0;
    for (std::uint32_t r = 0; r < num_regions; ++r) {
        rn[r] = normalized(rn[r]);
        rc[r] = ra[r] > 0 ? rc[r] / ra[r] : rc[r];
    }
    for (std::size_t f = 0; f < nf; ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        for (int k = 0; k < 3; ++k) {
            const double d =
                std::abs(dot(m.position(m.vertex(ff, k)) - rc[region[f]], rn[region[f]]));
            deviation = std::max(deviation, d);
        }
    }

    // 2. Borders and corners. A border half-edge has no twin or a twin in another region.
    auto is_border = [&](HalfedgeId h) {
        const HalfedgeId t = m.twin(h);
        return !t.is_valid() || region[Mesh::face(t).idx()] != region[Mesh::face(h).idx()];
    };
    auto pair_key = [&](HalfedgeId h) {
        const std::uint64_t a = region[Mesh::face(h).idx()];
        const HalfedgeId t = m.twin(h);
        const std::uint64_t b = t.is_valid() ? region[Mesh::face(t).idx()] : kNone;
        return a < b ? (a << 32) | b : (b << 32) | a;
    };
    // Per vertex: border degree and the two border neighbours (as canonical half-edges).
    std::vector<std::uint8_t> degree(nv, 0);
    std::vector<std::array<std::uint32_t, 2>> incident(nv, {kNone, kNone});
    auto canonical = [&](HalfedgeId h) {
        const HalfedgeId t = m.twin(h);
        return (!t.is_valid() || h.idx() < t.idx()) ? h : t;
    };
    for (std::size_t hi = 0; hi < nh; ++hi) {
        const HalfedgeId h(static_cast<std::uint32_t>(hi));
        if (!is_border(h) || canonical(h) != h) continue;
        for (VertexId v : {m.origin(h), m.target(h)}) {
            const std::uint8_t d = degree[v.idx()];
            if (d < 2) incident[v.idx()][d] = h.idx();
            degree[v.idx()] = static_cast<std::uint8_t>(std::min(3, d + 1));
        }
    }
    auto other_end = [&](std::uint32_t e, VertexId v) {
        const HalfedgeId h(e);
        return m.origin(h) == v ? m.target(h) : m.origin(h);
    };
    std::vector<std::uint8_t> corner(nv, 0);
    for (std::size_t v = 0; v < nv; ++v) {
        if (degree[v] == 0) continue;
        if (degree[v] != 2) {
            corner[v] = 1;
            continue;
        }
        const std::uint32_t e0 = incident[v][0], e1 = incident[v][1];
        if (pair_key(HalfedgeId(e0)) != pair_key(HalfedgeId(e1))) {
            corner[v] = 1;
            continue;
        }
        const VertexId vv(static_cast<std::uint32_t>(v));
        const Vec3 a = m.position(other_end(e0, vv)), b = m.position(other_end(e1, vv));
        if (!merge || distance_to_segment(m.position(vv), a, b) > tol) corner[v] = 1;
    }

    // Chains: from each corner along each of its border edges to the next corner, split into
    // straight segments within the tolerance. seg_of[canonical half-edge] = segment,
    // seg_from[segment] = its first vertex.
    std::vector<std::uint32_t> seg_of(nh, kNone);
    std::vector<std::array<std::uint32_t, 2>> seg_ends;
    std::vector<std::uint32_t> chain_v, chain_e;
    auto walk_chain = [&](VertexId start, std::uint32_t first_edge) {
        chain_v.assign(1, start.idx());
        chain_e.clear();
        VertexId v = start;
        std::uint32_t e = first_edge;
        for (std::size_t guard = 0; guard <= nh; ++guard) {
            chain_e.push_back(e);
            v = other_end(e, v);
            chain_v.push_back(v.idx());
            if (corner[v.idx()] || v == start) break;
            e = incident[v.idx()][0] == e ? incident[v.idx()][1] : incident[v.idx()][0];
        }
        // Greedy straight segments: extend while every inner vertex stays within tol.
        std::size_t s = 0;
        while (s + 1 < chain_v.size()) {
            std::size_t t = s + 1;
            while (merge && t + 1 < chain_v.size()) {
                const Vec3 a = m.position(VertexId(chain_v[s]));
                const Vec3 b = m.position(VertexId(chain_v[t + 1]));
                bool straight = true;
                for (std::size_t i = s + 1; i <= t && straight; ++i) {
                    straight = distance_to_segment(m.position(VertexId(chain_v[i])), a, b) <= tol;
                }
                if (!straight) break;
                ++t;
            }
            const auto seg = static_cast<std::uint32_t>(seg_ends.size());
            seg_ends.push_back({chain_v[s], chain_v[t]});
            for (std::size_t i = s; i < t; ++i) seg_of[chain_e[i]] = seg;
            s = t;
        }
    };
    // Every border edge not yet in a segment: go back to the corner its chain starts at, then
    // walk the chain forward (a corner of degree > 2 is left once per chain this way).
    for (std::size_t hi = 0; hi < nh; ++hi) {
        const HalfedgeId h(static_cast<std::uint32_t>(hi));
        if (!is_border(h) || canonical(h) != h || seg_of[hi] != kNone) continue;
        VertexId v = m.origin(h);
        std::uint32_t e = h.idx();
        bool corner_free_loop = false;
        for (std::size_t guard = 0; guard <= nh && !corner[v.idx()]; ++guard) {
            const std::uint32_t back =
                incident[v.idx()][0] == e ? incident[v.idx()][1] : incident[v.idx()][0];
            if (back == h.idx()) {
                corner_free_loop = true;
                break;
            }
            v = other_end(back, v);
            e = back;
        }
        if (corner_free_loop) {  // a closed border with no corner: start it anywhere
            v = m.origin(h);
            e = h.idx();
            corner[v.idx()] = 1;
        }
        walk_chain(v, e);
    }

    // 3. Faces: loops of border half-edges per region, compressed to oriented segments.
    out.tolerance = std::max(kMinTolerance, 1.001 * std::max(deviation, merge ? tol : 0.0));
    out.segments = std::move(seg_ends);
    std::vector<std::uint8_t> walked(nh, 0);
    // Border half-edges grouped by region, in half-edge order.
    std::vector<std::uint32_t> start(num_regions + 1, 0), border;
    for (std::size_t hi = 0; hi < nh; ++hi) {
        if (is_border(HalfedgeId(static_cast<std::uint32_t>(hi)))) ++start[region[hi / 3] + 1];
    }
    for (std::uint32_t r = 0; r < num_regions; ++r) start[r + 1] += start[r];
    border.resize(start[num_regions]);
    {
        std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
        for (std::size_t hi = 0; hi < nh; ++hi) {
            if (is_border(HalfedgeId(static_cast<std::uint32_t>(hi)))) {
                border[fill[region[hi / 3]]++] = static_cast<std::uint32_t>(hi);
            }
        }
    }
    std::vector<PlanarTopology::Loop> loops;
    std::vector<std::uint32_t> loop_h;
    for (std::uint32_t r = 0; r < num_regions; ++r) {
        loops.clear();
        for (std::uint32_t k = start[r]; k < start[r + 1]; ++k) {
            if (walked[border[k]]) continue;
            loop_h.clear();
            HalfedgeId h(border[k]);
            for (std::size_t guard = 0; guard <= nh && !walked[h.idx()]; ++guard) {
                walked[h.idx()] = 1;
                loop_h.push_back(h.idx());
                HalfedgeId g = Mesh::next(h);
                for (std::size_t g2 = 0; g2 <= nh && !is_border(g); ++g2) g = Mesh::next(m.twin(g));
                h = g;
            }
            // Rotate so that the loop starts where a segment starts, then compress.
            std::size_t first = 0;
            for (std::size_t i = 0; i < loop_h.size(); ++i) {
                const HalfedgeId hh(loop_h[i]);
                const auto& ends = out.segments[seg_of[canonical(hh).idx()]];
                const std::uint32_t o = m.origin(hh).idx();
                if (ends[0] == o || ends[1] == o) {
                    first = i;
                    break;
                }
            }
            PlanarTopology::Loop loop;
            Vec3 area2{};
            const Vec3 origin = rc[r];
            for (std::size_t i = 0; i < loop_h.size(); ++i) {
                const HalfedgeId hh(loop_h[(first + i) % loop_h.size()]);
                const Vec3 a = m.position(m.origin(hh)) - origin;
                const Vec3 b = m.position(m.target(hh)) - origin;
                area2 += cross(a, b);
                const std::uint32_t seg = seg_of[canonical(hh).idx()];
                if (!loop.edges.empty() && loop.edges.back().first == seg) continue;
                // The segment runs ends[0] -> ends[1] (straight within tol): hh runs along it
                // when its origin is nearer to the segment's start than its target.
                const Vec3 s0 = m.position(VertexId(out.segments[seg][0]));
                const bool forward =
                    norm(m.position(m.origin(hh)) - s0) < norm(m.position(m.target(hh)) - s0);
                loop.edges.emplace_back(seg, forward);
            }
            loop.area = 0.5 * dot(area2, rn[r]);
            loops.push_back(std::move(loop));
        }
        if (loops.empty()) continue;
        // The loop of largest signed area is the outer wire; the others are holes.
        std::size_t outer = 0;
        for (std::size_t i = 1; i < loops.size(); ++i) {
            if (loops[i].area > loops[outer].area) outer = i;
        }
        std::swap(loops[0], loops[outer]);
        out.faces.push_back({rc[r], rn[r], std::move(loops)});
        loops = {};
    }
    out.closed = nf > 0;
    for (std::size_t hi = 0; hi < nh && out.closed; ++hi) {
        out.closed = !m.is_boundary(HalfedgeId(static_cast<std::uint32_t>(hi)));
    }
    number_bodies(out, m, nesting);
    return out;
}

std::string check_topology(const PlanarTopology& topo, const Mesh& m) {
    std::vector<std::uint8_t> forward_uses(topo.segments.size(), 0),
        backward_uses(topo.segments.size(), 0);
    auto start_of = [&](std::pair<std::uint32_t, bool> e) {
        return e.second ? topo.segments[e.first][0] : topo.segments[e.first][1];
    };
    auto end_of = [&](std::pair<std::uint32_t, bool> e) {
        return e.second ? topo.segments[e.first][1] : topo.segments[e.first][0];
    };
    for (std::size_t s = 0; s < topo.segments.size(); ++s) {
        const auto [a, b] = topo.segments[s];
        if (a == b || norm(m.position(VertexId(a)) - m.position(VertexId(b))) <= topo.tolerance) {
            return "segment " + std::to_string(s) + " has no length";
        }
    }
    for (std::size_t f = 0; f < topo.faces.size(); ++f) {
        const auto& face = topo.faces[f];
        if (face.loops.empty()) return "face " + std::to_string(f) + " has no loop";
        for (const auto& loop : face.loops) {
            if (loop.edges.size() < 3)
                return "face " + std::to_string(f) + " has a loop of fewer than 3 edges";
            for (std::size_t k = 0; k < loop.edges.size(); ++k) {
                const auto e = loop.edges[k];
                if (end_of(e) != start_of(loop.edges[(k + 1) % loop.edges.size()])) {
                    return "face " + std::to_string(f) + " has a loop that does not chain";
                }
                (e.second ? forward_uses : backward_uses)[e.first] += 1;
                const Vec3 p = m.position(VertexId(start_of(e)));
                if (std::abs(dot(p - face.origin, face.normal)) > topo.tolerance) {
                    return "face " + std::to_string(f) + " has a vertex off its plane";
                }
            }
        }
    }
    for (std::size_t s = 0; s < topo.segments.size(); ++s) {
        const int fw = forward_uses[s], bw = backward_uses[s];
        const bool shared = fw == 1 && bw == 1;
        const bool boundary = !topo.closed && fw + bw == 1;
        if (!shared && !boundary) {
            return "segment " + std::to_string(s) + " is used " + std::to_string(fw) +
                   " times forward and " + std::to_string(bw) + " times backward";
        }
    }
    return {};
}

void measure_topology(const PlanarTopology& topo, const Mesh& m, double& area, double& volume) {
    area = 0;
    volume = 0;
    for (const auto& face : topo.faces) {
        double face_area = 0;
        for (const auto& loop : face.loops) {
            Vec3 a2{};
            for (const auto& [seg, forward] : loop.edges) {
                const Vec3 a =
                    m.position(VertexId(topo.segments[seg][forward ? 0 : 1])) - face.origin;
                const Vec3 b =
                    m.position(VertexId(topo.segments[seg][forward ? 1 : 0])) - face.origin;
                a2 += cross(a, b);
            }
            face_area += 0.5 * dot(a2, face.normal);
        }
        area += face_area;
        volume += dot(face.origin, face.normal) * face_area / 3.0;
    }
}

PlanarShape to_occt(const PlanarTopology& topo, const Mesh& m) {
    PlanarShape out;
    const double tol = topo.tolerance;
    BRep_Builder builder;
    std::vector<TopoDS_Vertex> vertex(m.num_vertices());
    auto vertex_of = [&](std::uint32_t v) -> const TopoDS_Vertex& {
        if (vertex[v].IsNull()) builder.MakeVertex(vertex[v], pnt(m.position(VertexId(v))), tol);
        return vertex[v];
    };
    std::vector<TopoDS_Edge> edge(topo.segments.size());
    for (std::size_t s = 0; s < topo.segments.size(); ++s) {
        const Vec3 a = m.position(VertexId(topo.segments[s][0]));
        const Vec3 b = m.position(VertexId(topo.segments[s][1]));
        Handle(Geom_Line) line = new Geom_Line(pnt(a), gp_Dir(b.x - a.x, b.y - a.y, b.z - a.z));
        builder.MakeEdge(edge[s], line, tol);
        builder.Add(edge[s], vertex_of(topo.segments[s][0]).Oriented(TopAbs_FORWARD));
        builder.Add(edge[s], vertex_of(topo.segments[s][1]).Oriented(TopAbs_REVERSED));
        builder.Range(edge[s], 0.0, norm(b - a));
    }
    std::vector<TopoDS_Shell> shells(topo.bodies);
    for (TopoDS_Shell& shell : shells) builder.MakeShell(shell);
    for (std::size_t k = 0; k < topo.faces.size(); ++k) {
        const PlanarTopology::Face& f = topo.faces[k];
        Handle(Geom_Plane) plane =
            new Geom_Plane(pnt(f.origin), gp_Dir(f.normal.x, f.normal.y, f.normal.z));
        TopoDS_Face face;
        builder.MakeFace(face, plane, tol);
        for (const PlanarTopology::Loop& loop : f.loops) {
            TopoDS_Wire wire;
            builder.MakeWire(wire);
            for (const auto& [seg, forward] : loop.edges) {
                builder.Add(wire, edge[seg].Oriented(forward ? TopAbs_FORWARD : TopAbs_REVERSED));
            }
            wire.Closed(true);
            builder.Add(face, wire);
        }
        builder.Add(shells[topo.body[k]], face);
    }
    // A void's shell goes into the solid around it, its faces facing into the void.
    std::vector<TopoDS_Shape> bodies;
    std::vector<TopoDS_Solid> solids(topo.bodies);
    for (std::uint32_t b = 0; b < topo.bodies; ++b) {
        shells[b].Closed(topo.closed);
        if (!topo.closed) {
            bodies.push_back(shells[b]);
        } else if (topo.void_of[b] == PlanarTopology::kNoBody) {
            builder.MakeSolid(solids[b]);
            builder.Add(solids[b], shells[b]);
            bodies.push_back(solids[b]);
        }
    }
    for (std::uint32_t b = 0; b < topo.bodies && topo.closed; ++b) {
        if (topo.void_of[b] != PlanarTopology::kNoBody)
            builder.Add(solids[topo.void_of[b]], shells[b]);
    }
    out.solid = topo.closed;
    if (bodies.size() == 1) {
        out.shape = bodies.front();
    } else {
        TopoDS_Compound all;
        builder.MakeCompound(all);
        for (const TopoDS_Shape& b : bodies) builder.Add(all, b);
        out.shape = all;
    }
    return out;
}

}  // namespace ncrev::brep_detail
