// brep: the mesh as an OpenCASCADE solid, written as STEP (../shared/docs/method.md, Step 2a).
//
// Methods:
//  - surfaces (method.md Step 2b): the mesh segmented into regions (or the SRE's surface per
//    facet), one face per region on its fitted surface (plane, cylinder, cone, sphere, torus,
//    sheared kinds from SRE, B-spline), edges where the surfaces meet, trimmed at the corners
//    solved onto them; fails rather than give a region up;
//  - auto (the default): surfaces, with the local fallback: a region whose face cannot be
//    built with exact edges comes back as one face on its surface bounded by the mesh edges of
//    its border, or where even that fails as its facets, sewn to its neighbours, and is
//    reported;
//  - facets: the paper's method 1, one planar face per facet;
//  - planar: coplanar neighbours merged into one planar face, bounded by its outer wire and
//    its inner wires (holes), with collinear boundary vertices removed.
// The planar B-reps are built directly with BRep_Builder, every vertex and every edge shared by
// the faces that meet there (no sewing), so they scale to a million facets. A closed mesh gives
// a solid (a MANIFOLD_SOLID_BREP in the STEP); an open one a shell (a surface model) — with the
// planar method, since surfaces need a closed mesh.
// OpenCASCADE stays inside src/brep: this header speaks plain data only.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ncrev/common.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"
#include "ncrev/segment.h"

namespace ncrev {

enum class ReverseMethod { kAuto, kSurfaces, kFacets, kPlanar };
/// "auto", "surfaces", "facets", "planar".
const char* to_string(ReverseMethod method);

enum class StepSchema { kAP214, kAP203, kAP242 };
/// "ap214", "ap203", "ap242".
const char* to_string(StepSchema schema);

struct ReverseOptions {
    ReverseMethod method = ReverseMethod::kAuto;
    StepSchema schema = StepSchema::kAP214;
    Unit unit = Unit::kMillimetre;  ///< the unit the STEP file declares (the mesh's own)
    std::string product_name;       ///< STEP product name; empty: "ncrev"
    /// Planar merging: largest distance of a facet's vertices from the plane of the face it
    /// joins, in model units. Negative: derived from the mesh (see ReverseReport).
    double planar_tolerance = -1;
    /// surfaces / auto: how the mesh is segmented (tolerance, sharp angle, the SRE surfaces
    /// table with `use_surface_indices`).
    SegmentOptions segment;
    /// Face colors in the STEP (XDE): the SRE tool color of a region's facets where the mesh
    /// carries colors, else one color per surface kind (kind_color()). False: plain geometry.
    bool colors = true;
    /// Measure the deviation between the solid and the mesh (ReverseReport::deviation).
    bool measure_deviation = true;
    /// Write nothing (a warning says why) unless the result is solids: an open mesh with the
    /// planar methods, or with auto / surfaces when its closed components are not most of it,
    /// and a mesh that passes through itself (its solid would too; find_self_intersections()).
    bool require_solid = false;
    /// The healing report of `mesh` (build_mesh()), when the caller has it: require_solid then
    /// takes its self_intersections instead of searching the mesh again. Not owned; null: the
    /// mesh is searched (find_self_intersections(), at the default weld tolerance).
    const HealReport* heal = nullptr;
    ProgressFn progress;  ///< one call at the start and end of each stage
};

/// The STEP color (0xRRGGBB) of faces of a kind when no tool color is given: "plane",
/// "cylinder", "cone", "sphere", "torus", "bspline", other kinds and facets a neutral grey.
std::uint32_t kind_color(const std::string& kind);

/// Distance statistics over a set of points, model units.
struct DistanceStats {
    double max = 0, mean = 0, rms = 0;
    std::uint64_t points = 0;
};

/// How far the solid is from the mesh: from every mesh vertex to the solid, and from the
/// nodes of a fine triangulation of the solid's faces to the mesh.
struct SolidDeviation {
    DistanceStats mesh_to_solid, solid_to_mesh;
    /// The deflection of that triangulation (a quarter of the mesh's chordal deflection): the
    /// figures may exceed the true distances by up to this.
    double deflection = 0;
    std::uint64_t faces_without_triangles = 0;
};

/// A region whose face with exact edges could not be built (the local fallback): it came back
/// as one face on its surface bounded by the mesh edges of its border (`mesh_edges`; its edges
/// are chords of the surfaces, within the chordal deflection), or as its facets.
struct ReverseFallback {
    std::int32_t region = 0;
    std::uint64_t facets = 0;  ///< mesh facets in the region
    std::string kind;          ///< the region's surface kind, "none" without one
    std::string reason;        ///< why its exact face could not be built
    bool mesh_edges = false;
};

/// What reverse_to_step() built, in numbers.
struct ReverseReport {
    ReverseMethod method = ReverseMethod::kPlanar;
    std::vector<std::pair<std::string, double>> stage_seconds;  ///< in order
    double planar_tolerance = 0;                                ///< used by `planar`, model units
    std::string planar_tolerance_rule;                          ///< how it was chosen
    std::map<std::string, std::uint64_t> faces_by_kind;         ///< e.g. {"plane": 12}
    std::uint64_t faces = 0, edges = 0, vertices = 0;
    bool solid = false;  ///< the closed shells were made into solids
    /// Bodies: connected shells, one per component of the mesh (several parts side by side
    /// give several), each a solid when closed; written as that many solids (or shells).
    std::uint64_t bodies = 0;
    /// Cavities: closed shells inside a body (healing faces them into the cavity), each a void
    /// of the body's solid (written as a BREP_WITH_VOIDS).
    std::uint64_t voids = 0;
    /// auto / surfaces on an open mesh whose closed components are most of it: the facets of
    /// its open components (stray facets, scraps), left out of the solids (a warning says so).
    std::uint64_t left_out_facets = 0;
    bool valid = false;         ///< the structural check (and BRepCheck_Analyzer) found no defect
    bool occt_checked = false;  ///< BRepCheck_Analyzer ran too (B-reps of up to 5000 faces)
    double solid_volume = 0, solid_area = 0;  ///< of the B-rep's faces
    double mesh_volume = 0, mesh_area = 0;    ///< of the mesh it came from
    /// surfaces / auto: the segmentation (regions, their surfaces, facet labels), the
    /// fallbacks, the B-rep's edges by how their curve was made, and its largest tolerance.
    std::optional<SegmentResult> segmentation;
    std::vector<ReverseFallback> fallbacks;
    std::uint64_t fallback_faces = 0;  ///< faces of the fallback regions
    /// Regions whose own face failed and whose facets joined a neighbour's face (slivers that
    /// lie on the neighbour's surface).
    std::uint64_t absorbed_regions = 0;
    /// Edges by how their curve was made: intersection, tangency (a fillet's exact contact),
    /// fitted, polyline; and analytic: of the intersection and tangency edges, those whose
    /// curve is exact (a line, circle or ellipse, a B-spline extrusion's profile).
    std::map<std::string, std::uint64_t> edges_by_curve;
    /// Regions whose cylinder was moved a hair apart from a larger one it overlapped by a
    /// fitting error where the two are tangent (a fillet and an arc; docs/brep.md, 1).
    std::uint64_t exact_tangencies = 0;
    std::uint64_t corners = 0;
    /// Of those, the corners put on the contact curve of two tangent surfaces (a fillet and
    /// its neighbour), where the other surfaces cross it.
    std::uint64_t tangent_corners = 0;
    double max_corner_residual = 0;  ///< largest distance of a solved corner from its surfaces
    double max_tolerance = 0;        ///< largest vertex or edge tolerance of the B-rep
    double chordal_deflection = 0;   ///< the mesh's, as segmentation estimated it
    std::optional<SolidDeviation> deviation;
    /// (solid volume - mesh volume) / mesh volume; 0 for a shell.
    double volume_difference = 0;
    bool written = false;  ///< the STEP file was written (not when the shape is invalid)
    std::uint64_t step_bytes = 0;
    std::vector<std::string> warnings;
};

/// Builds the B-rep of `mesh` with `options.method`, checks it (surfaces: BRepCheck_Analyzer;
/// planar: a structural check always, BRepCheck_Analyzer too up to 5000 faces) and, when valid,
/// writes it to `output` as STEP,
/// atomically (a temporary file beside it, then a rename). An invalid shape is not written:
/// `written` false, `valid` false. Fails with kCannotWrite when the file cannot be written, kEmpty
/// for a mesh without facets, kBadValue when OpenCASCADE cannot build or transfer the shape (its
/// reason in the message). An open mesh is not an error: it gives a shell, `solid` false and a
/// warning (surfaces and auto build it with the planar method). With `surfaces`, a region whose
/// face cannot be built leaves the result unwritten (`written` false, the region and the reason
/// in `warnings`).
Result<ReverseReport> reverse_to_step(const Mesh& mesh, const std::filesystem::path& output,
                                      const ReverseOptions& options = {});

}  // namespace ncrev
