#include "ncrev/report.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

namespace ncrev {

namespace {

std::vector<std::string> make_warnings(const InfoReport& r) {
    std::vector<std::string> w;
    auto n = [](std::uint64_t v) { return std::to_string(v); };
    if (r.unit_assumed) w.push_back("STL has no unit: millimetres assumed");
    if (r.mesh.faces == 0) w.push_back("no facet left after healing");
    if (r.heal.welded_vertices) {
        w.push_back(n(r.heal.welded_vertices) +
                    " vertices welded within the tolerance (cracks closed)");
    }
    if (r.heal.degenerate_facets_removed) {
        w.push_back(n(r.heal.degenerate_facets_removed) + " degenerate facets removed");
    }
    if (r.heal.duplicate_facets_removed) {
        w.push_back(n(r.heal.duplicate_facets_removed) + " duplicate facets removed");
    }
    if (r.heal.flipped_facets)
        w.push_back(n(r.heal.flipped_facets) + " facets flipped to agree with their neighbours");
    if (r.heal.components_turned_outward) {
        w.push_back(n(r.heal.components_turned_outward) + " inside-out components turned outward");
    }
    if (r.heal.facets_split_at_t_junctions) {
        w.push_back(n(r.heal.facets_split_at_t_junctions) +
                    " facets split at T-junctions (vertices in the middle of their open edges)");
    }
    if (r.heal.holes_filled) {
        w.push_back(n(r.heal.holes_filled) + " small holes closed with " +
                    n(r.heal.hole_facets_added) + " new facets (facets missing from the file)");
    }
    if (r.heal.cavities_turned_inward) {
        w.push_back(n(r.heal.cavities_turned_inward) +
                    " cavity shells turned inward (they faced out of the cavity)");
    }
    if (r.heal.nesting_unchecked) {
        w.push_back(
            "too many components to check which lies inside which: a cavity's shell, if any, "
            "is turned outward and the volume counts it as material");
    }
    if (r.heal.crossing_components) {
        w.push_back(n(r.heal.crossing_components) +
                    " closed components cross one another (parts overlapping without their "
                    "union, or fitted into each other with facets that cut in, as a pin in its "
                    "hole tessellated apart): each stays a solid of its own, and the volume "
                    "counts the overlap twice");
    }
    if (r.heal.crossing_unchecked) {
        w.push_back(
            "too many large components with meeting boxes to check which cross one another");
    }
    if (r.heal.self_intersections) {
        const Vec3 at = r.heal.self_intersection_at;
        char where[96];
        std::snprintf(where, sizeof where, "(%.6g, %.6g, %.6g)", at.x, at.y, at.z);
        w.push_back("the mesh passes through itself: " + n(r.heal.self_intersections) +
                    " pairs of facets cross, the first near " + where +
                    " (a vertex pushed through a wall, a surface folded over its neighbour); a "
                    "solid built from it intersects itself too, which CAD systems reject");
    }
    if (r.heal.self_intersection_unchecked) {
        w.push_back(
            "too many facets over one another to check whether the mesh passes "
            "through itself");
    }
    if (r.heal.nonmanifold_edges)
        w.push_back(n(r.heal.nonmanifold_edges) + " non-manifold edges split");
    if (r.heal.nonmanifold_vertices) {
        w.push_back(n(r.heal.nonmanifold_vertices) + " non-manifold vertices split");
    }
    if (r.heal.orientation_conflicts) {
        w.push_back(n(r.heal.orientation_conflicts) + " edges cut to orient a non-orientable part");
    }
    if (r.mesh.faces > 0 && !r.mesh.closed) {
        w.push_back("mesh is open: " + n(r.mesh.boundary_loops) + " boundary loops, " +
                    n(r.mesh.boundary_edges) + " boundary edges");
    }
    return w;
}

}  // namespace

Result<InfoReport> inspect_file(const std::filesystem::path& path, const HealOptions& options,
                                const ProgressFn& progress) {
    auto healed = read_and_heal(path, options, progress);
    if (!healed) return healed.error();
    return std::move(healed->report);
}

Result<HealedMesh> read_and_heal(const std::filesystem::path& path, const HealOptions& options,
                                 const ProgressFn& progress) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    if (progress) progress("read", 0.0);
    ReadOptions read;
    read.weld_exact = true;  // same mesh, a third of the memory
    auto soup = read_mesh_file(path, read);
    if (!soup) return soup.error();
    if (progress) progress("read", 1.0);
    const auto t1 = Clock::now();
    InfoReport r;
    r.path = path.string();
    r.format = soup->format;
    r.unit = soup->unit;
    r.unit_assumed = soup->format != InputFormat::kSre;
    r.input_facets = soup->num_facets();
    r.input_points = soup->points.size() + soup->welded_points;
    r.tools = soup->tools.size();
    r.surfaces = soup->surfaces.size();
    std::vector<ToolRecord> tools = std::move(soup->tools);
    std::vector<SurfaceRecord> surfaces = std::move(soup->surfaces);
    auto built = build_mesh(std::move(soup).value(), options, progress);
    if (!built) {
        Error e = built.error();
        e.path = path.string();
        return e;
    }
    const auto t2 = Clock::now();
    r.heal = built->heal;
    r.mesh = compute_stats(built->mesh);
    r.read_seconds = std::chrono::duration<double>(t1 - t0).count();
    r.build_seconds = std::chrono::duration<double>(t2 - t1).count();
    r.warnings = make_warnings(r);
    return HealedMesh{std::move(built->mesh), std::move(r), std::move(tools), std::move(surfaces)};
}

namespace {

/// A segmentation's steps and their seconds, in order: [{"name", "seconds"}...].
nlohmann::json steps_json(const SegmentResult& r) {
    nlohmann::json steps = nlohmann::json::array();
    for (const auto& [name, seconds] : r.step_seconds)
        steps.push_back({{"name", name}, {"seconds", seconds}});
    return steps;
}

nlohmann::json info_json(const InfoReport& r) {
    using nlohmann::json;
    auto vec = [](Vec3 v) { return json::array({v.x, v.y, v.z}); };
    json j;
    j["input"] = {{"path", r.path},
                  {"format", to_string(r.format)},
                  {"facets", r.input_facets},
                  {"points", r.input_points},
                  {"unit", to_string(r.unit)},
                  {"unit_assumed", r.unit_assumed}};
    if (r.format == InputFormat::kSre) {
        j["input"]["tools"] = r.tools;
        j["input"]["surfaces"] = r.surfaces;
    }
    const HealReport& h = r.heal;
    j["healing"] = {{"tolerance", h.tolerance},
                    {"tolerance_rule", h.tolerance_rule},
                    {"exact_welded_points", h.exact_welded_points},
                    {"welded_vertices", h.welded_vertices},
                    {"unreferenced_vertices", h.unreferenced_vertices},
                    {"degenerate_facets_removed", h.degenerate_facets_removed},
                    {"caps_split", h.caps_split},
                    {"duplicate_facets_removed", h.duplicate_facets_removed},
                    {"flipped_facets", h.flipped_facets},
                    {"components_turned_outward", h.components_turned_outward},
                    {"cavities", h.cavities},
                    {"cavities_turned_inward", h.cavities_turned_inward},
                    {"nesting_checked", !h.nesting_unchecked},
                    {"crossing_components", h.crossing_components},
                    {"crossing_checked", !h.crossing_unchecked},
                    {"self_intersections", h.self_intersections},
                    {"self_intersection_checked", !h.self_intersection_unchecked},
                    {"facets_split_at_t_junctions", h.facets_split_at_t_junctions},
                    {"holes_filled", h.holes_filled},
                    {"hole_facets_added", h.hole_facets_added},
                    {"nonmanifold_edges", h.nonmanifold_edges},
                    {"nonmanifold_vertices", h.nonmanifold_vertices},
                    {"orientation_conflicts", h.orientation_conflicts}};
    if (h.self_intersections) j["healing"]["self_intersection_at"] = vec(h.self_intersection_at);
    const MeshStats& m = r.mesh;
    json bbox = m.bbox.empty() ? json::array({vec({}), vec({})})
                               : json::array({vec(m.bbox.min), vec(m.bbox.max)});
    j["mesh"] = {{"vertices", m.vertices},
                 {"facets", m.faces},
                 {"edges", m.edges},
                 {"components", m.components},
                 {"boundary_loops", m.boundary_loops},
                 {"boundary_edges", m.boundary_edges},
                 {"boundary_loop_sizes", m.boundary_loop_sizes},
                 {"euler_characteristic", m.euler_characteristic},
                 {"closed", m.closed},
                 {"area", m.area},
                 {"volume", m.volume},
                 {"bbox", bbox}};
    j["timing"] = {{"read_seconds", r.read_seconds}, {"build_seconds", r.build_seconds}};
    j["warnings"] = r.warnings;
    return j;
}

}  // namespace

std::string to_json(const InfoReport& r, int indent) { return info_json(r).dump(indent); }

std::string to_json(const InfoReport& info, const ReverseReport& rev, int indent) {
    using nlohmann::json;
    json j = info_json(info);
    json stages = json::array();
    for (const auto& [name, seconds] : rev.stage_seconds) {
        stages.push_back({{"name", name}, {"seconds", seconds}});
    }
    j["reverse"] = {{"method", to_string(rev.method)},
                    {"stages", stages},
                    {"planar_tolerance", rev.planar_tolerance},
                    {"planar_tolerance_rule", rev.planar_tolerance_rule},
                    {"faces_by_kind", rev.faces_by_kind},
                    {"faces", rev.faces},
                    {"edges", rev.edges},
                    {"vertices", rev.vertices},
                    {"solid", rev.solid},
                    {"bodies", rev.bodies},
                    {"voids", rev.voids},
                    {"left_out_facets", rev.left_out_facets},
                    {"valid", rev.valid},
                    {"occt_checked", rev.occt_checked},
                    {"closed_valid_solid", rev.solid && rev.valid},
                    {"mesh_volume", rev.mesh_volume},
                    {"mesh_area", rev.mesh_area},
                    {"solid_volume", rev.solid_volume},
                    {"solid_area", rev.solid_area},
                    {"written", rev.written},
                    {"step_bytes", rev.step_bytes}};
    json& r = j["reverse"];
    if (rev.segmentation) {
        const SegmentResult& seg = *rev.segmentation;
        r["segment"] = {{"method", to_string(seg.method)},
                        {"tolerance", seg.tolerance},
                        {"tolerance_rule", seg.tolerance_rule},
                        {"chordal_deflection", seg.chordal_deflection},
                        {"given_facets", seg.given_facets},
                        {"snapped", seg.snapped},
                        {"steps", steps_json(seg)}};
        r["regions"] = seg.regions.size();
        json fallbacks = json::array();
        for (const ReverseFallback& f : rev.fallbacks) {
            fallbacks.push_back({{"region", f.region},
                                 {"kind", f.kind},
                                 {"facets", f.facets},
                                 {"built_as", f.mesh_edges ? "surface, mesh edges" : "facets"},
                                 {"reason", f.reason}});
        }
        r["fallbacks"] = fallbacks;
        r["fallback_faces"] = rev.fallback_faces;
        r["absorbed_regions"] = rev.absorbed_regions;
        r["edges_by_curve"] = rev.edges_by_curve;
        r["exact_tangencies"] = rev.exact_tangencies;
        r["corners"] = rev.corners;
        r["tangent_corners"] = rev.tangent_corners;
        r["max_corner_residual"] = rev.max_corner_residual;
        r["max_tolerance"] = rev.max_tolerance;
        r["volume_difference"] = rev.volume_difference;
    }
    if (rev.deviation) {
        const auto stats = [](const DistanceStats& d) {
            return json{{"max", d.max}, {"mean", d.mean}, {"rms", d.rms}, {"points", d.points}};
        };
        r["deviation"] = {{"mesh_to_solid", stats(rev.deviation->mesh_to_solid)},
                          {"solid_to_mesh", stats(rev.deviation->solid_to_mesh)},
                          {"triangulation_deflection", rev.deviation->deflection},
                          {"faces_without_triangles", rev.deviation->faces_without_triangles}};
    }
    for (const std::string& w : rev.warnings) j["warnings"].push_back(w);
    return j.dump(indent);
}

namespace {

nlohmann::json curvature_json(const CurvatureResult& c, double seconds) {
    using nlohmann::json;
    const CurvatureThresholds& t = c.thresholds;
    json by_type = json::object();
    for (int i = 0; i < kNumShapeTypes; ++i) {
        by_type[to_string(static_cast<ShapeType>(i))] =
            c.count_by_type[static_cast<std::size_t>(i)];
    }
    return {{"estimator", to_string(t.estimator)},
            {"neighbourhood", t.neighbourhood},
            {"thresholds",
             {{"planar_curvedness", t.planar_curvedness},
              {"planar_rule", t.planar_rule},
              {"sharp_edge_angle", t.sharp_edge_angle},
              {"high_rule", t.high_rule},
              {"median_edge_length", t.median_edge_length},
              {"coordinate_precision", t.coordinate_precision}}},
            {"vertices_by_type", by_type},
            {"high_points", c.high_points},
            {"seconds", seconds}};
}

}  // namespace

std::string to_json(const InfoReport& info, const CurvatureResult& curvature, double seconds,
                    int indent) {
    nlohmann::json j = info_json(info);
    j["curvature"] = curvature_json(curvature, seconds);
    return j.dump(indent);
}

namespace {

nlohmann::json params_json(const Surface& s) {
    using nlohmann::json;
    auto vec = [](Vec3 v) { return json::array({v.x, v.y, v.z}); };
    switch (s.kind) {
        case FitKind::kPlane:
            return {{"point", vec(s.point)}, {"normal", vec(s.axis)}};
        case FitKind::kCylinder:
            return {{"axis_point", vec(s.point)}, {"axis_dir", vec(s.axis)}, {"radius", s.radius}};
        case FitKind::kCone: {
            // The apex: where the radius, growing along the axis, is zero.
            const Vec3 apex = s.point - s.axis * (s.radius / std::tan(s.angle));
            return {{"apex", vec(apex)},
                    {"axis_dir", vec(s.axis)},
                    {"half_angle", s.angle},
                    {"axis_point", vec(s.point)},
                    {"radius", s.radius}};
        }
        case FitKind::kSphere:
            return {{"center", vec(s.point)}, {"radius", s.radius}};
        case FitKind::kTorus:
            return {{"center", vec(s.point)},
                    {"axis_dir", vec(s.axis)},
                    {"major_radius", s.radius},
                    {"minor_radius", s.minor_radius}};
        case FitKind::kShearCylinder:
            return {{"center", vec(s.point)},
                    {"axis_dir", vec(s.axis)},
                    {"radius", s.radius},
                    {"sweep_dir", vec(s.sweep)}};
        case FitKind::kSweptTorus:
            return {{"center", vec(s.point)},
                    {"axis_dir", vec(s.axis)},
                    {"major_radius", s.radius},
                    {"minor_radius", s.minor_radius},
                    {"sweep_dir", vec(s.sweep)}};
        case FitKind::kBSpline: {
            json poles = json::array();
            if (s.bspline) {
                for (const Vec3& p : s.bspline->poles) poles.push_back(vec(p));
            }
            json out = {{"degree", s.bspline ? s.bspline->degree : 3},
                        {"num_u", s.bspline ? s.bspline->num_u : 0},
                        {"num_v", s.bspline ? s.bspline->num_v : 0},
                        {"poles", poles}};
            // A thread's flank: its screw motion, the climb per turn signed by the hand.
            if (s.bspline && s.bspline->helical) {
                const BSplineSurface::Helix& hx = s.bspline->helix;
                out["helix"] = {{"axis_point", vec(hx.origin)},
                                {"axis_dir", vec(hx.axis)},
                                {"pitch", 2 * std::numbers::pi * hx.pitch}};
            }
            return out;
        }
    }
    return json::object();
}

}  // namespace

std::string surface_params_json(const Surface& surface) { return params_json(surface).dump(); }

std::string to_json(const InfoReport& info, const SegmentResult& r, int indent) {
    using nlohmann::json;
    json j = info_json(info);
    std::map<std::string, std::uint64_t> by_kind;
    json regions = json::array();
    for (const Region& g : r.regions) {
        const char* kind = g.fit.ok ? to_string(g.fit.surface.kind) : "none";
        ++by_kind[kind];
        regions.push_back({{"id", g.id},
                           {"kind", kind},
                           {"params", g.fit.ok ? params_json(g.fit.surface) : json::object()},
                           {"facets", g.facets},
                           {"area", g.area},
                           {"rms", g.fit.rms},
                           {"max", g.fit.max},
                           {"within_tolerance", g.within_tolerance},
                           {"surface_index", g.surface_index}});
    }
    j["segment"] = {{"method", to_string(r.method)},
                    {"tolerance", r.tolerance},
                    {"tolerance_rule", r.tolerance_rule},
                    {"chordal_deflection", r.chordal_deflection},
                    {"sharp_angle", r.sharp_angle},
                    {"regions", r.regions.size()},
                    {"regions_by_kind", by_kind},
                    {"given_facets", r.given_facets},
                    {"patches", r.patches},
                    {"merges", r.merges},
                    {"freeform_groups", r.freeform_groups},
                    {"reassigned_facets", r.reassigned_facets},
                    {"snapped", r.snapped},
                    {"seconds",
                     {{"curvature", r.curvature_seconds},
                      {"segment", r.segment_seconds},
                      {"fit", r.fit_seconds}}},
                    {"steps", steps_json(r)}};
    j["regions"] = std::move(regions);
    return j.dump(indent);
}

std::string to_text(const SegmentResult& r, Unit unit) {
    std::map<std::string, std::uint64_t> by_kind;
    std::uint64_t outside = 0;
    for (const Region& g : r.regions) {
        ++by_kind[g.fit.ok ? to_string(g.fit.surface.kind) : "none"];
        outside += !g.within_tolerance;
    }
    std::string s;
    char buf[256];
    std::snprintf(buf, sizeof buf, "segment: %s method, %zu regions (", to_string(r.method),
                  r.regions.size());
    s += buf;
    bool first = true;
    for (const auto& [k, n] : by_kind) {
        s += (first ? "" : ", ") + std::to_string(n) + " " + k;
        first = false;
    }
    s += ")\n";
    std::snprintf(buf, sizeof buf,
                  "tolerance %.4g %s (%s), chordal deflection %.4g %s, sharp edges from %.1f deg\n",
                  r.tolerance, to_string(unit), r.tolerance_rule.c_str(), r.chordal_deflection,
                  to_string(unit), r.sharp_angle * 180 / std::numbers::pi);
    s += buf;
    if (r.given_facets) s += std::to_string(r.given_facets) + " facets kept their SRE surface\n";
    if (outside)
        s += std::to_string(outside) + " regions not within the tolerance of any surface\n";
    if (r.snapped)
        s += std::to_string(r.snapped) +
             " regions snapped to round values, parallel or coaxial axes\n";
    std::snprintf(buf, sizeof buf, "seconds: curvature %.3f, segment %.3f, fit %.3f\n",
                  r.curvature_seconds, r.segment_seconds, r.fit_seconds);
    s += buf;
    if (!r.step_seconds.empty()) {
        s += "steps:";
        for (std::size_t i = 0; i < r.step_seconds.size(); ++i) {
            std::snprintf(buf, sizeof buf, "%s %s %.3f s", i ? "," : "",
                          r.step_seconds[i].first.c_str(), r.step_seconds[i].second);
            s += buf;
        }
        s += "\n";
    }
    return s;
}

std::string to_text(const CurvatureResult& c, Unit unit) {
    const char* u = to_string(unit);
    std::uint64_t total = 0;
    for (const std::uint64_t n : c.count_by_type) total += n;
    std::string s;
    char buf[256];
    std::snprintf(buf, sizeof buf, "curvature: %s estimator, %s\n",
                  to_string(c.thresholds.estimator), c.thresholds.neighbourhood.c_str());
    s += buf;
    std::snprintf(buf, sizeof buf,
                  "thresholds: planar below curvedness %.4g 1/%s; sharp edges from %.3g rad\n",
                  c.thresholds.planar_curvedness, u, c.thresholds.sharp_edge_angle);
    s += buf;
    s += "types:";
    for (int i = 0; i < kNumShapeTypes; ++i) {
        const std::uint64_t n = c.count_by_type[static_cast<std::size_t>(i)];
        std::snprintf(buf, sizeof buf, " %s %llu (%.1f %%)%s", to_string(static_cast<ShapeType>(i)),
                      static_cast<unsigned long long>(n), total ? 100.0 * n / total : 0.0,
                      i + 1 < kNumShapeTypes ? "," : "\n");
        s += buf;
    }
    std::snprintf(buf, sizeof buf, "high-curvature points: %llu\n",
                  static_cast<unsigned long long>(c.high_points));
    s += buf;
    return s;
}

std::string to_text(const InfoReport& r) {
    char buf[512];
    std::string s;
    const MeshStats& m = r.mesh;
    const HealReport& h = r.heal;
    const char* unit = to_string(r.unit);
    std::snprintf(buf, sizeof buf, "%s: %s, %llu facets, unit %s%s\n", r.path.c_str(),
                  to_string(r.format), static_cast<unsigned long long>(r.input_facets), unit,
                  r.unit_assumed ? " (assumed)" : "");
    s += buf;
    std::snprintf(buf, sizeof buf,
                  "healing: tolerance %.3g %s; %llu welded, %llu degenerate, %llu duplicate, "
                  "%llu flipped, %llu turned outward, %llu non-manifold edges, %llu non-manifold "
                  "vertices\n",
                  h.tolerance, unit, static_cast<unsigned long long>(h.welded_vertices),
                  static_cast<unsigned long long>(h.degenerate_facets_removed),
                  static_cast<unsigned long long>(h.duplicate_facets_removed),
                  static_cast<unsigned long long>(h.flipped_facets),
                  static_cast<unsigned long long>(h.components_turned_outward),
                  static_cast<unsigned long long>(h.nonmanifold_edges),
                  static_cast<unsigned long long>(h.nonmanifold_vertices));
    s += buf;
    std::snprintf(
        buf, sizeof buf,
        "mesh: %llu vertices, %llu facets, %llu edges, %llu components, %s "
        "(%llu boundary loops, %llu boundary edges), Euler characteristic %lld\n",
        static_cast<unsigned long long>(m.vertices), static_cast<unsigned long long>(m.faces),
        static_cast<unsigned long long>(m.edges), static_cast<unsigned long long>(m.components),
        m.closed ? "closed" : "open", static_cast<unsigned long long>(m.boundary_loops),
        static_cast<unsigned long long>(m.boundary_edges),
        static_cast<long long>(m.euler_characteristic));
    s += buf;
    if (h.cavities) {
        std::snprintf(buf, sizeof buf,
                      "cavities: %llu (closed components inside a part, each a void in its "
                      "solid)\n",
                      static_cast<unsigned long long>(h.cavities));
        s += buf;
    }
    if (!m.bbox.empty()) {
        const Vec3 d = m.bbox.max - m.bbox.min;
        std::snprintf(buf, sizeof buf,
                      "geometry: area %.6g %s^2, volume %.6g %s^3, size %.4g x %.4g x %.4g %s\n",
                      m.area, unit, m.volume, unit, d.x, d.y, d.z, unit);
        s += buf;
    }
    std::snprintf(buf, sizeof buf, "time: read %.3f s, build %.3f s\n", r.read_seconds,
                  r.build_seconds);
    s += buf;
    return s;
}

}  // namespace ncrev
