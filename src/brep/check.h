// What OpenCASCADE's checker finds wrong with a shape, in words. Internal.
#pragma once

#include <TopoDS_Shape.hxx>
#include <optional>
#include <string>
#include <vector>

namespace ncrev::brep_detail {

/// What BRepCheck_Analyzer finds wrong with `shape`, in words (empty when valid; at most ~300
/// characters, each kind of defect once), and, when `bad` is given, the sub-shapes it finds
/// wrong (vertices, edges, wires, faces, shells, solids) appended to it. `parallel`: the
/// analyzer checks the sub-shapes on several threads (same findings).
std::string check_failure(const TopoDS_Shape& shape, std::vector<TopoDS_Shape>* bad = nullptr,
                          bool parallel = false);

/// Relative error of the volumes we measure (BRepGProp's adaptive integration). Its default,
/// a fixed Gauss rule per face, put a 15 x 14-pole B-spline top 0.24 % off (the freeform die
/// at 159k facets: 266578 mm3 for 265937), CTC 02's reversed solid 0.023 % off and the die's
/// own exact solid 0.003 % (a temporary program on the written STEP files, both ways); the
/// bench cases pay 0.1-0.4 s for it (docs/benchmarks.md).
constexpr double kVolumeRelativeError = 1e-7;

/// The volume of `shape` (a solid, or a shape holding one) within kVolumeRelativeError; a face
/// that goes round its periodic surface more than once is measured in pieces of one turn. The
/// faces are integrated on all cores (volume_by_faces()), BRepGProp's way where that cannot.
double solid_volume(const TopoDS_Shape& shape);

/// BRepGProp::VolumeProperties(shape, props, relative_error)'s volume to the bit, its faces
/// integrated on all cores and summed in its order; nothing for a shape it measures otherwise
/// (no vertex; a face without a surface or a wire, or with an edge without its curve on it).
std::optional<double> volume_by_faces(const TopoDS_Shape& shape, double relative_error);

}  // namespace ncrev::brep_detail
