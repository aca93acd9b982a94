// What OpenCASCADE's checker finds wrong with a shape, in words. Internal.
#pragma once

#include <TopoDS_Shape.hxx>
#include <string>
#include <vector>

namespace ncrev::brep_detail {

/// What BRepCheck_Analyzer finds wrong with `shape`, in words (empty when valid; at most ~300
/// characters, each kind of defect once), and, when `bad` is given, the sub-shapes it finds
/// wrong (vertices, edges, wires, faces, shells, solids) appended to it. `parallel`: the
/// analyzer checks the sub-shapes on several threads (same findings).
std::string check_failure(const TopoDS_Shape& shape, std::vector<TopoDS_Shape>* bad = nullptr,
                          bool parallel = false);

}  // namespace ncrev::brep_detail
