// segment: see include/ncrev/segment.h. The facets method is in this file's first half, the
// paper's vertex method after it; both end in the same merging, refining and final fitting.
#include "ncrev/segment.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <queue>
#include <tuple>

#include "detail/huge_pages.h"

namespace ncrev {

const char* to_string(SegmentMethod method) {
    switch (method) {
        case SegmentMethod::kFacets:
            return "facets";
        case SegmentMethod::kPaper:
            return "paper";
    }
    return "?";
}

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A group of curved pieces is tried as one free-form region from this many pieces on: fewer
/// are a real chain of analytic faces far more often than a free-form face.
constexpr std::size_t kFreeformMinPieces = 3;
/// The largest B-spline net (16 x 16 cubic) that may replace a group of pieces: a free-form
/// face needs few poles, while a chain of analytic faces with curvature jumps needs many.
constexpr int kFreeformMaxPoles = 256;
/// An extrusion replaces its pieces only within this multiple of their RMS residual (see
/// merge_freeform()).
constexpr double kFreeformRms = 2;
/// Pieces of a group that are not chords of its B-spline are left out of it while they hold at
/// most this share of its facets (see merge_freeform()).
constexpr double kFreeformStrayShare = 0.02;
/// An analytic face's vertices lie on its surface to the rounding of the file that carried
/// them; a free-form face's analytic pieces fit only within the tolerance. A final region
/// whose RMS residual passes this share of the chordal deflection is loose, a piece of a
/// free-form face perhaps (see merge_loose_pieces()): the link rods' free-form faces' pieces
/// are at 0.015-0.05, their tori and cylinders at most 0.003, NIST FTC 10's exact fillets at
/// 0.0002 and below (a temporary print of the pieces' fits, not in the repository).
constexpr double kLooseRms = 0.01;
/// Vertices a region needs before a kind is fitted to it: one more than the kind's parameters
/// (plane 3, sphere 4, cylinder 5, cone 6, torus 7), except the plane of a single facet. With
/// no spare point any point set fits: the corners of a rectangle and a strip of its neighbour
/// lie on a sphere.
constexpr std::size_t kMinVertices[5] = {3, 5, 6, 7, 8};
/// The order kinds are tried in: plane, cylinder, cone, sphere, torus. A band one facet row
/// wide has its vertices on two circles, which a cone, a sphere and (equal radii) a cylinder
/// all pass through; machined parts have far more bores and chamfers than spherical zones, and
/// a spherical face of any size gets more than one row.
constexpr FitKind kKindOrder[5] = {FitKind::kPlane, FitKind::kCylinder, FitKind::kCone,
                                   FitKind::kSphere, FitKind::kTorus};
/// The chordal deflection estimate: kSagFactor x the kSagQuantile quantile of the sags of the
/// curved edges (a tessellation's sags spread up to its deflection).
constexpr double kSagQuantile = 0.9;
constexpr double kSagFactor = 2;
/// Dihedral angle (rad) below which an edge is flat for the sag estimate: far above float32
/// rounding of the normals of facets a thousandth of the part wide.
constexpr double kFlatDihedral = 1e-3;
/// The share of a region's area whose facet normals may disagree with its surface.
constexpr double kNormalOutlierArea = 0.02;
/// How far a facet's middle may lie from its surface, in chordal deflections (the sag estimate
/// measures edges). A triangle's middle sags more than its edges' middles: 4/3 as much on a
/// sphere, more for a fan triangle on a torus whose corners lie on two of its circles —
/// BRepMesh's fans on NIST FTC 11's bull-nose tori sag 1.3 x the estimate with every corner on
/// the torus, and came back as dozens of one-facet planes. A facet whose three corners lie on
/// the surface and whose middle is 2 deflections off is still a chord of it; one that bridges
/// two faces (a cap triangle on a bore's rim) is off by the bore's radius.
constexpr double kMiddleSagFactor = 2;
/// A triangle's middle sags 4/3 as much as its edges' middles on a sphere (see kMiddleSagFactor).
constexpr double kChordMiddleFactor = 4.0 / 3.0;
/// An edge's middle may sag this much more than a triangle's middle may (chords_agree()): on a
/// cylinder a facet across two generators sags 9/8 as much at its slanted edges' middles as at
/// its own; the margin is the sphere's factor the other way. Held to the growing's bound for a
/// middle (kMiddleSagFactor deflections), not to the chords' own: BRepMesh's fans on NIST CTC
/// 02's fillets sag up to 1.9 deflections at their long edges' middles, and their tori were
/// refused (two more cone faces) when held to 4/3.
constexpr double kEdgeMiddleFactor = kChordMiddleFactor;
/// A region of at most this many facets says nothing of its kind (its plane is its facets'):
/// a ruled surface may take it with middles up to kMiddleSagFactor deflections off (see
/// chords_agree()).
constexpr std::size_t kLooseFacets = 2;
/// Facets of a coarse cylinder's strip have their long edges along its generators, or across
/// one step of its outline from rim to rim (see strip_fit()): FTC 08's fillets 24 mm long, 3 mm
/// in radius, in steps of 18 degrees, tilt theirs by 3.3 degrees. 10 degrees.
constexpr double kStripParallel = 0.175;
/// A plane with at least this share of the area of the regions smoothly joined to it is a face,
/// not a piece of a free-form face.
constexpr double kFreeformPlaneShare = 0.1;
/// A region this many times larger than the one it merges with keeps its kind.
constexpr std::size_t kDominantRatio = 4;
/// Growing regions are refitted each time they double, up to this many facets: by then the
/// surface is known far better than the tolerance, and the final fit uses every facet anyway.
constexpr std::size_t kMaxGrowthRefit = 1u << 14;
/// From this many facets a growing region's kind is settled (see settled()).
constexpr std::size_t kSettledFacets = 4096;
/// Large unions are refused on a sample's fit off by an RMS of more than this many
/// tolerances (FitInput::refuse_rms; see fit_faces()): the margin covers a fit that stops short
/// of the least squares (a local minimum, the iteration cap). The unions refused are far
/// beyond it: their kinds miss them by many tolerances; the study's rows are the same with 3.
constexpr double kSampleRefuseTolerances = 3;
/// See firm_plane().
constexpr std::size_t kFirmPlaneFacets = 8;
constexpr double kFirmPlaneShare = 0.01;
/// The fillet rows held 0.15 % of NIST CTC 01's top face at 92k facets and 1.2-3.4 % of CTC
/// 03's large planes at 68k; a patch of a fine torus bends up to a quarter of the tolerance
/// from its plane across it, so most of its facets have a vertex beyond kFirmPlaneShare.
constexpr double kFirmPlaneOffArea = 0.05;
/// Segmenting again for noise: at kNoiseFactor x the measured RMS (the largest of a million
/// gaussian deviates is about 5 sigma), at most kNoisePasses times.
constexpr double kNoiseFactor = 6;
constexpr int kNoisePasses = 3;
/// Facets of each region that order the merge queue (see unlikeness()).
constexpr std::size_t kLikenessSamples = 1024;
/// The merge queue's lower bounds take every kLikenessBoundThin-th of those (merge_regions()).
constexpr std::size_t kLikenessBoundThin = 32;
/// A merge may leave out this share of its area as strays for its neighbours (see
/// fit_without_strays()): a few small facets of a corner, never a face's row.
constexpr double kStrayShare = 0.1;
/// Strays that no neighbour takes become regions of their own while each group holds at most
/// this share of the merge's area: the few small facets of a corner beside a coarse fillet's
/// long strips (NIST FTC 07: 0.2 %), not the rim rows of two small regions of like facets
/// (CTC 03's cone and cylinder at 3-4 %, which stay apart).
constexpr double kOrphanShare = 0.01;
/// A small neighbour whose vertices lie this many tolerances from the surface of a dominant
/// region of at least kMaxGrowthRefit facets cannot join it (see merge_regions()):
/// the union's surface fits the dominant region's vertices within the tolerance as its own
/// does, so the two are within 2 tolerances of each other there, and by little more a facet
/// beside them; the rest is margin.
constexpr double kHopelessTolerances = 10;
/// Pairs merge_regions() fits ahead of their turn, at most, on all cores: a few per core (most
/// are refused, so most fits ahead are used).
constexpr std::size_t kFitAhead = 8;
/// A cylinder or cone region of at most this many facets may be a piece of a coarse fan (see
/// merge_fans()): what pairwise merging makes of two of its facets.
constexpr std::size_t kFanPieceFacets = 2;
/// Regions of at most this many facets are dissolved into their neighbours when these fit them.
constexpr std::size_t kSmallRegion = 8;
/// Rounds of absorbing small regions (each dissolves facets one row deep at most).
constexpr int kAbsorbRounds = 3;
/// Rounds of border refinement in which any region takes facets its surface fits clearly better
/// than their own (each round moves facets one row at most); after them only an exact one
/// does (see refine_borders()).
constexpr int kRefineRounds = 3;
/// A surface is exact for a region when it holds the region's vertices with an RMS residual of
/// at most this share of the tolerance, and a facet is on it when its vertices are within that
/// share: a CAD tessellation's vertices lie on their faces to rounding (fillet block at 345k
/// facets: 0.000-0.016), while a surface grown across a tangent line or an analytic piece of
/// a free-form blend holds its vertices at 0.04-0.4 of the tolerance (NIST CTC 02's tori; both
/// by a temporary print). A noisy mesh's tolerance is six times its noise (kNoiseFactor): none
/// of its surfaces is exact.
constexpr double kExactShare = 0.05;
/// Passes of border refinement, the regions refitted after each (see refine_borders()): a
/// bound on the work, not a tuning; the passes stop when no facet moves.
constexpr int kRefinePasses = 20;
/// A border facet moves only when it fits the other region better by this part of the
/// tolerance (no flip-flopping of facets that fit both, such as those on a tangent line).
constexpr double kMoveMargin = 0.1;
/// The paper method's refining rounds (method.md 3.5: "a bounded number of rounds").
constexpr int kPaperRefineRounds = 10;
/// The derived tolerance stays this many coordinate rounding units above the coordinates'
/// own precision (float32 files: rounding alone moves vertices off their surface).
constexpr double kPrecisionFactor = 16;

using Clock = std::chrono::steady_clock;

FaceId fid(std::uint32_t f) { return FaceId(f); }

/// Per-face unit normal, area and centroid.
struct FaceData {
    std::vector<Vec3> normal, centroid;
    std::vector<double> area;
    std::vector<std::array<std::uint32_t, 3>> adj;  ///< face across each edge, kNone on a border
};

FaceData face_data(const Mesh& m) {
    const std::size_t nf = m.num_faces();
    FaceData d;
    detail::resize_huge(d.normal, nf);
    detail::resize_huge(d.centroid, nf);
    detail::resize_huge(d.area, nf);
    detail::resize_huge(d.adj, nf);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 4096), [&](const auto& r) {
        for (std::size_t f = r.begin(); f != r.end(); ++f) {
            const FaceId ff = fid(static_cast<std::uint32_t>(f));
            const Vec3 n2 = m.face_normal_area2(ff);
            const double l = norm(n2);
            d.normal[f] = l > 0 ? n2 / l : Vec3{0, 0, 0};
            d.area[f] = 0.5 * l;
            d.centroid[f] = (m.position(m.vertex(ff, 0)) + m.position(m.vertex(ff, 1)) +
                             m.position(m.vertex(ff, 2))) /
                            3.0;
            for (int i = 0; i < 3; ++i) {
                const HalfedgeId t = m.twin(Mesh::halfedge(ff, i));
                d.adj[f][static_cast<std::size_t>(i)] = t.is_valid() ? Mesh::face(t).idx() : kNone;
            }
        }
    });
    return d;
}

/// The points of a set of faces, for fitting: each vertex once, with the area-weighted normal
/// of the set's facets around it (so a vertex on a border gets its normal from this side) and a
/// third of their area as its weight.
struct PointSet {
    std::vector<Vec3> points, normals;
    std::vector<double> weights;
    FitInput input() const { return {points, normals, weights}; }
};

class Gatherer {
   public:
    explicit Gatherer(std::size_t num_vertices) : slot_(num_vertices, kNone) {}
    void gather(const Mesh& m, const FaceData& fd, std::span<const std::uint32_t> faces,
                PointSet& out) {
        out.points.clear();
        out.normals.clear();
        out.weights.clear();
        for (const std::uint32_t f : faces) {
            for (int i = 0; i < 3; ++i) {
                const std::uint32_t v = m.vertex(fid(f), i).idx();
                if (slot_[v] == kNone) {
                    slot_[v] = static_cast<std::uint32_t>(out.points.size());
                    touched_.push_back(v);
                    out.points.push_back(m.position(VertexId(v)));
                    out.normals.push_back({0, 0, 0});
                    out.weights.push_back(0);
                }
                const std::uint32_t k = slot_[v];
                out.normals[k] += fd.normal[f] * fd.area[f];
                out.weights[k] += fd.area[f] / 3;
            }
        }
        for (std::size_t k = 0; k < out.normals.size(); ++k) {
            const double l = norm(out.normals[k]);
            if (l > 0) out.normals[k] = out.normals[k] / l;
        }
        for (const std::uint32_t v : touched_) slot_[v] = kNone;
        touched_.clear();
    }

   private:
    std::vector<std::uint32_t> slot_;
    std::vector<std::uint32_t> touched_;
};

/// Everything the stages share.
struct Context {
    const Mesh& m;
    FaceData fd;
    double tol = 0;
    double cos_normal = 0;
    double sharp = 0;
    double sag = 0;  ///< the mesh's chordal deflection, estimated (estimate_sag())
    std::vector<std::uint8_t> sharp_edge;  ///< per half-edge
    std::vector<float> edge_turn;          ///< |dihedral angle| per half-edge (0 on a border)
    /// Per facet: the largest sag estimate of its smooth curved edges (estimate_sag()), 0 where
    /// none turns: how far its middle may sag as a ruled surface's chord (chords_agree()).
    std::vector<float> facet_sag;
    tbb::enumerable_thread_specific<Gatherer> gatherers;
    explicit Context(const Mesh& mesh)
        : m(mesh), gatherers([&mesh] { return Gatherer(mesh.num_vertices()); }) {}
};

/// The mesh's chordal deflection, from its smooth curved edges: where the normal turns by beta
/// across an edge between facets of heights h1, h2 over it, chords of width h = min(h1, h2)
/// sag by about 2 h beta / 8 (a circle's chords of step beta and length h sag h beta / 8). The
/// smaller height: a plane's large facet next to a tangent fillet is no chord of the fillet.
/// kSagFactor x the kSagQuantile quantile, never below the tolerance. Fills c.facet_sag.
double estimate_sag(Context& c) {
    const Mesh& m = c.m;
    detail::assign_huge(c.facet_sag, m.num_faces(), 0.0f);
    std::vector<double> sags;
    for (std::uint32_t h = 0; h < m.num_halfedges(); ++h) {
        const HalfedgeId he(h);
        const HalfedgeId t = m.twin(he);
        if (!t.is_valid() || t.idx() < h || c.sharp_edge[h]) continue;
        const double beta = c.edge_turn[h];
        if (beta < kFlatDihedral) continue;  // a plane's edges say nothing of the sag
        const Vec3 a = m.position(m.origin(he)), b = m.position(m.target(he));
        const double len = norm(b - a);
        if (!(len > 0)) continue;
        const double h1 = 2 * c.fd.area[Mesh::face(he).idx()] / len;
        const double h2 = 2 * c.fd.area[Mesh::face(t).idx()] / len;
        sags.push_back(2 * std::min(h1, h2) * beta / 8);
        for (const HalfedgeId x : {he, t}) {
            float& fs = c.facet_sag[Mesh::face(x).idx()];
            fs = std::max(fs, static_cast<float>(sags.back()));
        }
    }
    if (sags.empty()) return c.tol;
    auto q =
        sags.begin() + static_cast<std::ptrdiff_t>(kSagQuantile * static_cast<double>(sags.size()));
    std::nth_element(sags.begin(), q, sags.end());
    return std::max(c.tol, kSagFactor * *q);
}

/// The facet's normal is the surface's at its middle within kSegmentNormalAngle, or within the
/// turn of the surface's normal across the facet (its corners' normals) when that is larger: a
/// chord's normal is one of the normals it spans, and the large fan triangles of a coarse torus
/// span 40 degrees.
bool normal_agrees(const Context& c, const Surface& s, std::uint32_t f) {
    const Vec3 n = c.fd.normal[f];
    const Vec3 sn = normal_at(s, c.fd.centroid[f]);
    const double cos_mid = std::abs(dot(sn, n));
    if (cos_mid >= c.cos_normal) return true;
    if (s.kind == FitKind::kPlane) return false;
    double cos_span = 1;
    for (int i = 0; i < 3; ++i) {
        const Vec3 p = c.m.position(c.m.vertex(fid(f), i));
        cos_span = std::min(cos_span, std::abs(dot(normal_at(s, p), sn)));
    }
    return cos_mid >= cos_span;
}

/// The largest distance of a corner of `faces` from `s`.
double farthest_corner(const Context& c, const Surface& s, std::span<const std::uint32_t> faces) {
    double worst = 0;
    for (const std::uint32_t f : faces)
        for (int i = 0; i < 3; ++i)
            worst = std::max(worst, distance(s, c.m.position(c.m.vertex(fid(f), i))));
    return worst;
}

/// How badly facet f fits s: the largest distance of its corners; infinite when its normal
/// disagrees with the surface's or its middle is further from the surface than
/// kMiddleSagFactor chordal deflections (a chord of the surface: corners on it, middle within
/// the sag).
double facet_cost(const Context& c, const Surface& s, std::uint32_t f, bool check_normal = true) {
    const double worst = farthest_corner(c, s, std::span(&f, 1));
    if (worst > c.tol) return worst;
    if (distance(s, c.fd.centroid[f]) > kMiddleSagFactor * c.sag) return kInf;
    return !check_normal || normal_agrees(c, s, f) ? worst : kInf;
}

bool facet_fits(const Context& c, const Surface& s, std::uint32_t f) {
    return facet_cost(c, s, f) <= c.tol;
}

/// How far the middle of a chord of length `len` may lie from `s` near the points `corners`:
/// len^2 / (8 rho), rho the smallest radius of curvature of s there (a cone's at the corner
/// nearest its axis); 0 for a plane or a B-spline.
double chord_sag(const Surface& s, double len, std::span<const Vec3> corners) {
    double rho = 0;
    switch (s.kind) {
        case FitKind::kSphere:
        case FitKind::kCylinder:
            rho = s.radius;
            break;
        case FitKind::kTorus:  // 1/r across the tube; 1/|R - r| along its inner equator
            rho = std::min(s.minor_radius, std::abs(s.radius - s.minor_radius));
            break;
        case FitKind::kCone: {
            rho = kInf;
            for (const Vec3& p : corners) {
                const Vec3 d = p - s.point;
                rho = std::min(rho, norm(d - dot(d, s.axis) * s.axis));
            }
            rho /= std::cos(s.angle);
            break;
        }
        default:
            return 0;
    }
    // No middle of a chord of a sphere is farther off than its radius; a "chord" whose middle
    // is farther off than rho spans the hole of a torus or the inside of a bore (a plane's cap
    // facet with its corners on the rim its fillet or bore meets), it is not one of s.
    return rho > 0 ? std::min(len * len / (8 * rho), rho) : 0;
}

/// How far the middle of facet f may lie from the B-spline s as a chord of it: as far as s
/// bends between f's corners. An edge whose corners' normals on s turn by theta sags
/// c theta / 8, c its length across the turn (a circle's chord of length c and angle theta
/// sags c^2 / 8 rho = c theta / 8), and the triangle's middle 4/3 as much as its edges'
/// middles (kChordMiddleFactor, a sphere's). 0 where an edge turns by the sharp angle or more:
/// that facet spans an edge of s, it is no chord. A B-spline has no one radius (chord_sag()),
/// and the deflection estimate is the part's, not the surface's where it bends most: at the end
/// of trimesh_featuretype's spline wall meshed at 0.02 rad, facets with their corners on the
/// wall to 0.002 mm have middles 0.032-0.050 mm off it, above twice the estimate (0.029), and
/// within what their edges alone bend (0.034-0.093 mm; temporary print).
double bspline_chord_sag(const Context& c, const Surface& s, std::uint32_t f) {
    std::array<Vec3, 3> p, n;
    for (std::size_t i = 0; i < 3; ++i) {
        p[i] = c.m.position(c.m.vertex(fid(f), static_cast<int>(i)));
        n[i] = normal_at(s, p[i]);
    }
    double edge = 0;
    for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t j = (i + 1) % 3;
        const double cos_turn = dot(n[i], n[j]);
        if (!(cos_turn > std::cos(c.sharp))) return 0;
        const Vec3 turn = n[j] - n[i];
        const double len = norm(turn);
        if (!(len > 0)) continue;
        const double across = std::abs(dot(p[j] - p[i], turn / len));
        edge = std::max(edge, across * std::acos(std::min(cos_turn, 1.0)) / 8);
    }
    return kChordMiddleFactor * edge;
}

/// Facet f as a chord of s where the deflection estimate is too tight: its corners within
/// `corners` (the tolerance, or the deflection for a surface held to that), its middle no
/// farther than a chord of its longest side across s (chord_sag(); on a B-spline, as far as s
/// bends between the corners: bspline_chord_sag()), nor than kMiddleSagFactor
/// deflections. BRepMesh's fans on the large fillets of NIST CTC 05 sag 2.1 - 3.5 x the
/// estimate with every corner on the torus to rounding: 24 one-facet planes. Only for leftovers
/// no neighbour takes otherwise: a cap triangle of a plane on a bore's rim is a chord of the
/// bore too.
bool chord_fits(const Context& c, const Surface& s, std::uint32_t f, double corners) {
    std::array<Vec3, 3> p;
    for (int i = 0; i < 3; ++i)
        p[static_cast<std::size_t>(i)] = c.m.position(c.m.vertex(fid(f), i));
    double len = 0;
    for (std::size_t i = 0; i < 3; ++i) {
        if (distance(s, p[i]) > corners) return false;
        len = std::max(len, norm(p[(i + 1) % 3] - p[i]));
    }
    const double mid = distance(s, c.fd.centroid[f]);
    if (mid <= std::max(kMiddleSagFactor * c.sag, chord_sag(s, len, p))) return true;
    return s.kind == FitKind::kBSpline && mid <= bspline_chord_sag(c, s, f);
}

/// Facet f's smallest height: twice its area over its longest side.
double narrowest_width(const Context& c, std::uint32_t f) {
    double longest = 0;
    for (int i = 0; i < 3; ++i) {
        const Vec3 a = c.m.position(c.m.vertex(fid(f), i));
        const Vec3 b = c.m.position(c.m.vertex(fid(f), (i + 1) % 3));
        longest = std::max(longest, norm(b - a));
    }
    return longest > 0 ? 2 * c.fd.area[f] / longest : 0;
}

/// Whether facet f has an edge along a generator of s (a cylinder or a cone): its middle on s
/// within `near` though a chord of that length across s would sag four times as much.
bool has_generator(const Context& c, const Surface& s, std::uint32_t f, double near) {
    for (int i = 0; i < 3; ++i) {
        const Vec3 a = c.m.position(c.m.vertex(fid(f), i));
        const Vec3 b = c.m.position(c.m.vertex(fid(f), (i + 1) % 3));
        const Vec3 mid = (a + b) / 2.0;
        if (distance(s, mid) > near) continue;
        const std::array<Vec3, 3> p{a, b, mid};
        if (chord_sag(s, norm(b - a), p) > 4 * near) return true;
    }
    return false;
}

/// How far the middle of facet f's longest edge lies from s. A facet with its corners and its
/// middle on s can still be no chord of it: one of a plane's two long thin facets (2 x 22 mm
/// on NIST CTC 01 meshed at 0.05 mm and 0.05 rad) with a strip of the small bore beside it fit
/// a spindle torus at its corners and middle, its long edges' middles 10 tolerances off; the
/// face built on the torus stood 1.24 mm off the mesh.
double longest_edge_middle_off(const Context& c, const Surface& s, std::uint32_t f) {
    std::array<Vec3, 3> p;
    for (int i = 0; i < 3; ++i)
        p[static_cast<std::size_t>(i)] = c.m.position(c.m.vertex(fid(f), i));
    std::size_t best = 0;
    double longest = -1;
    for (std::size_t i = 0; i < 3; ++i) {
        const Vec3 e = p[(i + 1) % 3] - p[i];
        if (dot(e, e) > longest) longest = dot(e, e), best = i;
    }
    return distance(s, 0.5 * (p[best] + p[(best + 1) % 3]));
}

/// Whether an edge between two of `faces` is sharp.
bool sharp_inside(const Context& c, std::span<const std::uint32_t> faces) {
    std::vector<std::uint32_t> sorted(faces.begin(), faces.end());
    std::sort(sorted.begin(), sorted.end());
    for (const std::uint32_t f : sorted) {
        for (int i = 0; i < 3; ++i) {
            const std::uint32_t g = c.fd.adj[f][static_cast<std::size_t>(i)];
            if (g != kNone && c.sharp_edge[3 * f + static_cast<std::uint32_t>(i)] &&
                std::binary_search(sorted.begin(), sorted.end(), g)) {
                return true;
            }
        }
    }
    return false;
}

/// How far a cylinder's or cone's chords may sag (chords_agree()).
enum class RuledSag {
    kDeflection,  ///< the deflection, as any surface's
    kTwice,       ///< kMiddleSagFactor x the deflection: merging a region of kLooseFacets
    kOwnEdges,    ///< that, and no more than kSagFactor x the facet's edges' estimate: growing
};

/// The facets are chords of s: every middle within the sag, and the normals close to s's,
/// except on at most kNormalOutlierArea of the area (slivers: a thin triangle whose corners lie
/// on one circle of a torus has that circle's plane, whatever the torus's normal there).
/// A B-spline is itself held only to the sag at the vertices: its chords' middles get twice,
/// or as far as it bends between their corners where that is more (bspline_chord_sag()).
/// So may a cylinder's and a cone's with `ruled_sag` (RuledSag) where no sharp edge runs between
/// the facets: facets from rim to rim of a wide drafted wall (NIST CTC 02's cones of radius 101
/// at 3 degrees) have generators for edges, which show no sag, and their middles sag 1.6 x the
/// estimate from the part's curved edges, mostly small fillets held by the angular deflection.
/// Twice the estimate when merging a region of at most kLooseFacets facets with a cylinder or
/// cone (kTwice: 180 one-facet planes on four cones came back 102). When a growing region takes
/// its next ring (kOwnEdges: the other 102), twice the estimate but no more than twice the
/// facet's own edges' estimate (Context::facet_sag): a flat strip tangent to a small bore (a plane
/// of two facets, its edges turning by nothing) lies within the tolerance of a cone or a wide
/// cylinder through both, and NIST CTC 01, 03 and FTC 06 lost faces to them when every middle in a
/// ring could sag twice the estimate; not for a plane of more than kLooseFacets facets, which would
/// take a fillet with it (trimesh_featuretype meshed at 0.02 rad: a plane of 70 facets became a
/// cone of radius 0.37 at 0.3 tolerances RMS, and the free-form wall beside it lost its face). Not
/// across a sharp edge: the sides of a prism lie on their circumscribed cylinder within that.
bool chords_agree(const Context& c, const Surface& s, std::span<const std::uint32_t> faces,
                  RuledSag ruled_sag = RuledSag::kDeflection) {
    const bool ruled = ruled_sag != RuledSag::kDeflection &&
                       (s.kind == FitKind::kCylinder || s.kind == FitKind::kCone);
    const double limit = s.kind == FitKind::kBSpline ? 2 * c.sag : c.sag;
    double total = 0, outliers = 0;
    bool beyond = false;  // a middle beyond the sag, within twice (a ruled surface)
    for (const std::uint32_t f : faces) {
        const double d = distance(s, c.fd.centroid[f]);
        if (d > limit && !(s.kind == FitKind::kBSpline && d <= bspline_chord_sag(c, s, f))) {
            if (!ruled || d > kMiddleSagFactor * c.sag) return false;
            if (ruled_sag == RuledSag::kOwnEdges && d > kSagFactor * c.facet_sag[f]) return false;
            beyond = true;
        }
        // Its longest edge's middle: within what a facet's middle may sag when growing
        // (facet_cost()), and the factor by which an edge's can sag more. (Not on a B-spline,
        // whose chords are held to how far it bends between their corners, above.)
        if (s.kind != FitKind::kBSpline &&
            longest_edge_middle_off(c, s, f) > kEdgeMiddleFactor * kMiddleSagFactor * c.sag)
            return false;
        total += c.fd.area[f];
        if (!normal_agrees(c, s, f)) outliers += c.fd.area[f];
    }
    if (outliers > kNormalOutlierArea * total) return false;
    return !beyond || !sharp_inside(c, faces);
}

/// The first kind in kKindOrder (of `kinds`) whose fit keeps every vertex of `faces` within
/// the tolerance and whose chords the facets are (chords_agree()).
/// `misses`, when given, receives the surfaces that were fitted but refused (a vertex beyond the
/// tolerance, or facets that are not their chords), in the order tried.
std::optional<FitResult> fit_faces(Context& c, std::span<const std::uint32_t> faces,
                                   FitKindSet kinds = kRevolutionFitKinds,
                                   std::optional<FitKind> first = std::nullopt,
                                   std::vector<Surface>* misses = nullptr,
                                   RuledSag ruled_sag = RuledSag::kDeflection) {
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, faces, ps);
    // `first` (the kind a growing region has) is tried before the others: refitting a torus of
    // a million facets should not fit a plane, a cylinder, a cone and a sphere to it first.
    std::array<FitKind, 6> order;
    std::size_t n = 0;
    if (first) order[n++] = *first;
    for (const FitKind kind : kKindOrder)
        if (!first || kind != *first) order[n++] = kind;
    FitInput in = ps.input();
    in.accept = c.tol;
    // A large union that a strided sample of its points refuses is not fitted whole
    // (FitInput::refuse_rms): growing a 213k-facet torus stalls on unions with the cone beside
    // it, far off every kind, which were fitted kind by kind over all their points. Not for
    // callers that take the refused surfaces (`misses`) as starts: theirs are the whole fit's.
    if (!misses) in.refuse_rms = kSampleRefuseTolerances * c.tol;
    for (std::size_t i = 0; i < n; ++i) {
        const FitKind kind = order[i];
        if ((kinds & fit_kind_bit(kind)) == 0) continue;
        if (ps.points.size() < kMinVertices[static_cast<int>(kind)]) continue;
        FitResult r = fit(kind, in);
        if (!r.ok) continue;
        if (r.max <= c.tol && chords_agree(c, r.surface, faces, ruled_sag)) return r;
        if (misses) misses->push_back(r.surface);
    }
    return std::nullopt;
}

/// A region while segmenting: its faces and the surface they fit.
struct Draft {
    std::vector<std::uint32_t> faces;
    Surface surface;
    bool alive = true;
    std::int32_t surface_index = -1;  ///< given by SRE: never merged, never refined
    /// > 0: an analytic surface that replaced a B-spline (analytic_instead()), held to how
    /// closely that B-spline held the vertices (within the sag) rather than to the tolerance:
    /// never merged, refitted within the sag, grown by grow_loose().
    double loose = 0;
};

// ---------------------------------------------------------------------------------------------
// Facets method: patches, growing.

/// Smooth patches: components of the faces in `mask` joined across edges that are not sharp.
std::vector<std::vector<std::uint32_t>> smooth_patches(const Context& c,
                                                       const std::vector<std::uint8_t>& mask) {
    const std::size_t nf = c.m.num_faces();
    std::vector<std::uint32_t> parent;
    detail::resize_huge(parent, nf);
    std::iota(parent.begin(), parent.end(), 0u);
    const auto find = [&](std::uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (std::uint32_t f = 0; f < nf; ++f) {
        if (!mask[f]) continue;
        for (int i = 0; i < 3; ++i) {
            const std::uint32_t g = c.fd.adj[f][static_cast<std::size_t>(i)];
            if (g == kNone || g < f || !mask[g] ||
                c.sharp_edge[3 * f + static_cast<std::uint32_t>(i)])
                continue;
            const std::uint32_t a = find(f), b = find(g);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
    }
    std::vector<std::uint32_t> index;
    detail::assign_huge(index, nf, kNone);
    std::vector<std::vector<std::uint32_t>> patches;
    for (std::uint32_t f = 0; f < nf; ++f) {
        if (!mask[f]) continue;
        const std::uint32_t r = find(f);
        if (index[r] == kNone) {
            index[r] = static_cast<std::uint32_t>(patches.size());
            patches.emplace_back();
        }
        patches[index[r]].push_back(f);
    }
    return patches;
}

/// A region that is surely a plane: at least kFirmPlaneFacets facets with every vertex within a
/// kFirmPlaneShare of the tolerance of a plane (a machined plane's vertices lie on it to
/// rounding; a patch of a finely tessellated torus is flat within a quarter of the tolerance
/// over many facets, and must stay free to become the torus), and the facets that have a vertex
/// farther holding at most kFirmPlaneOffArea of its area: the rows of a fillet tangent to the
/// plane that lie within the tolerance of it, which growing takes. That plane is the region's
/// own, or where those rows pull it off the others by more than kFirmPlaneShare, the plane of
/// its facets nearest to it (the half by count). Before, NIST CTC 01 meshed to 92k facets grew
/// its top face into a nearly flat cylinder, and each union with one of that face's neighbours
/// was fitted as that cylinder, most to LM's 100 iterations: 3.4 s of merging, against 0.5 s.
/// On NIST CTC 03 meshed to 68k facets the rows held 1.2-3.4 % of six large planes' area.
bool firm_plane(Context& c, const Draft& d) {
    if (d.surface.kind != FitKind::kPlane || d.faces.size() < kFirmPlaneFacets) return false;
    double total = 0;
    for (const std::uint32_t f : d.faces) total += c.fd.area[f];
    const auto worst = [&](const Surface& s, std::uint32_t f) {
        double w = 0;
        for (int i = 0; i < 3; ++i)
            w = std::max(w, distance(s, c.m.position(c.m.vertex(fid(f), i))));
        return w;
    };
    const auto firm_on = [&](const Surface& s) {
        double off = 0;
        std::size_t on = 0;
        for (const std::uint32_t f : d.faces) {
            if (worst(s, f) <= kFirmPlaneShare * c.tol) {
                ++on;
                continue;
            }
            off += c.fd.area[f];
            if (off > kFirmPlaneOffArea * total) return false;
        }
        return on >= kFirmPlaneFacets;
    };
    if (firm_on(d.surface)) return true;
    std::vector<double> dist(d.faces.size());
    for (std::size_t k = 0; k < d.faces.size(); ++k) dist[k] = worst(d.surface, d.faces[k]);
    std::vector<double> sorted = dist;
    const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    std::nth_element(sorted.begin(), mid, sorted.end());
    std::vector<std::uint32_t> nearest;
    for (std::size_t k = 0; k < d.faces.size(); ++k)
        if (dist[k] <= *mid) nearest.push_back(d.faces[k]);
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, nearest, ps);
    const FitResult r = fit(FitKind::kPlane, ps.input());
    return r.ok && firm_on(r.surface);
}

/// The kind of a region large enough for it to be settled (tried first when refitting, see
/// fit_faces()); none for a smaller one, whose kind is chosen afresh, simplest first.
std::optional<FitKind> settled(const Draft& d) {
    if (d.faces.size() < kSettledFacets) return std::nullopt;
    return d.surface.kind;
}

/// A lone facet's strip of a coarsely meshed cylinder or cone (a CAD system's tessellation:
/// facets from rim to rim, NIST FTC 08's 3368-facet mesh has fillets in six such slivers, each
/// a plane of its own): the facets among `trial` after its first `fixed` (taken whole) that
/// have an edge parallel to the seed's longest within kStripParallel (with `fixed` the
/// region's own facets only), taken one at a time while `fit` takes them all and each has an
/// edge along a generator of the surface (has_generator(), within `near`). Returns the surface
/// and the faces taken, or nothing when no facet is taken.
template <class Fit>
std::optional<std::pair<FitResult, std::vector<std::uint32_t>>> strip_fit(
    const Context& c, std::span<const std::uint32_t> faces, std::span<const std::uint32_t> trial,
    std::size_t fixed, double near, const Fit& fit) {
    const std::uint32_t seed = faces.front();
    Vec3 dir{0, 0, 0};
    for (int i = 0; i < 3; ++i) {
        const Vec3 e = c.m.position(c.m.vertex(fid(seed), (i + 1) % 3)) -
                       c.m.position(c.m.vertex(fid(seed), i));
        if (norm(e) > norm(dir)) dir = e;
    }
    if (norm(dir) == 0) return std::nullopt;
    dir = normalized(dir);
    const bool own = fixed == faces.size();
    const auto parallel = [&](std::uint32_t f) {
        if (!own) return true;
        for (int i = 0; i < 3; ++i) {
            const Vec3 e =
                c.m.position(c.m.vertex(fid(f), (i + 1) % 3)) - c.m.position(c.m.vertex(fid(f), i));
            const double l = norm(e);
            if (l > 0 && std::abs(dot(e, dir)) / l >= std::cos(kStripParallel)) return true;
        }
        return false;
    };
    std::vector<std::uint32_t> taken(trial.begin(),
                                     trial.begin() + static_cast<std::ptrdiff_t>(fixed));
    std::optional<FitResult> best;
    std::vector<std::uint32_t> best_faces;
    std::vector<VertexId> points;
    for (std::size_t i = fixed; i < trial.size(); ++i) {
        const std::uint32_t f = trial[i];
        if (!parallel(f)) continue;
        taken.push_back(f);
        // Too few points for a cylinder yet: taken on trust only along the seed's own strip.
        if (own) {
            points.clear();
            for (const std::uint32_t g : taken)
                for (int k = 0; k < 3; ++k) points.push_back(c.m.vertex(fid(g), k));
            std::sort(points.begin(), points.end());
            points.erase(std::unique(points.begin(), points.end()), points.end());
            if (points.size() < kMinVertices[static_cast<int>(FitKind::kCylinder)]) continue;
        }
        auto r = fit(taken);
        bool ok = r && (r->surface.kind == FitKind::kCylinder || r->surface.kind == FitKind::kCone);
        for (std::size_t k = 0; ok && k < taken.size(); ++k)
            ok = has_generator(c, r->surface, taken[k], near);
        if (!ok) {
            taken.pop_back();
            continue;
        }
        best = std::move(r);
        best_faces = taken;
    }
    if (!best) return std::nullopt;
    return std::make_pair(std::move(*best), std::move(best_faces));
}

/// Grows the regions of one patch (see the header). `owner` and `mark` are per-face arrays
/// shared by all patches (patches are disjoint, so threads never touch the same entry).
std::vector<Draft> grow_patch(Context& c, const std::vector<std::uint32_t>& patch,
                              const std::vector<std::uint32_t>& patch_of,
                              std::vector<std::uint32_t>& owner, std::vector<std::uint32_t>& queued,
                              std::vector<std::uint32_t>& depth, std::uint32_t patch_id) {
    // Only this patch's entries of owner, queued and depth are read or written here.
    const auto in_patch = [&](std::uint32_t g) { return g != kNone && patch_of[g] == patch_id; };
    // Depth: edges from the patch's border, by breadth-first search; seeds deepest first.
    std::vector<std::uint32_t> queue;
    queue.reserve(patch.size());
    for (const std::uint32_t f : patch) {
        for (const std::uint32_t g : c.fd.adj[f]) {
            if (!in_patch(g)) {
                depth[f] = 0;
                queue.push_back(f);
                break;
            }
        }
    }
    if (queue.empty()) {  // a closed smooth surface: start anywhere
        depth[patch.front()] = 0;
        queue.push_back(patch.front());
    }
    for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::uint32_t f = queue[head];
        for (const std::uint32_t g : c.fd.adj[f]) {
            if (in_patch(g) && depth[g] == kNone) depth[g] = depth[f] + 1, queue.push_back(g);
        }
    }
    // Seeds: facets with fewer edges that turn (curved or sharp) first (inside planes, then inside
    // curved faces), deepest first among those: a seed on a face's border would take the first kind
    // that fits a few facets of two faces.
    const auto curved_edges = [&](std::uint32_t f) {
        int n = 0;
        for (int i = 0; i < 3; ++i)
            n += c.edge_turn[3 * f + static_cast<std::uint32_t>(i)] >= kFlatDihedral;
        return n;
    };
    std::vector<std::uint32_t> seeds = patch;
    std::stable_sort(seeds.begin(), seeds.end(), [&](std::uint32_t a, std::uint32_t b) {
        const int ca = curved_edges(a), cb = curved_edges(b);
        return ca != cb ? ca < cb : depth[a] > depth[b];
    });

    std::vector<Draft> drafts;
    std::vector<std::uint32_t> rejected;
    for (const std::uint32_t seed : seeds) {
        if (owner[seed] != kNone) continue;
        const std::uint32_t rid = static_cast<std::uint32_t>(drafts.size());
        Draft d;
        d.surface.kind = FitKind::kPlane;
        d.surface.point = c.fd.centroid[seed];
        d.surface.axis = c.fd.normal[seed];
        owner[seed] = rid;
        d.faces.push_back(seed);
        queue.clear();
        rejected.clear();
        const auto push_neighbours = [&](std::uint32_t f) {
            for (const std::uint32_t g : c.fd.adj[f]) {
                if (!in_patch(g) || owner[g] != kNone || queued[g] == rid) continue;
                queued[g] = rid;
                queue.push_back(g);
            }
        };
        push_neighbours(seed);
        std::size_t last_fit = 1;
        std::size_t head = 0;
        for (;;) {
            while (head < queue.size()) {
                const std::uint32_t f = queue[head++];
                if (owner[f] != kNone) continue;
                if (!facet_fits(c, d.surface, f)) {
                    rejected.push_back(f);
                    continue;
                }
                owner[f] = rid;
                d.faces.push_back(f);
                push_neighbours(f);
                if (d.faces.size() >= 2 * last_fit && d.faces.size() >= 16 &&
                    d.faces.size() <= kMaxGrowthRefit) {
                    // Refit as the region doubles: noise averages out, the kind may change.
                    if (auto r = fit_faces(c, d.faces, kRevolutionFitKinds, settled(d)))
                        d.surface = r->surface;
                    last_fit = d.faces.size();
                }
            }
            // Stalled: does one surface take the whole next ring too (or the next two: a few
            // facets have too few vertices for the richer kinds)?
            std::erase_if(rejected, [&](std::uint32_t f) { return owner[f] != kNone; });
            if (rejected.empty()) break;
            std::vector<std::uint32_t> trial = d.faces;
            trial.insert(trial.end(), rejected.begin(), rejected.end());
            // A firm plane keeps its kind: a flat torus would take in the plane and half the
            // fillet beside it. Curved regions may change kind however large (a patch of a
            // fine torus grows as a cylinder until the torus leaves it by the tolerance).
            const FitKindSet kinds =
                firm_plane(c, d) ? fit_kind_bit(d.surface.kind) : kRevolutionFitKinds;
            // As growing takes a facet (facet_fits()), a cylinder's or cone's chords may sag
            // more than the deflection where the facets' own edges say so (chords_agree()).
            const RuledSag ruled_sag =
                d.surface.kind != FitKind::kPlane || d.faces.size() <= kLooseFacets
                    ? RuledSag::kOwnEdges
                    : RuledSag::kDeflection;
            const auto ring_fit = [&](std::span<const std::uint32_t> t) {
                return fit_faces(c, t, kinds, settled(d), nullptr, ruled_sag);
            };
            auto r = ring_fit(trial);
            if (!r) {
                // The second ring: unassigned neighbours of the first, not yet queued.
                const std::size_t first = trial.size();
                for (std::size_t i = d.faces.size(); i < first; ++i) {
                    for (const std::uint32_t g : c.fd.adj[trial[i]]) {
                        if (!in_patch(g) || owner[g] != kNone || queued[g] == rid) continue;
                        queued[g] = rid;
                        trial.push_back(g);
                    }
                }
                if (trial.size() > first) r = ring_fit(trial);
                if (!r && d.faces.size() <= kLooseFacets && trial.size() > first) {
                    auto g = strip_fit(c, d.faces, trial, d.faces.size(), c.sag, ring_fit);
                    if (!g) g = strip_fit(c, d.faces, trial, first, c.tol, ring_fit);
                    if (g) {
                        r = std::move(g->first);
                        for (std::size_t i = d.faces.size(); i < trial.size(); ++i)
                            if (std::find(g->second.begin(), g->second.end(), trial[i]) ==
                                g->second.end())
                                queued[trial[i]] = kNone;
                        trial = std::move(g->second);
                    }
                }
                if (r) {
                    rejected.assign(trial.begin() + static_cast<std::ptrdiff_t>(d.faces.size()),
                                    trial.end());
                }
            }
            if (!r) break;
            d.surface = r->surface;
            for (const std::uint32_t f : rejected) {
                owner[f] = rid;
                d.faces.push_back(f);
                push_neighbours(f);
            }
            rejected.clear();
            last_fit = d.faces.size();
        }
        drafts.push_back(std::move(d));
    }
    return drafts;
}

// ---------------------------------------------------------------------------------------------
// Shared stages: merging, free-form groups, refining, final fits.

/// Region adjacency: pairs (a, b), a < b, sharing at least one edge; `smooth_only` keeps
/// pairs that share a non-sharp edge.
std::vector<std::pair<std::uint32_t, std::uint32_t>> adjacent_pairs(
    const Context& c, const std::vector<std::uint32_t>& region, bool smooth_only) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    const std::size_t nf = c.m.num_faces();
    for (std::uint32_t f = 0; f < nf; ++f) {
        for (int i = 0; i < 3; ++i) {
            const std::uint32_t g = c.fd.adj[f][static_cast<std::size_t>(i)];
            if (g == kNone || g < f) continue;
            if (smooth_only && c.sharp_edge[3 * f + static_cast<std::uint32_t>(i)]) continue;
            const std::uint32_t a = region[f], b = region[g];
            if (a == b || a == kNone || b == kNone) continue;
            pairs.emplace_back(std::min(a, b), std::max(a, b));
        }
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    return pairs;
}

/// Sorts a region's facet list as std::sort does, in linear time when the list is a few
/// sorted runs: two regions' lists one after the other, and the strays a region took since.
/// A large region takes hundreds of small neighbours one by one; sorting its whole list each
/// time cost the turned shaft meshed to 1.4M facets 13 of its 19 s of segmentation (perf).
void sort_facets(std::vector<std::uint32_t>& faces) {
    // More runs than this: a list in no particular order (a grown region's), sorted outright.
    constexpr std::size_t kMaxRuns = 8;
    std::vector<std::size_t> ends;  // where each sorted run ends
    for (auto it = faces.begin(); it != faces.end();) {
        it = std::is_sorted_until(it, faces.end());
        ends.push_back(static_cast<std::size_t>(it - faces.begin()));
        if (ends.size() > kMaxRuns) {
            std::sort(faces.begin(), faces.end());
            return;
        }
    }
    for (std::size_t i = 1; i < ends.size(); ++i) {
        const auto first = faces.begin();
        std::inplace_merge(first, first + static_cast<std::ptrdiff_t>(ends[i - 1]),
                           first + static_cast<std::ptrdiff_t>(ends[i]));
    }
}

std::vector<std::uint32_t> region_of_faces(const Mesh& m, const std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> region;
    detail::assign_huge(region, m.num_faces(), kNone);
    for (std::uint32_t r = 0; r < drafts.size(); ++r) {
        if (!drafts[r].alive) continue;
        for (const std::uint32_t f : drafts[r].faces) region[f] = r;
    }
    return region;
}

/// How alike two regions are (smaller: more alike): the largest distance of one's vertices to
/// the other's surface, the smaller of the two ways. With `thin` > 1, from every thin-th of
/// those facets only: a lower bound of the whole (a maximum over some of the same points).
double unlikeness(const Context& c, const Draft& a, const Draft& b, std::size_t thin = 1) {
    // At most kLikenessSamples facets of each, evenly strided: an order, not a test.
    const auto worst = [&](const Draft& from, const Surface& to) {
        double w = 0;
        const std::size_t step =
            std::max<std::size_t>(1, from.faces.size() / kLikenessSamples) * thin;
        for (std::size_t k = 0; k < from.faces.size(); k += step)
            for (int i = 0; i < 3; ++i)
                w = std::max(w, distance(to, c.m.position(c.m.vertex(fid(from.faces[k]), i))));
        return w;
    };
    return std::min(worst(a, b.surface), worst(b, a.surface));
}

/// The surface that fits `faces` but for a few strays, tried on each of `misses` (surfaces
/// the whole refused) in turn: the facets that do not fit one (facet_cost()) left out, worst
/// first, while they hold at most kStrayShare of the area, and its kind refitted to the rest.
/// `strays` receives the facets the refitted surface does not take back either.
std::optional<FitResult> fit_without_strays(Context& c, std::span<const std::uint32_t> faces,
                                            const std::vector<Surface>& misses,
                                            std::vector<std::uint32_t>& strays) {
    double total = 0;
    for (const std::uint32_t f : faces) total += c.fd.area[f];
    std::vector<std::pair<double, std::uint32_t>> cost;  // worst first
    std::vector<std::uint32_t> rest;
    for (const Surface& s : misses) {
        // The facets that miss the surface, worst first, while their area allows: a few
        // facets of a neighbour pull the whole fit off, and those of the region beside them
        // may miss it too by a little (they fit the refitted surface, which takes them back).
        cost.clear();
        for (const std::uint32_t f : faces) {
            const double k = facet_cost(c, s, f);
            if (k > c.tol) cost.emplace_back(k, f);
        }
        std::sort(cost.begin(), cost.end(), std::greater<>());
        strays.clear();
        double stray_area = 0;
        for (const auto& [k, f] : cost) {
            if (stray_area + c.fd.area[f] > kStrayShare * total) continue;
            strays.push_back(f);
            stray_area += c.fd.area[f];
        }
        if (strays.empty()) continue;
        std::sort(strays.begin(), strays.end());
        rest.clear();
        for (const std::uint32_t f : faces)
            if (!std::binary_search(strays.begin(), strays.end(), f)) rest.push_back(f);
        auto r = fit_faces(c, rest, fit_kind_bit(s.kind));
        if (!r) continue;
        std::erase_if(strays, [&](std::uint32_t f) { return facet_fits(c, r->surface, f); });
        return r;
    }
    strays.clear();
    return std::nullopt;
}

/// Merges adjacent regions that one analytic surface fits, most alike pair first (method.md
/// 3.6); the merged region keeps the larger one's index. Returns the number of merges. With
/// `fragments`, only pairs one of which lies within the tolerance of the other's surface
/// (unlikeness() at most the tolerance): the pass after border refinement, which must not
/// reopen what the first pass refused (FTC 08: a cylinder face beside its fillet, both taken
/// by one torus within the tolerance, the cylinder's vertices 4 x the tolerance off the
/// torus's own fit).
///
/// A union that one surface fits but for a few facets on its border (fit_without_strays())
/// merges too, those facets going to the neighbouring region that fits them best: a facet of
/// a corner patch that the growing took into a strip of a coarse fillet (it lies within the
/// tolerance of the strip's plane, not of the fillet's cylinder) would otherwise keep the
/// fillet in one plane per strip.
std::uint64_t merge_regions(Context& c, std::vector<Draft>& drafts, bool fragments = false) {
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    // Across sharp edges too (a coarse fillet's facets meet at more than the sharp angle): a
    // surface through the corners of two faces meeting at a crease (a prism's sides lie on
    // their circumscribed cylinder) is refused by the sag of their facets.
    const auto pairs = adjacent_pairs(c, region, false);
    std::vector<std::vector<std::uint32_t>> nbrs(drafts.size());
    for (const auto& [a, b] : pairs) nbrs[a].push_back(b), nbrs[b].push_back(a);
    std::vector<std::uint32_t> version(drafts.size(), 0);
    // (cost, a, b, their versions, whether the cost is exact or a lower bound).
    using Item =
        std::tuple<double, std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t, bool>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> pq;
    const auto mergeable = [&](std::uint32_t a) {
        return drafts[a].alive && drafts[a].surface_index < 0 && drafts[a].loose == 0 &&
               drafts[a].surface.kind != FitKind::kBSpline;
    };
    // A merge changes its region's pairs with all its neighbours, and a large region merges
    // many times before most of them come up: a pair is queued by a lower bound of its cost
    // (kLikenessBoundThin), its exact cost taken when it first reaches the top. A pair is
    // still taken only when no pair of smaller exact cost is left (all bounds behind it are
    // no smaller), so the order, ties included, is that of exact costs throughout.
    const auto push = [&](std::uint32_t a, std::uint32_t b) {
        if (a > b) std::swap(a, b);
        if (!mergeable(a) || !mergeable(b)) return;
        pq.emplace(unlikeness(c, drafts[a], drafts[b], kLikenessBoundThin), a, b, version[a],
                   version[b], false);
    };
    for (const auto& [a, b] : pairs) push(a, b);
    const auto union_of = [&](std::uint32_t a, std::uint32_t b) {
        std::vector<std::uint32_t> faces = drafts[a].faces;
        faces.insert(faces.end(), drafts[b].faces.begin(), drafts[b].faces.end());
        return faces;
    };
    // A much larger region keeps its kind (and may take a firm plane that is its chords: a
    // coarse cone's strip between two generators is exactly planar). Between regions of like
    // size a firm plane keeps its kind: a plane does not become a torus of large radius to take
    // in the fillet beside it, which the tolerance allows.
    const auto union_kinds = [&](std::uint32_t a, std::uint32_t b) {
        const std::size_t na = drafts[a].faces.size(), nb = drafts[b].faces.size();
        FitKindSet kinds = kRevolutionFitKinds;
        if (na >= kDominantRatio * nb) {
            kinds = fit_kind_bit(drafts[a].surface.kind);
        } else if (nb >= kDominantRatio * na) {
            kinds = fit_kind_bit(drafts[b].surface.kind);
        } else {
            if (firm_plane(c, drafts[a])) kinds = fit_kind_bit(drafts[a].surface.kind);
            if (firm_plane(c, drafts[b])) kinds &= fit_kind_bit(drafts[b].surface.kind);
        }
        return kinds;
    };
    // Whether the larger of a pair (the first of two alike in size) dominates a small neighbour
    // with at least kMaxGrowthRefit facets: a pair mostly decided on its surface, refitted only
    // when the neighbour lies neither far from it nor on it (below).
    const auto large_and_dominant = [&](std::uint32_t big, std::uint32_t small) {
        return drafts[big].faces.size() >= kDominantRatio * drafts[small].faces.size() &&
               drafts[big].faces.size() >= kMaxGrowthRefit;
    };
    const auto union_sag = [&](std::uint32_t a, std::uint32_t b) {
        return std::min(drafts[a].faces.size(), drafts[b].faces.size()) <= kLooseFacets
                   ? RuledSag::kTwice
                   : RuledSag::kDeflection;
    };
    // Most pairs that come up are refused, each after one or two refits of their union, and a
    // refit depends on nothing but the two regions as they are (their versions). So the next
    // pairs of the queue are fitted on all cores ahead of their turn (kFitAhead at a time), and
    // a pair takes its result when it comes up with both versions unchanged: the same results
    // in the same order as fitting each in turn (docs/benchmarks.md: the freeform die).
    struct Ahead {
        std::optional<FitResult> fit;
        std::vector<Surface> misses;
        bool without_strays_tried = false;
        std::optional<FitResult> without_strays;
        std::vector<std::uint32_t> strays;
    };
    using Key = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>;
    const auto key_of = [](const Item& it) {
        return Key{std::get<1>(it), std::get<2>(it), std::get<3>(it), std::get<4>(it)};
    };
    std::map<Key, Ahead> fitted_ahead;
    const auto fit_ahead = [&] {
        std::vector<Item> next;
        while (!pq.empty() && next.size() < kFitAhead) {
            const Item it = pq.top();
            const auto [cost, a, b, va, vb, exact] = it;
            if (!drafts[a].alive || !drafts[b].alive || version[a] != va || version[b] != vb) {
                pq.pop();  // stale: dropped when it came up, as now
                fitted_ahead.erase({a, b, va, vb});
                continue;
            }
            pq.pop();
            if (!exact) {  // its exact cost now, as when it came up (the same regions)
                pq.emplace(unlikeness(c, drafts[a], drafts[b]), a, b, va, vb, true);
                continue;
            }
            next.push_back(it);
        }
        // Fitted in batches: once the next pair's fit is missing, the missing ones of the next
        // kFitAhead together (one at a time would leave a core idle).
        const bool batch = !next.empty() && !fitted_ahead.count(key_of(next.front()));
        std::vector<Key> todo;
        for (const Item& it : next) {
            pq.push(it);
            if (!batch) continue;
            const Key key = key_of(it);
            if (fitted_ahead.count(key)) continue;
            // Not a pair with a large dominant region: mostly decided without its refit (an
            // expensive one), which then comes in turn.
            const auto [cost, a, b, va, vb, exact] = it;
            const bool a_larger = drafts[a].faces.size() >= drafts[b].faces.size();
            if (a_larger ? large_and_dominant(a, b) : large_and_dominant(b, a)) continue;
            todo.push_back(key);
        }
        if (todo.size() < 2) return;  // one: fitted in turn, as before
        std::vector<Ahead> done(todo.size());
        tbb::parallel_for(std::size_t{0}, todo.size(), [&](std::size_t k) {
            const auto [a, b, va, vb] = todo[k];
            const std::vector<std::uint32_t> faces = union_of(a, b);
            Ahead& d = done[k];
            d.fit =
                fit_faces(c, faces, union_kinds(a, b), std::nullopt, &d.misses, union_sag(a, b));
            if (!d.fit && !d.misses.empty()) {
                d.without_strays_tried = true;
                d.without_strays = fit_without_strays(c, faces, d.misses, d.strays);
            }
        });
        for (std::size_t k = 0; k < todo.size(); ++k)
            fitted_ahead.emplace(todo[k], std::move(done[k]));
    };
    std::uint64_t merges = 0;
    std::vector<Surface> misses;
    std::vector<std::uint32_t> strays;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> homes;  // (stray facet, its region)
    std::vector<std::uint32_t> orphans;                          // strays no neighbour takes
    std::vector<Draft> groups;                                   // ... as new regions
    while (!pq.empty()) {
        if (!fragments) {
            fit_ahead();
            if (pq.empty()) break;  // it found only stale pairs
        }
        const auto [cost, a, b, va, vb, exact] = pq.top();
        pq.pop();
        if (!drafts[a].alive || !drafts[b].alive || version[a] != va || version[b] != vb) continue;
        if (!exact) {
            pq.emplace(unlikeness(c, drafts[a], drafts[b]), a, b, va, vb, true);
            continue;
        }
        // Fragments: every pair left is one neither of whose surfaces takes the other.
        if (fragments && cost > c.tol) break;
        std::vector<std::uint32_t> faces = union_of(a, b);
        const std::size_t na = drafts[a].faces.size(), nb = drafts[b].faces.size();
        const FitKindSet kinds = union_kinds(a, b);
        misses.clear();
        homes.clear();
        groups.clear();
        const RuledSag ruled_sag = union_sag(a, b);
        std::optional<FitResult> r;
        // A dominant region of kMaxGrowthRefit facets or more (its surface known far better
        // than the tolerance: growing refits no larger region) and a small
        // neighbour: refitting the union costs the large region's every point (a fillet of 72k
        // facets met 138 one- and two-facet neighbours on the fillet block meshed to 345k
        // facets, and the pairs it refused came back each time it grew). The union's surface,
        // of the large one's kind, fits the large one's vertices within the tolerance as its
        // own surface does: a neighbour most of whose area lies far from that surface cannot
        // join (its far facets are no strays either: strays are never the better part of a
        // region), and one that lies on it as it is joins on it unfitted. (Not for smaller
        // regions: a drafted wall's narrow strips of NIST CTC 02 fit cones that their
        // neighbour strips move by more than 10 tolerances, 640 -> 708 faces.)
        const std::uint32_t big = na >= nb ? a : b, small = big == a ? b : a;
        if (!fragments && large_and_dominant(big, small)) {
            const Surface& sb = drafts[big].surface;
            double far_area = 0, small_area = 0;
            bool on = true;
            for (const std::uint32_t f : drafts[small].faces) {
                double worst = 0;
                for (int i = 0; i < 3; ++i)
                    worst = std::max(worst, distance(sb, c.m.position(c.m.vertex(fid(f), i))));
                small_area += c.fd.area[f];
                if (worst > kHopelessTolerances * c.tol) far_area += c.fd.area[f];
                on = on && worst <= c.tol;
            }
            if (2 * far_area >= small_area && small_area > 0) continue;
            if (on && chords_agree(c, sb, drafts[small].faces, ruled_sag)) {
                r.emplace();
                r->ok = true;
                r->surface = sb;
            }
        }
        // Its fit ahead, if any (taken out: an entry serves once, so the map stays small).
        std::optional<Ahead> ahead;
        if (const auto it = fitted_ahead.find({a, b, va, vb}); it != fitted_ahead.end()) {
            ahead = std::move(it->second);
            fitted_ahead.erase(it);
        }
        const bool known = ahead.has_value();
        if (!r && known) {
            r = std::move(ahead->fit);
            misses = std::move(ahead->misses);
        } else if (!r) {
            r = fit_faces(c, faces, kinds, std::nullopt, &misses, ruled_sag);
        }
        if (!r && fragments) {
            // A fragment joins its neighbour as it is when its facets are chords of the other's
            // surface: the union's fit holds the fans of a coarse fillet, which sag beyond the
            // deflection estimate (chord_fits()), to that estimate again. Across kinds only
            // when that surface has the fragment's corners no farther than its own does: a
            // strip of a large fillet grown as a cylinder lies on the fillet's torus to
            // rounding, while a torus took a cone strip of the M6 screw within the tolerance
            // only (the B-rep then built a valid solid 41 % short of its volume).
            const auto takes = [&](std::uint32_t from, std::uint32_t to) {
                const Surface& st = drafts[to].surface;
                const Surface& own = drafts[from].surface;
                double on_own = 0, on_to = 0;
                for (const std::uint32_t f : drafts[from].faces) {
                    if (!chord_fits(c, st, f, c.tol)) return false;  // (all facet_cost() takes too)
                    for (int i = 0; i < 3; ++i) {
                        const Vec3 p = c.m.position(c.m.vertex(fid(f), i));
                        on_own = std::max(on_own, distance(own, p));
                        on_to = std::max(on_to, distance(st, p));
                    }
                }
                return own.kind == st.kind || on_to <= on_own;
            };
            const std::uint32_t to = takes(b, a) ? a : takes(a, b) ? b : kNone;
            if (to != kNone) {
                r.emplace();
                r->ok = true;
                r->surface = drafts[to].surface;
            }
        }
        if (!r && !misses.empty()) {
            if (known && ahead->without_strays_tried) {
                r = std::move(ahead->without_strays);
                strays = std::move(ahead->strays);
            } else {
                r = fit_without_strays(c, faces, misses, strays);
            }
            // Strays are a few facets of one of the two, never the better part of either
            // (a region whose every facet fits elsewhere is not merged by leaving it out).
            double from_a = 0, from_b = 0, area_a = 0, area_b = 0;
            if (!strays.empty()) {  // (most refused unions have none: no sums for them)
                for (const std::uint32_t f : strays)
                    (region[f] == a ? from_a : from_b) += c.fd.area[f];
                for (const std::uint32_t f : drafts[a].faces) area_a += c.fd.area[f];
                for (const std::uint32_t f : drafts[b].faces) area_b += c.fd.area[f];
                if (2 * from_a >= area_a || 2 * from_b >= area_b) r.reset();
            }
            // Each stray goes to the neighbouring region (other than these two) that fits it
            // best. Those no neighbour takes (the corner beside them not yet fitted well) become
            // regions of their own, one per connected group, each fitted; with none, no merge.
            orphans.clear();
            for (const std::uint32_t f : strays) {
                if (!r) break;
                std::uint32_t best = kNone;
                double best_cost = kInf;
                for (const std::uint32_t g : c.fd.adj[f]) {
                    const std::uint32_t x = g == kNone ? kNone : region[g];
                    if (x == kNone || x == a || x == b || !mergeable(x)) continue;
                    const double fc = facet_cost(c, drafts[x].surface, f);
                    if (fc > c.tol) continue;
                    if (best == kNone || fc < best_cost || (fc == best_cost && x < best)) {
                        best = x;
                        best_cost = fc;
                    }
                }
                if (best == kNone) {
                    orphans.push_back(f);
                } else {
                    homes.emplace_back(f, best);
                }
            }
            std::sort(orphans.begin(), orphans.end());
            std::vector<std::uint8_t> taken(orphans.size(), 0);
            for (std::size_t i = 0; r && i < orphans.size(); ++i) {
                if (taken[i]) continue;
                Draft d;
                d.faces.push_back(orphans[i]);
                taken[i] = 1;
                for (std::size_t k = 0; k < d.faces.size(); ++k) {
                    for (const std::uint32_t g : c.fd.adj[d.faces[k]]) {
                        const auto it = std::lower_bound(orphans.begin(), orphans.end(), g);
                        if (it == orphans.end() || *it != g) continue;
                        const auto j = static_cast<std::size_t>(it - orphans.begin());
                        if (taken[j]) continue;
                        taken[j] = 1;
                        d.faces.push_back(g);
                    }
                }
                double group_area = 0;
                for (const std::uint32_t f : d.faces) group_area += c.fd.area[f];
                const auto fr = fit_faces(c, d.faces);
                if (!fr || group_area > kOrphanShare * (area_a + area_b)) {
                    r.reset();
                    break;
                }
                d.surface = fr->surface;
                groups.push_back(std::move(d));
            }
        }
        if (!r) continue;
        const bool keep_a = drafts[a].faces.size() >= drafts[b].faces.size();
        const std::uint32_t keep = keep_a ? a : b, gone = keep_a ? b : a;
        for (const std::uint32_t f : faces) region[f] = keep;
        for (const auto& [f, x] : homes) {
            std::erase(faces, f);
            region[f] = x;
            drafts[x].faces.push_back(f);
            ++version[x];
        }
        std::vector<std::uint32_t> born;  // the new regions of strays no neighbour took
        for (Draft& d : groups) {
            const auto id = static_cast<std::uint32_t>(drafts.size());
            for (const std::uint32_t f : d.faces) {
                std::erase(faces, f);
                region[f] = id;
            }
            drafts.push_back(std::move(d));
            version.push_back(0);
            nbrs.emplace_back();
            born.push_back(id);
        }
        sort_facets(faces);
        drafts[keep].faces = std::move(faces);
        drafts[keep].surface = r->surface;
        drafts[gone].alive = false;
        drafts[gone].faces.clear();
        ++version[keep];
        ++merges;
        std::vector<std::uint32_t> n = nbrs[keep];
        n.insert(n.end(), nbrs[gone].begin(), nbrs[gone].end());
        std::sort(n.begin(), n.end());
        n.erase(std::unique(n.begin(), n.end()), n.end());
        std::erase_if(n,
                      [&](std::uint32_t x) { return x == keep || x == gone || !drafts[x].alive; });
        nbrs[keep] = n;
        // (A stray's new region bordered one of the two through it: it is among these.)
        for (const std::uint32_t x : n) {
            std::replace(nbrs[x].begin(), nbrs[x].end(), gone, keep);
            std::sort(nbrs[x].begin(), nbrs[x].end());
            nbrs[x].erase(std::unique(nbrs[x].begin(), nbrs[x].end()), nbrs[x].end());
            push(keep, x);
        }
        // A region that took a stray has a new version: its other pairs again.
        std::vector<std::uint32_t> took;
        for (const auto& [f, x] : homes) took.push_back(x);
        std::sort(took.begin(), took.end());
        took.erase(std::unique(took.begin(), took.end()), took.end());
        for (const std::uint32_t x : took) {
            for (const std::uint32_t y : nbrs[x])
                if (y != keep) push(x, y);
        }
        for (const std::uint32_t id : born) {
            std::vector<std::uint32_t> around;
            for (const std::uint32_t f : drafts[id].faces)
                for (const std::uint32_t g : c.fd.adj[f])
                    if (g != kNone && region[g] != id && region[g] != kNone)
                        around.push_back(region[g]);
            std::sort(around.begin(), around.end());
            around.erase(std::unique(around.begin(), around.end()), around.end());
            nbrs[id] = around;
            for (const std::uint32_t x : around) {
                nbrs[x].insert(std::lower_bound(nbrs[x].begin(), nbrs[x].end(), id), id);
                push(id, x);
            }
        }
    }
    return merges;
}

/// The numbers that fix a surface: an analytic kind's parameters; a B-spline's pole heights over
/// its plane (a net), or its profile poles' two coordinates and the direction (an extrusion).
std::size_t free_parameters(const Surface& s) {
    if (s.kind != FitKind::kBSpline) return static_cast<std::size_t>(fit_parameters(s.kind));
    if (!s.bspline) return 0;
    const auto nu = static_cast<std::size_t>(s.bspline->num_u),
               nv = static_cast<std::size_t>(s.bspline->num_v);
    // A helical sweep: its profile's poles, the axis (4) and the pitch.
    if (s.bspline->helical) return 2 * nu + 5;
    return s.bspline->extruded ? 2 * nu + 2 : nu * nv;
}

/// The residuals of the vertices of `faces` from `s` (unweighted); `points` receives how many
/// vertices they are.
FitResult residuals_of(Context& c, std::span<const std::uint32_t> faces, const Surface& s,
                       double* points = nullptr) {
    PointSet own;
    c.gatherers.local().gather(c.m, c.fd, faces, own);
    if (points) *points = static_cast<double>(own.points.size());
    return residuals(s, FitInput{own.points, own.normals, {}});
}

/// Regions' free parameters together and the RMS residual of their vertices from their surfaces
/// (over `points` vertices).
struct Pieces {
    std::size_t parameters = 0;
    double rms = 0;
    double points = 0;
    /// With a region of `faces` on `s` too.
    void add(Context& c, std::span<const std::uint32_t> faces, const Surface& s) {
        parameters += free_parameters(s);
        double np = 0;
        const FitResult r = residuals_of(c, faces, s, &np);
        const double total = points + np;
        rms = total > 0 ? std::sqrt((rms * rms * points + r.rms * r.rms * np) / total) : 0;
        points = total;
    }
};
Pieces measure_pieces(Context& c, const std::vector<Draft>& drafts,
                      std::span<const std::uint32_t> pieces) {
    Pieces out;
    for (const std::uint32_t p : pieces) out.add(c, drafts[p].faces, drafts[p].surface);
    return out;
}

/// One B-spline for a group of pieces (`whole`: theirs together), held to the chordal
/// deflection with a net of at most kFreeformMaxPoles; `ok` false otherwise.
FitResult fit_group(Context& c, std::span<const std::uint32_t> faces, const Pieces& whole) {
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, faces, ps);
    // Unweighted: the smoothing term is scaled to the weights, and area weights (tiny
    // near dense borders) let the net drift there (0.46 against 0.036 on a coarse die).
    FitInput in{ps.points, ps.normals, {}};
    // An extrusion is held to kFreeformRms x the pieces' RMS (extrusion_pays()): its profile
    // gets the poles that takes, if it can...
    in.rms_goal = kFreeformRms * whole.rms;
    // ... and has fewer free parameters (2 per pole + 2) than they do.
    in.max_profile_poles =
        std::max(1, (static_cast<int>(std::min<std::size_t>(whole.parameters, 1u << 20)) - 3) / 2);
    // A net is taken with at most kFreeformMaxPoles (below): none larger is fitted.
    in.max_net_poles = kFreeformMaxPoles;
    // A large group that a strided sample of its points refuses is not fitted whole (as
    // fit_faces()): the fillet block at 950k facets is one group of 423k vertices, off every
    // net by an RMS of a millimetre.
    in.refuse_rms = kSampleRefuseTolerances * c.sag;
    FitResult r = fit_bspline(in, c.sag);
    if (r.ok &&
        (r.max > c.sag || r.surface.bspline->num_u * r.surface.bspline->num_v > kFreeformMaxPoles))
        r.ok = false;
    return r;
}

/// Whether an extrusion replaces its pieces. Not when its pieces say it in fewer numbers: a
/// chain of tangent analytic faces (the arcs and lines of a pocket's outline) is an extrusion
/// too, its profile of many poles. (A height field's net is held by kFreeformMaxPoles: analytic
/// pieces of a free-form face are few and large, and fewer numbers than its net.) Nor when it
/// describes the points less closely than its pieces (kFreeformRms x their RMS): a CAD mesh's
/// analytic faces lie on their surfaces to rounding, a free-form face's pieces only within the
/// tolerance (without this, NIST CTC 01 and 03 lose a chain of coarse fillets to one extrusion:
/// Segment.FindsTheFacesOfPrismaticCorpusParts). Unless it is kFreeformRms x closer than they
/// are: then it is the better description whatever its numbers (trimesh_featuretype's spline
/// wall meshed at 0.02 rad is 29 cylinder pieces, 127 numbers at an RMS of 0.0038 mm, and one
/// extrusion of 130 at 0.00076 mm; analytic pieces at rounding are never beaten so).
bool extrusion_pays(const FitResult& r, const Pieces& whole) {
    if (!(r.rms <= kFreeformRms * whole.rms)) return false;
    return free_parameters(r.surface) < whole.parameters || kFreeformRms * r.rms <= whole.rms;
}

/// How deep inside its surface a vertex on a chord may lie: the tessellation's own sag, the
/// deflection estimate without its factor (Context::sag is kSagFactor x the kSagQuantile
/// quantile of the curved edges' sags). A faceted cut's chord vertices lie at up to a quarter of
/// the estimate (crossed 12- to 120-sided bores: faceted_cut_test.cpp), the angle block's 0.4.
double chord_depth(const Context& c) { return c.sag / kSagFactor; }

/// A fit of a cylinder, cone or sphere to the vertices of `faces` that may lie inside it by up
/// to chord_depth(): the vertices more than the tolerance inside are left out of the
/// fit (refitted twice). A mesh made by booleans on faceted solids (a mesh-based NC simulator's,
/// a CSG modeller's) puts the vertices where a cut crosses another on the facets of the cutting
/// solid, not on its surface: on chords, which lie inside a circle (towards a cylinder's or
/// cone's axis, a sphere's center), never outside. `fit` has the distances of all the vertices;
/// `kept` is the largest of those fitted, `inside` the deepest of those left out (0 if none).
struct ChordFit {
    FitResult fit;
    double kept = 0;
    double inside = 0;
    /// How deep a vertex on a chord of it may lie: as deep as its own facets' chords go (the
    /// tessellation's sag on this surface), else chord_depth().
    double reach = 0;
};
std::optional<ChordFit> chord_fit(Context& c, FitKind kind, std::span<const std::uint32_t> faces) {
    if (kind != FitKind::kCylinder && kind != FitKind::kCone && kind != FitKind::kSphere)
        return std::nullopt;
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, faces, ps);
    const auto n = ps.points.size();
    if (n < kMinVertices[static_cast<int>(kind)]) return std::nullopt;
    const auto signed_distance = [&](const Surface& s, Vec3 p) {
        const Vec3 q = closest_point(s, p);
        return dot(p - q, normal_at(s, q));
    };
    std::vector<double> weights = ps.weights;
    FitResult r = fit(kind, ps.input());
    // Twice: the first fit, pulled inside by the chords' vertices, shows them less deep.
    for (int pass = 0; pass < 2 && r.ok; ++pass) {
        std::size_t kept = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const bool chord = signed_distance(r.surface, ps.points[i]) < -c.tol;
            weights[i] = chord ? 0.0 : ps.weights[i];
            kept += !chord;
        }
        if (kept < kMinVertices[static_cast<int>(kind)]) return std::nullopt;
        r = fit(kind, FitInput{ps.points, ps.normals, weights});
    }
    if (!r.ok) return std::nullopt;
    ChordFit out;
    out.fit = residuals(r.surface, FitInput{ps.points, ps.normals, {}});
    for (std::size_t i = 0; i < n; ++i) {
        const double d = signed_distance(r.surface, ps.points[i]);
        if (d < -c.tol)
            out.inside = std::max(out.inside, -d);
        else
            out.kept = std::max(out.kept, std::fabs(d));
    }
    // The reach: how deep this surface's own chords go, from the facets whose corners it keeps
    // (their edges' middles; a triangle's middle sags up to kChordMiddleFactor x as much).
    double own = 0;
    for (const std::uint32_t f : faces) {
        Vec3 p[3];
        bool on = true;
        for (int i = 0; i < 3; ++i) {
            p[i] = c.m.position(c.m.vertex(fid(f), i));
            on = on && signed_distance(r.surface, p[i]) >= -c.tol;
        }
        if (!on) continue;
        for (int i = 0; i < 3; ++i)
            own = std::max(own, -signed_distance(r.surface, 0.5 * (p[i] + p[(i + 1) % 3])));
    }
    out.reach = own > c.tol ? std::min(c.sag, kChordMiddleFactor * own) : chord_depth(c);
    return out;
}

/// An analytic surface for `faces` that holds their vertices at least as closely as their
/// B-spline `bspline` does, its facets its chords: then it is their surface, fewer numbers for
/// as good a description, and the name a machinist would give. Such a group broke into pieces
/// because its vertices stray from the analytic surface by more than the tolerance yet well
/// within the chordal deflection: a mesh made by booleans on faceted solids puts the vertices
/// of a cut on the facets, not on the surface (trimesh's angle block: a bore of radius 0.25 in,
/// its rim's vertices 8e-4 in inside it, its tessellation's sag 2e-3 in).
struct Analytic {
    FitResult fit;
    double bar = 0;  ///< the B-spline's largest distance from the vertices (or the tolerance)
};
std::optional<Analytic> analytic_instead(Context& c, const FitResult& bspline,
                                         std::span<const std::uint32_t> faces) {
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, faces, ps);
    const FitInput in = ps.input();
    const double bar = residuals(bspline.surface, FitInput{ps.points, ps.normals, {}}).max;
    for (const FitKind kind : kKindOrder) {
        if (ps.points.size() < kMinVertices[static_cast<int>(kind)]) continue;
        FitResult r = fit(kind, in);
        if (r.ok && r.max <= bar && chords_agree(c, r.surface, faces))
            return Analytic{std::move(r), std::max(bar, c.tol)};
    }
    // Or as closely but for vertices on chords of it, inside by at most the chordal deflection
    // (chord_fit()): a coarse faceted cut's (24 sides) pull a fit of them all further off than
    // the B-spline.
    for (const FitKind kind : kKindOrder) {
        const std::optional<ChordFit> cf = chord_fit(c, kind, faces);
        if (cf && cf->kept <= bar && cf->inside <= cf->reach &&
            chords_agree(c, cf->fit.surface, faces))
            return Analytic{cf->fit, std::max(bar, c.tol)};
    }
    return std::nullopt;
}

/// Groups of at least kFreeformMinPieces curved (non-plane) regions joined by smooth edges
/// that one B-spline of at most kFreeformMaxPoles fits (an extrusion: with fewer free
/// parameters than the pieces together, within kFreeformRms x their RMS) become one free-form
/// region. The
/// B-spline is held to the mesh's chordal deflection, not the tolerance: a free-form face is
/// known only as well as its tessellation samples it, and a net small enough to be a face
/// (not a copy of the mesh) cannot pass through every vertex of it.
std::uint64_t merge_freeform(Context& c, std::vector<Draft>& drafts) {
    const std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    const auto pairs = adjacent_pairs(c, region, true);
    const auto open = [&](std::uint32_t r) {
        return drafts[r].alive && drafts[r].surface_index < 0 && drafts[r].loose == 0 &&
               drafts[r].surface.kind != FitKind::kBSpline;
    };
    std::vector<std::uint32_t> parent(drafts.size());
    const auto find = [&](std::uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    const auto components = [&](const auto& member) {
        std::iota(parent.begin(), parent.end(), 0u);
        for (const auto& [a, b] : pairs) {
            if (!member(a) || !member(b)) continue;
            const std::uint32_t ra = find(a), rb = find(b);
            if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
        }
    };
    // The smoothly joined regions' areas; in them, a plane of at least kFreeformPlaneShare of
    // the area is a face of its own (a floor next to a tangent free-form wall), smaller ones
    // are pieces (a free-form face is flat within the tolerance here and there).
    const auto area = [&](std::uint32_t r) {
        double a = 0;
        for (const std::uint32_t f : drafts[r].faces) a += c.fd.area[f];
        return a;
    };
    components(open);
    std::vector<double> comp_area(drafts.size(), 0);
    for (std::uint32_t r = 0; r < drafts.size(); ++r)
        if (open(r)) comp_area[find(r)] += area(r);
    std::vector<std::uint8_t> piece(drafts.size(), 0);
    for (std::uint32_t r = 0; r < drafts.size(); ++r) {
        piece[r] = open(r) && (drafts[r].surface.kind != FitKind::kPlane ||
                               area(r) < kFreeformPlaneShare * comp_area[find(r)]);
    }
    const auto curved = [&](std::uint32_t r) { return piece[r] != 0; };
    components(curved);
    std::vector<std::vector<std::uint32_t>> groups(drafts.size());
    for (std::uint32_t r = 0; r < drafts.size(); ++r)
        if (curved(r)) groups[find(r)].push_back(r);
    std::uint64_t replaced = 0;
    for (const auto& g : groups) {
        if (g.size() < kFreeformMinPieces) continue;
        std::vector<std::uint32_t> faces;
        for (const std::uint32_t r : g)
            faces.insert(faces.end(), drafts[r].faces.begin(), drafts[r].faces.end());
        Pieces whole = measure_pieces(c, drafts, g);
        FitResult r = fit_group(c, faces, whole);
        if (!r.ok) continue;
        // Leftovers at a free-form face's rims (a few facets bridging it and its floor, grown
        // into a plane or a torus of their own) join the group through smooth edges but are no
        // chords of its surface: the group goes on without them, while they are a small part of
        // it (those of at most kSmallRegion facets are dissolved into their neighbours
        // afterwards, larger ones stay regions of their own).
        const double limit = 2 * c.sag;  // as chords_agree() for a B-spline
        std::vector<std::uint32_t> kept;
        std::size_t stray = 0;
        for (const std::uint32_t p : g) {
            const auto& pf = drafts[p].faces;
            const bool chords = std::none_of(pf.begin(), pf.end(), [&](std::uint32_t f) {
                return distance(r.surface, c.fd.centroid[f]) > limit;
            });
            if (chords)
                kept.push_back(p);
            else
                stray += pf.size();
        }
        if (stray > 0) {
            if (kept.size() < kFreeformMinPieces ||
                static_cast<double>(stray) >
                    kFreeformStrayShare * static_cast<double>(faces.size()))
                continue;
            faces.clear();
            for (const std::uint32_t p : kept)
                faces.insert(faces.end(), drafts[p].faces.begin(), drafts[p].faces.end());
        }
        if (!chords_agree(c, r.surface, faces)) continue;
        if (auto simple = analytic_instead(c, r, faces)) {
            std::sort(faces.begin(), faces.end());
            drafts[kept.front()].faces = std::move(faces);
            drafts[kept.front()].surface = simple->fit.surface;
            drafts[kept.front()].loose = simple->bar;
            for (std::size_t i = 1; i < kept.size(); ++i) {
                drafts[kept[i]].alive = false;
                drafts[kept[i]].faces.clear();
            }
            ++replaced;
            continue;
        }
        if (r.surface.bspline->extruded) {
            if (stray > 0) whole = measure_pieces(c, drafts, kept);
            if (!extrusion_pays(r, whole)) continue;
        }
        std::sort(faces.begin(), faces.end());
        drafts[kept.front()].faces = std::move(faces);
        drafts[kept.front()].surface = r.surface;
        for (std::size_t i = 1; i < kept.size(); ++i) {
            drafts[kept[i]].alive = false;
            drafts[kept[i]].faces.clear();
        }
        ++replaced;
    }
    return replaced;
}

/// Two axes this close to perpendicular (sine of the angle from 90 degrees) may carry the
/// fillets a corner torus joins: a vertical fillet round a pocket's corner and the floor fillet
/// beside it. CAD places them exactly; a fitted axis is off by a few thousandths.
constexpr double kCornerAxesSine = 0.01;
/// Cylinders whose axes are this close to parallel (sine of the angle), and planes whose
/// normals are this close to perpendicular to them, may be pieces of one wall extruded along a
/// spline outline (merge_loose_pieces()): as kCornerAxesSine, a fitted axis is off by a few
/// thousandths (the NIST crada plate's lettering: up to 0.002).
constexpr double kWallAxesSine = 0.01;

/// The torus where two fillets meet at a corner (see corner_surfaces()): about `a`'s axis, through
/// the point of it nearest `b`'s axis, its spine at the distance between the two axes, its tube
/// `b`'s radius. False when the axes are not perpendicular or meet.
bool corner_torus(const Surface& a, const Surface& b, Surface& out) {
    const Vec3 da = normalized(a.axis), db = normalized(b.axis);
    if (std::fabs(dot(da, db)) > kCornerAxesSine) return false;
    // The nearest points of the two lines: b's axis runs across a's, so the foot on a's axis
    // of b's is where a's axis meets the plane through b's axis normal to their common normal.
    const Vec3 n = cross(da, db);
    const double nn = dot(n, n);
    if (!(nn > 0)) return false;
    const Vec3 w = b.point - a.point;
    const double ta = dot(cross(w, db), n) / nn;  // along a's axis
    const Vec3 center = a.point + ta * da;
    const double spine = std::fabs(dot(w, n)) / std::sqrt(nn);
    if (!(spine > 0)) return false;
    out = Surface{};
    out.kind = FitKind::kTorus;
    out.point = center;
    out.axis = da;
    out.radius = spine;
    out.minor_radius = b.radius;
    return true;
}

/// The ball where two fillets of one radius meet, their axes crossing: about the crossing, of
/// their radius. False when the axes are near parallel, pass apart or the radii differ (by
/// more than `tol`).
bool corner_sphere(const Surface& a, const Surface& b, double tol, Surface& out) {
    const Vec3 da = normalized(a.axis), db = normalized(b.axis);
    const Vec3 n = cross(da, db);
    const double nn = dot(n, n);
    if (!(nn > kCornerAxesSine * kCornerAxesSine) || std::fabs(a.radius - b.radius) > tol)
        return false;
    const Vec3 w = b.point - a.point;
    if (std::fabs(dot(w, n)) / std::sqrt(nn) > tol) return false;
    const Vec3 pa = a.point + (dot(cross(w, db), n) / nn) * da;
    const Vec3 pb = b.point + (dot(cross(w, da), n) / nn) * db;
    out = Surface{};
    out.kind = FitKind::kSphere;
    out.point = 0.5 * (pa + pb);
    out.radius = 0.5 * (a.radius + b.radius);
    return true;
}

/// A corner torus between two fillets (a pocket's vertical corner fillet and its floor fillet)
/// is known from them: its axis the first's, its tube the second's, its spine as far from the
/// axis as the two axes are apart. A small piece of a torus fits many tori within the
/// tolerance, and the fillets, tangent to it, grow into it: NIST FTC 08's four corners (a
/// torus of radii 4.57 and 1.52) came back as a torus of 5.31 and 3.83 over half of each,
/// cylinders over the rest, and faces that failed. A curved region smoothly joined to two
/// cylinders whose axes are perpendicular takes the torus they make when every vertex of it
/// lies on that within the tolerance and its facets are chords of it; border refinement then
/// gives it back the facets the fillets took. Likewise a torus, sphere or cone region between
/// two fillets of one radius whose axes cross takes the ball they make (corner_sphere()).
void corner_surfaces(Context& c, std::vector<Draft>& drafts) {
    const std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    std::vector<std::vector<std::uint32_t>> nbrs(drafts.size());
    for (const auto& [a, b] : adjacent_pairs(c, region, true)) {
        nbrs[a].push_back(b);
        nbrs[b].push_back(a);
    }
    const auto cylinder = [&](std::uint32_t r) {
        return drafts[r].alive && drafts[r].surface.kind == FitKind::kCylinder;
    };
    PointSet ps;
    for (std::uint32_t t = 0; t < drafts.size(); ++t) {
        Draft& d = drafts[t];
        if (!d.alive || d.surface_index >= 0 || d.faces.empty() ||
            (d.surface.kind != FitKind::kTorus && d.surface.kind != FitKind::kSphere &&
             d.surface.kind != FitKind::kCone))
            continue;
        std::vector<std::uint32_t> cyl;
        for (const std::uint32_t n : nbrs[t])
            if (cylinder(n)) cyl.push_back(n);
        if (cyl.size() < 2) continue;
        c.gatherers.local().gather(c.m, c.fd, d.faces, ps);
        std::optional<FitResult> best;
        const auto consider = [&](bool made, const Surface& h) {
            if (!made) return;
            FitResult r = residuals(h, ps.input());
            if (!(r.max <= c.tol) || !chords_agree(c, h, d.faces)) return;
            if (!best || r.rms < best->rms) best = std::move(r);
        };
        for (std::size_t i = 0; i < cyl.size(); ++i) {
            for (std::size_t j = i + 1; j < cyl.size(); ++j) {
                const Surface& a = drafts[cyl[i]].surface;
                const Surface& b = drafts[cyl[j]].surface;
                Surface h;
                consider(corner_torus(a, b, h), h);  // about a's axis
                consider(corner_torus(b, a, h), h);  // about b's
                consider(corner_sphere(a, b, c.tol, h), h);
            }
        }
        if (best) d.surface = best->surface;
    }
}

/// Small regions whose facets each fit a neighbouring region's surface are dissolved into
/// them: the leftovers of growing where three faces meet (a facet of the fillet and one of the
/// corner torus, coplanar within the tolerance, grown together as a plane). So are a larger
/// region's small detached pieces (all but its largest piece, of at most kSmallRegion facets):
/// each piece becomes a face of its own in the B-rep, and on a fine mesh border refinement
/// leaves dozens of one- or two-facet pieces where fillets meet, too small for a face.
/// Returns the facets moved.
std::uint64_t absorb_small_regions(Context& c, std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    std::uint64_t moved = 0;
    bool changed = true;
    // Per facet, its piece (a component of its region across shared edges) this round.
    std::vector<std::uint32_t> piece(c.m.num_faces(), kNone);
    std::vector<std::uint32_t> stack, sizes;
    for (int round = 0; round < kAbsorbRounds && changed; ++round) {
        changed = false;
        for (std::uint32_t r = 0; r < drafts.size(); ++r) {
            Draft& d = drafts[r];
            if (!d.alive || d.surface_index >= 0) continue;
            // The facets to dissolve: all of a small region; a larger one's small pieces.
            std::vector<std::uint8_t> loose(d.faces.size(), 0);
            if (d.faces.size() <= kSmallRegion) {
                std::fill(loose.begin(), loose.end(), 1);
            } else {
                sizes.clear();
                for (const std::uint32_t f0 : d.faces) piece[f0] = kNone;
                for (const std::uint32_t f0 : d.faces) {
                    if (piece[f0] != kNone) continue;
                    const auto id = static_cast<std::uint32_t>(sizes.size());
                    sizes.push_back(0);
                    piece[f0] = id;
                    stack.assign(1, f0);
                    while (!stack.empty()) {
                        const std::uint32_t f = stack.back();
                        stack.pop_back();
                        ++sizes[id];
                        for (const std::uint32_t g : c.fd.adj[f]) {
                            if (g == kNone || region[g] != r || piece[g] != kNone) continue;
                            piece[g] = id;
                            stack.push_back(g);
                        }
                    }
                }
                if (sizes.size() < 2) continue;
                const auto largest = static_cast<std::uint32_t>(
                    std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
                bool any = false;
                for (std::size_t k = 0; k < d.faces.size(); ++k) {
                    const std::uint32_t p = piece[d.faces[k]];
                    loose[k] = p != largest && sizes[p] <= kSmallRegion;
                    any = any || loose[k];
                }
                if (!any) continue;
            }
            std::vector<std::uint32_t> kept;
            for (std::size_t k = 0; k < d.faces.size(); ++k) {
                const std::uint32_t f = d.faces[k];
                if (!loose[k]) {
                    kept.push_back(f);
                    continue;
                }
                std::uint32_t best = kNone;
                double best_cost = c.tol;
                // The neighbour across edge i, when the facet may join it that way: not across
                // a sharp edge unless the facet's normal agrees with the neighbour's surface, if
                // the facet is wider than the deflection (a narrower one's normal says nothing:
                // CTC 05's fan slivers on a fillet, 0.6 x the deflection wide). A coarse bore's
                // end cap (an octagon in six triangles, OCCT's TR12J housing) has its four ear
                // triangles' corners on the bore and their middles within twice the deflection;
                // they joined the bore across its rim (1.9 x the deflection wide), and the two
                // triangles left of the cap got no edge with it (20 caps, 20 fallbacks).
                const bool wide = narrowest_width(c, f) > c.sag;
                std::array<std::uint32_t, 3> joinable{kNone, kNone, kNone};
                for (std::size_t i = 0; i < 3; ++i) {
                    const std::uint32_t g = c.fd.adj[f][i];
                    if (g == kNone) continue;
                    const std::uint32_t other = region[g];
                    if (other == r || other == kNone || drafts[other].surface_index >= 0) continue;
                    if (wide && c.sharp_edge[3 * f + static_cast<std::uint32_t>(i)] &&
                        !normal_agrees(c, drafts[other].surface, f))
                        continue;
                    joinable[i] = other;
                }
                for (const std::uint32_t other : joinable) {
                    if (other == kNone) continue;
                    // No normal test across a smooth edge: the neighbour's surface is
                    // established, and the leftovers are often slivers, whose normals say
                    // nothing (see chords_agree()).
                    const double cost = facet_cost(c, drafts[other].surface, f, false);
                    if (cost <= best_cost) best_cost = cost, best = other;
                }
                // No neighbour takes it as a chord of the deflection: one whose surface has
                // the facet's corners and whose middle sags no more than a chord of its length
                // across that surface can (chord_fits()).
                for (const std::uint32_t other : joinable) {
                    if (best != kNone) break;
                    if (other != kNone && chord_fits(c, drafts[other].surface, f, c.tol))
                        best = other;
                }
                // Nor so: a B-spline neighbour, held to the deflection, not the tolerance (a
                // free-form face is known only as well as its tessellation samples it), takes
                // it as such a chord with its corners within the deflection (its middle then
                // within kMiddleSagFactor deflections, as chords_agree() holds a B-spline's). The
                // link rods' one-facet planes between a free-form face and its neighbours: corners
                // 0.0007-0.0010 mm off it, the tolerance 0.00056 mm, the deflection 0.0054 mm. Not
                // a loose analytic region's (held to the deflection too): OCCT's TR12J then had 40
                // faces on fallbacks for 11, a B-spline beside them as its facets.
                for (const std::uint32_t other : joinable) {
                    if (best != kNone) break;
                    if (other != kNone && drafts[other].surface.kind == FitKind::kBSpline &&
                        chord_fits(c, drafts[other].surface, f, c.sag))
                        best = other;
                }
                if (best == kNone) {
                    kept.push_back(f);
                    continue;
                }
                region[f] = best;
                drafts[best].faces.push_back(f);
                ++moved;
                changed = true;
            }
            d.faces = std::move(kept);
            if (d.faces.empty()) d.alive = false;
        }
    }
    return moved;
}

/// Whether border refinement refits `d`: a region of plane to torus fitted to the tolerance,
/// not one given by SRE.
bool refittable(const Draft& d) {
    return d.surface_index < 0 && d.loose <= 0 &&
           static_cast<std::size_t>(d.surface.kind) < std::size(kMinVertices);
}

/// The surface of `d`, its kind refitted to its facets, when that is exact for them (see
/// kExactShare) with its facets as chords; nothing otherwise, or for a region refining keeps as
/// it is (a B-spline, an analytic surface held to the sag, one given by SRE). A surface
/// between two sides of a tangent line refitted to what is left of it is still between them
/// unless it lost all of one side, and the link rods' analytic pieces of free-form faces,
/// refitted, took their neighbours' rows (7 fallbacks for 5).
std::optional<Surface> refit_same_kind(Context& c, const Draft& d) {
    if (!refittable(d)) return std::nullopt;
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, d.faces, ps);
    const FitInput in = ps.input();
    if (in.points.size() < kMinVertices[static_cast<int>(d.surface.kind)]) return std::nullopt;
    // A settled region (settled()) from its surface: a refinement pass moves facets on the
    // borders only, and fitting the fillet block's corner tori of 200k facets (at 950k) afresh
    // after each pass cost a quarter of refining (1.98 -> 1.44 s without). A smaller one afresh: a
    // few facets more or less can move its least squares to another minimum, which a refinement
    // from the old one would miss (the link rods' free-form pieces: a face and a fallback more when
    // all were refitted so).
    const FitResult r = settled(d) ? refit(d.surface, in) : fit(d.surface.kind, in);
    if (!r.ok || !(r.max <= c.tol) || !chords_agree(c, r.surface, d.faces)) return std::nullopt;
    if (!(r.rms <= kExactShare * c.tol)) return std::nullopt;
    return r.surface;
}

/// Moves border facets to the neighbouring region they fit clearly better, in passes: a pass
/// moves facets in rounds (all moves of a round decided before any is made, each moving
/// facets one row; the next round looks at the moved facets' neighbours only) until none
/// moves, then refits the regions that changed (refit_same_kind()). A move makes the facet's
/// cost lower by kMoveMargin of the tolerance, so a pass ends; the passes stop when no facet
/// moves or no refit changes a surface (at most kRefinePasses). After the first kRefineRounds
/// rounds facets move only onto exact surfaces (see the loop). A region grown across a tangent line
/// takes a surface between its two sides (a fillet's cylinder 0.02 mm thin reaching 1.4 mm into the
/// corner tori and a strip of the top plane on a fine mesh): its neighbours take back what
/// they fit better, and its surface refitted to the rest is the true one.
/// Returns the facets moved.
std::uint64_t refine_borders(Context& c, std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    const std::size_t nf = c.m.num_faces();
    std::uint64_t moved = 0;
    std::vector<std::uint32_t> look, target, next;
    std::vector<std::uint8_t> queued(nf, 0);
    for (int pass = 0; pass < kRefinePasses; ++pass) {
        std::vector<std::uint8_t> changed(drafts.size(), 0);
        int rounds = 0;
        // Per region, its RMS residual as a share of the tolerance (kInf: not refitted).
        std::vector<double> share(drafts.size(), kInf);
        tbb::parallel_for(std::size_t{0}, drafts.size(), [&](std::size_t r) {
            const Draft& d = drafts[r];
            if (!d.alive || d.faces.empty() || !refittable(d)) return;
            PointSet ps;
            c.gatherers.local().gather(c.m, c.fd, d.faces, ps);
            const FitResult fr = residuals(d.surface, ps.input());
            share[r] = fr.rms / c.tol;
        });
        std::vector<std::uint64_t> size(drafts.size(), 0);
        for (std::size_t r = 0; r < drafts.size(); ++r) size[r] = drafts[r].faces.size();
        std::uint64_t pass_moves = 0;
        look.resize(nf);
        std::iota(look.begin(), look.end(), 0u);
        while (!look.empty()) {
            // After kRefineRounds rounds, a facet moves only onto an exact surface that it lies
            // on, and not out of a region refining does not refit (a B-spline, a surface held
            // to the sag). Any surface fits the rows beyond its border within the tolerance for
            // a while, and a surface that is not exact reaches into its neighbour as far as it
            // is allowed to: on NIST CTC 02, one torus piece of a blend ring took 225 facets of
            // the next piece in 27 rounds, and the B-splines the ring became lost their edge
            // with the wall beside them (4 fallbacks, volume -0.04 %).
            const bool exact_only = pass > 0 || rounds >= kRefineRounds;
            ++rounds;
            target.assign(look.size(), kNone);
            tbb::parallel_for(
                tbb::blocked_range<std::size_t>(0, look.size(), 1024), [&](const auto& rng) {
                    for (std::size_t k = rng.begin(); k != rng.end(); ++k) {
                        const std::uint32_t f = look[k];
                        const std::uint32_t own = region[f];
                        if (own == kNone || drafts[own].surface_index >= 0) continue;
                        if (exact_only && !refittable(drafts[own])) continue;
                        std::uint32_t best = kNone;
                        double own_cost = -1, best_cost = kInf;
                        for (const std::uint32_t g : c.fd.adj[f]) {
                            if (g == kNone) continue;
                            const std::uint32_t other = region[g];
                            if (other == own || other == kNone || other == best ||
                                drafts[other].surface_index >= 0 ||
                                (exact_only && !(share[other] <= kExactShare)))
                                continue;
                            if (own_cost < 0) own_cost = facet_cost(c, drafts[own].surface, f);
                            const double cost = facet_cost(c, drafts[other].surface, f);
                            if (cost < best_cost) best_cost = cost, best = other;
                        }
                        if (best != kNone &&
                            best_cost <= (exact_only ? kExactShare * c.tol : c.tol) &&
                            best_cost + kMoveMargin * c.tol < own_cost)
                            target[k] = best;
                    }
                });
            next.clear();
            for (std::size_t k = 0; k < look.size(); ++k) {
                const std::uint32_t f = look[k];
                if (target[k] == kNone || size[region[f]] <= 1) continue;
                --size[region[f]];
                ++size[target[k]];
                changed[region[f]] = changed[target[k]] = 1;
                region[f] = target[k];
                ++pass_moves;
                for (const std::uint32_t g : c.fd.adj[f])
                    if (g != kNone && !queued[g]) queued[g] = 1, next.push_back(g);
            }
            std::sort(next.begin(), next.end());
            for (const std::uint32_t g : next) queued[g] = 0;
            look.swap(next);
        }
        moved += pass_moves;
        if (pass_moves == 0) break;
        for (Draft& d : drafts) d.faces.clear();
        for (std::uint32_t f = 0; f < nf; ++f)
            if (region[f] != kNone) drafts[region[f]].faces.push_back(f);
        if (pass + 1 == kRefinePasses) break;
        // Refitted in parallel, each region's surface its own (the same whatever the threads).
        std::vector<std::optional<Surface>> refits(drafts.size());
        tbb::parallel_for(std::size_t{0}, drafts.size(), [&](std::size_t r) {
            if (changed[r] && drafts[r].alive && !drafts[r].faces.empty())
                refits[r] = refit_same_kind(c, drafts[r]);
        });
        bool any = false;
        for (std::size_t r = 0; r < drafts.size(); ++r) {
            if (!refits[r]) continue;
            drafts[r].surface = *refits[r];
            any = true;
        }
        if (!any) break;
    }
    return moved;
}

/// The first kind in kKindOrder within the tolerance whose facets are its chords; `fallback`
/// when none is. No RMS contest between passing kinds (fit_simplest() has one): it turns a
/// plane that took in a facet of the fillet beside it into a torus.
FitResult select_kind(const Context& c, const FitInput& in, std::span<const std::uint32_t> faces,
                      const FitResult& fallback) {
    for (const FitKind kind : kKindOrder) {
        if (in.points.size() < kMinVertices[static_cast<int>(kind)]) continue;
        FitResult r = fit(kind, in);
        if (r.ok && r.max <= c.tol && chords_agree(c, r.surface, faces)) return r;
    }
    return fallback;
}

/// The final fit of a region: the simplest kind within the tolerance (method.md Step 4) among
/// plane to torus, else the surface it was grown with, refitted when it is a B-spline.
Region final_region(Context& c, const Draft& d, std::span<const SurfaceRecord> records) {
    Region out;
    out.surface_index = d.surface_index;
    out.facets = d.faces.size();
    for (const std::uint32_t f : d.faces) out.area += c.fd.area[f];
    PointSet ps;
    c.gatherers.local().gather(c.m, c.fd, d.faces, ps);
    const FitInput in = ps.input();
    if (d.surface_index >= 0) {
        out.fit =
            residuals(surface_from_record(records[static_cast<std::size_t>(d.surface_index)]), in);
    } else if (d.loose > 0) {
        // Its kind refitted, the vertices on chords left out (chord_fit()), as closely as it was
        // held; else to them all within the sag; else the surface as it was.
        const std::optional<ChordFit> chords = chord_fit(c, d.surface.kind, d.faces);
        if (chords && chords->kept <= d.loose && chords->inside <= chords->reach) {
            out.fit = chords->fit;
        } else {
            out.fit = fit(d.surface.kind, in);
            if (!out.fit.ok || !(out.fit.max <= c.sag)) out.fit = residuals(d.surface, in);
        }
    } else if (d.surface.kind == FitKind::kBSpline) {
        // The surface merge_freeform() fitted while it holds the region's vertices as it did
        // (refining the borders moves a few facets); refitted otherwise.
        // A thread's flank (merge_helical()) is no height field or extrusion: refitted as the
        // helical sweep it is.
        out.fit = residuals(d.surface, in);
        if (!(out.fit.max <= c.sag)) {
            const FitInput unweighted{ps.points, ps.normals, {}};
            FitResult again = d.surface.bspline && d.surface.bspline->helical
                                  ? fit_helical(unweighted, c.sag)
                                  : fit_bspline(unweighted, c.sag);
            if (again.ok) out.fit = std::move(again);
        }
    } else {
        // A settled region's own kind first (no four failed fits to a million facets of a
        // torus); otherwise the simplest kind afresh (a band of a cone grown from a few
        // facets that a sphere fitted is a cone).
        FitResult same;
        if (settled(d)) same = fit(d.surface.kind, in);
        if (same.ok && same.max <= c.tol && chords_agree(c, same.surface, d.faces))
            out.fit = std::move(same);
        else
            out.fit = select_kind(c, in, d.faces, residuals(d.surface, in));
    }
    out.within_tolerance =
        out.fit.ok &&
        out.fit.max <= (d.loose > 0 || out.fit.surface.kind == FitKind::kBSpline ? c.sag : c.tol);
    return out;
}

/// The noise of a segmentation: the RMS residual of its largest segmented analytic region within
/// the tolerance (a CAD tessellation's is rounding; a noisy mesh's is the noise, somewhat less
/// since the region kept only the vertices within the tolerance). A free-form face left in
/// analytic pieces shows their misfit here instead (see extrusion_pays()).
double noise_level(std::span<const Region> regions) {
    const Region* largest = nullptr;
    for (const Region& g : regions) {
        if (g.surface_index >= 0 || !g.within_tolerance || g.fit.surface.kind == FitKind::kBSpline)
            continue;
        if (largest == nullptr || g.facets > largest->facets) largest = &g;
    }
    return largest != nullptr ? largest->fit.rms : 0;
}

/// The live drafts (faces sorted), in the order of their first face.
std::vector<std::uint32_t> live_drafts(std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> order;
    for (std::uint32_t r = 0; r < drafts.size(); ++r) {
        if (drafts[r].alive && !drafts[r].faces.empty()) {
            sort_facets(drafts[r].faces);
            order.push_back(r);
        }
    }
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        return drafts[a].faces.front() < drafts[b].faces.front();
    });
    return order;
}

/// A facet of an extruded strip has its normal within this cosine of normal to the extrusion
/// direction: about 2.5 degrees, as fit_bspline() asks of the normals of an extrusion (a mean
/// squared cosine of 2e-3, kExtrusionNormals there). The pieces of the faces beside a link rods'
/// strip lean 10 degrees and more.
constexpr double kStripLean = 0.045;

/// Directions strip_direction() tries at most: each is checked against every facet, and a
/// strip's adjacent pairs all give about the same one (a component of a few dozen small pieces
/// has fewer pairs than this; a larger one is sampled evenly).
constexpr std::size_t kStripCandidates = 64;

/// The direction most of `faces`' area is normal to (within kStripLean), from the cross
/// products of the normals of pairs of adjacent facets among them (the axis a strip's facets
/// turn about; not the normals' least eigenvector, which the pieces beside the strip in the
/// same component tilt); none when no pair turns or no direction holds half the area.
std::optional<Vec3> strip_direction(const Context& c, std::span<const std::uint32_t> faces) {
    std::vector<Vec3> candidates;
    std::vector<std::uint32_t> member(faces.begin(), faces.end());
    std::sort(member.begin(), member.end());
    for (const std::uint32_t f : faces) {
        for (const std::uint32_t g : c.fd.adj[f]) {
            if (g == kNone || g < f || !std::binary_search(member.begin(), member.end(), g))
                continue;
            const Vec3 axis = cross(c.fd.normal[f], c.fd.normal[g]);
            if (norm(axis) > kFlatDihedral) candidates.push_back(normalized(axis));
        }
    }
    double total = 0;
    for (const std::uint32_t f : faces) total += c.fd.area[f];
    std::optional<Vec3> best;
    double best_area = 0.5 * total;
    const std::size_t stride = (candidates.size() + kStripCandidates - 1) / kStripCandidates;
    for (std::size_t i = 0; i < candidates.size(); i += stride) {
        const Vec3& e = candidates[i];
        double a = 0;
        for (const std::uint32_t f : faces)
            if (std::fabs(dot(c.fd.normal[f], e)) <= kStripLean) a += c.fd.area[f];
        if (a > best_area) {
            best_area = a;
            best = e;
        }
    }
    return best;
}

/// Free-form faces in many analytic pieces among exact analytic faces: merge_freeform() takes
/// a smooth component whole, and a free-form blend between fillets (NIST FTC 10: six tori and
/// three planes) or free-form faces tangent to each other round a part (link rods: 178
/// pieces) are no one height field. Here, on the final fits: pieces that are loose (RMS over
/// kLooseRms x the deflection: not an analytic face of the file) seed groups, largest first;
/// a group takes its smooth neighbours that are loose or small (at most kSmallRegion facets:
/// their fit says nothing), largest first, one by one while one B-spline (fit_group()) still
/// fits it all. The first loose neighbour it cannot take, once the group is one to keep (see
/// below; until then it grows on past it: NIST FTC 10's blend meshed at 139k facets met such
/// neighbours at two pieces, and came back as a B-spline and three tori), ends the group's
/// growth: a free-form face that one height field cannot cover (NIST CTC 02's blends, closed
/// rings round drafted walls, in 5-7 pieces each) comes back in a few B-splines, and a larger
/// free-form area (the link rods' faces, tangent to each other all round) in patches. Their borders
/// are tangent seams between two B-splines, whose edges go through points midway between the two
/// (docs/brep.md); until those, such a group stayed in pieces (growing on past a refused
/// neighbour made groups steep enough to fold their net, 19 fallbacks and 5.8 deflections off on
/// the link rods). With kFreeformMinPieces curved pieces (a few planes of a facet or two between
/// a fillet and its corner are no evidence: NIST FTC 07 lost the ends of fillets in strips to
/// B-splines) it becomes one region. Exact analytic faces
/// never join: a chain of fillets stays fillets. Returns the drafts that took a group.
std::vector<std::uint32_t> merge_loose_pieces(Context& c, std::vector<Draft>& drafts,
                                              const std::vector<Region>& fitted) {
    std::vector<std::uint32_t> merged;
    const auto open = [&](std::uint32_t r) {
        const Draft& d = drafts[r];
        return d.alive && !d.faces.empty() && d.surface_index < 0 && fitted[r].fit.ok &&
               fitted[r].fit.surface.kind != FitKind::kBSpline;
    };
    const auto seed = [&](std::uint32_t r) {
        return open(r) && fitted[r].fit.rms > kLooseRms * c.sag;
    };
    const auto member = [&](std::uint32_t r) {
        return seed(r) || (open(r) && drafts[r].faces.size() <= kSmallRegion);
    };
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t r = 0; r < drafts.size(); ++r)
        if (seed(r)) seeds.push_back(r);
    // A lone loose piece seeds no group; the strips below are looked for all the same.
    if (seeds.size() < 2) seeds.clear();
    const std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    std::vector<std::vector<std::uint32_t>> nbrs(drafts.size());
    for (const auto& [a, b] : adjacent_pairs(c, region, true)) {
        if (!member(a) || !member(b)) continue;
        nbrs[a].push_back(b);
        nbrs[b].push_back(a);
    }
    const auto larger = [&](std::uint32_t a, std::uint32_t b) {
        const std::size_t na = drafts[a].faces.size(), nb = drafts[b].faces.size();
        return na != nb ? na > nb : a < b;
    };
    std::sort(seeds.begin(), seeds.end(), larger);
    std::vector<std::uint8_t> taken(drafts.size(), 0);
    std::vector<std::uint32_t> mark(drafts.size(), kNone);  // last seed that met it
    const auto curved_in = [&](const std::vector<std::uint32_t>& group) {
        return static_cast<std::size_t>(std::count_if(
            group.begin(), group.end(),
            [&](std::uint32_t p) { return fitted[p].fit.surface.kind != FitKind::kPlane; }));
    };
    // Whether the group with n are pieces of one wall: cylinders about one direction (a wall
    // along a spline outline, in arcs) and planes along it.
    const auto wall_of = [&](const std::vector<std::uint32_t>& group, std::uint32_t n) {
        std::vector<std::uint32_t> all = group;
        all.push_back(n);
        const auto cylinder = std::find_if(all.begin(), all.end(), [&](std::uint32_t p) {
            return fitted[p].fit.surface.kind == FitKind::kCylinder;
        });
        if (cylinder == all.end()) return false;
        const Vec3 e = fitted[*cylinder].fit.surface.axis;
        return std::all_of(all.begin(), all.end(), [&](std::uint32_t p) {
            const Surface& sf = fitted[p].fit.surface;
            return sf.kind == FitKind::kCylinder ? norm(cross(e, sf.axis)) <= kWallAxesSine
                   : sf.kind == FitKind::kPlane  ? std::fabs(dot(e, sf.axis)) <= kWallAxesSine
                                                 : false;
        });
    };
    for (const std::uint32_t s : seeds) {
        if (taken[s] || nbrs[s].empty()) continue;
        std::vector<std::uint32_t> group{s}, frontier;
        mark[s] = s;
        const auto reach = [&](std::uint32_t r) {
            for (const std::uint32_t n : nbrs[r]) {
                if (taken[n] || mark[n] == s) continue;
                mark[n] = s;
                frontier.push_back(n);
            }
        };
        reach(s);
        std::vector<std::uint32_t> faces = drafts[s].faces;
        // The group's pieces together: their parameters, and the loosest one's RMS (what an
        // extrusion of them is held to, as merge_freeform() holds one to the pieces' RMS).
        Pieces whole{free_parameters(fitted[s].fit.surface), fitted[s].fit.rms};
        FitResult best;
        while (!frontier.empty()) {
            const auto it = std::min_element(frontier.begin(), frontier.end(), larger);
            const std::uint32_t n = *it;
            frontier.erase(it);
            std::vector<std::uint32_t> more = faces;
            more.insert(more.end(), drafts[n].faces.begin(), drafts[n].faces.end());
            const Pieces with{whole.parameters + free_parameters(fitted[n].fit.surface),
                              std::max(whole.rms, fitted[n].fit.rms)};
            // A group still too small to keep is held to the parameters of one that is, its
            // pieces' mean times kFreeformMinPieces: two tangent cylinders of a spline wall (10
            // numbers) leave a cubic profile 3 poles, none fits, and the group never grows to
            // the three pieces it takes to be kept. A group kept has passed the real count: its
            // last piece taken made it one to keep.
            const std::size_t curved_with =
                curved_in(group) + (fitted[n].fit.surface.kind != FitKind::kPlane ? 1 : 0);
            Pieces budget = with;
            if (curved_with < kFreeformMinPieces && wall_of(group, n))
                budget.parameters = with.parameters * kFreeformMinPieces / (group.size() + 1);
            FitResult r = fit_group(c, more, budget);
            if (r.ok && chords_agree(c, r.surface, more) &&
                (!r.surface.bspline->extruded || extrusion_pays(r, budget))) {
                group.push_back(n);
                whole = with;
                faces = std::move(more);
                best = std::move(r);
                reach(n);
            } else if (seed(n) && curved_in(group) >= kFreeformMinPieces) {
                // A loose neighbour it cannot take: grown as far as it goes. A group too small
                // to keep grows on past it instead; stopping would drop the group.
                break;
            }
        }
        if (curved_in(group) < kFreeformMinPieces) continue;
        const std::optional<Analytic> simple = analytic_instead(c, best, faces);
        std::sort(faces.begin(), faces.end());
        drafts[s].faces = std::move(faces);
        drafts[s].surface = simple ? simple->fit.surface : best.surface;
        drafts[s].loose = simple ? simple->bar : 0;
        for (const std::uint32_t p : group) {
            taken[p] = 1;
            if (p == s) continue;
            drafts[p].alive = false;
            drafts[p].faces.clear();
        }
        merged.push_back(s);
    }
    // Strips of small pieces no group took: a free-form face one facet across (the link rods'
    // walls between two tangent free-form faces, 20-25 facets in a row, each a plane of its own)
    // has no loose piece to seed it, its facets' planes fit them to rounding. Such a wall is
    // extruded: of a smooth component of small pieces, those whose facets are all normal to one
    // direction (strip_direction()) and chain together, at least kFreeformMinPieces of them,
    // that one B-spline fits (within the deflection, its facets its chords) are one region. The
    // pieces' own fits say nothing, so no RMS is asked of it, only fewer parameters than theirs.
    const auto small = [&](std::uint32_t r) {
        return !taken[r] && open(r) && drafts[r].faces.size() <= kSmallRegion;
    };
    const auto component = [&](std::uint32_t s, const auto& in, std::vector<std::uint8_t>& seen) {
        std::vector<std::uint32_t> group{s};
        seen[s] = 1;
        for (std::size_t i = 0; i < group.size(); ++i) {
            for (const std::uint32_t n : nbrs[group[i]]) {
                if (seen[n] || !in(n)) continue;
                seen[n] = 1;
                group.push_back(n);
            }
        }
        return group;
    };
    std::vector<std::uint8_t> seen(drafts.size(), 0), along(drafts.size(), 0),
        chained(drafts.size(), 0);
    for (std::uint32_t s = 0; s < drafts.size(); ++s) {
        if (seen[s] || !small(s)) continue;
        const std::vector<std::uint32_t> comp = component(s, small, seen);
        if (comp.size() < kFreeformMinPieces) continue;
        std::vector<std::uint32_t> comp_faces;
        for (const std::uint32_t p : comp)
            comp_faces.insert(comp_faces.end(), drafts[p].faces.begin(), drafts[p].faces.end());
        const std::optional<Vec3> e = strip_direction(c, comp_faces);
        if (!e) continue;
        for (const std::uint32_t p : comp) {
            const auto& pf = drafts[p].faces;
            along[p] = std::all_of(pf.begin(), pf.end(), [&](std::uint32_t f) {
                return std::fabs(dot(c.fd.normal[f], *e)) <= kStripLean;
            });
        }
        const auto in_strip = [&](std::uint32_t r) { return along[r] != 0; };
        // One strip's pieces in a row (a ring's too), by walking from one with the fewest strip
        // neighbours to the lowest-numbered unvisited neighbour; pieces off that walk (a branch)
        // are left for a row of their own.
        const auto in_a_row = [&](const std::vector<std::uint32_t>& group) {
            std::vector<std::uint32_t> row;
            std::vector<std::uint32_t> sorted = group;
            std::sort(sorted.begin(), sorted.end());
            const auto in_group = [&](std::uint32_t r) {
                return std::binary_search(sorted.begin(), sorted.end(), r);
            };
            const auto degree = [&](std::uint32_t r) {
                return std::count_if(nbrs[r].begin(), nbrs[r].end(), in_group);
            };
            std::uint32_t at = *std::min_element(sorted.begin(), sorted.end(),
                                                 [&](std::uint32_t a, std::uint32_t b) {
                                                     const auto da = degree(a), db = degree(b);
                                                     return da != db ? da < db : a < b;
                                                 });
            std::vector<std::uint8_t> walked(sorted.size(), 0);
            for (;;) {
                row.push_back(at);
                walked[static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), at) -
                                                sorted.begin())] = 1;
                std::uint32_t next = kNone;
                for (const std::uint32_t n : nbrs[at]) {
                    if (!in_group(n)) continue;
                    const auto k = static_cast<std::size_t>(
                        std::lower_bound(sorted.begin(), sorted.end(), n) - sorted.begin());
                    if (!walked[k]) next = std::min(next, n);
                }
                if (next == kNone) break;
                at = next;
            }
            return row;
        };
        // A run of the row as one region, when one B-spline takes it (see above); a run it does
        // not take in halves, each from kFreeformMinPieces pieces on: a closed wall round a boss
        // (trimesh's idler riser, 143 one-facet planes in a ring) is no height field whole.
        const auto take = [&](std::span<const std::uint32_t> run) {
            std::vector<std::uint32_t> faces;
            Pieces whole;
            for (const std::uint32_t p : run) {
                faces.insert(faces.end(), drafts[p].faces.begin(), drafts[p].faces.end());
                whole.parameters += free_parameters(fitted[p].fit.surface);
            }
            FitResult r = fit_group(c, faces, whole);
            if (!r.ok || !chords_agree(c, r.surface, faces)) return false;
            const std::optional<Analytic> simple = analytic_instead(c, r, faces);
            std::vector<std::uint32_t> group(run.begin(), run.end());
            std::sort(group.begin(), group.end());
            std::sort(faces.begin(), faces.end());
            drafts[group.front()].faces = std::move(faces);
            drafts[group.front()].surface = simple ? simple->fit.surface : r.surface;
            drafts[group.front()].loose = simple ? simple->bar : 0;
            for (const std::uint32_t p : group) {
                taken[p] = 1;
                if (p == group.front()) continue;
                drafts[p].alive = false;
                drafts[p].faces.clear();
            }
            merged.push_back(group.front());
            return true;
        };
        const auto take_runs = [&](const auto& self, std::span<const std::uint32_t> run) -> void {
            if (run.size() < kFreeformMinPieces || take(run)) return;
            if (run.size() < 2 * kFreeformMinPieces) return;
            const std::size_t half = run.size() / 2;
            self(self, run.first(half));
            self(self, run.subspan(half));
        };
        for (const std::uint32_t t : comp) {
            if (!along[t] || chained[t]) continue;
            std::vector<std::uint32_t> group = component(t, in_strip, chained);
            if (group.size() < kFreeformMinPieces) continue;
            while (!group.empty()) {
                const std::vector<std::uint32_t> row = in_a_row(group);
                take_runs(take_runs, row);
                std::vector<std::uint32_t> rest;
                for (const std::uint32_t p : group)
                    if (std::find(row.begin(), row.end(), p) == row.end()) rest.push_back(p);
                group = std::move(rest);
            }
        }
    }
    return merged;
}

/// The first region of `group` takes the others: their facets relabelled in `region`, they die,
/// and it has `faces` (sorted here) on `surface`.
void take_group(std::vector<Draft>& drafts, std::vector<std::uint32_t>& region,
                std::span<const std::uint32_t> group, std::vector<std::uint32_t> faces,
                const Surface& surface) {
    const std::uint32_t s = group.front();
    std::sort(faces.begin(), faces.end());
    for (std::size_t i = 1; i < group.size(); ++i) {
        for (const std::uint32_t f : drafts[group[i]].faces) region[f] = s;
        drafts[group[i]].alive = false;
        drafts[group[i]].faces.clear();
    }
    drafts[s].faces = std::move(faces);
    drafts[s].surface = surface;
}

/// Analytic pieces along a free-form face: a piece of a blend fits a cylinder, torus or cone of
/// its own within the tolerance where the tolerance is far below the deflection (the link
/// rods: 0.00056 mm against 0.0054), and merge_loose_pieces() groups such pieces into a new
/// B-spline but never gives one to a B-spline region already there. So a B-spline region
/// (largest first; not a thread's flank) takes its smoothly joined neighbours that are loose (a
/// final fit whose RMS is above kLooseRms x the deflection: one its surface does not hold to
/// rounding), lowest index first, while one B-spline refitted to them all holds them within the
/// deflection with their facets as its chords (fit_group(), as the groups are held) and the
/// piece's middles within the deflection. A region of kMaxGrowthRefit facets or more is not
/// refitted: its surface takes the piece as it is (vertices and middles within the deflection,
/// its chords) or not at all. Not a piece of one or two facets whose fit is exact: a coarse
/// mesh's small planar face beside a free-form one (shallow_freeform's, 46 facets in all) would
/// go. `changed`: the regions merge_loose_pieces() made, whose `fitted` fits are stale.
/// Returns the regions that grew.
std::vector<std::uint32_t> widen_freeform(Context& c, std::vector<Draft>& drafts,
                                          const std::vector<Region>& fitted,
                                          std::span<const std::uint32_t> changed) {
    std::vector<std::uint32_t> grown;
    std::vector<std::uint8_t> stale(drafts.size(), 0);
    for (const std::uint32_t r : changed) stale[r] = 1;
    const auto freeform = [&](std::uint32_t r) {
        const Draft& d = drafts[r];
        return d.alive && d.surface_index < 0 && d.surface.kind == FitKind::kBSpline &&
               d.surface.bspline && !d.surface.bspline->helical;
    };
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t r = 0; r < drafts.size(); ++r)
        if (freeform(r)) seeds.push_back(r);
    if (seeds.empty()) return grown;
    // Analytic as its final fit left it.
    const auto analytic = [&](std::uint32_t r) {
        const Draft& d = drafts[r];
        return d.alive && !stale[r] && d.surface_index < 0 && d.loose <= 0 && !d.faces.empty() &&
               d.surface.kind != FitKind::kBSpline && fitted[r].fit.ok &&
               fitted[r].fit.surface.kind != FitKind::kBSpline;
    };
    // A piece: analytic and loose.
    const auto piece = [&](std::uint32_t r) {
        return analytic(r) && fitted[r].fit.rms > kLooseRms * c.sag;
    };
    std::stable_sort(seeds.begin(), seeds.end(), [&](std::uint32_t a, std::uint32_t b) {
        return drafts[a].faces.size() > drafts[b].faces.size();
    });
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    std::vector<std::uint32_t> mark(drafts.size(), kNone);
    for (const std::uint32_t s : seeds) {
        if (!freeform(s)) continue;
        const bool large = drafts[s].faces.size() >= kMaxGrowthRefit;
        // The surface so far: the final fit's where it is the region's (it may have replaced
        // the draft's), else the draft's.
        Surface so_far = !stale[s] && fitted[s].fit.ok &&
                                 fitted[s].fit.surface.kind == FitKind::kBSpline &&
                                 fitted[s].facets == drafts[s].faces.size()
                             ? fitted[s].fit.surface
                             : drafts[s].surface;
        std::vector<std::uint32_t> faces = drafts[s].faces, group{s};
        std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> frontier;
        mark[s] = s;
        const auto reach = [&](std::span<const std::uint32_t> from) {
            for (const std::uint32_t f : from) {
                for (std::uint32_t i = 0; i < 3; ++i) {
                    const std::uint32_t g = c.fd.adj[f][i];
                    if (g == kNone || c.sharp_edge[3 * f + i]) continue;
                    const std::uint32_t n = region[g];
                    if (n == kNone || mark[n] == s || !(large ? analytic(n) : piece(n))) continue;
                    mark[n] = s;
                    frontier.push(n);
                }
            }
        };
        reach(faces);
        // The group's pieces together (measure_pieces(), kept as they grow: the seed's
        // points are measured once), for a refit.
        Pieces whole;
        if (!large) whole.add(c, faces, so_far);
        bool grew = false;
        while (!frontier.empty()) {
            const std::uint32_t n = frontier.top();
            frontier.pop();
            const auto& pf = drafts[n].faces;
            FitResult r;
            Pieces with = whole;
            if (large) {
                // A large region's surface is known far better than the deflection, and a refit
                // costs every one of its points (0.25 s for 29k facets of trimesh_featuretype's
                // spline wall, three times over). So it takes a piece as it is, or not at all:
                // a loose one within the deflection, an exact one within the tolerance, as an
                // analytic region holds its vertices (a band of a few rows fits a torus or cone
                // of its own to rounding: the end of that wall in seven such pieces, its vertices
                // within 0.005 mm of the wall, the tolerance 0.015 mm).
                const double hold = piece(n) ? c.sag : c.tol;
                if (farthest_corner(c, so_far, pf) > hold || !chords_agree(c, so_far, pf)) continue;
                r.ok = true;
                r.surface = so_far;
            } else {
                std::vector<std::uint32_t> more = faces;
                more.insert(more.end(), pf.begin(), pf.end());
                with.add(c, pf, drafts[n].surface);
                r = fit_group(c, more, with);
                if (!r.ok || !chords_agree(c, r.surface, more) ||
                    (r.surface.bspline->extruded && !extrusion_pays(r, with)))
                    continue;
            }
            // The piece's facets within the deflection at their middles too, not the twice a
            // B-spline's chords may sag: a net stretched over pieces at its border bulged
            // between their vertices (the link rods' solid 2.4 deflections from the mesh).
            // A large region's surface is its own, not stretched over the piece: its middles may
            // sag as far as that surface bends between their corners (bspline_chord_sag(); at
            // the wall's end its pieces' middles are 0.03-0.09 mm off it, the deflection
            // 0.015 mm).
            if (std::any_of(pf.begin(), pf.end(), [&](std::uint32_t f) {
                    const double d = distance(r.surface, c.fd.centroid[f]);
                    return d > c.sag && !(large && d <= bspline_chord_sag(c, r.surface, f));
                }))
                continue;
            so_far = r.surface;
            whole = with;
            grew = true;
            group.push_back(n);
            faces.insert(faces.end(), pf.begin(), pf.end());
            reach(pf);
        }
        if (!grew) continue;
        take_group(drafts, region, group, std::move(faces), so_far);
        grown.push_back(s);
    }
    return grown;
}

/// Adjacent regions of one kind (cylinder, cone, sphere) that one surface of that kind holds
/// within the tolerance (or as loosely as either was held) but for vertices on its chords
/// (chord_fit()) are one region, held so (Draft::loose): a faceted cut in pieces, each fitted
/// within the tolerance by a surface of its own and none by the cut's (a 48-sided cross bore of
/// radius 5 came as 12 pieces of radius 4.98 - 5.05). Most alike pairs first (unlikeness(),
/// within the chordal deflection), one merge per region per pass. Returns the regions that grew.
std::vector<std::uint32_t> merge_chords(Context& c, std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> grown;
    const auto curved = [&](std::uint32_t r) {
        const FitKind k = drafts[r].surface.kind;
        return k == FitKind::kCylinder || k == FitKind::kCone || k == FitKind::kSphere;
    };
    const auto open = [&](std::uint32_t r) {
        const Draft& d = drafts[r];
        return d.alive && d.surface_index < 0 && (curved(r) || d.surface.kind == FitKind::kPlane);
    };
    for (bool more = true; more;) {
        more = false;
        const std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
        // (cost, the curved one, the other): two of one kind, or a curved one and a plane (a
        // facet of the cutting solid beside the cut's crossing is exactly planar).
        std::vector<std::tuple<double, std::uint32_t, std::uint32_t>> queue;
        for (auto [a, b] : adjacent_pairs(c, region, false)) {
            if (!open(a) || !open(b)) continue;
            // Of two curved ones, the larger one's kind (a ball's pieces by a crossing bore
            // fit cylinders of their own within the tolerance).
            if (!curved(a) || (curved(b) && drafts[b].faces.size() > drafts[a].faces.size()))
                std::swap(a, b);
            if (!curved(a)) continue;
            const double cost = unlikeness(c, drafts[a], drafts[b]);
            if (cost <= c.sag) queue.emplace_back(cost, a, b);
        }
        std::sort(queue.begin(), queue.end());
        std::vector<std::uint8_t> touched(drafts.size(), 0);
        for (const auto& [cost, a, b] : queue) {
            if (touched[a] || touched[b]) continue;
            std::vector<std::uint32_t> both = drafts[a].faces;
            both.insert(both.end(), drafts[b].faces.begin(), drafts[b].faces.end());
            const double bar = std::max({c.tol, drafts[a].loose, drafts[b].loose});
            const std::optional<ChordFit> cf = chord_fit(c, drafts[a].surface.kind, both);
            // Only a union that vertices on chords keep apart: one the merging refused for
            // other reasons stays refused (a cone of 5 facets took two one-facet planes of
            // the AP242 FTC 08 mesh, and its solid lost 0.1 % of its volume).
            if (!cf || cf->inside == 0 || cf->kept > bar || cf->inside > cf->reach ||
                !chords_agree(c, cf->fit.surface, both))
                continue;
            const bool keep_a = drafts[a].faces.size() >= drafts[b].faces.size() ||
                                drafts[b].surface.kind == FitKind::kPlane;
            const std::uint32_t keep = keep_a ? a : b, gone = keep_a ? b : a;
            std::sort(both.begin(), both.end());
            drafts[keep].faces = std::move(both);
            drafts[keep].surface = cf->fit.surface;
            drafts[keep].loose = bar;
            drafts[gone].alive = false;
            drafts[gone].faces.clear();
            touched[keep] = touched[gone] = 1;
            grown.push_back(keep);
            more = true;
        }
    }
    std::erase_if(grown, [&](std::uint32_t r) { return !drafts[r].alive; });
    return grown;
}

/// The number of distinct vertices of `faces`.
std::size_t point_count(const Context& c, std::span<const std::uint32_t> faces) {
    std::vector<std::uint32_t> v;
    v.reserve(3 * faces.size());
    for (const std::uint32_t f : faces)
        for (int i = 0; i < 3; ++i) v.push_back(c.m.vertex(fid(f), i).idx());
    std::sort(v.begin(), v.end());
    return static_cast<std::size_t>(std::unique(v.begin(), v.end()) - v.begin());
}

/// Fans: a coarse cylinder or cone face as a CAD system tessellates it, one row of facets from
/// rim to rim with its two rims divided unevenly, comes as one-facet planes, with perhaps a
/// small cylinder or cone among them. Few of its facets have an edge along a generator
/// (strip_fit() grows on those), neighbours turn by up to 45 degrees (growing stops at sharp
/// edges), and merging goes pair by pair while a cylinder needs kMinVertices (6) vertices, four
/// facets of a fan: the AP242 mesh of NIST FTC 08 had 167 one-facet planes, every one on a
/// cylinder or a B-spline face. So a seed (a cylinder or cone region, largest first, then a
/// small region) takes its small neighbours (a facet, or a cylinder or cone of at most
/// kFanPieceFacets), across any edge and lowest index first, while a cylinder or cone fits the
/// union within the tolerance with its facets as chords (fit_faces()). A small seed takes them
/// on trust until a cone could be fitted (7 vertices), and keeps nothing no fit has taken (but
/// a fan of three facets, which a cylinder fits with its normals for the spare data). A
/// two-facet plane is never a member: a prism's sides lie on their circumscribed cylinder, and a
/// many-sided one's sides sag less than the deflection; a planar face of a CAD tessellation is
/// rarely one facet. Returns the regions that grew.
std::vector<std::uint32_t> merge_fans(Context& c, std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> grown;
    const auto ruled = [&](std::uint32_t r) {
        const Draft& d = drafts[r];
        return d.alive && d.surface_index < 0 && d.loose == 0 &&
               (d.surface.kind == FitKind::kCylinder || d.surface.kind == FitKind::kCone);
    };
    // A member: a one-facet region, or a small cylinder or cone (a fan's piece that merging
    // made before the rest of the fan was there to join).
    const auto small = [&](std::uint32_t r) {
        const Draft& d = drafts[r];
        return d.alive && d.surface_index < 0 && d.loose == 0 &&
               (d.faces.size() == 1 || (d.faces.size() <= kFanPieceFacets && ruled(r)));
    };
    std::vector<std::uint32_t> seeds, smalls;
    for (std::uint32_t r = 0; r < drafts.size(); ++r) {
        if (small(r))
            smalls.push_back(r);
        else if (ruled(r))
            seeds.push_back(r);
    }
    // (Most meshes have no small region left: no region map, no pass over the seeds.)
    if (smalls.empty()) return grown;
    std::stable_sort(seeds.begin(), seeds.end(), [&](std::uint32_t a, std::uint32_t b) {
        return drafts[a].faces.size() > drafts[b].faces.size();
    });
    seeds.insert(seeds.end(), smalls.begin(), smalls.end());
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    constexpr FitKindSet kRuled = fit_kind_bit(FitKind::kCylinder) | fit_kind_bit(FitKind::kCone);
    constexpr std::size_t kConeVertices = kMinVertices[static_cast<int>(FitKind::kCone)];
    std::vector<std::uint32_t> mark(drafts.size(), kNone);  // the last seed that met it
    for (const std::uint32_t s : seeds) {
        if (!drafts[s].alive) continue;
        const bool trusting = small(s);
        const std::optional<FitKind> first =
            ruled(s) ? std::optional<FitKind>(drafts[s].surface.kind) : std::nullopt;
        std::vector<std::uint32_t> faces = drafts[s].faces, group{s};
        // Lowest index first: the same order whatever the threads.
        std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> frontier;
        mark[s] = s;
        const auto reach = [&](std::span<const std::uint32_t> from) {
            for (const std::uint32_t f : from) {
                for (const std::uint32_t g : c.fd.adj[f]) {
                    if (g == kNone) continue;
                    const std::uint32_t n = region[g];
                    if (n == kNone || mark[n] == s || !small(n)) continue;
                    mark[n] = s;
                    frontier.push(n);
                }
            }
        };
        reach(faces);
        std::optional<FitResult> last;  // the fit of `faces`, once one took them
        // The surface so far: none while on trust.
        const auto current = [&]() -> const Surface* {
            return last ? &last->surface : trusting ? nullptr : &drafts[s].surface;
        };
        // The candidate's farthest vertex from the surface so far (0 with none).
        const auto off = [&](std::uint32_t n) {
            const Surface* sf = current();
            return sf ? farthest_corner(c, *sf, drafts[n].faces) : 0.0;
        };
        while (!frontier.empty()) {
            const std::uint32_t n = frontier.top();
            frontier.pop();
            // No refit for a candidate far off the surface (as merge_regions() refuses one), nor
            // for one a large region's surface takes as it is: that surface is known far better
            // than the tolerance, and each refit would cost every one of its points.
            const double worst = off(n);
            if (worst > kHopelessTolerances * c.tol) continue;
            const auto& nf = drafts[n].faces;
            std::optional<FitResult> r;
            bool trusted = false;
            if (faces.size() >= kMaxGrowthRefit && current()) {
                if (worst > c.tol || !chords_agree(c, *current(), nf)) continue;
                r.emplace();
                r->ok = true;
                r->surface = *current();
            } else {
                std::vector<std::uint32_t> more = faces;
                more.insert(more.end(), nf.begin(), nf.end());
                r = fit_faces(c, more, kRuled, first);
                // (A small seed's trusted facets that nothing fits keep it from growing.)
                trusted = !r && !last && trusting && point_count(c, more) < kConeVertices;
            }
            if (r)
                last = std::move(r);
            else if (!trusted)
                continue;
            group.push_back(n);
            faces.insert(faces.end(), nf.begin(), nf.end());
            reach(nf);
        }
        // A fan of three facets (a fillet from rim to rim in three slivers) has five vertices,
        // one fewer than a cylinder needs for a spare one: any five points fit some cylinder.
        // What tests it then is the facets: their middles within the deflection and their
        // normals across its axis (within kStripLean, as an extrusion's), which a fan's
        // slivers along the axis have and a corner's facets do not. The AP242 FTC 08 mesh's
        // fillets of 3.048 mm, 42 mm long, come out at 3.048 mm.
        if (!last && trusting && faces.size() == 3 &&
            point_count(c, faces) == kMinVertices[static_cast<int>(FitKind::kCylinder)] - 1) {
            PointSet ps;
            c.gatherers.local().gather(c.m, c.fd, faces, ps);
            FitInput in = ps.input();
            in.accept = c.tol;
            FitResult r = fit(FitKind::kCylinder, in);
            const bool across = std::all_of(faces.begin(), faces.end(), [&](std::uint32_t f) {
                return std::abs(dot(c.fd.normal[f], r.surface.axis)) <= kStripLean;
            });
            if (r.ok && r.max <= c.tol && across && chords_agree(c, r.surface, faces))
                last = std::move(r);
        }
        // On trust only while nothing fitted: `last` took every facet, if any fit did.
        if (!last) continue;
        take_group(drafts, region, group, std::move(faces), last->surface);
        grown.push_back(s);
    }
    return grown;
}

/// Each loose region (an analytic surface held to the sag: analytic_instead()) takes the
/// neighbours across smooth edges that its kind, refitted to both, holds as closely as it held
/// its own vertices (or within the tolerance), their facets its chords: the rest of a bore whose
/// rim strays, grown apart from it within the tolerance (trimesh's angle block: its bore in two
/// faces, 95 and 13 facets). Returns the regions that grew.
std::vector<std::uint32_t> grow_loose(Context& c, std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> grown;
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    for (std::uint32_t l = 0; l < drafts.size(); ++l) {
        Draft& d = drafts[l];
        if (!d.alive || d.loose == 0) continue;
        bool grew = false;
        for (bool more = true; more;) {
            more = false;
            // Its neighbours across smooth edges, in order.
            std::vector<std::uint32_t> nbrs;
            for (const std::uint32_t f : d.faces) {
                for (int i = 0; i < 3; ++i) {
                    const std::uint32_t g = c.fd.adj[f][static_cast<std::size_t>(i)];
                    if (g == kNone || c.sharp_edge[3 * f + static_cast<std::uint32_t>(i)]) continue;
                    if (region[g] != l && region[g] != kNone) nbrs.push_back(region[g]);
                }
            }
            std::sort(nbrs.begin(), nbrs.end());
            nbrs.erase(std::unique(nbrs.begin(), nbrs.end()), nbrs.end());
            for (const std::uint32_t n : nbrs) {
                const Draft& e = drafts[n];
                // (A free-form piece too: a bit of a faceted ball beside a crossing bore, 22
                // facets, fits a sphere of its own only 1.2 x as loosely as its B-spline.)
                if (!e.alive || e.surface_index >= 0) continue;
                std::vector<std::uint32_t> both = d.faces;
                both.insert(both.end(), e.faces.begin(), e.faces.end());
                // As closely as the region was held, but for vertices on chords; or as the
                // surface that replaced the B-spline did (analytic_instead()).
                FitResult r;
                if (const auto cf = chord_fit(c, d.surface.kind, both);
                    cf && cf->kept <= d.loose && cf->inside <= cf->reach) {
                    r = cf->fit;
                } else {
                    PointSet bs;
                    c.gatherers.local().gather(c.m, c.fd, both, bs);
                    r = fit(d.surface.kind, bs.input());
                    if (!r.ok || r.max > d.loose) continue;
                }
                if (!chords_agree(c, r.surface, both)) continue;
                for (const std::uint32_t f : e.faces) region[f] = l;
                std::sort(both.begin(), both.end());
                d.faces = std::move(both);
                d.surface = r.surface;
                drafts[n].alive = false;
                drafts[n].faces.clear();
                grew = more = true;
            }
        }
        if (grew) grown.push_back(l);
    }
    return grown;
}

/// Facet f moved along a helical sweep's screw motion (fit_helical()) to the middle of the
/// angles its surface spans, from the turn whose profile heights its middle lies at (`turn`
/// 0) or the next one towards it (1): the sweep is invariant under the motion, so the moved
/// facet's distances to the surface are the facet's to the sweep unbounded along its helix.
struct MovedFacet {
    std::array<Vec3, 3> corners;
    Vec3 middle, normal;
};
MovedFacet along_helix(const Context& c, const BSplineSurface::Helix& hx, std::uint32_t f,
                       int turn) {
    constexpr double kTwoPi = 2 * std::numbers::pi;
    double theta = 0;
    const double turns = hx.turns(c.fd.centroid[f], theta);
    const double k =
        turn == 0 ? std::round(turns) : std::round(turns) + (turns > std::round(turns) ? 1 : -1);
    const double d = 0.5 * (hx.a0 + hx.a1) - (theta + kTwoPi * k);
    const double cd = std::cos(d), sd = std::sin(d);
    const auto rotate = [&](Vec3 v) {
        return v * cd + cross(hx.axis, v) * sd + hx.axis * (dot(hx.axis, v) * (1 - cd));
    };
    const auto move = [&](Vec3 p) {
        return hx.origin + rotate(p - hx.origin) + hx.axis * (hx.pitch * d);
    };
    MovedFacet out;
    for (int i = 0; i < 3; ++i)
        out.corners[static_cast<std::size_t>(i)] = move(c.m.position(c.m.vertex(fid(f), i)));
    out.middle = move(c.fd.centroid[f]);
    out.normal = rotate(c.fd.normal[f]);
    return out;
}

/// Whether facet f lies on the helical sweep s unbounded along its helix: corners within the
/// tolerance, middle within kMiddleSagFactor deflections, normal within kSegmentNormalAngle of
/// the surface's at the middle (facet_fits() without normal_agrees()'s allowance for large fan
/// triangles, which a flank's rows are not).
bool fits_along_helix(const Context& c, const Surface& s, std::uint32_t f) {
    if (!s.bspline || !s.bspline->helical || !(s.bspline->helix.pitch != 0)) return false;
    const BSplineSurface::Helix& hx = s.bspline->helix;
    for (const int turn : {0, 1}) {
        const MovedFacet mf = along_helix(c, hx, f, turn);
        bool on = true;
        for (const Vec3& p : mf.corners) on = on && distance(s, p) <= c.tol;
        if (on && distance(s, mf.middle) <= kMiddleSagFactor * c.sag &&
            std::abs(dot(normal_at(s, mf.middle), mf.normal)) >= c.cos_normal)
            return true;
    }
    return false;
}

/// Whether a region's own surface says little of its facets: a B-spline that is no helical
/// sweep, a loose analytic region (Draft::loose), a small one (kSmallRegion), or one whose
/// vertices' RMS residual passes kLooseRms x the deflection (no analytic face of the file, as
/// merge_loose_pieces() says). Never a helical sweep, nor a region given by SRE. Cached per
/// region in `known` (-1: unknown). A region that gave facets keeps its verdict and its
/// surface (fitted to more than it now holds) until the final fit.
bool vague_region(Context& c, const Draft& d, std::int8_t& known) {
    if (known < 0) {
        const Surface& s = d.surface;
        bool v = false;
        if (d.alive && d.surface_index < 0 && !(s.bspline && s.bspline->helical)) {
            v = s.kind == FitKind::kBSpline || d.loose > 0 || d.faces.size() <= kSmallRegion ||
                residuals_of(c, d.faces, s).rms > kLooseRms * c.sag;
        }
        known = v ? 1 : 0;
    }
    return known > 0;
}

/// Whether a facet of `faces` shares a smooth edge with one of `group`.
bool touches_smoothly(const Context& c, std::span<const std::uint32_t> faces,
                      std::span<const std::uint32_t> group) {
    std::vector<std::uint32_t> sorted(group.begin(), group.end());
    std::sort(sorted.begin(), sorted.end());
    for (const std::uint32_t f : faces) {
        for (std::uint32_t i = 0; i < 3; ++i) {
            const std::uint32_t g = c.fd.adj[f][i];
            if (g != kNone && !c.sharp_edge[3 * f + i] &&
                std::binary_search(sorted.begin(), sorted.end(), g))
                return true;
        }
    }
    return false;
}

/// The facets of region s's neighbours, reached across smooth edges ring by ring, that lie on
/// its helical sweep unbounded along its helix (fits_along_helix()): the flank's facets in a
/// piece that holds the flank's end and part of the thread's faded end, which fits no sweep
/// whole. Only from a piece whose own surface says little: a B-spline that is no helical sweep,
/// a loose analytic region, a small one. Sorted.
std::vector<std::uint32_t> facets_along_helix(Context& c, const std::vector<Draft>& drafts,
                                              const std::vector<std::uint32_t>& region,
                                              std::uint32_t s, std::vector<std::int8_t>& vague) {
    const Surface& sweep = drafts[s].surface;
    std::vector<std::uint32_t> taken, ring = drafts[s].faces, next;
    std::vector<std::uint8_t> seen(c.m.num_faces(), 0);
    while (!ring.empty()) {
        next.clear();
        for (const std::uint32_t f : ring) {
            for (std::uint32_t i = 0; i < 3; ++i) {
                const std::uint32_t g = c.fd.adj[f][i];
                if (g == kNone || seen[g] || c.sharp_edge[3 * f + i]) continue;
                const std::uint32_t r = region[g];
                if (r == s || r == kNone) continue;
                if (!vague_region(c, drafts[r], vague[r])) continue;
                seen[g] = 1;
                if (!fits_along_helix(c, sweep, g)) continue;
                taken.push_back(g);
                next.push_back(g);
            }
        }
        std::swap(ring, next);
    }
    std::sort(taken.begin(), taken.end());
    return taken;
}

/// Thread flanks: a free-form region whose facets fit one helical sweep (fit_helical(); half a
/// turn of a flank fixes its screw motion) takes its smoothly joined neighbours, of any kind,
/// whose facets lie on that sweep (chords_agree()) while the sweep refitted to them all stays
/// within the chordal deflection: the flank's other pieces along its helix, a B-spline patch, cone
/// and torus pieces and one-facet planes each, become one region. Kept when the sweep pays as an
/// extrusion does (extrusion_pays(): within kFreeformRms x the pieces' RMS, in fewer numbers).
/// A region kept then takes the facets of vague neighbours that lie on its sweep
/// (facets_along_helix()), when the sweep refitted to them still holds. Seeds are taken largest
/// first. Returns the regions that grew or gave facets.
std::vector<std::uint32_t> merge_helical(Context& c, std::vector<Draft>& drafts) {
    std::vector<std::uint32_t> grown;
    const auto open = [&](std::uint32_t r) {
        return drafts[r].alive && drafts[r].surface_index < 0 && !drafts[r].faces.empty();
    };
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t r = 0; r < drafts.size(); ++r) {
        const Surface& s = drafts[r].surface;
        if (open(r) && s.kind == FitKind::kBSpline && s.bspline && !s.bspline->extruded)
            seeds.push_back(r);
    }
    // No B-spline, no thread: the region adjacency (a pass over every facet) is not needed.
    if (seeds.empty()) return grown;
    std::stable_sort(seeds.begin(), seeds.end(), [&](std::uint32_t a, std::uint32_t b) {
        return drafts[a].faces.size() > drafts[b].faces.size();
    });
    std::vector<std::uint32_t> region = region_of_faces(c.m, drafts);
    std::vector<std::vector<std::uint32_t>> nbrs(drafts.size());
    // Along smooth edges only: a crease (the flank's edge with the thread's crest or root, a
    // coaxial cylinder that every screw motion about the axis keeps in place) is a face's edge.
    for (const auto& [a, b] : adjacent_pairs(c, region, true))
        nbrs[a].push_back(b), nbrs[b].push_back(a);
    std::vector<std::uint32_t> mark(drafts.size(), kNone);
    const auto helix_of = [&](std::span<const std::uint32_t> faces) {
        PointSet ps;
        c.gatherers.local().gather(c.m, c.fd, faces, ps);
        return fit_helical(FitInput{ps.points, ps.normals, {}}, c.sag);  // ok: within the sag
    };
    std::vector<std::uint8_t> tried(drafts.size(), 0), gave(drafts.size(), 0);
    std::vector<std::int8_t> known(drafts.size(), -1);
    const auto vague = [&](std::uint32_t r) { return vague_region(c, drafts[r], known[r]); };
    for (const std::uint32_t s : seeds) {
        if (!open(s) || tried[s]) continue;
        std::vector<std::uint32_t> group{s}, faces = drafts[s].faces, frontier;
        mark[s] = s;
        const auto reach = [&](std::uint32_t r) {
            for (const std::uint32_t n : nbrs[r]) {
                if (mark[n] == s || !open(n)) continue;
                mark[n] = s;
                frontier.push_back(n);
            }
        };
        reach(s);
        FitResult best = helix_of(faces);
        // What is left of a piece that gave a flank its end (facets_along_helix()) lies on the
        // thread's faded end, which is in small pieces: too few points for a fit, it first
        // takes its vague smooth neighbours, lowest index first, until it has enough.
        // Adjacency is checked on the facets: the region lists were made before any capture,
        // and a donor no longer touches what it touched only through the facets it gave.
        while (!best.ok && gave[s] && point_count(c, faces) < kMinBSplinePoints) {
            auto low = frontier.end();
            for (auto it = frontier.begin(); it != frontier.end(); ++it) {
                if ((low == frontier.end() || *it < *low) && vague(*it) &&
                    touches_smoothly(c, drafts[*it].faces, faces))
                    low = it;
            }
            if (low == frontier.end()) break;
            const std::uint32_t n = *low;
            frontier.erase(low);
            group.push_back(n);
            faces.insert(faces.end(), drafts[n].faces.begin(), drafts[n].faces.end());
            reach(n);
            best = helix_of(faces);
        }
        // Taken unchecked: its sweep must have the facets as chords, as every growth step asks.
        if (best.ok && group.size() > 1 && !chords_agree(c, best.surface, faces)) best.ok = false;
        if (!best.ok) continue;
        while (!frontier.empty()) {
            // The smallest index first: the same order whatever the threads.
            const auto it = std::min_element(frontier.begin(), frontier.end());
            const std::uint32_t n = *it;
            frontier.erase(it);
            std::vector<std::uint32_t> more = faces;
            more.insert(more.end(), drafts[n].faces.begin(), drafts[n].faces.end());
            FitResult r = helix_of(more);
            if (!r.ok || !chords_agree(c, r.surface, more)) continue;
            group.push_back(n);
            faces = std::move(more);
            best = std::move(r);
            reach(n);
        }
        if (group.size() < 2 || !extrusion_pays(best, measure_pieces(c, drafts, group))) {
            // Its pieces seed no group of their own: one would grow into the same.
            for (const std::uint32_t p : group) tried[p] = 1;
            continue;
        }
        take_group(drafts, region, group, std::move(faces), best.surface);
        grown.push_back(s);
        known[s] = -1;  // a helical sweep now
        // Then the flank's facets in pieces it could not take whole, when the sweep refitted
        // to them as well still holds.
        const std::vector<std::uint32_t> taken = facets_along_helix(c, drafts, region, s, known);
        if (taken.empty()) continue;
        std::vector<std::uint32_t> more = drafts[s].faces;
        more.insert(more.end(), taken.begin(), taken.end());
        std::sort(more.begin(), more.end());
        FitResult r = helix_of(more);
        if (!r.ok || !chords_agree(c, r.surface, more)) continue;
        std::vector<std::uint32_t> donors;
        for (const std::uint32_t f : taken) {
            donors.push_back(region[f]);
            gave[region[f]] = 1;
            region[f] = s;
        }
        std::sort(donors.begin(), donors.end());
        donors.erase(std::unique(donors.begin(), donors.end()), donors.end());
        for (const std::uint32_t d : donors) {
            std::erase_if(drafts[d].faces, [&](std::uint32_t f) { return region[f] == s; });
            if (drafts[d].faces.empty())
                drafts[d].alive = false;
            else
                grown.push_back(d);
        }
        drafts[s].faces = std::move(more);
        drafts[s].surface = r.surface;
    }
    return grown;
}

/// Snapping (SnapOptions::rms_floor) allows a rise of the RMS residual of this many rounding
/// units of the coordinates (coordinate_rounding()) whatever the noise: a change the rounding of
/// the vertices could hide. A binary STL rounds them to floats, not at random across a face:
/// OCCT's sh1 cylinder of radius 37.5 fits 37.4999964 (`ncrev segment occt_sh1.stl --no-snap
/// --json`), by more standard errors than noise that random allows, and less than a unit. A
/// floor in the model's size instead lets exact faces of a double-precision tessellation take
/// round values far beyond its rounding.
constexpr double kSnapRmsFloor = 1;

/// A region whose fit's RMS residual exceeds the noise (plus the floor) by more than this factor
/// is not on its surface to within the noise, as a face of the part is (a noisy region's RMS is
/// the noise, somewhat less). It is not snapped: a cylinder piece of a free-form blend, whose
/// values are no part's and whose snapped radius moves the edges it shares with its neighbours
/// (ReverseSurfaces.FinelyMeshedIllConditionedCornersAndTangentEdgesHoldTheMesh fails when such
/// pieces snap); a fillet strip that took a few vertices of its neighbour, whose radius and place
/// trade off so that the points cannot tell a round radius from the true one.
constexpr double kSnapFitNoise = 3;

bool same_surface(const Surface& a, const Surface& b) {
    return a.kind == b.kind && a.point == b.point && a.axis == b.axis && a.radius == b.radius &&
           a.angle == b.angle && a.minor_radius == b.minor_radius;
}

/// Machined parts have round numbers and features that share axes (method.md Step 4). The
/// segmented regions that are planes, spheres, cylinders, cones or tori and hold their vertices
/// within the tolerance and to the noise (kSnapFitNoise) get parallel axes and coaxial lines
/// (snap_together()), then axes along coordinate axes, round positions, radii (the SRE `tools`'
/// first) and cone angles (snap()); each change only while every vertex stays within the
/// tolerance, the RMS as close to the free fit's as the noise (the median region's) allows
/// (SnapOptions::noise), and the facets are chords of the surface. Regions given by SRE and
/// loose ones (held to chords) are left as they are. Returns the regions whose surface changed.
std::uint64_t snap_regions(Context& c, const std::vector<Draft>& drafts,
                           std::span<const std::uint32_t> order, std::vector<Region>& fitted,
                           std::span<const ToolRecord> tools) {
    std::vector<std::uint32_t> which;
    for (const std::uint32_t r : order) {
        const Region& g = fitted[r];
        const Draft& d = drafts[r];
        if (d.surface_index >= 0 || d.loose > 0 || !g.fit.ok || !g.within_tolerance) continue;
        if (!(fit_kind_bit(g.fit.surface.kind) & kRevolutionFitKinds)) continue;
        which.push_back(r);
    }
    std::vector<PointSet> sets(which.size());
    tbb::parallel_for(std::size_t{0}, which.size(), [&](std::size_t i) {
        c.gatherers.local().gather(c.m, c.fd, drafts[which[i]].faces, sets[i]);
    });
    // The noise: the median of the regions' own estimates, RMS^2 n / (n - p) for n vertices and
    // p parameters (unbiased: a 2-facet plane's RMS is half the noise). The largest region's RMS
    // (noise_level()) may be a misfit: on the sample shallow_freeform a torus piece of its
    // free-form face, while its planes are exact.
    std::vector<double> estimates;
    for (std::size_t i = 0; i < which.size(); ++i) {
        const double nv = static_cast<double>(sets[i].points.size());
        const double p = fit_parameters(fitted[which[i]].fit.surface.kind);
        if (nv > p + 1) estimates.push_back(fitted[which[i]].fit.rms * std::sqrt(nv / (nv - p)));
    }
    double noise = 0;
    if (!estimates.empty()) {
        std::nth_element(estimates.begin(),
                         estimates.begin() + static_cast<std::ptrdiff_t>(estimates.size() / 2),
                         estimates.end());
        noise = estimates[estimates.size() / 2];
    }
    const double floor = kSnapRmsFloor * coordinate_rounding(c.m);
    std::size_t n = 0;
    for (std::size_t i = 0; i < which.size(); ++i) {
        if (fitted[which[i]].fit.rms > kSnapFitNoise * (noise + floor)) continue;
        if (n != i) {
            which[n] = which[i];
            sets[n] = std::move(sets[i]);
        }
        ++n;
    }
    which.resize(n);
    sets.resize(n);
    std::vector<FitResult> fits(n);
    std::vector<FitInput> inputs(n);
    for (std::size_t i = 0; i < n; ++i) {
        fits[i] = fitted[which[i]].fit;
        inputs[i] = sets[i].input();
    }
    SnapOptions o;
    o.tolerance = c.tol;
    o.noise = noise;
    o.rms_floor = floor;
    for (const ToolRecord& t : tools) {
        o.tool_radii.push_back(t.diameter / 2);
        if (t.corner_radius > 0) o.tool_radii.push_back(t.corner_radius);
    }
    std::vector<SnapHold> holds;
    snap_together(fits, inputs, o, {}, &holds);  // measured from the free fits' RMS
    std::vector<std::uint8_t> changed(n, 0);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
        Region& g = fitted[which[i]];  // the free fit until it is replaced below
        SnapOptions own = o;
        own.base_rms = g.fit.rms;
        own.hold = holds[i];
        const std::span<const std::uint32_t> faces = drafts[which[i]].faces;
        // The fully snapped surface, else the one snap_together() gave (its group's axis),
        // while the facets are its chords; else the free fit.
        for (FitResult s : {snap(fits[i], inputs[i], own), fits[i]}) {
            if (same_surface(s.surface, g.fit.surface)) return;
            if (!chords_agree(c, s.surface, faces)) continue;
            g.fit = std::move(s);
            changed[i] = 1;
            return;
        }
    });
    return static_cast<std::uint64_t>(std::count(changed.begin(), changed.end(), 1));
}

/// Regions numbered in the order of their first face; faces labelled; final fits, snapped with
/// `snap` (snap_regions(), with the SRE `tools`). With `loose`, free-form faces in loose pieces are
/// merged on the way (merge_loose_pieces()). Returns the noise (noise_level()) of the regions
/// before that: a free-form face merged from noisy pieces would hide it.
double finish(Context& c, std::vector<Draft>& drafts, std::span<const SurfaceRecord> records,
              SegmentResult& result, bool loose, bool snap, std::span<const ToolRecord> tools) {
    std::vector<std::uint32_t> order = live_drafts(drafts);
    std::vector<Region> fitted(drafts.size());
    tbb::parallel_for(std::size_t{0}, order.size(), [&](std::size_t i) {
        fitted[order[i]] = final_region(c, drafts[order[i]], records);
    });
    // Not from a loose region (Draft::loose): its vertices on chords are no noise.
    std::vector<Region> held;
    for (const std::uint32_t r : order)
        if (drafts[r].loose == 0) held.push_back(fitted[r]);
    const double noise = noise_level(held);
    if (loose) {
        std::vector<std::uint32_t> merged = merge_loose_pieces(c, drafts, fitted);
        result.freeform_groups += merged.size();
        for (const std::uint32_t g : widen_freeform(c, drafts, fitted, merged)) merged.push_back(g);
        for (const std::uint32_t g : merge_chords(c, drafts)) merged.push_back(g);
        for (const std::uint32_t g : merge_fans(c, drafts)) merged.push_back(g);
        for (const std::uint32_t g : grow_loose(c, drafts)) merged.push_back(g);
        for (const std::uint32_t g : merge_helical(c, drafts)) merged.push_back(g);
        // The groups' new surfaces may take the small regions left between them and their
        // neighbours (one-facet planes along a free-form face's seams), as the regions before
        // the final fits took theirs; a region that took or gave facets is fitted again.
        if (!merged.empty()) {
            std::vector<std::vector<std::uint32_t>> before(drafts.size());
            for (std::uint32_t r = 0; r < drafts.size(); ++r) before[r] = drafts[r].faces;
            result.reassigned_facets += absorb_small_regions(c, drafts);
            for (std::uint32_t r = 0; r < drafts.size(); ++r)
                if (drafts[r].alive && drafts[r].faces != before[r]) merged.push_back(r);
        }
        std::sort(merged.begin(), merged.end());
        merged.erase(std::unique(merged.begin(), merged.end()), merged.end());
        std::erase_if(merged, [&](std::uint32_t r) { return !drafts[r].alive; });
        tbb::parallel_for(std::size_t{0}, merged.size(), [&](std::size_t i) {
            fitted[merged[i]] = final_region(c, drafts[merged[i]], records);
        });
        if (!merged.empty()) order = live_drafts(drafts);
    }
    result.snapped = snap ? snap_regions(c, drafts, order, fitted, tools) : 0;
    result.region = FaceMap<std::int32_t>(c.m.num_faces(), -1);
    result.regions.resize(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
        result.regions[i] = std::move(fitted[order[i]]);
        result.regions[i].id = static_cast<std::int32_t>(i);
        for (const std::uint32_t f : drafts[order[i]].faces)
            result.region[fid(f)] = static_cast<std::int32_t>(i);
    }
    return noise;
}

/// One draft per SRE surface index present; mask[f] = 1 for the faces left to segment.
std::vector<Draft> given_regions(const Mesh& m, std::span<const SurfaceRecord> records, bool use,
                                 std::vector<std::uint8_t>& mask, std::uint64_t& given) {
    const std::size_t nf = m.num_faces();
    mask.assign(nf, 1);
    std::vector<Draft> drafts;
    given = 0;
    if (!use || !m.has_attributes() || records.empty()) return drafts;
    std::vector<std::uint32_t> draft_of(records.size(), kNone);
    const auto surf = m.surfaces();
    for (std::uint32_t f = 0; f < nf; ++f) {
        const std::int32_t s = surf[f];
        if (s < 0 || static_cast<std::size_t>(s) >= records.size()) continue;
        if (draft_of[static_cast<std::size_t>(s)] == kNone) {
            draft_of[static_cast<std::size_t>(s)] = static_cast<std::uint32_t>(drafts.size());
            drafts.emplace_back();
            drafts.back().surface_index = s;
            drafts.back().surface = surface_from_record(records[static_cast<std::size_t>(s)]);
        }
        drafts[draft_of[static_cast<std::size_t>(s)]].faces.push_back(f);
        mask[f] = 0;
        ++given;
    }
    return drafts;
}

// ---------------------------------------------------------------------------------------------
// Paper method.

std::vector<Draft> paper_regions(Context& c, const std::vector<std::uint8_t>& mask,
                                 const CurvatureOptions& co, SegmentResult& result);

}  // namespace

Surface surface_from_record(const SurfaceRecord& rec) {
    // The SRE layouts (sre-format.md): a point first; then the radius (sphere) or an axis (or
    // the plane's normal) and the radius; then the kind's own parameters.
    const auto& p = rec.params;
    const auto unit = [&](std::size_t i) {
        const Vec3 v{p[i], p[i + 1], p[i + 2]};
        const double l = norm(v);
        return l > 0 ? v / l : Vec3{0, 0, 1};
    };
    Surface s;
    s.point = {p[0], p[1], p[2]};
    if (rec.kind == SurfaceKind::kSphere) {
        s.kind = FitKind::kSphere;
        s.radius = p[3];
        return s;
    }
    s.axis = unit(3);
    s.radius = rec.kind == SurfaceKind::kPlane ? 0 : p[6];
    switch (rec.kind) {
        case SurfaceKind::kPlane:
            s.kind = FitKind::kPlane;
            break;
        case SurfaceKind::kCylinder:
            s.kind = FitKind::kCylinder;
            break;
        case SurfaceKind::kCone:
            s.kind = FitKind::kCone;
            s.angle = p[7];
            break;
        case SurfaceKind::kTorus:
            s.kind = FitKind::kTorus;
            s.minor_radius = p[7];
            break;
        case SurfaceKind::kShearCylinder:
            s.kind = FitKind::kShearCylinder;
            s.sweep = unit(7);
            break;
        case SurfaceKind::kSweptTorus:
            s.kind = FitKind::kSweptTorus;
            s.minor_radius = p[7];
            s.sweep = unit(8);
            break;
        case SurfaceKind::kSphere:
            break;
    }
    return s;
}

double default_segment_tolerance(const Mesh& m, std::string* rule) {
    // The part's size in any pose (part_size()): turned 0.7 rad out of its axes, NIST FTC 08's
    // AP242 mesh had a box diagonal 1.38 times as long, and came out in 246 faces for 254, with
    // a fallback more.
    const double by_size = kSegmentRelativeTolerance * part_size(m);
    const double precision = coordinate_rounding(m);
    const double by_precision = kPrecisionFactor * precision;
    if (rule) {
        *rule = by_size >= by_precision
                    ? "1e-4 x the part's size (the diagonal of its smallest box)"
                    : "16 x the coordinates' rounding unit (above 1e-4 x the part's size)";
    }
    return std::max(by_size, by_precision);
}

namespace {

/// One segmentation at tolerance `tol` (see segment()); `noise` receives its noise (finish()).
SegmentResult run_segment(const Mesh& m, const SegmentOptions& options, double tol,
                          std::string rule, const ProgressFn& progress, double& noise) {
    const auto t0 = Clock::now();
    SegmentResult result;
    result.method = options.method;
    Context c(m);
    c.tol = tol;
    result.tolerance_rule = std::move(rule);
    result.tolerance = c.tol;
    c.sharp = options.sharp_angle > 0 ? options.sharp_angle : kDefaultSegmentSharpAngle;
    result.sharp_angle = c.sharp;
    c.cos_normal = std::cos(kSegmentNormalAngle);
    if (progress) progress("segment", 0.0);
    c.fd = face_data(m);
    detail::assign_huge(c.sharp_edge, m.num_halfedges(), std::uint8_t{0});
    detail::assign_huge(c.edge_turn, m.num_halfedges(), 0.0f);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, m.num_halfedges(), 4096), [&](const auto& r) {
            for (std::size_t h = r.begin(); h != r.end(); ++h) {
                const double turn =
                    std::abs(dihedral_angle(m, HalfedgeId(static_cast<std::uint32_t>(h))));
                c.edge_turn[h] = static_cast<float>(turn);
                c.sharp_edge[h] = turn >= c.sharp;
            }
        });
    c.sag = estimate_sag(c);
    result.chordal_deflection = c.sag;
    // One clock for the steps; the stage totals (curvature, segment, fit) are sums of them.
    auto step_start = t0;
    double stepped = 0;  // the steps' seconds so far
    const auto step_done = [&](const char* name) {
        const auto now = Clock::now();
        const double seconds = std::chrono::duration<double>(now - step_start).count();
        result.step_seconds.emplace_back(name, seconds);
        step_start = now;
        stepped += seconds;
        return seconds;
    };
    step_done("edges");
    std::vector<std::uint8_t> mask;
    std::vector<Draft> drafts =
        given_regions(m, options.surfaces, options.use_surface_indices, mask, result.given_facets);
    if (options.method == SegmentMethod::kFacets) {
        const auto patches = smooth_patches(c, mask);
        result.patches = patches.size();
        const std::size_t nf = m.num_faces();
        std::vector<std::uint32_t> patch_of, owner, queued, depth;
        for (auto* v : {&patch_of, &owner, &queued, &depth}) detail::assign_huge(*v, nf, kNone);
        for (std::uint32_t i = 0; i < patches.size(); ++i)
            for (const std::uint32_t f : patches[i]) patch_of[f] = i;
        std::vector<std::vector<Draft>> grown(patches.size());
        tbb::parallel_for(std::size_t{0}, patches.size(), [&](std::size_t i) {
            grown[i] = grow_patch(c, patches[i], patch_of, owner, queued, depth,
                                  static_cast<std::uint32_t>(i));
        });
        for (auto& g : grown)
            for (Draft& d : g) drafts.push_back(std::move(d));
        step_done("grow");
    } else {
        auto more = paper_regions(c, mask, options.curvature, result);
        for (Draft& d : more) drafts.push_back(std::move(d));
        result.curvature_seconds = step_done("curvature");
    }
    if (progress) progress("segment", 0.5);
    result.merges = merge_regions(c, drafts);
    step_done("merge");
    result.freeform_groups = merge_freeform(c, drafts);
    step_done("freeform");
    // Border refinement is the facets method's (the paper assigns facets from their vertices).
    if (options.method == SegmentMethod::kFacets) {
        corner_surfaces(c, drafts);
        result.reassigned_facets = absorb_small_regions(c, drafts);
        result.reassigned_facets += refine_borders(c, drafts);
        // Refining can leave a few facets of two faces on their own again.
        result.reassigned_facets += absorb_small_regions(c, drafts);
        // Refining moved facets between regions after the merging: a fragment that one of its
        // neighbours' surfaces takes as it is joins it (CTC 04: 427 -> 421 faces).
        result.merges += merge_regions(c, drafts, /*fragments=*/true);
        step_done("refine");
    }
    result.segment_seconds = stepped - result.curvature_seconds;
    if (progress) progress("segment", 1.0);
    if (progress) progress("fit", 0.0);
    noise = finish(c, drafts, options.surfaces, result, options.method == SegmentMethod::kFacets,
                   options.snap, options.tools);
    result.fit_seconds = step_done("fit");
    if (progress) progress("fit", 1.0);
    return result;
}

}  // namespace

Result<SegmentResult> segment(const Mesh& m, const SegmentOptions& options,
                              const ProgressFn& progress) {
    if (!std::isfinite(options.tolerance) || !std::isfinite(options.sharp_angle)) {
        return Error{ErrorCode::kBadValue, "tolerance and sharp angle must be finite", {}, -1, -1};
    }
    double sigma = 0;
    if (options.tolerance > 0)
        return run_segment(m, options, options.tolerance, "given", progress, sigma);
    std::string rule;
    double tol = default_segment_tolerance(m, &rule);
    SegmentResult r = run_segment(m, options, tol, rule, progress, sigma);
    // A noisy mesh: its vertices stray from their surfaces by more than the size-derived
    // tolerance allows, and the faces break up. Segment again at kNoiseFactor x the noise the
    // first pass measured (a few passes: a region that kept only the vertices within the
    // tolerance understates the noise).
    double seconds = r.curvature_seconds + r.segment_seconds + r.fit_seconds;
    // (The facets method's: the paper's regions are too loose a measure of the noise.)
    for (int pass = 0; pass < kNoisePasses && options.method == SegmentMethod::kFacets; ++pass) {
        if (!(kNoiseFactor * sigma > tol)) break;
        tol = kNoiseFactor * sigma;
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "%g x the noise (RMS %.3g of the largest region, segmented again)",
                      kNoiseFactor, sigma);
        r = run_segment(m, options, tol, buf, progress, sigma);
        r.segment_seconds += seconds;  // the earlier passes count
        r.step_seconds.insert(r.step_seconds.begin(), {"earlier passes", seconds});
        seconds = r.curvature_seconds + r.segment_seconds + r.fit_seconds;
    }
    return r;
}

std::vector<std::int32_t> input_labels(const Mesh& m, const SegmentResult& result,
                                       std::size_t input_facets) {
    std::vector<std::int32_t> labels(input_facets, -1);
    for (std::uint32_t f = 0; f < m.num_faces(); ++f) {
        const std::uint32_t s = m.source_face(fid(f));
        if (s < input_facets) labels[s] = result.region[fid(f)];
    }
    return labels;
}

std::vector<std::byte> encode_segments_ply(const Mesh& m, const SegmentResult& result) {
    const std::size_t nf = m.num_faces();
    std::vector<std::array<std::uint32_t, 3>> triangles(nf);
    using Type = PlyColumn::Type;
    std::vector<PlyColumn> columns = {{"region", Type::kInt32, {}},
                                      {"red", Type::kUint8, {}},
                                      {"green", Type::kUint8, {}},
                                      {"blue", Type::kUint8, {}}};
    for (PlyColumn& col : columns) col.values.resize(nf);
    for (std::size_t f = 0; f < nf; ++f) {
        const FaceId ff = fid(static_cast<std::uint32_t>(f));
        triangles[f] = {m.vertex(ff, 0).idx(), m.vertex(ff, 1).idx(), m.vertex(ff, 2).idx()};
        const std::int32_t r = result.region[ff];
        const std::uint32_t rgb = r >= 0 ? label_color(static_cast<std::uint32_t>(r)) : 0x808080u;
        columns[0].values[f] = r;
        columns[1].values[f] = (rgb >> 16) & 0xff;
        columns[2].values[f] = (rgb >> 8) & 0xff;
        columns[3].values[f] = rgb & 0xff;
    }
    return encode_ply(m.positions(), triangles, {}, columns);
}

namespace {

// ---------------------------------------------------------------------------------------------
// The paper's method (method.md 3.3-3.6).

std::vector<Draft> paper_regions(Context& c, const std::vector<std::uint8_t>& mask,
                                 const CurvatureOptions& co, SegmentResult& result) {
    const Mesh& m = c.m;
    const std::size_t nv = m.num_vertices(), nf = m.num_faces();
    const CurvatureResult cr = compute_curvature(m, co);
    const VertexMap<double> area = mixed_voronoi_areas(m);
    // Vertices to cluster: those of a face left to segment, not high-curvature.
    std::vector<std::uint8_t> active(nv, 0);
    for (std::uint32_t f = 0; f < nf; ++f) {
        if (!mask[f]) continue;
        for (int i = 0; i < 3; ++i) active[m.vertex(fid(f), i).idx()] = 1;
    }
    constexpr std::uint8_t kHigh = 255;
    std::vector<std::uint8_t> type(nv, kHigh);
    for (std::uint32_t v = 0; v < nv; ++v) {
        if (active[v] && !cr.field.high[VertexId(v)])
            type[v] = static_cast<std::uint8_t>(cr.field.type[VertexId(v)]);
    }
    // 3.5 Refining: each vertex takes the type with the largest area in its closed one-ring.
    std::vector<std::uint8_t> next = type;
    for (int round = 0; round < kPaperRefineRounds; ++round) {
        std::atomic<bool> changed{false};
        tbb::parallel_for(
            tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(nv), 4096),
            [&](const auto& r) {
                for (std::uint32_t v = r.begin(); v != r.end(); ++v) {
                    next[v] = type[v];
                    if (type[v] == kHigh) continue;
                    std::array<double, kNumShapeTypes> score{};
                    score[type[v]] += area[VertexId(v)];
                    m.for_each_neighbour(VertexId(v), [&](VertexId w) {
                        if (type[w.idx()] != kHigh) score[type[w.idx()]] += area[w];
                    });
                    std::uint8_t best = type[v];
                    for (std::uint8_t t = 0; t < kNumShapeTypes; ++t)
                        if (score[t] > score[best]) best = t;
                    if (best != type[v]) {
                        next[v] = best;
                        changed = true;
                    }
                }
            });
        type.swap(next);
        if (!changed) break;
    }
    // 3.6 Connected components of same-type vertices.
    std::vector<std::uint32_t> comp(nv, kNone);
    std::vector<std::vector<std::uint32_t>> comps;
    std::vector<std::uint32_t> stack;
    for (std::uint32_t v = 0; v < nv; ++v) {
        if (type[v] == kHigh || comp[v] != kNone) continue;
        const std::uint32_t id = static_cast<std::uint32_t>(comps.size());
        comps.emplace_back();
        comp[v] = id;
        stack.assign(1, v);
        while (!stack.empty()) {
            const std::uint32_t x = stack.back();
            stack.pop_back();
            comps[id].push_back(x);
            m.for_each_neighbour(VertexId(x), [&](VertexId w) {
                if (comp[w.idx()] == kNone && type[w.idx()] == type[x]) {
                    comp[w.idx()] = id;
                    stack.push_back(w.idx());
                }
            });
        }
    }
    result.patches = comps.size();
    // The set-aside vertices join the nearest component along edges (breadth first, in
    // vertex order: deterministic).
    {
        std::vector<std::uint32_t> frontier;
        for (std::uint32_t v = 0; v < nv; ++v)
            if (comp[v] != kNone) frontier.push_back(v);
        std::vector<std::uint32_t> nxt;
        while (!frontier.empty()) {
            nxt.clear();
            for (const std::uint32_t x : frontier) {
                m.for_each_neighbour(VertexId(x), [&](VertexId w) {
                    if (comp[w.idx()] == kNone && active[w.idx()]) {
                        comp[w.idx()] = comp[x];
                        nxt.push_back(w.idx());
                    }
                });
            }
            frontier.swap(nxt);
        }
    }
    // Facets: the component of two or three of their vertices, else of the first corner whose
    // component's vertices it fits best (decided below, after the components are fitted).
    std::vector<Draft> drafts(comps.size());
    std::vector<std::uint32_t> undecided;
    for (std::uint32_t f = 0; f < nf; ++f) {
        if (!mask[f]) continue;
        const std::uint32_t a = comp[m.vertex(fid(f), 0).idx()],
                            b = comp[m.vertex(fid(f), 1).idx()],
                            d = comp[m.vertex(fid(f), 2).idx()];
        std::uint32_t r = kNone;
        if (a == b || a == d)
            r = a;
        else if (b == d)
            r = b;
        if (r != kNone)
            drafts[r].faces.push_back(f);
        else
            undecided.push_back(f);
    }
    // Fit every component's facets (the paper's merging needs each region's surface).
    tbb::parallel_for(std::size_t{0}, drafts.size(), [&](std::size_t i) {
        Draft& d = drafts[i];
        if (d.faces.empty()) {
            d.alive = false;
            return;
        }
        if (auto r = fit_faces(c, d.faces)) {
            d.surface = r->surface;
            return;
        }
        PointSet ps;
        c.gatherers.local().gather(c.m, c.fd, d.faces, ps);
        FitResult best;
        double best_max = kInf;
        for (int k = 0; k < 5; ++k) {
            FitResult r = fit(static_cast<FitKind>(k), ps.input());
            if (r.ok && r.max < best_max) best_max = r.max, best = r;
        }
        if (best.ok)
            d.surface = best.surface;
        else {
            d.surface.kind = FitKind::kPlane;
            d.surface.point = c.fd.centroid[d.faces.front()];
            d.surface.axis = c.fd.normal[d.faces.front()];
        }
    });
    for (const std::uint32_t f : undecided) {
        std::uint32_t best = kNone;
        double best_cost = kInf;
        for (int i = 0; i < 3; ++i) {
            const std::uint32_t r = comp[m.vertex(fid(f), i).idx()];
            if (r == kNone || !drafts[r].alive) continue;
            const double cost = facet_cost(c, drafts[r].surface, f);
            if (best == kNone || cost < best_cost) best = r, best_cost = cost;
        }
        if (best == kNone) {  // every corner set aside with no component reachable
            drafts.emplace_back();
            drafts.back().faces.push_back(f);
            drafts.back().surface.point = c.fd.centroid[f];
            drafts.back().surface.axis = c.fd.normal[f];
            continue;
        }
        drafts[best].faces.push_back(f);
    }
    return drafts;
}

}  // namespace

}  // namespace ncrev

namespace ncrev {

RegionBorders region_borders(const Mesh& m, const FaceMap<std::int32_t>& face_region) {
    const std::size_t nv = m.num_vertices();
    // The region across half-edge h (-1 on the boundary).
    const auto across = [&](HalfedgeId h) {
        const HalfedgeId t = m.twin(h);
        return t.is_valid() ? face_region[Mesh::face(t)] : -1;
    };
    // Each border edge is walked once, from the side of the larger region (the boundary, -1,
    // is always on the right).
    const auto is_border = [&](HalfedgeId h) { return face_region[Mesh::face(h)] > across(h); };
    // Corners: vertices whose fan meets three or more sides (regions, the boundary as one), or
    // where more than two border edges meet.
    RegionBorders out;
    std::vector<std::uint8_t> corner(nv, 0);
    std::vector<std::int32_t> sides;
    for (std::uint32_t v = 0; v < nv; ++v) {
        sides.clear();
        bool boundary = false;
        // Border edges at v: more than two where a region's border touches itself (a pinch:
        // two regions meeting at v along two separate borders), which must end chains too.
        int border_edges = 0;
        m.for_each_outgoing(VertexId(v), [&](HalfedgeId h) {
            sides.push_back(face_region[Mesh::face(h)]);
            boundary = boundary || !m.twin(h).is_valid() || !m.twin(Mesh::prev(h)).is_valid();
            if (face_region[Mesh::face(h)] != across(h)) ++border_edges;
        });
        std::sort(sides.begin(), sides.end());
        const std::size_t distinct =
            static_cast<std::size_t>(std::unique(sides.begin(), sides.end()) - sides.begin());
        if (distinct + (boundary ? 1 : 0) >= 3 || border_edges > 2) {
            corner[v] = 1;
            out.corners.push_back(VertexId(v));
        }
    }
    // Walk every border half-edge once, keeping its face's region on the left: from a
    // border half-edge h (origin o, target t), the next one starts at t, is a border, and
    // separates the same two sides.
    std::vector<std::uint8_t> used(m.num_halfedges(), 0);
    const auto next_along = [&](HalfedgeId h) {
        const std::int32_t l = face_region[Mesh::face(h)], r = across(h);
        HalfedgeId found;
        m.for_each_outgoing(m.target(h), [&](HalfedgeId g) {
            if (!found.is_valid() && !used[g.idx()] && is_border(g) &&
                face_region[Mesh::face(g)] == l && across(g) == r)
                found = g;
        });
        return found;
    };
    const auto walk = [&](HalfedgeId h0) {
        BorderChain c;
        c.left = face_region[Mesh::face(h0)];
        c.right = across(h0);
        c.vertices.push_back(m.origin(h0));
        HalfedgeId h = h0;
        for (;;) {
            used[h.idx()] = 1;
            const VertexId t = m.target(h);
            c.vertices.push_back(t);
            if (corner[t.idx()] || t == c.vertices.front()) break;
            h = next_along(h);
            if (!h.is_valid()) break;  // cannot happen on a manifold labelling; stay safe
        }
        c.closed = c.vertices.front() == c.vertices.back() && !corner[c.vertices.front().idx()];
        out.chains.push_back(std::move(c));
    };
    // Chains from corners first (in vertex order), then the loops.
    for (const VertexId v : out.corners) {
        m.for_each_outgoing(v, [&](HalfedgeId h) {
            if (!used[h.idx()] && is_border(h)) walk(h);
        });
    }
    // A loop starts at its lowest vertex.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> rest;  // (origin, half-edge)
    for (std::uint32_t h = 0; h < m.num_halfedges(); ++h)
        if (!used[h] && is_border(HalfedgeId(h)))
            rest.emplace_back(m.origin(HalfedgeId(h)).idx(), h);
    std::sort(rest.begin(), rest.end());
    for (const auto& [o, h] : rest)
        if (!used[h]) walk(HalfedgeId(h));
    return out;
}

}  // namespace ncrev
