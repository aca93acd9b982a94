// sample: machined parts with ground truth. Each part is built exactly with OpenCASCADE from a
// few named dimensions (pocket, holes, counterbore, countersink, slots, fillets, chamfers, a
// boss, a bracket, a turned shaft, a ball-end pocket, a free-form die, a flange ...), then
// tessellated once so that every facet knows the face (and the analytic surface) it lies on.
// What it produces is what the rest of ncrev must recover: the mesh (STL, SRE), the solid
// (STEP), the facet labels and the face parameters (truth JSON). docs/samples.md describes the
// parts, the files and the conventions.
//
// OpenCASCADE stays inside src/sample: this header speaks plain data only.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ncrev/common.h"
#include "ncrev/io.h"

namespace ncrev {

/// Default chordal deflection as a fraction of the part's bounding-box diagonal: 0.05 % gives
/// about 0.06 mm on a 100 mm part, finer than a typical NC simulation's tolerance yet small
/// enough files (tens of thousands of facets).
constexpr double kSampleRelativeDeflection = 0.0005;
/// Default angular deflection (rad, about 20 degrees): bounds the facet count of small radii
/// (fillets, holes) that the chordal deflection alone would leave coarse.
constexpr double kSampleAngularDeflection = 0.35;

/// A part the sample module can build.
struct SamplePartInfo {
    std::string_view name;         ///< e.g. "pocket_block"
    std::string_view description;  ///< one line
};

/// Every part, in a fixed order (the order of `ncrev sample all`).
std::span<const SamplePartInfo> sample_parts();

/// True when `name` names a part of sample_parts().
bool is_sample_part(std::string_view name);

/// How to build and tessellate a part.
struct SampleOptions {
    /// 0: the nominal dimensions. Other values vary every dimension deterministically (own
    /// splitmix64 stream per part; the same seed gives the same part on every platform).
    std::uint64_t seed = 0;
    /// Chordal deflection in mm; <= 0: relative_deflection x bounding-box diagonal.
    double deflection = 0;
    /// Chordal deflection as a fraction of the bounding-box diagonal, used when `deflection`
    /// is <= 0; > 0.
    double relative_deflection = kSampleRelativeDeflection;
    /// Angular deflection in radians, > 0.
    double angular_deflection = kSampleAngularDeflection;
    /// Also produce the STEP text (the slowest output; tests may skip it).
    bool with_step = true;
};

/// A named dimension of a part (mm, or degrees / a count where the name says so).
struct SampleDimension {
    std::string name;
    double value = 0;
};

/// One face of the exact solid. Faces are numbered from 0 in OpenCASCADE's
/// TopExp::MapShapes order; that number is the facet label and the SRE cut number.
struct SampleFace {
    std::uint32_t index = 0;
    /// "plane", "cylinder", "cone", "sphere", "torus", "bspline", "bezier", "revolution",
    /// "extrusion", "offset" or "other".
    std::string kind;
    /// Index into the SRE surface table (TriangleSoup::surfaces); -1 when not analytic.
    std::int32_t surface = -1;
    double area = 0;               ///< exact face area, mm^2
    std::uint64_t num_facets = 0;  ///< facets carrying this face's label
};

/// Numbers of the exact solid.
struct SampleSolid {
    bool valid = false;   ///< BRepCheck_Analyzer found no defect
    bool closed = false;  ///< every non-degenerate edge bounds exactly two face sides
    double volume = 0;    ///< mm^3
    double area = 0;      ///< mm^2
    Box3 bbox;            ///< tight bounding box
    std::uint64_t num_faces = 0, num_edges = 0, num_vertices = 0;
};

/// How the per-face triangulations were joined into one mesh.
struct SampleWeld {
    /// Face-triangulation nodes merged because they are the same node of a shared edge or
    /// vertex (topological weld).
    std::uint64_t merged_nodes = 0;
    /// Of those, nodes whose float32-rounded coordinates differ from their vertex's: 0 means
    /// the STL welds exactly (it is written from the merged vertices either way).
    std::uint64_t float32_mismatches = 0;
    double max_gap = 0;  ///< largest distance between merged nodes, mm
    /// Distinct nodes that round to the same float32 point (e.g. a cone apex) and were merged.
    std::uint64_t coincident_merges = 0;
    /// Facets dropped because two of their corners became one vertex (at poles and apexes).
    std::uint64_t degenerate_facets_dropped = 0;
};

/// A built, tessellated part and all it is written as.
struct SamplePart {
    std::string name;
    std::uint64_t seed = 0;
    double deflection = 0;          ///< the chordal deflection used, mm
    double angular_deflection = 0;  ///< rad
    std::string deflection_rule;    ///< how `deflection` was chosen, in words
    std::vector<SampleDimension> dimensions;

    /// The mesh with shared vertices, facets counter-clockwise seen from outside; SRE
    /// attributes per facet: color (one per surface kind, see `tools`), cut (= face index),
    /// surface (index into `surfaces`, -1 for free-form faces).
    TriangleSoup mesh;
    std::vector<std::int32_t> labels;  ///< the face index of every facet, in facet order
    std::vector<SampleFace> faces;     ///< indexed by face index
    SampleSolid solid;
    SampleWeld weld;

    std::string truth_json;  ///< the NAME.truth.json document
    std::string step;        ///< the NAME.step text (AP214, mm); empty without with_step
};

/// Builds part `name` with `options`. Errors: kBadValue for an unknown name, a
/// non-finite deflection or a non-positive angular or relative deflection; kBadValue with
/// OpenCASCADE's reason when modelling or meshing fails (a seed that yields an impossible part);
/// kCannotWrite when the STEP text cannot be produced. Never throws, never prints. Deterministic:
/// the same name and options give byte-identical outputs.
Result<SamplePart> make_sample_part(std::string_view name, const SampleOptions& options = {});

/// A STEP file's solid (the largest, when it holds several) described and tessellated like a
/// sample part: labels, faces, surfaces, truth document; `name` is the file's stem, `seed` and
/// `dimensions` are empty, `options.with_step` writes the solid back. The solid need not pass
/// BRepCheck (`solid.valid` says whether it does): real files often do not. Errors: kBadSyntax
/// when OpenCASCADE cannot read the file, kBadValue when it holds no solid or meshing fails;
/// the error names the file. Never throws, never prints.
Result<SamplePart> sample_from_step(const std::filesystem::path& path,
                                    const SampleOptions& options = {});

/// The files write_sample_part() wrote.
struct SampleFiles {
    std::filesystem::path folder, stl, sre, step, labels, truth;
};

/// Writes `part` into `dir/NAME/` (created if missing) as NAME.stl (binary), NAME.sre,
/// NAME.step (when the part has STEP text), NAME.labels (one face index per facet, one per
/// line) and NAME.truth.json, each atomically. Error kCannotWrite names the file.
Result<SampleFiles> write_sample_part(const SamplePart& part, const std::filesystem::path& dir);

}  // namespace ncrev
