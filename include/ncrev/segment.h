// segment: the mesh split into regions, one surface each (../shared/docs/method.md, Step 3).
//
// Two methods:
// - facets (the default, it measures better, docs/segmentation.md): sharp edges (dihedral
//   angle) split the mesh into smooth patches; each patch is grown region by region from its
//   flattest, most interior facets, a region taking a neighbouring facet while the facets are
//   chords of one analytic surface: corners within the tolerance, middles within the mesh's
//   chordal deflection, normals agreeing (so a fillet stops where the plane it is tangent to
//   begins: the type changes, the fit fails); adjacent regions that one surface fits are
//   merged, most alike first; groups of small curved pieces that one B-spline fits become one
//   free-form region; border facets go to the neighbouring region they fit best. A noisy mesh
//   is segmented again at a tolerance raised to its measured noise.
// - paper: the paper's vertex method: vertex types from `curvature`, high-curvature points set
//   aside, refining over one-rings, connected components, merging region pairs through a
//   priority queue while one surface fits the union, then the set-aside points and the facets.
//
// With SRE input the given surface indices are used where present (one region per surface
// index, its surface the given one); only the facets with index -1 are segmented.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ncrev/common.h"
#include "ncrev/curvature.h"
#include "ncrev/fit.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"

namespace ncrev {

enum class SegmentMethod { kFacets, kPaper };
/// "facets", "paper".
const char* to_string(SegmentMethod method);

/// Default tolerance as a fraction of the part's size (part_size()): 0.01 mm on a 100 mm
/// part, a tenth of a general machining tolerance. The vertices of a CAD tessellation lie on the
/// surface they sample to float rounding (`ncrev segment PART.sre --json`: every given
/// surface's max residual is 0); vertices further than this from a region's surface belong to
/// another surface. A noisy mesh raises it (segment()).
constexpr double kSegmentRelativeTolerance = 1e-4;
/// Default sharp-edge angle (rad, 30 degrees): above the normal step inside curved faces of
/// usual tessellations (20 degrees and less), below a 45-degree chamfer or countersink. It only
/// cuts the mesh into patches to grow in: fitting decides, so a missed sharp edge is still a
/// border and a false one is merged over.
constexpr double kDefaultSegmentSharpAngle = 0.5235987755982988;
/// Largest angle (rad, 15 degrees) between a facet's normal and its region surface's normal at
/// the facet: chords of a curved face differ from it by about a sixth of the normal step
/// between neighbouring facets (7.5 degrees for 45-degree steps), while a surface fitted through
/// the corners of two faces that meet at a crease (a slot's walls and floor lie on one
/// cylinder) misses their normals by far more.
constexpr double kSegmentNormalAngle = 0.2617993877991494;

/// Options of segment(). The defaults need no tuning.
struct SegmentOptions {
    SegmentMethod method = SegmentMethod::kFacets;
    /// Max distance of a region's vertices to its surface, model units; <= 0: derived (see
    /// SegmentResult::tolerance_rule).
    double tolerance = 0;
    /// Dihedral angle (rad) from which an edge is sharp; <= 0: kDefaultSegmentSharpAngle.
    double sharp_angle = 0;
    /// The SRE surfaces table (HealedMesh::surfaces): with it, faces whose surface index names
    /// a surface keep that surface as their region (when `use_surface_indices`).
    std::span<const SurfaceRecord> surfaces;
    bool use_surface_indices = true;
    /// Curvature for the paper method (its vertex types and high-curvature points).
    CurvatureOptions curvature;
    /// The SRE tools table (HealedMesh::tools): the radii snapping tries before round values,
    /// each tool's diameter / 2 and corner radius.
    std::span<const ToolRecord> tools;
    /// The final surfaces with machined-part values (method.md Step 4): parallel and coaxial
    /// axes, axes along coordinate axes, round positions, radii and cone angles, each only
    /// where the points cannot tell it from the fitted value (SegmentResult::snapped).
    bool snap = true;
};

/// One region: the facets that one surface describes.
struct Region {
    std::int32_t id = 0;  ///< the label of its facets
    /// Its surface and the residuals of its vertices (points of the facets, weighted by area).
    /// `fit.ok` is false only when no surface fits the region at all (paper method).
    FitResult fit;
    /// Every vertex within the tolerance of the surface.
    bool within_tolerance = false;
    /// The SRE surface index it came from; -1 when segmented.
    std::int32_t surface_index = -1;
    std::uint64_t facets = 0;
    double area = 0;
};

struct SegmentResult {
    SegmentMethod method = SegmentMethod::kFacets;
    double tolerance = 0;
    std::string tolerance_rule;
    double sharp_angle = 0;
    /// The mesh's chordal deflection as estimated from its curved edges: a facet belongs to a
    /// surface only if its middle is within this of it.
    double chordal_deflection = 0;
    /// The region of every face (ids index `regions`).
    FaceMap<std::int32_t> region;
    /// Regions in the order of their first face.
    std::vector<Region> regions;
    std::uint64_t given_facets = 0;       ///< facets whose region came from an SRE surface index
    std::uint64_t patches = 0;            ///< smooth patches (facets) or initial regions (paper)
    std::uint64_t merges = 0;             ///< region pairs merged
    std::uint64_t freeform_groups = 0;    ///< groups of pieces replaced by one B-spline
    std::uint64_t reassigned_facets = 0;  ///< border facets moved to a better-fitting region
    std::uint64_t snapped = 0;            ///< regions whose surface was snapped (options.snap)
    double curvature_seconds = 0, segment_seconds = 0, fit_seconds = 0;
    /// Wall-clock seconds of each step, in order: "edges" (dihedral angles, sharp edges, the
    /// deflection estimate), "grow" (the facets method's regions; "curvature" for the paper's),
    /// "merge", "freeform", "refine" (corner surfaces, small regions, borders, fragments; the
    /// facets method) and "fit". When the noise rule segmented again, these are the last pass's,
    /// after an "earlier passes" entry for the ones before.
    std::vector<std::pair<std::string, double>> step_seconds;
};

/// Segments `mesh`. Never throws; deterministic whatever the thread count. Fails (kBadValue)
/// only for a non-finite tolerance or angle.
Result<SegmentResult> segment(const Mesh& mesh, const SegmentOptions& options = {},
                              const ProgressFn& progress = {});

/// The default tolerance of segment() for `mesh`, and its rule in words.
double default_segment_tolerance(const Mesh& mesh, std::string* rule = nullptr);

/// The analytic surface an SRE record states (directions normalised, lengths as given).
Surface surface_from_record(const SurfaceRecord& record);

/// One label per input facet, in input order: the region of the face it became, -1 for a facet
/// that healing removed. `input_facets` is the number of facets the file had.
std::vector<std::int32_t> input_labels(const Mesh& mesh, const SegmentResult& result,
                                       std::size_t input_facets);

/// A binary PLY of the mesh whose faces carry `region` (int) and `red green blue` (uchar), one
/// color per region.
std::vector<std::byte> encode_segments_ply(const Mesh& mesh, const SegmentResult& result);

/// A border between two regions (or a region and the mesh boundary): a chain of mesh edges
/// from corner to corner, or a closed loop with no corner on it.
struct BorderChain {
    /// The regions on either side, left > right: `left` lies to the left walking along
    /// `vertices` seen from outside; `right` is -1 for the mesh boundary.
    std::int32_t left = -1, right = -1;
    /// The chain's vertices in order; a closed loop repeats its first vertex at the end.
    std::vector<VertexId> vertices;
    bool closed = false;
};

/// The borders of a labelling: every mesh edge between two regions (or on the boundary) lies
/// on exactly one chain; chains end at corners — vertices where three or more regions meet,
/// counting the mesh boundary as one — and a chain between the same two regions that meets no
/// corner is a closed loop (a hole's rim). What method.md Step 2b calls border chains and
/// corners: the edges and vertices of the B-rep to come.
struct RegionBorders {
    std::vector<BorderChain> chains;
    std::vector<VertexId> corners;  ///< ascending
};

/// The borders of `face_region` (one region id >= 0 per face, e.g. SegmentResult::region).
/// Deterministic: chains start at the lowest corner, or the lowest vertex of a loop.
RegionBorders region_borders(const Mesh& mesh, const FaceMap<std::int32_t>& face_region);

}  // namespace ncrev
