// brep: the mesh as an OpenCASCADE solid, written as STEP (../shared/docs/method.md, Step 2a).
//
// Methods:
//  - facets: the paper's method 1, one planar face per facet;
//  - planar: coplanar neighbours merged into one planar face, bounded by its outer wire and
//    its inner wires (holes), with collinear boundary vertices removed.
// The B-rep is built directly with BRep_Builder, every vertex and every edge shared by the
// faces that meet there (no sewing), so it scales to a million facets. A closed mesh gives a
// solid (a MANIFOLD_SOLID_BREP in the STEP); an open one a shell (a surface model).
// OpenCASCADE stays inside src/brep: this header speaks plain data only.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "ncrev/common.h"
#include "ncrev/io.h"
#include "ncrev/mesh.h"

namespace ncrev {

enum class ReverseMethod { kFacets, kPlanar };
/// "facets", "planar".
const char* to_string(ReverseMethod method);

enum class StepSchema { kAP214, kAP203, kAP242 };
/// "ap214", "ap203", "ap242".
const char* to_string(StepSchema schema);

struct ReverseOptions {
    ReverseMethod method = ReverseMethod::kPlanar;
    StepSchema schema = StepSchema::kAP214;
    Unit unit = Unit::kMillimetre;  ///< the unit the STEP file declares (the mesh's own)
    std::string product_name;       ///< STEP product name; empty: "ncrev"
    /// Planar merging: largest distance of a facet's vertices from the plane of the face it
    /// joins, in model units. Negative: derived from the mesh (see ReverseReport).
    double planar_tolerance = -1;
    ProgressFn progress;  ///< one call at the start and end of each stage
};

/// What reverse_to_step() built, in numbers.
struct ReverseReport {
    ReverseMethod method = ReverseMethod::kPlanar;
    std::vector<std::pair<std::string, double>> stage_seconds;  ///< in order
    double planar_tolerance = 0;                                ///< used by `planar`, model units
    std::string planar_tolerance_rule;                          ///< how it was chosen
    std::map<std::string, std::uint64_t> faces_by_kind;         ///< e.g. {"plane": 12}
    std::uint64_t faces = 0, edges = 0, vertices = 0;
    bool solid = false;         ///< a closed shell was made into a solid
    bool valid = false;         ///< the structural check (and BRepCheck_Analyzer) found no defect
    bool occt_checked = false;  ///< BRepCheck_Analyzer ran too (B-reps of up to 5000 faces)
    double solid_volume = 0, solid_area = 0;  ///< of the B-rep's faces
    double mesh_volume = 0, mesh_area = 0;    ///< of the mesh it came from
    bool written = false;  ///< the STEP file was written (not when the shape is invalid)
    std::uint64_t step_bytes = 0;
    std::vector<std::string> warnings;
};

/// Builds the B-rep of `mesh` with `options.method`, checks it (a structural check always,
/// BRepCheck_Analyzer too up to 5000 faces) and, when valid, writes it to `output` as STEP,
/// atomically (a temporary file beside it, then a rename). An invalid shape is not written:
/// `written` false, `valid` false. Fails with kCannotWrite when the file cannot be written, kEmpty
/// for a mesh without facets, kBadValue when OpenCASCADE cannot build or transfer the shape (its
/// reason in the message). An open mesh is not an error: it gives a shell, `solid` false and a
/// warning.
Result<ReverseReport> reverse_to_step(const Mesh& mesh, const std::filesystem::path& output,
                                      const ReverseOptions& options = {});

}  // namespace ncrev
