// Differential-geometry building blocks on the mesh: dihedral angles, mixed Voronoi areas
// (Meyer, Desbrun, Schröder and Barr, "Discrete Differential-Geometry Operators for
// Triangulated 2-Manifolds", 2003), angle-weighted vertex normals.
#include <algorithm>
#include <cmath>

#include "ncrev/mesh.h"

namespace ncrev {

double dihedral_angle(const Mesh& m, HalfedgeId h) {
    const HalfedgeId t = m.twin(h);
    if (!t.is_valid()) return 0.0;
    const Vec3 n1 = m.face_normal(Mesh::face(h)), n2 = m.face_normal(Mesh::face(t));
    const Vec3 a = m.position(m.origin(h)), b = m.position(m.target(h));
    const Vec3 e = normalized(b - a);
    // The angle from n1 to n2 about the edge direction of h (h runs a -> b in facet 1): for a
    // convex edge, n2 is n1 turned positively about e.
    const double sin_angle = dot(cross(n1, n2), e);
    const double cos_angle = std::clamp(dot(n1, n2), -1.0, 1.0);
    return std::atan2(sin_angle, cos_angle);
}

VertexMap<double> mixed_voronoi_areas(const Mesh& m) {
    VertexMap<double> area(m.num_vertices(), 0.0);
    for (std::size_t f = 0; f < m.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const VertexId v[3] = {m.vertex(ff, 0), m.vertex(ff, 1), m.vertex(ff, 2)};
        const Vec3 p[3] = {m.position(v[0]), m.position(v[1]), m.position(v[2])};
        const double face_area = 0.5 * norm(cross(p[1] - p[0], p[2] - p[0]));
        if (face_area <= 0) continue;
        // cot of the angle at corner i, and whether it is obtuse.
        double cot[3];
        int obtuse = -1;
        for (int i = 0; i < 3; ++i) {
            const Vec3 u = p[(i + 1) % 3] - p[i], w = p[(i + 2) % 3] - p[i];
            const double d = dot(u, w);
            cot[i] = d / norm(cross(u, w));
            if (d < 0) obtuse = i;
        }
        if (obtuse < 0) {
            // Voronoi share of vertex i: (|e_ij|^2 cot(k) + |e_ik|^2 cot(j)) / 8.
            for (int i = 0; i < 3; ++i) {
                const int j = (i + 1) % 3, k = (i + 2) % 3;
                const Vec3 eij = p[j] - p[i], eik = p[k] - p[i];
                area[v[i]] += (dot(eij, eij) * cot[k] + dot(eik, eik) * cot[j]) / 8.0;
            }
        } else {
            for (int i = 0; i < 3; ++i) area[v[i]] += face_area * (i == obtuse ? 0.5 : 0.25);
        }
    }
    return area;
}

VertexMap<Vec3> vertex_normals(const Mesh& m) {
    VertexMap<Vec3> normal(m.num_vertices(), Vec3{});
    for (std::size_t f = 0; f < m.num_faces(); ++f) {
        const FaceId ff(static_cast<std::uint32_t>(f));
        const Vec3 n = m.face_normal(ff);
        for (int i = 0; i < 3; ++i) {
            const Vec3 p = m.position(m.vertex(ff, i));
            const Vec3 u = normalized(m.position(m.vertex(ff, (i + 1) % 3)) - p);
            const Vec3 w = normalized(m.position(m.vertex(ff, (i + 2) % 3)) - p);
            const double angle = std::acos(std::clamp(dot(u, w), -1.0, 1.0));
            normal[m.vertex(ff, i)] += angle * n;
        }
    }
    for (Vec3& n : normal.data()) n = normalized(n);
    return normal;
}

}  // namespace ncrev
