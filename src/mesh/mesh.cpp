// Mesh queries, invariant checks and statistics.
#include "ncrev/mesh.h"

#include <algorithm>
#include <array>
#include <numeric>

#include "detail/huge_pages.h"
#include "detail/nesting.h"

namespace ncrev {

Vec3 Mesh::face_normal_area2(FaceId f) const {
    const Vec3 a = position(vertex(f, 0)), b = position(vertex(f, 1)), c = position(vertex(f, 2));
    return cross(b - a, c - a);
}

std::string Mesh::validate() const {
    const std::size_t nh = num_halfedges(), nv = num_vertices();
    if (nh % 3 != 0) return "half-edge count is not a multiple of 3";
    if (twin_.size() != nh) return "twin column size differs from origin column";
    if (outgoing_.size() != nv) return "outgoing column size differs from vertex count";
    if (source_face_.size() != num_faces())
        return "source-face column size differs from face count";
    if (!color_.empty() && (color_.size() != num_faces() || cut_.size() != num_faces() ||
                            surface_.size() != num_faces())) {
        return "attribute column sizes differ from face count";
    }
    auto str = [](std::size_t v) { return std::to_string(v); };
    std::vector<std::uint32_t> fans(nv, 0);
    for (std::size_t h = 0; h < nh; ++h) {
        const HalfedgeId hh(static_cast<std::uint32_t>(h));
        if (origin_[h] >= nv) return "half-edge " + str(h) + " starts at a vertex out of range";
        if (origin(hh) == target(hh)) return "half-edge " + str(h) + " is a loop";
        if (is_boundary(hh)) continue;
        if (twin_[h] >= nh) return "half-edge " + str(h) + " has a twin out of range";
        const HalfedgeId t = twin(hh);
        if (twin(t) != hh) return "twin(twin(" + str(h) + ")) != " + str(h);
        if (t == hh) return "half-edge " + str(h) + " is its own twin";
        if (origin(t) != target(hh) || target(t) != origin(hh)) {
            return "half-edge " + str(h) + " and its twin do not run opposite ways";
        }
    }
    for (std::size_t v = 0; v < nv; ++v) {
        const std::uint32_t h = outgoing_[v];
        if (h >= nh) return "vertex " + str(v) + " has no outgoing half-edge";
        if (origin_[h] != v) return "outgoing half-edge of vertex " + str(v) + " starts elsewhere";
    }
    // One fan per vertex: rotating from the outgoing half-edge reaches every half-edge that
    // starts at the vertex.
    std::vector<std::uint32_t> reached(nv, 0), total(nv, 0);
    for (std::size_t h = 0; h < nh; ++h) ++total[origin_[h]];
    for (std::size_t v = 0; v < nv; ++v) {
        const HalfedgeId start(outgoing_[v]);
        HalfedgeId g = start;
        std::uint32_t count = 0;
        // A boundary vertex's outgoing half-edge must be the one without twin: then rotating
        // with twin(prev(g)) walks the whole open fan.
        bool boundary_vertex = false;
        for (std::size_t guard = 0; guard <= nh; ++guard) {
            ++count;
            const HalfedgeId p = prev(g);
            if (is_boundary(p)) {
                boundary_vertex = true;
                break;
            }
            g = twin(p);
            if (g == start) break;
        }
        if (boundary_vertex && !is_boundary(start)) {
            return "boundary vertex " + str(v) + " has an outgoing half-edge with a twin";
        }
        if (count != total[v]) {
            return "vertex " + str(v) + " has " + str(total[v]) +
                   " outgoing half-edges but its fan holds " + str(count) +
                   " (non-manifold vertex)";
        }
    }
    return {};
}

Components face_components(const Mesh& mesh) {
    const std::size_t nf = mesh.num_faces();
    Components out;
    std::vector<std::uint32_t>& comp = out.of_face;
    detail::assign_huge(comp, nf, std::uint32_t{HalfedgeId::kInvalid});
    std::vector<std::uint32_t> stack;
    for (std::size_t seed = 0; seed < nf; ++seed) {
        if (comp[seed] != HalfedgeId::kInvalid) continue;
        const auto id = static_cast<std::uint32_t>(out.closed.size());
        out.closed.push_back(1);
        comp[seed] = id;
        stack.push_back(static_cast<std::uint32_t>(seed));
        while (!stack.empty()) {
            const std::uint32_t f = stack.back();
            stack.pop_back();
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t t = mesh.twins()[3 * f + k];
                if (t == HalfedgeId::kInvalid) {
                    out.closed[id] = 0;
                } else if (comp[t / 3] == HalfedgeId::kInvalid) {
                    comp[t / 3] = id;
                    stack.push_back(t / 3);
                }
            }
        }
    }
    return out;
}

std::vector<std::vector<HalfedgeId>> boundary_loops(const Mesh& mesh) {
    std::vector<std::vector<HalfedgeId>> loops;
    const std::size_t nh = mesh.num_halfedges();
    std::vector<std::uint8_t> seen;
    for (std::size_t h = 0; h < nh; ++h) {
        if (mesh.twins()[h] != HalfedgeId::kInvalid || (!seen.empty() && seen[h])) continue;
        if (seen.empty()) seen.assign(nh, 0);  // a closed mesh needs none
        std::vector<HalfedgeId>& loop = loops.emplace_back();
        HalfedgeId g(static_cast<std::uint32_t>(h));
        for (std::size_t guard = 0; guard <= nh && !seen[g.idx()]; ++guard) {
            seen[g.idx()] = 1;
            loop.push_back(g);
            g = mesh.outgoing(mesh.target(g));
            if (!mesh.is_boundary(g)) break;  // cannot happen on a valid mesh
        }
    }
    return loops;
}

Mesh keep_components(const Mesh& mesh, const Components& components,
                     std::span<const std::uint8_t> keep) {
    const std::vector<std::uint32_t>& component = components.of_face;
    constexpr std::uint32_t kNone = HalfedgeId::kInvalid;
    const std::size_t nf = mesh.num_faces(), nv = mesh.num_vertices();
    std::vector<std::uint32_t> face_to(nf, kNone), vertex_to(nv, kNone);
    std::uint32_t faces = 0, vertices = 0;
    for (std::size_t f = 0; f < nf; ++f) {
        if (!keep[component[f]]) continue;
        face_to[f] = faces++;
        for (int i = 0; i < 3; ++i) vertex_to[mesh.origin_[3 * f + i]] = 0;
    }
    Mesh out;
    for (std::size_t v = 0; v < nv; ++v) {
        if (vertex_to[v] == kNone) continue;
        vertex_to[v] = vertices++;
        out.position_.push_back(mesh.position_[v]);
    }
    const auto halfedge_to = [&](std::uint32_t h) {
        return h == kNone ? kNone : 3 * face_to[h / 3] + h % 3;
    };
    out.origin_.reserve(3 * std::size_t{faces});
    out.twin_.reserve(3 * std::size_t{faces});
    for (std::size_t f = 0; f < nf; ++f) {
        if (face_to[f] == kNone) continue;
        for (std::size_t h = 3 * f; h < 3 * f + 3; ++h) {
            out.origin_.push_back(vertex_to[mesh.origin_[h]]);
            out.twin_.push_back(halfedge_to(mesh.twin_[h]));
        }
        out.source_face_.push_back(mesh.source_face_[f]);
        if (!mesh.color_.empty()) out.color_.push_back(mesh.color_[f]);
        if (!mesh.cut_.empty()) out.cut_.push_back(mesh.cut_[f]);
        if (!mesh.surface_.empty()) out.surface_.push_back(mesh.surface_[f]);
    }
    out.outgoing_.resize(vertices);
    for (std::size_t v = 0; v < nv; ++v) {
        if (vertex_to[v] != kNone) out.outgoing_[vertex_to[v]] = halfedge_to(mesh.outgoing_[v]);
    }
    return out;
}

ComponentNesting component_nesting(const Mesh& mesh) {
    ComponentNesting out;
    out.components = face_components(mesh);
    const Components& c = out.components;
    const auto count = static_cast<std::uint32_t>(c.count());
    detail::Nesting n =
        detail::nest_components(c.of_face, count, c.closed, 0.0, [&](std::uint32_t f) {
            return std::array<Vec3, 3>{mesh.position(mesh.vertex(FaceId(f), 0)),
                                       mesh.position(mesh.vertex(FaceId(f), 1)),
                                       mesh.position(mesh.vertex(FaceId(f), 2))};
        });
    static_assert(ComponentNesting::kNone == detail::kNotNested);
    out.parent = std::move(n.parent);
    out.depth = std::move(n.depth);
    out.complete = n.complete;
    out.crossing = std::move(n.crossing);
    out.crossing_complete = n.crossing_complete;
    return out;
}

MeshStats compute_stats(const Mesh& mesh) {
    MeshStats s;
    const std::size_t nh = mesh.num_halfedges(), nf = mesh.num_faces();
    s.vertices = mesh.num_vertices();
    s.faces = nf;
    for (const Vec3& p : mesh.positions()) s.bbox.add(p);
    std::uint64_t boundary = 0;
    for (std::size_t h = 0; h < nh; ++h) boundary += mesh.twins()[h] == HalfedgeId::kInvalid;
    s.boundary_edges = boundary;
    s.edges = (nh - boundary) / 2 + boundary;
    s.euler_characteristic = static_cast<std::int64_t>(s.vertices) -
                             static_cast<std::int64_t>(s.edges) +
                             static_cast<std::int64_t>(s.faces);
    s.closed = boundary == 0 && nf > 0;

    // Area and volume, the volume about the box center for precision.
    const Vec3 c = s.bbox.empty() ? Vec3{} : 0.5 * (s.bbox.min + s.bbox.max);
    double area = 0, vol6 = 0;
    for (std::size_t f = 0; f < nf; ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const Vec3 a = mesh.position(mesh.vertex(ff, 0)) - c;
        const Vec3 b = mesh.position(mesh.vertex(ff, 1)) - c;
        const Vec3 d = mesh.position(mesh.vertex(ff, 2)) - c;
        area += 0.5 * norm(cross(b - a, d - a));
        vol6 += dot(a, cross(b, d));
    }
    s.area = area;
    s.volume = vol6 / 6.0;

    s.components = face_components(mesh).count();
    for (const auto& loop : boundary_loops(mesh)) {
        s.boundary_loop_sizes.push_back(static_cast<std::uint32_t>(loop.size()));
    }
    std::sort(s.boundary_loop_sizes.begin(), s.boundary_loop_sizes.end(), std::greater<>());
    s.boundary_loops = s.boundary_loop_sizes.size();
    return s;
}

}  // namespace ncrev
