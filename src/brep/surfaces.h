// The exact B-rep from regions and their surfaces (../shared/docs/method.md, Step 2b). Internal.
#pragma once

#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ncrev/fit.h"
#include "ncrev/mesh.h"

namespace ncrev::brep_detail {

/// A unit vector perpendicular to the unit `a`.
inline Vec3 any_perpendicular(Vec3 a) {
    const Vec3 t = std::abs(a.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    return normalized(cross(a, t));
}

/// One region of the labelling: its surface, or none (`has_surface` false: the region can only
/// be built from its facets).
struct RegionSurface {
    Surface surface;
    bool has_surface = false;
    std::string no_surface_reason;  ///< why not, when `has_surface` is false
};

struct SurfaceBrepOptions {
    /// Largest distance of the mesh vertices from their region's surface (the segmentation
    /// tolerance), model units: corners and edges are accepted on their surfaces within it.
    double tolerance = 0;
    /// The mesh's chordal deflection: the largest tolerance an edge or vertex may be given (an
    /// edge fitted to a chain, a polyline edge beside a fallback region).
    double chordal_deflection = 0;
    /// A region whose face cannot be built comes back as its facets (true), or the build fails.
    bool allow_fallback = true;
    /// When positive, each face is also triangulated with BRepMesh at this deflection and
    /// fails when it cannot be (it passes BRepCheck, but no viewer or FE mesher could use it).
    double mesh_deflection = 0;
    /// Per region (may be empty): built from its facets from the start where not empty, with
    /// this as the reason (its face came back wrong from a STEP file written before, or
    /// BRepMesh could not triangulate it).
    std::vector<std::string> facets_only;
    /// Per region (may be empty): its corners are solved without moving them onto the contact
    /// curve of two tangent surfaces (after its face failed with them).
    std::vector<std::uint8_t> plain_corners;
    /// Per region (may be empty): a fallback region comes back as its facets, not as one face
    /// on its surface bounded by its mesh edges (that face failed in a STEP written before).
    std::vector<std::uint8_t> as_facets;
    /// A round after the first keeps the corners, edge curves and face checks of the round
    /// before whose inputs did not change (only those around the regions that failed do);
    /// false solves everything again each round (the same result, slower: for tests).
    bool reuse_geometry = true;
};

/// What happened to one region.
struct RegionBuild {
    /// Its face with exact edges could not be built: it is one face on its surface bounded by
    /// the mesh edges of its border (`mesh_edges`), or its facets.
    bool fallback = false;
    bool mesh_edges = false;
    /// That face is on a B-spline fitted to points of the region's facets: on its own surface
    /// it failed (a torus cap over the tip, a strip whose polyline wires take no seam).
    bool spline = false;
    std::string reason;              ///< why, when `fallback`
    std::vector<TopoDS_Face> faces;  ///< the faces it became (one, or its facets)
    std::size_t facets = 0;          ///< mesh facets in the region
    /// The region whose face took its facets (a sliver whose own face failed and whose facets
    /// are chords of that neighbour's surface); -1 when not absorbed.
    std::int32_t absorbed_into = -1;
    /// A corner of its face was put on the contact curve of two tangent surfaces.
    bool contact_corners = false;
};

struct SurfaceBrep {
    TopoDS_Shape shape;  ///< a solid when `solid`, else the shell
    bool solid = false;
    bool valid = false;   ///< BRepCheck_Analyzer found no defect
    std::string problem;  ///< what is wrong when not valid
    std::vector<RegionBuild> regions;
    /// Edges by how their curve was made: "intersection" (OpenCASCADE's surface intersection,
    /// analytic for elementary pairs), "tangency" (a tangent junction with a tube: a curve
    /// through the exact contact points), "fitted" (a curve through the chain's points solved
    /// onto both surfaces: other tangent junctions, failed intersections), "polyline" (beside a
    /// fallback).
    std::uint64_t intersection_edges = 0, tangency_edges = 0, fitted_edges = 0, polyline_edges = 0;
    /// Of the intersection and tangency edges, those whose curve is exact: a line, circle or
    /// ellipse where two elementary surfaces meet (IntAna), a B-spline extrusion's profile
    /// moved onto a plane, a line or circle through a fillet's contact points.
    std::uint64_t analytic_edges = 0;
    std::uint64_t corners = 0;
    /// Of those, the corners put on the contact curve of two tangent surfaces.
    std::uint64_t tangent_corners = 0;
    double max_corner_residual = 0;  ///< largest distance of a solved corner from its surfaces
    double max_tolerance = 0;        ///< largest vertex / edge / face tolerance of the result
    int rounds = 0;                  ///< build rounds (each one after new fallbacks)
    /// Work over all rounds: corners solved onto their surfaces, edge curves made (each an
    /// intersection or a fit between two surfaces), faces checked.
    std::uint64_t corners_solved = 0, curves_made = 0, faces_checked = 0;
};

/// Builds the B-rep of the closed, outward-oriented `mesh` whose face f belongs to region
/// `region[f]` (0 <= region[f] < regions.size()). Never throws.
SurfaceBrep build_surface_brep(const Mesh& mesh, const FaceMap<std::int32_t>& region,
                               std::span<const RegionSurface> regions,
                               const SurfaceBrepOptions& options);

/// Tangent cylinders made exact (docs/brep.md, 1): of two adjacent regions that are cylinders
/// with parallel axes and overlap within what their fits leave open (their vertices' distances
/// from them plus four coordinate rounding units, at most `tolerance`), the smaller is moved
/// across its axis (its radius by a ten-thousandth as much, more only where no such move holds
/// all its contacts) so that the two are a hair apart (1e-9: a hundredth of OpenCASCADE's smallest
/// tolerance): a third face cutting both then has edges that do not cross beside their corner.
/// Larger ones first; a move is kept only while the region's vertices stay within `tolerance` of
/// its surface (or as near as before). Returns the regions moved.
std::size_t exact_tangencies(const Mesh& mesh, const FaceMap<std::int32_t>& region,
                             std::vector<RegionSurface>& regions, double tolerance);

/// How far a solid's volume may be from its mesh's, in units of the volume the mesh's own
/// error spans: the area of its facets on curved surfaces times its chordal deflection (their
/// vertices lie on the part's surface and the facets within the deflection of it), plus its
/// whole area times the tolerance (every face lies within it of its facets' vertices: a plane
/// fitted to them too). Twice that, since the deflection is an estimate and BRepMesh's fans on
/// a coarse fillet sag up to 3.5 times it (docs/segmentation.md, step 6) — over their own area,
/// a share of the curved area.
constexpr double kVolumeSlack = 2;

/// Whether a solid of `solid_volume` can be the part a closed mesh of `mesh_volume` came from
/// (kVolumeSlack), the mesh having `area` in all, `curved_area` of it on curved surfaces, with
/// that chordal deflection and segmentation tolerance. A valid solid can fail this: a face
/// built over the wrong piece of its surface.
bool volume_is_the_parts(double solid_volume, double mesh_volume, double area, double curved_area,
                         double chordal_deflection, double tolerance);

/// The region of `brep` built with its exact faces (not a fallback, not absorbed, and with
/// `facets_only[r]` empty) whose faces lie farthest from `mesh` (faces_from_mesh() at
/// `deflection`): where a solid of the wrong volume was built wrong — its neighbours, trimmed
/// by the wrong face, still lie on the mesh. -1 when there is none.
std::int32_t farthest_region(const Mesh& mesh, const SurfaceBrep& brep,
                             const std::vector<std::string>& facets_only, double deflection);

}  // namespace ncrev::brep_detail
