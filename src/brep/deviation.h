// How far a B-rep is from the mesh it was built from, both ways. Internal.
#pragma once

#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <array>
#include <span>
#include <vector>

#include "ncrev/brep.h"
#include "ncrev/mesh.h"

namespace ncrev::brep_detail {

/// Triangulates `shape` with BRepMesh at `deflection` and an angular deflection of 0.2 rad (in
/// parallel over its faces when `parallel`), then each face left without triangles once more
/// at BRepMesh's own default of 0.5 rad: a face BRepMesh cannot follow that finely (the M6
/// screw's faded thread end as one B-spline of a few facets) is still one a viewer shows.
void triangulate(const TopoDS_Shape& shape, double deflection, bool parallel);

/// Distances between `shape` and `mesh`: from every mesh vertex to the shape, and from every
/// node of the shape's own triangulation (BRepMesh at `deflection`, model units) to the mesh.
/// The shape is approximated by that triangulation, so both figures may exceed the true
/// distance by up to `deflection`; pass a fraction of the mesh's chordal deflection.
/// Deterministic whatever the thread count.
SolidDeviation measure_deviation(const TopoDS_Shape& shape, const Mesh& mesh, double deflection);

/// Triangulates `shape` (triangulate(), in parallel; measure_deviation() then reuses it) and
/// returns, for each face BRepMesh leaves without triangles, the point of the face nearest its
/// centre of area. Such a face passes BRepCheck but no viewer can show it, and the deviation would
/// not see it.
std::vector<std::array<double, 3>> untriangulated_faces(const TopoDS_Shape& shape,
                                                        double deflection);

/// For each of `faces`, the largest distance from a node of its triangulation (triangulate() at
/// `deflection`, made where the face has none) to `mesh`; -1 for a face BRepMesh leaves
/// without triangles. Deterministic whatever the thread count.
std::vector<double> faces_from_mesh(std::span<const TopoDS_Face> faces, const Mesh& mesh,
                                    double deflection);

}  // namespace ncrev::brep_detail
