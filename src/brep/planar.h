// Planar B-rep construction (facets and planar merging). Internal.
#pragma once

#include <TopoDS_Shape.hxx>
#include <cstdint>

#include "ncrev/mesh.h"

namespace ncrev::brep_detail {

struct PlanarBuild {
    TopoDS_Shape shape;  ///< a solid when the mesh is closed, else a shell
    bool solid = false;
    std::uint64_t faces = 0, edges = 0, vertices = 0;
    double tolerance = 0;  ///< the vertex / edge / face tolerance given to OpenCASCADE
};

/// `merge` false: one face per facet (the paper's method 1). `merge` true: coplanar
/// neighbours within `tol` (model units) become one face, boundary runs within `tol` of a
/// straight line one edge.
PlanarBuild build_planar_shape(const Mesh& mesh, bool merge, double tol);

}  // namespace ncrev::brep_detail
