// curvature: discrete curvature and local shape at every vertex of a mesh
// (../shared/docs/method.md, 3.1-3.4): the normal-cycle shape operator of Cohen-Steiner and
// Morvan ("Restricted Delaunay triangulations and normal cycle", 2003) with the per-edge weights
// of Anwer et al. (2010) as an option, principal curvatures and directions, Koenderink and van
// Doorn's shape index and curvedness ("Surface shape and curvature scales", 1992), the ten
// surface types and the high-curvature points.
//
// Sign convention: curvature is positive where the surface is convex, i.e. where it bends away
// from the outward facet normals (a ball has kappa1 = kappa2 = +1/r, a bore has kappa1 = 0,
// kappa2 = -1/r). The mesh built by build_mesh() has outward normals on closed components, so
// this is "convex as seen from outside the part". Curvatures are in 1/model unit.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ncrev/common.h"
#include "ncrev/mesh.h"

namespace ncrev {

/// How each edge of the neighbourhood is weighted in the shape operator.
enum class CurvatureEstimator {
    /// W = (1/A) sum_e beta(e) |e n B| e e^T: the normal cycle as Cohen-Steiner and Morvan
    /// define it.
    kPlain,
    /// The same with the per-edge weight of method.md 3.1, lambda_e proportional to the angle
    /// between the vertex normal and the edge normal, rescaled so the weights average 1.
    kWeighted,
};
/// "plain" or "weighted".
const char* to_string(CurvatureEstimator estimator);

/// The ten surface types of method.md 3.3, with the codes of the PLY output.
enum class ShapeType : std::uint8_t {
    kPlane = 0,
    kCup = 1,
    kTrough = 2,
    kRut = 3,
    kSaddleRut = 4,
    kSaddle = 5,
    kSaddleRidge = 6,
    kRidge = 7,
    kDome = 8,
    kCap = 9,
};
constexpr int kNumShapeTypes = 10;
/// "plane", "cup", "trough", "rut", "saddle_rut", "saddle", "saddle_ridge", "ridge", "dome",
/// "cap".
const char* to_string(ShapeType type);
/// An RGB color per type for viewers: planes grey, concave types blue to cyan, saddles green,
/// convex types yellow to red.
std::array<std::uint8_t, 3> shape_type_color(ShapeType type);

/// Shape index s = (2/pi) atan((k1 + k2) / (k1 - k2)) in [-1, 1] for k1 >= k2: +1 a convex
/// umbilic (cap), -1 a concave one (cup), +-1/2 a cylinder (ridge, rut), 0 a symmetric saddle.
double shape_index(double k1, double k2);
/// Curvedness c = sqrt((k1^2 + k2^2) / 2).
double curvedness(double k1, double k2);
/// The type of a point: kPlane when curvedness < planar_curvedness, otherwise Koenderink's
/// class of its shape index, bounded at +-1/8, +-3/8, +-5/8, +-7/8 (a shape index exactly on a
/// bound goes to the class nearer the saddle).
ShapeType classify_shape(double k1, double k2, double planar_curvedness);

/// Which cells make the neighbourhood B of a vertex p.
enum class Neighbourhood {
    /// The cells of the vertices within a radius R of p (reached from p through such
    /// vertices), each weighted by the smooth kernel (1 - d^2/R^2)^2 of its distance d (p's own
    /// cell weighs 1). R = min(kernel_edges x p's shortest incident edge, kernel_angle / the
    /// curvature of p's own cell): a few edges on a fine mesh, never more than a small arc of
    /// the surface on a coarse one. The smooth weights cancel most of the error that the ragged
    /// border of a union of cells makes on irregular meshes (docs/curvature.md).
    kKernel,
    /// The union of the cells of the vertices fewer than `rings` edges away from p (rings = 1:
    /// the cell of p, whose edges are those of its 1-ring; 2: also its neighbours' cells, the
    /// edges of its 2-ring), all of weight 1.
    kRings,
    /// The union of the cells of the vertices whose shortest path along edges from p is
    /// shorter than `radius`, all of weight 1.
    kGeodesic,
    /// `passes` rounds in which every vertex adds to its own tensor and area those of its
    /// neighbours, each tensor carried to its tangent plane and weighted by the kernel of
    /// kKernel: after n rounds, the cells within n rings under a bell-shaped kernel, about
    /// kKernel's accuracy at a fraction of its cost (docs/curvature.md). A neighbour takes part
    /// only when it is not on a sharp edge and it and its whole cell lie within p's kernel
    /// radius. Always transported (`transport` is ignored).
    kSmoothed,
};
/// "kernel", "rings", "geodesic".
const char* to_string(Neighbourhood neighbourhood);

/// Default kernel radius in shortest incident edges (docs/curvature.md: 3 meets the accuracy
/// targets on irregular isotropic meshes; 2.5 does not).
constexpr double kDefaultKernelEdges = 3.0;
/// Default cap of the kernel radius as a fraction of the curvature radius (0.15: a kernel
/// reaches at most about 9 degrees of arc, so the curvature's own variation, e.g. along a cone,
/// does not bias the estimate; on coarse CAD meshes this leaves the 1-ring, which measures
/// best there; docs/curvature.md).
constexpr double kDefaultKernelAngle = 0.15;

/// Options of compute_curvature(). The defaults need no tuning.
struct CurvatureOptions {
    CurvatureEstimator estimator = CurvatureEstimator::kPlain;
    Neighbourhood neighbourhood = Neighbourhood::kSmoothed;
    /// kRings: the number of rings, >= 1.
    int rings = 1;
    /// kGeodesic: the radius in model units, > 0.
    double radius = 0;
    /// kSmoothed: the number of rounds, >= 1 (3: docs/curvature.md).
    int passes = 3;
    /// kKernel and kSmoothed: see Neighbourhood::kKernel; <= 0 selects the default.
    double kernel_edges = kDefaultKernelEdges;
    double kernel_angle = kDefaultKernelAngle;
    /// Turn each neighbour's tensor by the rotation that takes its normal to p's before
    /// summing, so that the bending of the neighbourhood itself does not leak into the
    /// estimate (the tilt between normals otherwise shrinks the tangential eigenvalues).
    bool transport = true;
    /// Curvedness below which a point is planar (1/model unit). Negative: derived from the
    /// model size and the coordinate precision (see CurvatureThresholds).
    double planar_curvedness = -1;
    /// Dihedral angle (rad) from which an edge is sharp: its vertices are high-curvature
    /// points, and the cells of other vertices on sharp edges are left out of a neighbourhood
    /// so that it does not reach across into the next face. Negative: kDefaultSharpEdgeAngle.
    double sharp_edge_angle = -1;
};

/// Default sharp-edge angle: 0.6 rad (34 degrees). Above the angle between neighbouring facets
/// of any smooth surface meshed the usual ways (BRepMesh's default angular deflection is
/// 0.5 rad, ncrev's samples use 0.35 rad), below the 45 degrees of a chamfer.
constexpr double kDefaultSharpEdgeAngle = 0.6;

/// The thresholds compute_curvature() used, and how they were chosen.
struct CurvatureThresholds {
    double planar_curvedness = 0;  ///< 1/model unit
    std::string planar_rule;
    double sharp_edge_angle = 0;  ///< rad
    /// A vertex is high when an incident edge is sharp, or when its curvedness exceeds
    /// sharp_edge_angle / (mean length of its incident edges): the surface turns by more than a
    /// sharp edge within one edge length.
    std::string high_rule;
    double median_edge_length = 0;    ///< model units
    double coordinate_precision = 0;  ///< rounding unit of the coordinates, model units
    std::string neighbourhood;        ///< e.g. "2-ring" or "geodesic radius 0.5"
    CurvatureEstimator estimator = CurvatureEstimator::kPlain;
};

/// Per-vertex results, indexed by VertexId.
struct CurvatureField {
    VertexMap<double> k1, k2;       ///< principal curvatures, k1 >= k2 (1/model unit)
    VertexMap<Vec3> dir1, dir2;     ///< unit principal directions of k1 and k2 (tangent)
    VertexMap<Vec3> normal;         ///< unit vertex normal (angle-weighted)
    VertexMap<double> shape_index;  ///< in [-1, 1]; 2 for planar points
    VertexMap<double> curvedness;   ///< 1/model unit
    VertexMap<ShapeType> type;
    VertexMap<std::uint8_t> high;  ///< 1 for a high-curvature point
};

struct CurvatureResult {
    CurvatureField field;
    CurvatureThresholds thresholds;
    std::array<std::uint64_t, kNumShapeTypes> count_by_type{};  ///< vertices per type
    std::uint64_t high_points = 0;
};

/// Curvature, shape index, curvedness, type and high flag of every vertex of `mesh`
/// (method.md 3.1-3.4). W(B) is projected onto the tangent plane at p (normal: the
/// angle-weighted vertex normal); its two eigenvalues are the principal curvatures, and for
/// this estimator the eigenvector of each eigenvalue points along the direction of the *other*
/// principal curvature. Boundary edges contribute nothing. Vertices without any facet area get
/// zero curvature and the planar type. Parallel (oneTBB) and deterministic: the same mesh gives
/// the same bits whatever the thread count. Never fails: options out of range are clamped
/// (rings to >= 1).
CurvatureResult compute_curvature(const Mesh& mesh, const CurvatureOptions& options = {});

/// The PLY of `ncrev curvature`: binary little-endian; vertex properties x y z k1 k2
/// shape_index curvedness (float), type high red green blue (uchar; the color of the type, see
/// shape_type_color()); the faces as vertex_indices. Vertices and faces in the mesh's order.
std::vector<std::byte> encode_curvature_ply(const Mesh& mesh, const CurvatureResult& result);

}  // namespace ncrev
