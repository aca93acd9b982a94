// reverse_to_step(): mesh -> B-rep (facets or planar) -> check -> STEP, with the numbers.
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <chrono>

#include "brep/planar.h"
#include "brep/step.h"
#include "ncrev/brep.h"

namespace ncrev {

const char* to_string(ReverseMethod method) {
    return method == ReverseMethod::kFacets ? "facets" : "planar";
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

namespace {}  // namespace

Result<ReverseReport> reverse_to_step(const Mesh& mesh, const std::filesystem::path& output,
                                      const ReverseOptions& options) {
    using Clock = std::chrono::steady_clock;
    ReverseReport rep;
    rep.method = options.method;
    if (mesh.num_faces() == 0) {
        Error e;
        e.code = ErrorCode::kEmpty;
        e.path = output.string();
        e.message = "the mesh has no facet: nothing to write";
        return e;
    }
    auto stage = [&](const char* name, auto&& fn) {
        if (options.progress) options.progress(name, 0.0);
        const auto t0 = Clock::now();
        fn();
        rep.stage_seconds.emplace_back(name,
                                       std::chrono::duration<double>(Clock::now() - t0).count());
        if (options.progress) options.progress(name, 1.0);
    };
    const MeshStats stats = compute_stats(mesh);
    rep.mesh_volume = stats.volume;
    rep.mesh_area = stats.area;
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
    brep_detail::PlanarBuild built;
    try {
        stage("brep", [&] {
            built = brep_detail::build_planar_shape(mesh, options.method == ReverseMethod::kPlanar,
                                                    rep.planar_tolerance);
        });
        rep.faces = built.faces;
        rep.edges = built.edges;
        rep.vertices = built.vertices;
        rep.faces_by_kind["plane"] = built.faces;
        rep.solid = built.solid;
        stage("check", [&] {
            BRepCheck_Analyzer analyzer(built.shape);
            rep.valid = analyzer.IsValid();
            GProp_GProps props;
            BRepGProp::SurfaceProperties(built.shape, props);
            rep.solid_area = props.Mass();
            if (built.solid) {
                GProp_GProps vprops;
                BRepGProp::VolumeProperties(built.shape, vprops);
                rep.solid_volume = vprops.Mass();
            }
        });
    } catch (const Standard_Failure& f) {
        Error e;
        e.code = ErrorCode::kBadValue;
        e.path = output.string();
        e.message = std::string("OpenCASCADE failed building the B-rep: ") + f.GetMessageString();
        return e;
    }
    if (!built.solid)
        rep.warnings.push_back(
            "the mesh is open: written as a shell (a surface model), not a solid");
    if (!rep.valid) {
        rep.warnings.push_back("BRepCheck_Analyzer reports the shape invalid: nothing written");
        return rep;
    }
    Status written = Ok{};
    stage("step", [&] {
        brep_detail::StepWriteOptions w;
        w.schema = options.schema;
        w.unit = options.unit;
        w.product_name = options.product_name.empty() ? "ncrev" : options.product_name;
        written = brep_detail::write_step_file(built.shape, output, w);
    });
    if (!written) return written.error();
    rep.written = true;
    std::error_code ec;
    rep.step_bytes = std::filesystem::file_size(output, ec);
    return rep;
}

}  // namespace ncrev
