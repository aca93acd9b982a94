// fit: analytic surfaces fitted to points (../shared/docs/method.md, Step 4): plane, sphere,
// cylinder, cone and torus, each from a robust start (a normal-based or algebraic solution)
// refined by geometric least squares (Levenberg-Marquardt on the true point-to-surface
// distances); the simplest kind within a tolerance; distance and closest point for each kind.
//
// Lengths are in the points' unit; angles in radians. Directions are unit vectors.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ncrev/common.h"

namespace ncrev {

/// The kinds of surface fit() knows, simplest first (the order kind selection tries); the
/// B-spline is the free-form last resort.
enum class FitKind : std::uint8_t {
    kPlane,
    kSphere,
    kCylinder,
    kCone,
    kTorus,
    kShearCylinder,
    kSweptTorus,
    kBSpline
};
constexpr int kNumFitKinds = 8;
/// "plane", "sphere", "cylinder", "cone", "torus", "shear_cylinder", "swept_torus" (the SRE
/// keywords), "bspline".
const char* to_string(FitKind kind);

/// An analytic surface. Which fields mean something depends on `kind`:
/// - plane: `point` on it, `axis` its unit normal;
/// - sphere: `point` its center, `radius`;
/// - cylinder: `point` on the axis, `axis` the unit axis direction, `radius`;
/// - cone: `point` on the axis, `axis` the unit direction in which the radius grows, `radius`
///   of the section through `point` (>= 0), `angle` the half-angle in (0, pi/2);
/// - torus: `point` its center, `axis` its unit axis, `radius` the major radius R (center to
///   tube center), `minor_radius` r. R < 0 is the inner, lemon-shaped part of the spindle
///   torus (|R|, r): in each half-plane through the axis the tube circle's center lies across
///   the axis, at distance |R| (a domed screw head); fit() gives it for |R| < r / 2.
/// - shear_cylinder: the circle of center `point`, `radius`, in the plane normal to `axis`,
///   swept along the unit `sweep` (not in that plane): an elliptic cylinder along `sweep`;
/// - swept_torus: the torus (`point`, `axis`, `radius` R, `minor_radius` r) swept along
///   `sweep`: the points at distance r from the shear cylinder of radius R;
/// - bspline: `bspline` (below); `point` and `axis` the mean plane it is a height field over
///   (a net), its centroid and direction (an extrusion), or a point on its axis and the axis
///   (a helical sweep).
/// The orientation of `axis` carries no meaning except for cones.
struct BSplineSurface;
struct Surface {
    FitKind kind = FitKind::kPlane;
    Vec3 point;
    Vec3 axis{0, 0, 1};
    double radius = 0;
    double angle = 0;
    double minor_radius = 0;
    Vec3 sweep{0, 0, 1};                            ///< kShearCylinder, kSweptTorus
    std::shared_ptr<const BSplineSurface> bspline;  ///< kBSpline only
};

/// A non-rational B-spline surface, clamped, uniform knots on [0, 1] in both directions (for n
/// poles: degree + 1 zeros, the n - degree - 1 values i / (n - degree), degree + 1 ones):
/// poles[i + num_u * j] for i < num_u, j < num_v. Evaluation by de Boor's algorithm.
struct BSplineSurface {
    int degree = 3;
    int num_u = 0, num_v = 0;
    std::vector<Vec3> poles;
    /// A linear extrusion (fit_bspline()): num_v is 4 and each row across is one pole of a
    /// planar profile moved along one line, so the surface is exactly linear that way.
    bool extruded = false;
    /// A helical sweep (fit_bspline()): each column along u is one planar profile's poles, the
    /// rows along v follow one helix about one axis (within a small part of the tolerance), so
    /// the surface is a thread's flank.
    bool helical = false;
    /// A helical sweep's motion: the axis through `origin` along unit `axis`, angles measured
    /// from unit `x` (normal to the axis) towards axis x x, `pitch` the climb per radian; the
    /// surface spans the angles [a0, a1] from v = 0 to 1, its profile's heights about `h`
    /// (the height less pitch x angle). Projections start from it (closest_point()).
    struct Helix {
        Vec3 origin, axis{0, 0, 1}, x{1, 0, 0};
        double pitch = 0, a0 = 0, a1 = 0, h = 0;
        /// `p`'s angle about the axis from `x` (in [-pi, pi]), and how many turns its height
        /// less pitch x that angle lies from the profile's heights about `h`, unrounded: the
        /// turn whose profile p lies at is the angle plus 2 pi x the nearest whole number.
        double turns(Vec3 p, double& angle) const;
    } helix;
    /// The surface at the grid of parameters where projections onto it start (distance(),
    /// closest_point(), normal_at()), filled by fit_bspline(); evaluated on each call when
    /// empty. A cache: it must hold the grid's points of these poles.
    std::vector<Vec3> starts;
    Vec3 evaluate(double u, double v) const;
    /// Point and first derivatives.
    void evaluate(double u, double v, Vec3& p, Vec3& du, Vec3& dv) const;
};

/// Unsigned distance from `p` to the (unbounded) surface.
double distance(const Surface& s, Vec3 p);
/// The point of the surface nearest to `p` (for a point on a cylinder's or cone's axis, or at
/// a sphere's or torus's center, one of the nearest points).
Vec3 closest_point(const Surface& s, Vec3 p);

/// The unit normal of the surface at its point nearest to `p` (its sign carries no meaning).
Vec3 normal_at(const Surface& s, Vec3 p);

/// A point on several surfaces at once: where a B-rep vertex is (method.md Step 2b.3: a corner
/// solved onto its three or more surfaces, starting from the mesh vertex).
struct CommonPoint {
    Vec3 point;
    double residual = 0;  ///< the largest distance from `point` to the surfaces
    int iterations = 0;
};

/// Gauss–Newton from `start` on the distances to `surfaces`: each step is the least-norm
/// correction that puts the point on every surface's tangent plane, so where fewer than three
/// surfaces fix it, the point moves no farther from `start` than it must. Three surfaces that
/// cross are met to rounding in a few steps. Two tangent surfaces (a fillet and its plane:
/// parallel normals) are NOT: first-order steps cannot find their tangency line, and the
/// residual stays at about curvature x (distance from that line)^2 — read `residual`. Stops at
/// rounding level or after 50 steps. Deterministic; never throws.
CommonPoint common_point(std::span<const Surface> surfaces, Vec3 start);

/// Points to fit: positions, and optionally unit normals and weights (e.g. facet centroids,
/// their normals and areas). Empty `normals` or `weights` spans mean none / all 1.
struct FitInput {
    std::span<const Vec3> points;
    std::span<const Vec3> normals;
    std::span<const double> weights;
    /// When positive, the residual the caller accepts: a cylinder or cone fitted within it
    /// (and agreeing with the normals) is kept without trying the second start (fitting.md).
    double accept = 0;
    /// When positive, a linear extrusion (fit_bspline()) goes on to profiles of more poles
    /// until its RMS residual is within this too, not only its max within the tolerance.
    double rms_goal = 0;
    /// When positive, a linear extrusion's profile has at most this many poles (a caller that
    /// would take no larger one spares the fits).
    int max_profile_poles = 0;
    /// When positive, a net over the mean plane has at most this many poles (likewise).
    int max_net_poles = 0;
    /// When positive, a sphere, cylinder, cone or torus fit of many points (kSampledFitPoints
    /// or more) is first made on a strided sample of them, and refused (ok false) when that
    /// fit's weighted RMS exceeds this; otherwise the fit is the one made without it, to the
    /// bit. A surface holding every point within t holds the sample with an RMS within t, and
    /// the sample's least-squares minimum does no worse: a caller that keeps fits with max <= t
    /// passes a few t, the margin for a fit that stops short of that minimum (a local one, the
    /// iteration cap), and should lose none it keeps (docs/fitting.md: segmentation's study
    /// unchanged with 3 t). fit_bspline() does the same for its nets (after the extrusion, on
    /// the whole), refusing also when the sample's largest net misses by more than this: the
    /// sample tries nets at least as fine as the whole would, one of which holds it with that
    /// RMS at least.
    double refuse_rms = 0;
    /// Points a B-spline net over the mean plane (fit_bspline()) is drawn towards without
    /// being held to them: a mesh's facet and edge middles, which lie within its chordal
    /// deflection of the surface (inside it), where its vertices do not hold the net (a long
    /// border edge, whose two ends alone let the net swing between them). Each weighs
    /// kGuideWeight x the points' mean weight: enough to hold the net where no point does,
    /// too little to pull it off the points. Not in the residuals; no other kind uses them.
    std::span<const Vec3> guides{};
    /// When positive, a net over the mean plane (fit_bspline()) spans this fraction of the
    /// points' extent beyond them on each side (its smoothing term carries it on there), so
    /// that a curve along the points' border that bows out past them stays on the surface.
    double margin = 0;
};

/// The fewest points a fit samples first (FitInput::refuse_rms): eight times the sample, so
/// that a fit that is not refused costs at most an eighth more.
inline constexpr std::size_t kSampledFitPoints = 16384;

/// The outcome of one fit: `ok` false when the points do not determine the surface (too few,
/// collinear, a degenerate start, no convergence), with the reason in `failure`. Residuals are
/// the distances of the points to the fitted surface: weighted RMS and maximum.
struct FitResult {
    bool ok = false;
    Surface surface;
    double rms = 0;
    double max = 0;
    int iterations = 0;
    std::string failure;
};

/// `surface` as it is, with the residuals of `input` (weighted RMS, max): what fit() reports,
/// for a surface given rather than fitted (an SRE record, a kept fit on changed points).
FitResult residuals(const Surface& surface, const FitInput& input);

/// Fits one kind. Cylinders, cones and tori need normals for their start (the axis is found
/// as the line that meets every normal line); spheres and planes do not. A B-spline is fitted
/// to within 1e-4 of the points' extent (see fit_bspline()). Never throws.
FitResult fit(FitKind kind, const FitInput& input);

/// A sphere, cylinder, cone or torus refined on the points from `start` (Levenberg-Marquardt,
/// none of fit()'s starts): for a surface fitted to nearly the same points, a region that gained
/// or lost a few facets on its border, where it converges in a few steps. It settles in the
/// least-squares minimum nearest the start, which fit() may leave for a better one. fit()'s
/// input checks and its checks of the result (a radius running away, a cone's half-angle, a
/// torus's radii); not refuse_rms, accept or fit()'s choice between starts. Other kinds are
/// fitted by fit(). Never throws.
FitResult refit(const Surface& start, const FitInput& input);

/// The fewest points fit_bspline() and fit_helical() take: a bicubic net's 16 poles.
inline constexpr std::size_t kMinBSplinePoints = 16;

/// A helical sweep: a planar profile swept along a helix about an axis found from the normals
/// and refined on the points — a thread's flank. fit_bspline() does not try it (on a quarter
/// turn a wrong motion still fits); segmentation asks for it where a region is a B-spline. ok false
/// when the points are no such sweep within `tolerance`; the surface is a B-spline with `helical`
/// set.
FitResult fit_helical(const FitInput& input, double tolerance);

/// A cubic B-spline surface. First as a linear extrusion when the normals are all normal to one
/// direction (a pocket wall cut along a spline outline, which folds back over its mean plane):
/// its profile fitted in the plane across, with up to 64 poles (the fewest that reach the
/// tolerance and `rms_goal`; each size from two starts, parameters by length along the profile
/// and by length and turning), then extruded over the points' span (`BSplineSurface::extruded`);
/// an open profile only. Otherwise over the points' mean plane (they must be a height field over
/// it: free-form machined regions, a die's cavity, are), by least squares with a small smoothing
/// term that also spans cells without points; the control net starts at 4 x 4 and grows by half
/// in each direction until the max residual is within `tolerance` or the net would have more
/// poles than half the points (or 64 x 64). `ok` false when the points are not a height field
/// over their plane or no net reaches the tolerance.
FitResult fit_bspline(const FitInput& input, double tolerance);

/// The line nearest `points` in least squares: through their centroid along their principal
/// direction (unit). False when they all coincide.
bool fit_line(std::span<const Vec3> points, Vec3& point, Vec3& direction);

/// The circle nearest `points`: its plane by principal components (`normal`, unit), the circle
/// in it by Kasa's algebraic fit. Returns the mean squared distance of the points from it;
/// infinite when there is none. Through any three points not on a line; for points on a line
/// it is ill-conditioned (a circle of any huge radius): fit a line first.
double fit_circle(std::span<const Vec3> points, Vec3& center, Vec3& normal, double& radius);

/// The simplest kind whose fit keeps every point within `tolerance` (max residual), in the
/// order plane, sphere, cylinder, cone, torus, so that a plane is not called a cylinder of huge
/// radius, nor a cylinder a cone of tiny angle; unless a kind with more parameters fits clearly
/// better (RMS lower by more than 10 % plus 2 % of the tolerance): then the simpler one is
/// biased, e.g. a cylinder fitted to a narrow strip of a cone. Kinds are tried in rounds: plane
/// to torus; then shear cylinder and swept torus, only when none of those fits; then the
/// B-spline. `best.ok` false when nothing fits.
struct KindSelection {
    FitResult best;
    std::array<FitResult, kNumFitKinds> tried;  ///< every fit attempted, by kind
};
/// A set of kinds: bit (1 << kind).
using FitKindSet = std::uint32_t;
constexpr FitKindSet fit_kind_bit(FitKind kind) { return FitKindSet{1} << static_cast<int>(kind); }
constexpr FitKindSet kAllFitKinds = (FitKindSet{1} << kNumFitKinds) - 1;
/// Plane, sphere, cylinder, cone, torus.
constexpr FitKindSet kRevolutionFitKinds = (FitKindSet{1} << 5) - 1;
/// `kinds` restricts the kinds tried (the others stay not ok in `tried`).
KindSelection fit_simplest(const FitInput& input, double tolerance,
                           FitKindSet kinds = kAllFitKinds);

/// SnapOptions::noise: the rise of the sum of squared residuals, in units of the noise variance,
/// that holding parameters at their true values stays below: it is chi-square distributed with
/// as many degrees of freedom as parameters held, up to 7 (a torus's axis, line, center along it
/// and radii), whose 99.9 % quantile is 24.3. Every change is measured from the free fit, so
/// the test is on all the values held so far.
inline constexpr double kSnapChi2 = 24;

/// What snap_together() fixed of a fit, for snap() to hold: its axis direction (shared with
/// the parallel ones of its group, along a coordinate axis where the group's is), and its axis
/// line (shared with coaxial surfaces, at round values where the group's is).
struct SnapHold {
    bool direction = false;
    bool line = false;
};

/// The number of parameters of a kind's model: plane 3, sphere 4, cylinder 5, cone 6, torus and
/// shear cylinder 7, swept torus 8; 0 for a B-spline (its count depends on its net).
int fit_parameters(FitKind kind);

/// What snap() may do. Every change is kept only when the refitted surface (the snapped values
/// held, the other parameters fitted again) still keeps every point within `tolerance`, and,
/// with `noise`, explains the points as well as the fit before snapping, within chance.
struct SnapOptions {
    double tolerance = 0;  ///< max residual allowed after snapping, model units
    /// Axes and plane normals to the nearest coordinate axis when within 2 degrees.
    bool axes = true;
    /// Radii to round values (multiples of 1, 0.5, 0.1, 0.05, 0.01 model units, coarsest
    /// first) and cone half-angles to multiples of 5, 1, 0.5 degrees.
    bool round_values = true;
    /// Where an axis or a plane's normal is a coordinate axis (exactly, e.g. once snapped):
    /// the axis line's place across it (cylinders, cones, tori), a torus's center along it, a
    /// plane's offset; and a sphere's center; to round values, the radii's steps.
    bool positions = true;
    /// Radii to try before round values, e.g. the radii of the tools of an SRE file
    /// (diameter / 2, corner radius): the nearest one that keeps the tolerance wins.
    std::vector<double> tool_radii;
    /// When >= 0, the standard deviation of the points about their true surface (a mesh's
    /// noise; rounding for a CAD tessellation): a change is also kept only when it raises the
    /// mean square residual by at most kSnapChi2 x noise^2 / n (n points, or (sum of weights)^2
    /// / sum of squared weights) plus rms_floor^2, i.e. when the held values lie within a few
    /// standard errors of the fitted ones and the points cannot tell them apart. A fit whose own
    /// residuals show less noise (RMS^2 n / (n - p) for p parameters, n > p + 1) is held to that.
    /// Without it (< 0) the tolerance alone decides, and a loose tolerance takes round values that
    /// are not the part's (6.35 -> 6.4).
    double noise = -1;
    double rms_floor = 0;  ///< model units; see noise
    /// snap(): the RMS that `noise` compares with when >= 0 (the free fit's, for a fit already
    /// snapped by snap_together()); otherwise the fit's own.
    double base_rms = -1;
    /// snap(): what snap_together() fixed (its `holds`): held as it is, neither turned to a
    /// coordinate axis nor moved to round values here (snap_together() did that for the group).
    SnapHold hold;
};

/// A fit with machined-part values: see SnapOptions. `applied` lists what was snapped, in
/// words (e.g. "axis to +z", "radius 9.9987 -> 10"). Returns `fit` unchanged when it is not ok
/// or nothing snaps.
FitResult snap(const FitResult& fit, const FitInput& input, const SnapOptions& options,
               std::vector<std::string>* applied = nullptr);

/// Snaps surfaces to each other, as machined features are (method.md Step 4): axes (and plane
/// normals) within 0.5 degree of each other become one direction, and cylinders, cones and
/// tori whose axes are then within `options.tolerance` of each other share one axis line
/// (coaxial bores, a counterbore and its hole, a turned shaft's steps). Every member of a group
/// is refitted with the common axis held and must keep its points within the tolerance (and,
/// with options.noise, the RMS as snap() asks, from `base_rms[i]` when given, else from its
/// RMS on entry); members that do not are left out of the group, which is tried again without
/// them while it has two. Then, with options.axes, a group's direction goes to a coordinate
/// axis within 2 degrees, and with options.positions a coaxial group's line to round values
/// across it, as snap() does for one surface; each for all members or none. `holds` (when not
/// null) receives what each fit now shares, for snap() (SnapOptions::hold). `fits[i]` was
/// fitted to `inputs[i]`; fits that are not ok, spheres, B-splines and the sheared kinds are
/// left alone. Returns what was done, in words. Deterministic.
std::vector<std::string> snap_together(std::span<FitResult> fits, std::span<const FitInput> inputs,
                                       const SnapOptions& options,
                                       std::span<const double> base_rms = {},
                                       std::vector<SnapHold>* holds = nullptr);

}  // namespace ncrev
