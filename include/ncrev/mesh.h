// mesh: the half-edge triangle mesh, built once from a facet soup with healing
// (../shared/docs/method.md, Step 1).
//
// Storage (manifold's trick): half-edge h belongs to face h/3, next/prev are arithmetic, and
// only `origin` and `twin` are stored per half-edge; one outgoing half-edge per vertex (the
// boundary one for a boundary vertex). Every half-edge has at most one twin: non-manifold
// edges and vertices are split while building. Healing works on the soup before the mesh is
// built, so the mesh has no deleted elements.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ncrev/common.h"
#include "ncrev/io.h"

namespace ncrev {

/// A column of values indexed by a strong id.
template <class IdT, class T>
class IdMap {
   public:
    IdMap() = default;
    explicit IdMap(std::size_t n, const T& value = T{}) : v_(n, value) {}
    T& operator[](IdT id) { return v_[id.idx()]; }
    const T& operator[](IdT id) const { return v_[id.idx()]; }
    std::size_t size() const { return v_.size(); }
    std::vector<T>& data() { return v_; }
    const std::vector<T>& data() const { return v_; }

   private:
    std::vector<T> v_;
};
template <class T>
using VertexMap = IdMap<VertexId, T>;
template <class T>
using FaceMap = IdMap<FaceId, T>;
template <class T>
using HalfedgeMap = IdMap<HalfedgeId, T>;

struct Components;

/// A triangle mesh with half-edge connectivity. Built by build_mesh(); immutable afterwards.
class Mesh {
   public:
    std::size_t num_vertices() const { return position_.size(); }
    std::size_t num_faces() const { return origin_.size() / 3; }
    std::size_t num_halfedges() const { return origin_.size(); }

    Vec3 position(VertexId v) const { return position_[v.idx()]; }
    std::span<const Vec3> positions() const { return position_; }

    static FaceId face(HalfedgeId h) { return FaceId(h.idx() / 3); }
    static HalfedgeId halfedge(FaceId f, int i) { return HalfedgeId(3 * f.idx() + i); }
    static HalfedgeId next(HalfedgeId h) {
        return HalfedgeId(h.idx() % 3 == 2 ? h.idx() - 2 : h.idx() + 1);
    }
    static HalfedgeId prev(HalfedgeId h) {
        return HalfedgeId(h.idx() % 3 == 0 ? h.idx() + 2 : h.idx() - 1);
    }
    VertexId origin(HalfedgeId h) const { return VertexId(origin_[h.idx()]); }
    VertexId target(HalfedgeId h) const { return origin(next(h)); }
    /// The opposite half-edge, invalid on a boundary.
    HalfedgeId twin(HalfedgeId h) const { return HalfedgeId(twin_[h.idx()]); }
    bool is_boundary(HalfedgeId h) const { return twin_[h.idx()] == HalfedgeId::kInvalid; }
    /// An outgoing half-edge of v; for a boundary vertex the one whose twin is missing.
    HalfedgeId outgoing(VertexId v) const { return HalfedgeId(outgoing_[v.idx()]); }
    VertexId vertex(FaceId f, int i) const { return origin(halfedge(f, i)); }

    /// Calls f(h) for every outgoing half-edge of v, around its whole fan (open or closed).
    template <class F>
    void for_each_outgoing(VertexId v, F&& f) const {
        const HalfedgeId h0 = outgoing(v);
        if (!h0.is_valid()) return;
        HalfedgeId h = h0;
        do {
            f(h);
            const HalfedgeId t = twin(prev(h));
            if (!t.is_valid()) return;
            h = t;
        } while (h != h0);
    }
    /// Calls f(w) for every neighbour w of v, once each (also the far end of an open fan).
    template <class F>
    void for_each_neighbour(VertexId v, F&& f) const {
        const HalfedgeId h0 = outgoing(v);
        if (!h0.is_valid()) return;
        HalfedgeId h = h0;
        do {
            f(target(h));
            const HalfedgeId t = twin(prev(h));
            if (!t.is_valid()) {
                f(origin(prev(h)));
                return;
            }
            h = t;
        } while (h != h0);
    }

    /// Index of the input facet this face came from (for labels in input order).
    std::uint32_t source_face(FaceId f) const { return source_face_[f.idx()]; }
    std::span<const std::uint32_t> source_faces() const { return source_face_; }
    /// Per-face attributes carried from SRE; empty spans for STL.
    std::span<const std::int64_t> colors() const { return color_; }
    std::span<const std::int64_t> cuts() const { return cut_; }
    std::span<const std::int32_t> surfaces() const { return surface_; }
    bool has_attributes() const { return !surface_.empty(); }

    /// Unnormalised normal (cross product of two edges): length = twice the area.
    Vec3 face_normal_area2(FaceId f) const;
    double face_area(FaceId f) const { return 0.5 * norm(face_normal_area2(f)); }
    Vec3 face_normal(FaceId f) const { return normalized(face_normal_area2(f)); }

    /// Raw columns (for algorithms that loop over everything).
    std::span<const std::uint32_t> origins() const { return origin_; }
    std::span<const std::uint32_t> twins() const { return twin_; }

    /// Checks every invariant (twin symmetry and direction, face/vertex ids in range, the
    /// outgoing half-edge starts at its vertex and is the boundary one on a boundary, one fan
    /// per vertex). Returns an empty string when valid, else what is broken. O(n); for tests.
    std::string validate() const;

   private:
    friend class MeshBuilder;
    friend Mesh keep_components(const Mesh& mesh, const Components& components,
                                std::span<const std::uint8_t> keep);
    std::vector<Vec3> position_;
    std::vector<std::uint32_t> origin_;
    std::vector<std::uint32_t> twin_;
    std::vector<std::uint32_t> outgoing_;
    std::vector<std::uint32_t> source_face_;
    std::vector<std::int64_t> color_;
    std::vector<std::int64_t> cut_;
    std::vector<std::int32_t> surface_;
};

/// Options of build_mesh(). The defaults need no tuning.
struct HealOptions {
    /// Tolerance weld distance in model units. Negative: derived from the model (see
    /// HealReport::tolerance_rule). Zero: exact weld only.
    double weld_tolerance = -1.0;
    /// Orient facets consistently, turn closed components outward and cavities' shells inward.
    bool orient = true;
    /// Close small holes: a boundary loop of a few edges, short beside its part (missing facets,
    /// a crack along a T-junction), gets facets of its own (docs/healing.md). Deliberate
    /// openings, a sheet's border, a loose facet are left open.
    bool fill_holes = true;
};

/// What healing found and did, in numbers. Counts refer to the input facets / points.
struct HealReport {
    double tolerance = 0;        ///< the tolerance weld distance used (model units)
    std::string tolerance_rule;  ///< how it was chosen, in words
    std::uint64_t input_facets = 0;
    std::uint64_t input_points = 0;
    std::uint64_t exact_welded_points = 0;  ///< points merged with an identical point
    std::uint64_t welded_vertices = 0;      ///< distinct vertices merged by the tolerance weld
    std::uint64_t unreferenced_vertices = 0;
    std::uint64_t degenerate_facets_removed = 0;  ///< repeated vertex or zero area
    /// Zero-area facets stitched into the surface, removed by splitting the facet beyond their
    /// long edge (so no hole opens); counted in degenerate_facets_removed too.
    std::uint64_t caps_split = 0;
    std::uint64_t duplicate_facets_removed = 0;   ///< same three vertices as an earlier facet
    std::uint64_t flipped_facets = 0;             ///< minority side within each component
    std::uint64_t components_turned_outward = 0;  ///< closed components that were inside out
    /// Closed components inside another an odd number of times: a cavity's shell, oriented
    /// to face into the cavity (away from the material around it).
    std::uint64_t cavities = 0;
    std::uint64_t cavities_turned_inward = 0;  ///< of those, the ones that faced outward
    /// Too many components to check which lies inside which (detail::kNestingWork): every
    /// closed component was turned outward, a cavity's shell too.
    bool nesting_unchecked = false;
    /// Closed components whose surfaces cross another's: meshes of parts that overlap without
    /// their union (healing joins none). Each stays a whole closed component, and the volume
    /// counts their overlap twice.
    std::uint64_t crossing_components = 0;
    /// Too many components whose boxes meet, too large, to check which cross
    /// (detail::kCrossingWork): none is counted.
    bool crossing_unchecked = false;
    /// Facet pairs of one component that cross each other: the mesh passes through itself (a
    /// vertex pushed through a wall, a surface folded over its neighbour), and so does any
    /// solid built from it. Healing mends none; OpenCASCADE's check does not see them.
    std::uint64_t self_intersections = 0;
    /// Where the pair of least facet indices crosses (when self_intersections > 0).
    Vec3 self_intersection_at{};
    /// Too many facets over one another to check (detail::kSelfIntersectionWork): none is
    /// counted.
    bool self_intersection_unchecked = false;
    std::uint64_t nonmanifold_edges = 0;     ///< edges with more than two facets (then split)
    std::uint64_t nonmanifold_vertices = 0;  ///< vertices with more than one fan (then split)
    std::uint64_t orientation_conflicts =
        0;  ///< edges cut to make a non-orientable part orientable
    /// Facets split at the vertices lying in the middle of their open edges (T-junctions: the
    /// crack between faces tessellated apart), closing the crack (fill_holes).
    std::uint64_t facets_split_at_t_junctions = 0;
    std::uint64_t holes_filled = 0;       ///< small holes closed with new facets (fill_holes)
    std::uint64_t hole_facets_added = 0;  ///< facets added to close them
};

/// Numbers that describe a built mesh.
struct MeshStats {
    std::uint64_t vertices = 0, faces = 0, edges = 0, components = 0;
    std::uint64_t boundary_loops = 0, boundary_edges = 0;
    std::int64_t euler_characteristic = 0;
    bool closed = false;  ///< no boundary edge and at least one face
    double area = 0;
    double volume = 0;  ///< signed; meaningful when closed
    Box3 bbox;
    std::vector<std::uint32_t> boundary_loop_sizes;  ///< edges per loop, largest first
};

/// Progress: stage name and fraction done in [0, 1]. Called from the calling thread only.
using ProgressFn = std::function<void(std::string_view stage, double fraction)>;

struct BuildResult {
    Mesh mesh;
    HealReport heal;
};

/// Builds the half-edge mesh from a soup, healing as ../shared/docs/method.md Step 1 says:
/// exact weld, tolerance weld, degenerate and duplicate facets dropped, non-manifold edges
/// and vertices split, facets oriented consistently per component (the minority flipped),
/// closed components turned outward (positive volume) and those inside another an odd number
/// of times (a cavity's shell) inward, so that the signed volume is the material's. Deterministic:
/// the same soup gives the same mesh whatever the thread count. Fails only when the soup cannot be
/// addressed with 32-bit ids or a triangle names a point that does not exist.
Result<BuildResult> build_mesh(const TriangleSoup& soup, const HealOptions& options = {},
                               const ProgressFn& progress = {});

/// The same, consuming the soup: its points and triangles are reused or freed as soon as they
/// are no longer needed, which lowers the peak memory by about 80 bytes per facet.
Result<BuildResult> build_mesh(TriangleSoup&& soup, const HealOptions& options = {},
                               const ProgressFn& progress = {});

/// Counts, area, volume, bounding box, boundary loops of a mesh.
MeshStats compute_stats(const Mesh& mesh);

/// A mesh's components: facets joined across shared edges.
struct Components {
    /// Per facet, its component, numbered from 0 in the order of their first facet.
    std::vector<std::uint32_t> of_face;
    /// Per component: closed (none of its edges on a boundary).
    std::vector<std::uint8_t> closed;
    std::size_t count() const { return closed.size(); }  ///< MeshStats::components
};
Components face_components(const Mesh& mesh);

/// The boundary loops of a mesh, each its boundary half-edges in order: from one, the next
/// starts at its target and is that vertex's outgoing half-edge (the one without twin).
std::vector<std::vector<HalfedgeId>> boundary_loops(const Mesh& mesh);

/// The faces of `mesh` whose component (`components` of it) is kept (`keep[component]`
/// nonzero), as a mesh of its own. Whole components, so every half-edge keeps its twin and every
/// vertex its fan. Vertices and faces keep their order; each face its source face
/// (input_labels() still names the input facets) and its SRE attributes.
Mesh keep_components(const Mesh& mesh, const Components& components,
                     std::span<const std::uint8_t> keep);

/// How the closed components of a mesh lie in one another: a cavity's shell inside its part,
/// an island in the cavity inside both.
struct ComponentNesting {
    static constexpr std::uint32_t kNone = 0xffffffffu;
    Components components;              ///< face_components()
    std::vector<std::uint32_t> parent;  ///< per component: the closed one right around it, or kNone
    /// Per component: how many closed components lie around it; odd: a cavity's shell.
    std::vector<std::uint32_t> depth;
    /// False when there were too many components to check (thousands of loose pieces in one
    /// box): then none counts as nested.
    bool complete = true;
    /// Pairs (a < b) of closed components whose surfaces cross (an edge of one passes through
    /// a facet of the other, beyond rounding), sorted: parts overlapping without their union.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> crossing;
    /// False when too many facets lay near one another to check: then no pair is listed.
    bool crossing_complete = true;
};

/// Which closed component lies inside which, by the parity of ray crossings from its extreme
/// vertices (three rays each, the majority; all six inside), tested only where one's box lies
/// in the other's; and which cross each other (never nested). Open components are neither
/// inside nor around anything, nor cross anything.
ComponentNesting component_nesting(const Mesh& mesh);

/// Signed dihedral angle at the edge of `h`, in radians, in [-pi, pi]: the angle between the
/// normals of its two facets, positive where the surface is convex (it bends away from the
/// outward normals), negative where concave, 0 on a boundary edge or between coplanar facets.
/// The normal-cycle curvature estimator (method.md 3.1) weighs edges by it.
double dihedral_angle(const Mesh& mesh, HalfedgeId h);

/// Mixed Voronoi area of every vertex (Meyer, Desbrun, Schröder, Barr 2003): each triangle
/// gives its vertices their Voronoi share when it has no obtuse angle; otherwise half its area
/// to the obtuse vertex and a quarter to each other. The areas sum to the mesh area, and stay
/// positive on the long thin triangles of CAD tessellations.
VertexMap<double> mixed_voronoi_areas(const Mesh& mesh);

/// Unit vertex normals, each facet weighted by its angle at the vertex (independent of how
/// the surface around the vertex is split into triangles).
VertexMap<Vec3> vertex_normals(const Mesh& mesh);

/// The part's size, the same in every pose: the diagonal of the smallest box round it with an
/// axis along one of the three directions its 1024 largest facets face most (either sense;
/// normals within 1e-5 rad are one direction) and another along an edge of its outline seen
/// that way (convex hull, rotating calipers). Its bounding box's diagonal is not the same: turned
/// out of its axes, a part's box is up to sqrt(3) times as long across (NIST FTC 08's AP242 mesh
/// turned by 0.7 rad about (1, 2, 3): 1.38 times), and tolerances that followed it segmented the
/// same part differently. A block or a plate in its axes has its bounding-box diagonal for its
/// size, a turned part about that (its outline's polygon is measured along a side). A mesh without
/// area gives its bounding-box diagonal. Same in every pose to about 1e-9 of it, where the
/// directions are the same: facets of equal area (a surface of revolution's) that the cut at
/// 1024 or at three directions parts may be parted otherwise in another pose by rounding (a
/// round part's directions all give one box; a part's large planar faces are not parted).
double part_size(const Mesh& mesh);

/// The rounding unit of the mesh's coordinates: the largest |coordinate| times float32's
/// epsilon (2^-24) when every coordinate is a float (a binary STL, or text written from floats),
/// else double's (2^-53). The same whatever the thread count.
double coordinate_rounding(const Mesh& mesh);

/// The default weld tolerance for points whose bounding box is `box`, and its rule in words.
double default_weld_tolerance(const Box3& box, std::string* rule = nullptr);

/// Facet pairs of one component of a mesh that cross each other (find_self_intersections()).
struct SelfIntersectionReport {
    std::uint64_t pairs = 0;
    Vec3 at{};  ///< where the pair of least facet indices crosses (pairs > 0)
    /// False past the work bound (detail::kSelfIntersectionWork, a pile of facets over one
    /// another): then no pair is counted.
    bool complete = true;
};

/// Where `mesh` passes through itself: the facet pairs of one component that cross (a vertex
/// pushed through a wall, a surface folded over its neighbour; docs/healing.md step 9), which
/// any solid built from it crosses too. What build_mesh() reports as
/// HealReport::self_intersections, with `tolerance` the distance within which points touch
/// (HealReport::tolerance; at least 1e-6 of the mesh's size whatever is given). `oriented`: the
/// facets across each edge are turned alike (build_mesh() with HealOptions::orient, the
/// default), so a pierce through the border between two facets can be told from a graze.
SelfIntersectionReport find_self_intersections(const Mesh& mesh, double tolerance,
                                               bool oriented = true);

}  // namespace ncrev
