// reverse_to_step(): mesh -> B-rep (facets or planar) -> check -> STEP, with the numbers.
#include <BRepCheck_Analyzer.hxx>
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

namespace {  // Largest B-rep on which OpenCASCADE's BRepCheck_Analyzer also runs (it costs ~0.3 ms
             // a face:
// about 1.5 s here); larger ones rely on the structural check, which the construction
// guarantees anyway and which costs O(n).
constexpr std::uint64_t kOcctCheckMaxFaces = 5000;

}  // namespace

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
    brep_detail::PlanarTopology topo;
    stage("brep", [&] {
        topo = brep_detail::planar_topology(mesh, options.method == ReverseMethod::kPlanar,
                                            rep.planar_tolerance);
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
        brep_detail::StepWriteOptions w;
        w.schema = options.schema;
        w.unit = options.unit;
        w.product_name = options.product_name.empty() ? "ncrev" : options.product_name;
        written = brep_detail::write_planar_step(topo, mesh, output, w);
    });
    if (!written) return written.error();
    rep.written = true;
    std::error_code ec;
    rep.step_bytes = std::filesystem::file_size(output, ec);
    return rep;
}

}  // namespace ncrev
