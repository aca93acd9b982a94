// Planar B-rep construction (facets and planar merging). Internal.
#pragma once

#include <TopoDS_Shape.hxx>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "brep/step.h"
#include "ncrev/mesh.h"

namespace ncrev::brep_detail {

/// The planar B-rep as plain data: faces (plane and loops of oriented straight edges) over
/// segments between mesh vertices. Every segment is shared by the faces it bounds.
struct PlanarTopology {
    struct Loop {
        std::vector<std::pair<std::uint32_t, bool>> edges;  ///< (segment, runs forward)
        double area = 0;  ///< signed, about the face normal: > 0 outer, < 0 a hole
    };
    struct Face {
        Vec3 origin;              ///< on the plane (area-weighted centroid of its facets)
        Vec3 normal;              ///< unit, outward
        std::vector<Loop> loops;  ///< the outer loop first
    };
    std::vector<std::array<std::uint32_t, 2>> segments;  ///< mesh vertex ids, start -> end
    std::vector<Face> faces;
    double tolerance = 0;  ///< largest deviation of a vertex from its face plane or segment
    bool closed = false;   ///< the mesh is closed: each shell bounds a solid
    /// Per face, its body: the connected shell it belongs to (faces joined by shared
    /// segments), numbered from 0 in the order of their first face. A mesh of several
    /// components (parts side by side) has several bodies, each a shell (a solid when closed).
    std::vector<std::uint32_t> body;
    std::uint32_t bodies = 0;
    /// Per body: the body whose solid it is a void of (a cavity's shell, facing into the
    /// cavity), or kNoBody for a body that is a solid (or shell) of its own.
    std::vector<std::uint32_t> void_of;
    static constexpr std::uint32_t kNoBody = 0xffffffffu;
    std::uint32_t voids = 0;
};

/// `merge` false: one face per facet (the paper's method 1). `merge` true: coplanar
/// neighbours within `tol` (model units) become one face, boundary runs within `tol` of a
/// straight line one edge. `nesting`: the mesh's component_nesting(), when it has several
/// closed components (a closed component inside another an odd number of times becomes a void
/// of the body around it); null: none nested.
PlanarTopology planar_topology(const Mesh& mesh, bool merge, double tol,
                               const ComponentNesting* nesting = nullptr);

/// Structural check in O(n): loops closed and chained end to start, every segment used twice
/// in opposite directions (once, on an open mesh's boundary), segments of positive length,
/// every loop vertex within the tolerance of its face's plane. Empty when sound, else what
/// is wrong.
std::string check_topology(const PlanarTopology& topology, const Mesh& mesh);

/// Area of the faces, and the volume they bound (divergence theorem over the planar faces;
/// meaningful when closed).
void measure_topology(const PlanarTopology& topology, const Mesh& mesh, double& area,
                      double& volume);

struct PlanarShape {
    TopoDS_Shape shape;  ///< a solid per body when the mesh is closed (its voids' shells inside
                         ///< it), else a shell per body; several in a compound
    bool solid = false;
};

/// The topology as an OpenCASCADE shape built with BRep_Builder (shared vertices and edges).
PlanarShape to_occt(const PlanarTopology& topology, const Mesh& mesh);

/// Writes the topology as STEP text directly (no OpenCASCADE objects), atomically.
Status write_planar_step(const PlanarTopology& topology, const Mesh& mesh,
                         const std::filesystem::path& path, const StepWriteOptions& options);

}  // namespace ncrev::brep_detail
