// reverse_to_step(): mesh -> B-rep (facets, planar, or surfaces with the local fallback) ->
// check -> STEP, with the numbers.
#include <tbb/task_group.h>

#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <limits>
#include <numeric>
#include <optional>
#include <string>

#include "brep/check.h"
#include "brep/deviation.h"
#include "brep/planar.h"
#include "brep/step.h"
#include "brep/surfaces.h"
#include "detail/triangle_tree.h"
#include "ncrev/brep.h"

namespace ncrev {

const char* to_string(ReverseMethod method) {
    switch (method) {
        case ReverseMethod::kAuto:
            return "auto";
        case ReverseMethod::kSurfaces:
            return "surfaces";
        case ReverseMethod::kFacets:
            return "facets";
        case ReverseMethod::kPlanar:
            break;
    }
    return "planar";
}

std::uint32_t kind_color(const std::string& kind) {
    // Distinct, mid-light colors that read on white and dark backgrounds alike.
    static const std::map<std::string, std::uint32_t> colors{
        {"plane", 0xB4BCC8},          {"cylinder", 0x5B9BD5},   {"cone", 0xED7D31},
        {"sphere", 0x70AD47},         {"torus", 0xFFC000},      {"bspline", 0xC55A9E},
        {"shear_cylinder", 0x4BACC6}, {"swept_torus", 0xF4B183}};
    const auto it = colors.find(kind);
    return it == colors.end() ? 0x9E9E9E : it->second;
}

const char* to_string(StepSchema schema) {
    switch (schema) {
        case StepSchema::kAP203:
            return "ap203";
        case StepSchema::kAP242:
            return "ap242";
        case StepSchema::kAP214:
            break;
    }
    return "ap214";
}

namespace {  // Largest B-rep on which OpenCASCADE's BRepCheck_Analyzer also runs (it costs ~0.3 ms
             // a face:
// about 1.5 s here); larger ones rely on the structural check, which the construction
// guarantees anyway and which costs O(n).
constexpr std::uint64_t kOcctCheckMaxFaces = 5000;
// Rebuilds after the written STEP read back wrong, each with the regions found there as facets
// (one usually suffices; each costs the B-rep and STEP stages again).
constexpr int kReadBackRetries = 3;
/// A refitted B-spline keeps the middles of its region's facets and border edges within this
/// many chordal deflections, as segmentation holds a B-spline's chords (chords_agree()).
constexpr double kChordMiddles = 2;
/// A region's B-spline from segmentation whose middles of facets and border edges lie farther
/// than this many chordal deflections from it swings between its vertices: an edge's middle
/// sags up to one deflection off the surface, a facet's 4/3 as much (segment.cpp,
/// kMiddleSagFactor). TR12J: a 156-facet net 1.8 deflections off a border edge's middle whose
/// ends it holds within 0.02 mm, and 2.1 at three eighths of it; its two plane neighbours,
/// tangent to it there, found no edge curve within the deflection.
constexpr double kGuidedMiddles = 4.0 / 3;
/// A refitted net spans this fraction of its vertices' extent beyond them on each side
/// (FitInput::margin): a border curve bows out past the outermost vertices between them, and
/// on a net that ends at those vertices the edge curve along it leaves the surface (the link
/// rods' plane faces tangent to their B-splines: 4 -> 2 fallbacks; 2 % gave 3). Wider nets spread
/// their poles thinner: freeform_die's coarse net ends farther from the mesh (1.40 -> 1.60 δ).
constexpr double kNetMargin = 0.05;

}  // namespace

namespace brep_detail {

bool volume_is_the_parts(double solid_volume, double mesh_volume, double area, double curved_area,
                         double chordal_deflection, double tolerance) {
    return std::fabs(solid_volume - mesh_volume) <=
           kVolumeSlack * (curved_area * chordal_deflection + area * tolerance);
}

std::int32_t farthest_region(const Mesh& mesh, const SurfaceBrep& brep,
                             const std::vector<std::string>& facets_only, double deflection) {
    std::vector<TopoDS_Face> faces;
    std::vector<std::size_t> owner;
    for (std::size_t r = 0; r < brep.regions.size(); ++r) {
        const RegionBuild& b = brep.regions[r];
        if (b.fallback || b.absorbed_into >= 0 || !facets_only[r].empty()) continue;
        for (const TopoDS_Face& face : b.faces) {
            faces.push_back(face);
            owner.push_back(r);
        }
    }
    const std::vector<double> far = faces_from_mesh(faces, mesh, deflection);
    std::int32_t worst = -1;
    double worst_far = 0;
    for (std::size_t k = 0; k < faces.size(); ++k) {
        if (far[k] > worst_far) {
            worst_far = far[k];
            worst = static_cast<std::int32_t>(owner[k]);
        }
    }
    return worst;
}

}  // namespace brep_detail

namespace {

using Clock = std::chrono::steady_clock;

// Runs fn as the named stage: progress at its start and end, its time in the report.
template <class F>
void run_stage(ReverseReport& rep, const ReverseOptions& options, const char* name, F&& fn) {
    if (options.progress) options.progress(name, 0.0);
    const auto t0 = Clock::now();
    fn();
    rep.stage_seconds.emplace_back(name, std::chrono::duration<double>(Clock::now() - t0).count());
    if (options.progress) options.progress(name, 1.0);
}

brep_detail::StepWriteOptions step_write_options(const ReverseOptions& options) {
    brep_detail::StepWriteOptions w;
    w.schema = options.schema;
    w.unit = options.unit;
    w.product_name = options.product_name.empty() ? "ncrev" : options.product_name;
    return w;
}

// The report of a written STEP file: `written`, and its size.
ReverseReport mark_written(ReverseReport rep, const std::filesystem::path& output) {
    rep.written = true;
    std::error_code ec;
    rep.step_bytes = std::filesystem::file_size(output, ec);
    return rep;
}

Result<ReverseReport> reverse_planar(const Mesh& mesh, const MeshStats& stats,
                                     const std::filesystem::path& output,
                                     const ReverseOptions& options, ReverseReport rep) {
    const auto stage = [&](const char* name, auto&& fn) { run_stage(rep, options, name, fn); };
    if (options.planar_tolerance >= 0) {
        rep.planar_tolerance = options.planar_tolerance;
        rep.planar_tolerance_rule = "given by the caller";
    } else {
        // The weld tolerance: coplanar facets of a CAD export deviate from their plane by the
        // float32 rounding of their vertices (half an ulp), which that tolerance (8 ulps or
        // more) covers, while the facets of a curved surface, whose chordal error is orders
        // of magnitude larger, stay apart.
        std::string rule;
        rep.planar_tolerance = default_weld_tolerance(stats.bbox, &rule);
        rep.planar_tolerance_rule = "the weld tolerance: " + rule;
    }
    brep_detail::silence_occt();
    brep_detail::PlanarTopology topo;
    stage("brep", [&] {
        // Several closed components: which are cavities (voids of the solid around them).
        std::optional<ComponentNesting> nesting;
        if (stats.closed && stats.components > 1) nesting = component_nesting(mesh);
        topo = brep_detail::planar_topology(mesh, options.method != ReverseMethod::kFacets,
                                            rep.planar_tolerance, nesting ? &*nesting : nullptr);
    });
    rep.faces = topo.faces.size();
    rep.edges = topo.segments.size();
    {
        std::vector<std::uint8_t> used(mesh.num_vertices(), 0);
        for (const auto& [a, b] : topo.segments) used[a] = used[b] = 1;
        for (std::uint8_t u : used) rep.vertices += u;
    }
    rep.faces_by_kind["plane"] = rep.faces;
    rep.solid = topo.closed;
    rep.bodies = topo.bodies - topo.voids;
    rep.voids = topo.voids;
    std::string problem;
    try {
        stage("check", [&] {
            problem = brep_detail::check_topology(topo, mesh);
            brep_detail::measure_topology(topo, mesh, rep.solid_area, rep.solid_volume);
            if (!topo.closed) rep.solid_volume = 0;
            // OpenCASCADE's own check, where its cost (~0.3 ms a face) stays small.
            rep.occt_checked = problem.empty() && rep.faces <= kOcctCheckMaxFaces;
            if (rep.occt_checked) {
                const brep_detail::PlanarShape shape = brep_detail::to_occt(topo, mesh);
                if (!BRepCheck_Analyzer(shape.shape).IsValid()) {
                    problem = "BRepCheck_Analyzer reports the shape invalid";
                }
            }
        });
    } catch (const Standard_Failure& f) {
        problem = std::string("OpenCASCADE failed checking the B-rep: ") + f.GetMessageString();
    }
    rep.valid = problem.empty();
    if (!topo.closed) {
        rep.warnings.push_back(
            "the mesh is open: written as a shell (a surface model), not a solid");
    }
    if (!rep.valid) {
        rep.warnings.push_back("the B-rep is invalid (" + problem + "): nothing written");
        return rep;
    }
    Status written = Ok{};
    stage("step", [&] {
        written = brep_detail::write_planar_step(topo, mesh, output, step_write_options(options));
    });
    if (!written) return written.error();
    return mark_written(std::move(rep), output);
}

// The most frequent SRE color of each region's facets (-1 where the mesh has none).
std::vector<std::int64_t> region_colors(const Mesh& mesh, const SegmentResult& seg) {
    std::vector<std::int64_t> out(seg.regions.size(), -1);
    if (mesh.colors().empty()) return out;
    std::vector<std::map<std::int64_t, std::uint64_t>> votes(seg.regions.size());
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        ++votes[static_cast<std::size_t>(seg.region[FaceId(f)])][mesh.colors()[f]];
    }
    for (std::size_t r = 0; r < votes.size(); ++r) {
        std::uint64_t best = 0;
        for (const auto& [color, n] : votes[r]) {
            if (n > best && color >= 0) {
                best = n;
                out[r] = color;
            }
        }
    }
    return out;
}

// Marks the surface regions (not yet fallback) with a facet within `radius` of one of
// `places` — the curved ones, or the planes where no curved one is there (planes rarely fail;
// the curved faces beside them do) — to be built again: with plain corners if some were put on
// contact curves and that has not been tried, else from their facets (`facets_only`, with
// `reason`). Returns how many it marked.
std::size_t regions_near(const Mesh& mesh, const FaceMap<std::int32_t>& labels,
                         const brep_detail::SurfaceBrep& brep,
                         std::span<const brep_detail::RegionSurface> surfaces,
                         const std::vector<std::array<double, 3>>& places, double radius,
                         const std::string& reason, brep_detail::SurfaceBrepOptions& bo) {
    std::vector<std::string>& facets_only = bo.facets_only;
    std::size_t marked = 0;
    for (const auto& pl : places) {
        const Vec3 p{pl[0], pl[1], pl[2]};
        std::vector<std::size_t> curved, flat;
        for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
            const FaceId id(f);
            const Vec3 q = detail::closest_on_triangle(p, mesh.position(mesh.vertex(id, 0)),
                                                       mesh.position(mesh.vertex(id, 1)),
                                                       mesh.position(mesh.vertex(id, 2)));
            if (norm(q - p) > radius) continue;
            auto r = static_cast<std::size_t>(labels[id]);
            // A sliver absorbed by a neighbour is that neighbour's face now.
            while (brep.regions[r].absorbed_into >= 0) {
                r = static_cast<std::size_t>(brep.regions[r].absorbed_into);
            }
            // A fallback's face bounded by its mesh edges: its facets next time.
            if (brep.regions[r].mesh_edges && !bo.as_facets[r]) {
                bo.as_facets[r] = 1;
                ++marked;
            }
            if (brep.regions[r].fallback || !facets_only[r].empty()) continue;
            const bool plane =
                surfaces[r].has_surface && surfaces[r].surface.kind == FitKind::kPlane;
            (plane ? flat : curved).push_back(r);
        }
        for (std::size_t r : curved.empty() ? flat : curved) {
            // First without the corners moved onto contact curves, if it had any; then facets.
            if (brep.regions[r].contact_corners && !bo.plain_corners[r]) {
                bo.plain_corners[r] = 1;
                ++marked;
            } else if (facets_only[r].empty()) {
                facets_only[r] = reason;
                ++marked;
            }
        }
    }
    return marked;
}

Result<ReverseReport> reverse_surfaces(const Mesh& mesh, const MeshStats& stats,
                                       const std::filesystem::path& output,
                                       const ReverseOptions& options, ReverseReport rep) {
    const auto stage = [&](const char* name, auto&& fn) { run_stage(rep, options, name, fn); };
    // Segmentation (its own stages: curvature for the paper method, segment, fit).
    Result<SegmentResult> seg = Error{};
    {
        const auto t0 = Clock::now();
        if (options.progress) options.progress("segment", 0.0);
        seg = segment(mesh, options.segment, options.progress);
        if (options.progress) options.progress("segment", 1.0);
        if (!seg) return seg.error();
        rep.stage_seconds.emplace_back("segment",
                                       std::chrono::duration<double>(Clock::now() - t0).count());
    }
    const SegmentResult& sr = *seg;
    rep.chordal_deflection = sr.chordal_deflection;
    // Free-form regions were held to the chordal deflection while segmenting (their pieces
    // had to merge); the mesh's vertices lie on the surface itself, so the face's B-spline is
    // fitted again to them, to the segmentation tolerance where a net reaches it. A net that
    // close to the vertices may swing between them where nothing holds it, past the border's
    // edges most (NIST CTC 02: a 27-facet region's net 2.8 mm = 2.4 deflections off the middle
    // of a border edge whose ends it passes within 0.01 mm, and no edge curve with its
    // neighbour could follow it): it is kept only while the middles of the region's facets and
    // of its border's edges stay within twice the deflection, as segmenting held them
    // (kChordMiddles). Segmentation's own net may swing so too, where no refit holds: then it
    // is fitted again with the middles as guides (kGuidedMiddles).
    std::vector<FitResult> refits(sr.regions.size());
    stage("refit", [&] {
        std::vector<std::vector<Vec3>> points(sr.regions.size()), middles(sr.regions.size());
        std::vector<std::vector<std::uint8_t>> seen(sr.regions.size());
        // Not a helical sweep (a thread's flank, docs/fitting.md): segmentation fitted it to
        // the vertices and their normals already, and no net over one plane, the refit's, can
        // follow a flank round several turns.
        for (std::size_t r = 0; r < sr.regions.size(); ++r) {
            const FitResult& fr = sr.regions[r].fit;
            if (fr.ok && fr.surface.kind == FitKind::kBSpline && !fr.surface.bspline->helical) {
                seen[r].assign(mesh.num_vertices(), 0);
            }
        }
        for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
            const std::int32_t rf = sr.region[FaceId(f)];
            if (rf < 0) continue;
            const auto r = static_cast<std::size_t>(rf);
            if (seen[r].empty()) continue;
            Vec3 sum{0, 0, 0};
            for (int i = 0; i < 3; ++i) {
                const HalfedgeId h = Mesh::halfedge(FaceId(f), i);
                const VertexId v = mesh.origin(h);
                sum = sum + mesh.position(v);
                const HalfedgeId t = mesh.twin(h);
                if (!t.is_valid() || sr.region[Mesh::face(t)] != rf) {
                    middles[r].push_back(0.5 * (mesh.position(v) + mesh.position(mesh.target(h))));
                }
                if (seen[r][v.idx()]) continue;
                seen[r][v.idx()] = 1;
                points[r].push_back(mesh.position(v));
            }
            middles[r].push_back(sum / 3.0);
        }
        const double middle_limit = kChordMiddles * sr.chordal_deflection;
        for (std::size_t r = 0; r < sr.regions.size(); ++r) {
            if (points[r].empty()) continue;
            // The farthest middle from `s`, or the first farther than `stop`.
            const auto worst_middle = [&](const Surface& s, double stop) {
                double w = 0;
                for (const Vec3& p : middles[r]) {
                    w = std::max(w, distance(s, p));
                    if (w > stop) break;
                }
                return w;
            };
            constexpr double kAll = std::numeric_limits<double>::infinity();
            FitInput in;
            in.points = points[r];
            in.margin = kNetMargin;
            // The tightest of tolerance x 1, 4, 16 ... that a net reaches with the facets its
            // chords.
            const double held = sr.regions[r].fit.max;
            for (double tol = sr.tolerance; tol < held; tol *= 4) {
                FitResult f = fit_bspline(in, tol);
                if (!f.ok || !(f.max < held)) continue;
                if (worst_middle(f.surface, middle_limit) <= middle_limit) {
                    refits[r] = std::move(f);
                    break;
                }
            }
            // None, and segmentation's own net swings past a middle by more than a chord
            // sags (kGuidedMiddles): fitted again to the vertices within the deflection, as
            // segmentation held them, drawn towards the middles (FitInput::guides); taken
            // where its middles are nearer. Not an extrusion, which takes no guides (its
            // profile's fit over every vertex again: 0.2 s of trimesh_featuretype's 81.6k-facet
            // bench, for the same faces).
            if (refits[r].ok || sr.regions[r].fit.surface.bspline->extruded) continue;
            const double swing = worst_middle(sr.regions[r].fit.surface, kAll);
            if (!(swing > kGuidedMiddles * sr.chordal_deflection)) continue;
            in.guides = middles[r];
            FitResult f = fit_bspline(in, sr.chordal_deflection);
            if (f.ok && f.max <= sr.chordal_deflection && worst_middle(f.surface, swing) < swing) {
                refits[r] = std::move(f);
            }
        }
    });
    std::vector<brep_detail::RegionSurface> surfaces(sr.regions.size());
    for (std::size_t r = 0; r < sr.regions.size(); ++r) {
        const Region& g = sr.regions[r];
        surfaces[r].surface = refits[r].ok ? refits[r].surface : g.fit.surface;
        surfaces[r].has_surface = g.fit.ok && g.within_tolerance;
        if (!g.fit.ok) {
            surfaces[r].no_surface_reason = "no surface fits the region";
        } else if (!g.within_tolerance) {
            surfaces[r].no_surface_reason =
                std::string("its ") + to_string(g.fit.surface.kind) + " misses vertices by up to " +
                std::to_string(g.fit.max) + " (tolerance " + std::to_string(sr.tolerance) + ")";
        }
    }
    // Fillets fitted on their own overlap the arcs they run into by a rounding error; made a
    // hair apart, a floor cutting both has edges that do not cross beside their corner.
    rep.exact_tangencies = brep_detail::exact_tangencies(mesh, sr.region, surfaces, sr.tolerance);
    // One face per connected piece: a region in several pieces (segmentation joins every
    // facet that one surface fits, and border refinement can detach a few) becomes one region
    // per piece, each with the region's surface; `origin` maps them back.
    FaceMap<std::int32_t> labels = sr.region;
    std::vector<std::size_t> origin(sr.regions.size());
    std::iota(origin.begin(), origin.end(), std::size_t{0});
    {
        std::vector<std::uint8_t> seen(mesh.num_faces(), 0), kept(sr.regions.size(), 0);
        std::vector<FaceId> stack;
        for (std::uint32_t f0 = 0; f0 < mesh.num_faces(); ++f0) {
            if (seen[f0]) continue;
            const std::int32_t r = sr.region[FaceId(f0)];
            std::int32_t id = r;
            if (kept[static_cast<std::size_t>(r)]) {
                id = static_cast<std::int32_t>(origin.size());
                origin.push_back(static_cast<std::size_t>(r));
                surfaces.push_back(surfaces[static_cast<std::size_t>(r)]);
            }
            kept[static_cast<std::size_t>(r)] = 1;
            seen[f0] = 1;
            stack.assign(1, FaceId(f0));
            while (!stack.empty()) {
                const FaceId f = stack.back();
                stack.pop_back();
                labels[f] = id;
                for (int i = 0; i < 3; ++i) {
                    const HalfedgeId t = mesh.twin(Mesh::halfedge(f, i));
                    if (!t.is_valid()) continue;
                    const FaceId g = Mesh::face(t);
                    if (seen[g.idx()] || sr.region[g] != r) continue;
                    seen[g.idx()] = 1;
                    stack.push_back(g);
                }
            }
        }
    }
    brep_detail::SurfaceBrepOptions bo;
    bo.tolerance = sr.tolerance;
    bo.chordal_deflection = std::max(sr.chordal_deflection, sr.tolerance);
    bo.allow_fallback = options.method == ReverseMethod::kAuto;
    // Faces that pass BRepCheck in memory can still be wrong: BRepMesh cannot triangulate
    // them (no viewer shows them), or they fail once written and read back (STEP keeps no
    // tolerances and the reader heals). Their regions are found near where the shape is
    // wrong, built from their facets, and the part is built (and written) again, up to
    // kReadBackRetries times before the whole part goes planar.
    bo.facets_only.assign(surfaces.size(), std::string());
    bo.plain_corners.assign(surfaces.size(), 0);
    bo.as_facets.assign(surfaces.size(), 0);
    // The last resort, so that a closed mesh always gives a valid closed solid: the whole part
    // as planar faces (that construction cannot fail), reported as one fallback.
    const auto whole_planar = [&](ReverseReport base,
                                  const std::string& why) -> Result<ReverseReport> {
        ReverseReport planar = std::move(base);
        planar.faces_by_kind.clear();
        planar.deviation.reset();
        planar.volume_difference = 0;
        planar.warnings.push_back(why);
        ReverseFallback all;
        all.region = -1;
        all.facets = mesh.num_faces();
        all.kind = "all";
        all.reason = why;
        planar.fallbacks.push_back(all);
        planar.written = false;
        planar.step_bytes = 0;
        auto out = reverse_planar(mesh, stats, output, options, std::move(planar));
        if (out && out->solid && out->mesh_volume != 0) {
            out->volume_difference = (out->solid_volume - out->mesh_volume) / out->mesh_volume;
        }
        return out;
    };
    // The triangulation for the deviation: fine enough for the figures to reflect the mesh's
    // own chordal error (it may add up to this much).
    const double deflection = 0.5 * std::max(sr.chordal_deflection, sr.tolerance);
    bo.mesh_deflection = deflection;
    // The facets on curved surfaces, whose chords are where a solid's volume may differ from
    // the mesh's (brep_detail::volume_is_the_parts()).
    double curved_area = 0;
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        const auto r = static_cast<std::size_t>(labels[FaceId(f)]);
        if (surfaces[r].has_surface && surfaces[r].surface.kind != FitKind::kPlane)
            curved_area += mesh.face_area(FaceId(f));
    }
    const ReverseReport before_brep = rep;
    for (int attempt = 0;; ++attempt) {
        if (attempt > 0) {
            auto stages = std::move(rep.stage_seconds);
            rep = before_brep;
            rep.stage_seconds = std::move(stages);
        }
        brep_detail::SurfaceBrep brep;
        std::vector<std::array<double, 3>> unmeshed;
        stage("brep", [&] { brep = brep_detail::build_surface_brep(mesh, labels, surfaces, bo); });
        rep.corners = brep.corners;
        rep.tangent_corners = brep.tangent_corners;
        rep.max_corner_residual = brep.max_corner_residual;
        rep.max_tolerance = brep.max_tolerance;
        rep.edges_by_curve = {{"intersection", brep.intersection_edges},
                              {"analytic", brep.analytic_edges},
                              {"tangency", brep.tangency_edges},
                              {"fitted", brep.fitted_edges},
                              {"polyline", brep.polyline_edges}};
        for (std::size_t r = 0; r < brep.regions.size(); ++r) {
            const brep_detail::RegionBuild& b = brep.regions[r];
            const Region& g = sr.regions[origin[r]];
            if (b.absorbed_into >= 0) {
                ++rep.absorbed_regions;
            } else if (b.fallback) {
                ReverseFallback fb;
                fb.region = static_cast<std::int32_t>(origin[r]);
                fb.facets = b.facets;
                fb.kind = g.fit.ok ? to_string(g.fit.surface.kind) : "none";
                fb.reason = b.reason;
                fb.mesh_edges = b.mesh_edges;
                rep.fallback_faces += b.faces.size();
                if (b.spline) fb.reason += "; its face is on a B-spline fitted to its facets";
                rep.faces_by_kind[!b.mesh_edges ? "facet"
                                  : b.spline    ? "bspline"
                                                : fb.kind] += b.faces.size();
                rep.fallbacks.push_back(std::move(fb));
            } else if (!b.faces.empty()) {
                rep.faces_by_kind[to_string(g.fit.surface.kind)] += b.faces.size();
            }
        }
        rep.solid = brep.solid;
        rep.valid = brep.valid && brep.solid;
        rep.occt_checked = !brep.shape.IsNull();
        if (!brep.shape.IsNull()) {
            TopTools_IndexedMapOfShape faces, edges, vertices;
            TopExp::MapShapes(brep.shape, TopAbs_FACE, faces);
            TopExp::MapShapes(brep.shape, TopAbs_EDGE, edges);
            TopExp::MapShapes(brep.shape, TopAbs_VERTEX, vertices);
            TopTools_IndexedMapOfShape bodies, shells;
            TopExp::MapShapes(brep.shape, brep.solid ? TopAbs_SOLID : TopAbs_SHELL, bodies);
            TopExp::MapShapes(brep.shape, TopAbs_SHELL, shells);
            rep.bodies = static_cast<std::uint64_t>(bodies.Extent());
            if (brep.solid) rep.voids = static_cast<std::uint64_t>(shells.Extent()) - rep.bodies;
            rep.faces = static_cast<std::uint64_t>(faces.Extent());
            rep.edges = static_cast<std::uint64_t>(edges.Extent());
            rep.vertices = static_cast<std::uint64_t>(vertices.Extent());
            stage("measure", [&] {
                GProp_GProps sp;
                BRepGProp::SurfaceProperties(brep.shape, sp);
                rep.solid_area = sp.Mass();
                if (brep.solid) {
                    rep.solid_volume = brep_detail::solid_volume(brep.shape);
                    if (rep.mesh_volume != 0) {
                        rep.volume_difference =
                            (rep.solid_volume - rep.mesh_volume) / rep.mesh_volume;
                    }
                }
                if (rep.valid) unmeshed = brep_detail::untriangulated_faces(brep.shape, deflection);
            });
        }
        for (const ReverseFallback& fb : rep.fallbacks) {
            rep.warnings.push_back("region " + std::to_string(fb.region) + " (" + fb.kind + ", " +
                                   std::to_string(fb.facets) + " facets) built " +
                                   (fb.mesh_edges
                                        ? "as one face on its surface bounded by its mesh edges: "
                                        : "from its facets: ") +
                                   fb.reason);
        }
        rep.segmentation = sr;
        // A valid solid can still not be the part: a face built over the wrong piece of its
        // surface (a torus that took a cone strip of the M6 screw made a valid solid 41 %
        // short of the mesh's volume; docs/brep.md, 7). The region whose exact faces lie
        // farthest from the mesh is built from its facets and the part again, up to
        // kReadBackRetries times; then the whole part goes planar.
        if (rep.valid && rep.mesh_volume != 0 &&
            !brep_detail::volume_is_the_parts(rep.solid_volume, rep.mesh_volume, rep.mesh_area,
                                              curved_area, bo.chordal_deflection, bo.tolerance)) {
            char text[160];
            std::snprintf(text, sizeof text,
                          "the solid's volume is %+.3f %% off the mesh's, more than the "
                          "mesh's chordal deflection and the tolerance allow",
                          100 * (rep.solid_volume - rep.mesh_volume) / rep.mesh_volume);
            const std::string volume_problem = text;
            if (options.method == ReverseMethod::kAuto && attempt < kReadBackRetries) {
                const std::int32_t r =
                    brep_detail::farthest_region(mesh, brep, bo.facets_only, deflection);
                if (r >= 0) {
                    bo.facets_only[static_cast<std::size_t>(r)] =
                        volume_problem + "; its face lies the farthest from the mesh";
                    continue;
                }
            }
            if (options.method == ReverseMethod::kAuto) {
                return whole_planar(
                    rep, volume_problem + ": the whole part is built with the planar method");
            }
            rep.valid = false;
            brep.problem = volume_problem;
        }
        if (!rep.valid && options.method == ReverseMethod::kAuto) {
            return whole_planar(rep,
                                "the B-rep from the surfaces is invalid (" +
                                    (brep.problem.empty() ? std::string("unknown") : brep.problem) +
                                    "): the whole part is built with the planar method");
        }
        if (!rep.valid) {
            rep.warnings.push_back("the B-rep is invalid (" +
                                   (brep.problem.empty() ? std::string("unknown") : brep.problem) +
                                   "): nothing written");
            return rep;
        }
        if (!unmeshed.empty() && options.method == ReverseMethod::kAuto &&
            attempt < kReadBackRetries &&
            regions_near(mesh, labels, brep, surfaces, unmeshed,
                         2 * std::max(bo.chordal_deflection, brep.max_tolerance),
                         "BRepMesh cannot triangulate its face", bo) > 0) {
            continue;
        }
        Status written = Ok{};
        stage("step", [&] {
            brep_detail::StepWriteOptions w = step_write_options(options);
            if (options.colors) {
                w.shape_color = kind_color("facet");
                const std::vector<std::int64_t> tool = region_colors(mesh, *rep.segmentation);
                for (std::size_t r = 0; r < brep.regions.size(); ++r) {
                    const brep_detail::RegionBuild& b = brep.regions[r];
                    const std::int64_t t = tool[origin[r]];
                    const std::uint32_t rgb =
                        t >= 0 ? static_cast<std::uint32_t>(t & 0xFFFFFF)
                               : kind_color(to_string(
                                     rep.segmentation->regions[origin[r]].fit.surface.kind));
                    // Fallback facets take the shape's color (set above): thousands of colored
                    // sub-shapes would cost more than the rest of the STEP.
                    if (b.fallback && !b.mesh_edges && t < 0) continue;
                    for (const TopoDS_Face& f : b.faces) w.face_colors.emplace_back(f, rgb);
                }
            }
            written = brep_detail::write_step_file(brep.shape, output, w);
        });
        if (!written) return written.error();
        // What a CAD system will see: the file read back (STEP keeps no tolerances; the reader
        // derives them) must pass the check too — up to kOcctCheckMaxFaces faces (reading and
        // checking cost ~1 ms a face; larger B-reps are all but fallback facets).
        // The deviation is measured meanwhile, on the solid in memory (which reading the file
        // does not touch; the two take about as long), and dropped if the file reads back
        // wrong.
        brep_detail::ReadBack back;
        std::optional<SolidDeviation> deviation;
        const bool verify = rep.faces <= kOcctCheckMaxFaces;
        const char* name = !verify                     ? "measure"
                           : options.measure_deviation ? "verify+measure"
                                                       : "verify";
        stage(name, [&] {
            tbb::task_group measuring;
            if (options.measure_deviation) {
                measuring.run([&] {
                    deviation = brep_detail::measure_deviation(brep.shape, mesh, deflection);
                });
            }
            if (verify) {
                back = brep_detail::step_read_back(output, static_cast<int>(rep.bodies));
            }
            measuring.wait();
        });
        const std::string& back_problem = back.problem;
        if (!back_problem.empty() && options.method == ReverseMethod::kAuto &&
            attempt < kReadBackRetries) {
            const std::size_t found =
                regions_near(mesh, labels, brep, surfaces, back.places,
                             2 * std::max(bo.chordal_deflection, brep.max_tolerance),
                             "its face fails once the STEP is read back", bo);
            if (found > 0) continue;
        }
        if (!back_problem.empty()) {
            if (options.method == ReverseMethod::kAuto) {
                return whole_planar(rep, "the STEP of the surfaces reads back invalid (" +
                                             back_problem +
                                             "): the whole part is built with the planar method");
            }
            std::error_code ec;
            std::filesystem::remove(output, ec);
            rep.valid = false;
            rep.warnings.push_back("the STEP reads back invalid (" + back_problem +
                                   "): nothing written");
            return rep;
        }
        // Measured on the solid that was written (the triangulation is reused).
        if (deviation) {
            rep.deviation = std::move(deviation);
            if (rep.deviation->faces_without_triangles > 0) {
                rep.warnings.push_back(
                    std::to_string(rep.deviation->faces_without_triangles) +
                    " faces BRepMesh cannot triangulate: the deviation does not see them");
            }
        }
        return mark_written(std::move(rep), output);
    }
}

/// An open mesh's closed components, when they are the part: they hold more than half of its
/// area (kPartShare), the open ones then being stray facets or scraps that bound nothing. A
/// mesh whose open components hold most of it (an open part, a sheet) has none: it is built
/// with the planar method as a whole.
struct ClosedPart {
    Components components;  ///< of the whole mesh
    Mesh mesh;              ///< its closed components
};
constexpr double kPartShare = 0.5;

std::optional<ClosedPart> closed_part(const Mesh& mesh) {
    ClosedPart part;
    part.components = face_components(mesh);
    const Components& c = part.components;
    double closed_area = 0, area = 0;
    for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
        const double a = mesh.face_area(FaceId(f));
        area += a;
        if (c.closed[c.of_face[f]]) closed_area += a;
    }
    if (closed_area <= kPartShare * area) return std::nullopt;
    part.mesh = keep_components(mesh, c, c.closed);
    return part;
}

}  // namespace

Result<ReverseReport> reverse_to_step(const Mesh& mesh, const std::filesystem::path& output,
                                      const ReverseOptions& options) {
    ReverseReport rep;
    rep.method = options.method;
    if (mesh.num_faces() == 0) {
        Error e;
        e.code = ErrorCode::kEmpty;
        e.path = output.string();
        e.message = "the mesh has no facet: nothing to write";
        return e;
    }
    brep_detail::silence_occt();
    const MeshStats stats = compute_stats(mesh);
    rep.mesh_volume = stats.volume;
    rep.mesh_area = stats.area;
    if (options.require_solid) {
        // Whatever is built from a mesh through itself passes through itself too: no solid a
        // CAD system takes (OpenCASCADE's check would pass it: docs/healing.md step 9).
        const std::uint64_t crossing =
            options.heal != nullptr
                ? options.heal->self_intersections
                : find_self_intersections(mesh, default_weld_tolerance(stats.bbox)).pairs;
        if (crossing > 0) {
            rep.warnings.push_back("the mesh passes through itself (" + std::to_string(crossing) +
                                   " pairs of facets cross): no valid solid, nothing written "
                                   "(required)");
            return rep;
        }
    }
    const bool surfaces =
        options.method == ReverseMethod::kAuto || options.method == ReverseMethod::kSurfaces;
    if (surfaces && stats.closed) return reverse_surfaces(mesh, stats, output, options, rep);
    if (surfaces) {
        if (auto part = closed_part(mesh)) {
            const MeshStats part_stats = compute_stats(part->mesh);
            rep.mesh_volume = part_stats.volume;
            rep.mesh_area = part_stats.area;
            rep.left_out_facets = mesh.num_faces() - part->mesh.num_faces();
            char share[32];
            std::snprintf(share, sizeof share, "%.3g", 100 * (1 - part_stats.area / stats.area));
            const std::uint64_t open = stats.components - part_stats.components;
            rep.warnings.push_back(
                std::to_string(open) + (open > 1 ? " open components" : " open component") +
                " of the mesh (" + std::to_string(rep.left_out_facets) +
                (rep.left_out_facets > 1 ? " facets, " : " facet, ") + share +
                " % of its area) left out: they bound no solid (stray facets, scraps); the closed "
                "ones are built (--method planar keeps every facet)");
            auto out = reverse_surfaces(part->mesh, part_stats, output, options, rep);
            if (out && out->segmentation) {
                // The regions of the whole mesh's faces: -1 for those left out.
                FaceMap<std::int32_t> region(mesh.num_faces(), -1);
                std::uint32_t k = 0;
                for (std::uint32_t f = 0; f < mesh.num_faces(); ++f) {
                    const Components& c = part->components;
                    if (c.closed[c.of_face[f]])
                        region[FaceId(f)] = out->segmentation->region[FaceId(k++)];
                }
                out->segmentation->region = std::move(region);
            }
            return out;
        }
    }
    if (options.require_solid && !stats.closed) {
        rep.warnings.push_back("the mesh is open (" + std::to_string(stats.boundary_loops) +
                               " boundary loops): no solid, nothing written (required)");
        return rep;
    }
    if (surfaces) {
        rep.warnings.push_back(
            "the mesh is open: its surfaces cannot bound a solid, so it is built with the planar "
            "method");
        if (options.method == ReverseMethod::kSurfaces) {
            rep.warnings.push_back("--method surfaces needs a closed mesh: nothing written");
            return rep;
        }
    }
    return reverse_planar(mesh, stats, output, options, rep);
}

}  // namespace ncrev
