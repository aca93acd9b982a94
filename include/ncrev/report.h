// report: the numbers of every stage, as text for people and JSON for programs.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "ncrev/brep.h"
#include "ncrev/common.h"
#include "ncrev/curvature.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"
#include "ncrev/segment.h"

namespace ncrev {

/// What `ncrev info` tells about a file: what was read and what healing did.
struct InfoReport {
    std::string path;
    InputFormat format = InputFormat::kStlBinary;
    Unit unit = Unit::kMillimetre;
    bool unit_assumed = true;  ///< STL carries no unit: millimetres are assumed
    std::uint64_t input_facets = 0;
    std::uint64_t input_points = 0;
    std::uint64_t tools = 0, surfaces = 0;  ///< SRE tables
    HealReport heal;
    MeshStats mesh;
    double read_seconds = 0, build_seconds = 0;
    /// What a user should know (holes, non-manifold parts, flipped facets, ...).
    std::vector<std::string> warnings;
};

/// A healed mesh and the report of how it was read and healed.
struct HealedMesh {
    Mesh mesh;
    InfoReport report;
    std::vector<ToolRecord> tools;        ///< the SRE tools table (empty for STL)
    std::vector<SurfaceRecord> surfaces;  ///< the SRE surfaces table (empty for STL)
};

/// Reads and heals a mesh file (welding exactly while reading), keeping the mesh.
Result<HealedMesh> read_and_heal(const std::filesystem::path& path, const HealOptions& options = {},
                                 const ProgressFn& progress = {});

/// Reads and heals a mesh file and gathers the numbers. Fails with the reader's error.
Result<InfoReport> inspect_file(const std::filesystem::path& path, const HealOptions& options = {},
                                const ProgressFn& progress = {});

/// The report as one JSON object (keys: input, healing, mesh, timing, warnings).
std::string to_json(const InfoReport& report, int indent = 2);

/// The report of `ncrev reverse`: the info keys plus "reverse" (method, stages with seconds,
/// faces by surface kind, faces, edges, vertices, solid, valid, volumes and areas of the mesh
/// and of the solid, STEP bytes; for the surface methods also "segment": method, tolerance and
/// its rule, chordal deflection, given facets and "steps" as `ncrev segment` reports them);
/// warnings of both.
std::string to_json(const InfoReport& info, const ReverseReport& reverse, int indent = 2);

/// The report of `ncrev curvature`: the info keys plus "curvature" (estimator, neighbourhood,
/// thresholds with their rules, vertices per type, high-curvature points, seconds).
std::string to_json(const InfoReport& info, const CurvatureResult& curvature, double seconds,
                    int indent = 2);

/// The curvature summary as a few lines of text: vertices per type, thresholds.
std::string to_text(const CurvatureResult& curvature, Unit unit);

/// The report of `ncrev segment`: the info keys plus "segment" (method, tolerance, chordal
/// deflection and sharp angle with their rules, counts, seconds per stage, "steps": [{"name",
/// "seconds"}...] as SegmentResult::step_seconds, regions by kind) and
/// "regions": one object per region, {"id", "kind", "params", "facets", "area", "rms", "max",
/// "within_tolerance", "surface_index"}; params by kind: plane point, normal; cylinder
/// axis_point, axis_dir, radius; cone apex, axis_dir (the radius grows along it), half_angle
/// (rad), radius and axis_point (a section); sphere center, radius; torus center, axis_dir,
/// major_radius (negative for the inner, lemon part of a spindle torus: ncrev/fit.h),
/// minor_radius; shear_cylinder center, axis_dir, radius, sweep_dir;
/// swept_torus center, axis_dir, major_radius, minor_radius, sweep_dir; bspline degree,
/// num_u, num_v, poles (num_u x num_v points, u fastest), and for a helical sweep helix
/// (axis_point, axis_dir, pitch: the climb per turn along axis_dir, negative for a left hand).
std::string to_json(const InfoReport& info, const SegmentResult& segment, int indent = 2);

/// The region parameters of to_json() for one surface.
std::string surface_params_json(const Surface& surface);

/// The segmentation summary as a few lines of text: regions by kind, tolerance, times.
std::string to_text(const SegmentResult& segment, Unit unit);

/// The report as a few lines of text for a terminal.
std::string to_text(const InfoReport& report);

}  // namespace ncrev
