// Writing OpenCASCADE shapes as STEP files: schema, unit, product name, a silent messenger and
// an atomic write. Internal to the library (OpenCASCADE types allowed).
#pragma once

#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "ncrev/brep.h"
#include "ncrev/common.h"

namespace ncrev::brep_detail {

/// Removes OpenCASCADE's default stdout printer once per process: stdout belongs to the user
/// (and to `--json`), and OCCT prints transfer statistics there by default.
void silence_occt();

struct StepWriteOptions {
    StepSchema schema = StepSchema::kAP214;
    Unit unit = Unit::kMillimetre;
    std::string product_name = "ncrev";
    /// Header time stamp. Fixed by default so that the same input gives byte-identical STEP
    /// (the house rule on determinism); empty: the current time.
    std::string timestamp = "2000-01-01T00:00:00";
    /// Face colors (0xRRGGBB, sRGB), written through XDE (STEPCAFControl_Writer) as surface
    /// styles; empty: plain geometry.
    std::vector<std::pair<TopoDS_Face, std::uint32_t>> face_colors;
    /// The whole shape's color (faces without one of their own show it), with face_colors.
    std::uint32_t shape_color = 0x9E9E9E;
};

/// Writes `shape` to `path` atomically (a temporary file in the same folder, then a rename).
/// kBadValue when OpenCASCADE cannot transfer the shape, kCannotWrite when the file cannot
/// be written. Serialised: OpenCASCADE's STEP settings are process-wide.
Status write_step_file(const TopoDS_Shape& shape, const std::filesystem::path& path,
                       const StepWriteOptions& options);

/// What the STEP reader makes of a written file.
struct ReadBack {
    std::string problem;  ///< empty when it holds one solid that passes BRepCheck_Analyzer
    /// Where it is wrong, as far as the read-back shape tells: the middles of edges that bound
    /// only one face, and a vertex of each face BRepCheck_Analyzer finds wrong (at most
    /// kReadBackPlaces of them).
    std::vector<std::array<double, 3>> places;
};
inline constexpr std::size_t kReadBackPlaces = 64;

/// Reads `path` back with OpenCASCADE's STEP reader and checks it: `solids` solids (one per
/// body written), each valid.
ReadBack step_read_back(const std::filesystem::path& path, int solids);

}  // namespace ncrev::brep_detail
