// `ncrev reverse INPUT -o OUTPUT.step [--method auto|surfaces|planar|facets]`: the mesh as a STEP
// solid.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <span>
#include <string>

#include "commands.h"
#include "ncrev/brep.h"
#include "ncrev/report.h"
#include "ncrev/segment.h"

namespace ncrev::cli {
namespace {

struct ReverseCliOptions {
    std::string input, output, report, labels, segments;
    ReverseMethod method = ReverseMethod::kAuto;
    double tolerance = 0;
    bool no_colors = false;
    bool no_surfaces = false;
    bool no_snap = false;
    StepSchema schema = StepSchema::kAP214;
    bool require_solid = false;
    bool json = false;
    bool quiet = false;
};

void add_reverse(CLI::App& app, Context& ctx) {
    auto o = std::make_shared<ReverseCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "reverse",
        "Rebuild a CAD solid from a mesh (STL or SRE) and write it as STEP. Methods: 'auto' "
        "(default) segments the mesh into regions (an SRE file's surface indices kept), fits "
        "each one surface (plane, cylinder, cone, sphere, torus, B-spline) and builds one "
        "face per region, its edges where the surfaces meet; a region whose face cannot be "
        "built comes back as one face on its surface bounded by its mesh edges (or, where that "
        "fails too, as its facets) and is reported. 'surfaces' is the same but fails "
        "(exit 3, nothing written) rather than fall back. 'planar' merges coplanar facets "
        "into planar faces; 'facets' gives one planar face per facet (the paper's method 1). "
        "A closed mesh gives a solid; an open one a shell (a surface model, planar method) "
        "and a warning. Faces carry colors: the SRE tool color, else one per surface kind.");
    cmd->add_option("INPUT", o->input, "Mesh file: .stl (ASCII or binary) or .sre")->required();
    cmd->add_option("-o,--output", o->output, "STEP file to write (atomically)")->required();
    const std::map<std::string, ReverseMethod> methods{{"auto", ReverseMethod::kAuto},
                                                       {"surfaces", ReverseMethod::kSurfaces},
                                                       {"facets", ReverseMethod::kFacets},
                                                       {"planar", ReverseMethod::kPlanar}};
    cmd->add_option("--method", o->method,
                    "auto (default): true surfaces, a region that fails as one face bounded by "
                    "its mesh edges (or as its facets); surfaces: "
                    "true surfaces or nothing; planar: coplanar facets merged; facets: one face "
                    "per facet")
        ->transform(keywords(methods))
        ->option_text("auto|surfaces|planar|facets");
    cmd->add_option("--labels", o->labels,
                    "auto/surfaces: also write the region of every input facet, one per line, "
                    "in input order (-1 for a facet that healing removed)");
    cmd->add_option("--segments", o->segments,
                    "auto/surfaces: also write the regions as a binary PLY (faces carry "
                    "'region' and 'red green blue'), as `ncrev segment` does");
    cmd->add_option("--tolerance", o->tolerance,
                    "auto/surfaces: largest distance of a vertex from its region's surface, in "
                    "the file's unit (default: 1e-4 x the part's size, the diagonal of its "
                    "smallest box, the same in every pose; raised to the noise of a "
                    "noisy mesh)")
        ->check(kPositive);
    cmd->add_flag("--no-surface-indices", o->no_surfaces,
                  "Segment every facet, ignoring the surface indices of an SRE file");
    cmd->add_flag("--no-snap", o->no_snap,
                  "Keep the fitted values: by default axes are made parallel, coaxial and along "
                  "the coordinate axes, and positions, radii and cone angles round, where the "
                  "points cannot tell them from the fit");
    cmd->add_flag("--no-colors", o->no_colors, "Write plain geometry, without face colors");
    const std::map<std::string, StepSchema> schemas{{"ap214", StepSchema::kAP214},
                                                    {"ap203", StepSchema::kAP203},
                                                    {"ap242", StepSchema::kAP242}};
    cmd->add_option("--schema", o->schema, "STEP application protocol (default ap214)")
        ->transform(keywords(schemas))
        ->option_text("ap214|ap203|ap242");
    cmd->add_option("--report", o->report,
                    "Write a JSON report: stages with timings, healing, regions, faces by kind, "
                    "fallbacks, edges, vertices, whether the result is a closed valid solid, "
                    "volumes, areas and the deviation between the solid and the mesh");
    cmd->add_flag(
        "--require-solid", o->require_solid,
        "Fail (exit 3, nothing written) unless the result is closed solids (an open mesh's "
        "closed components are, with auto and surfaces, when they are most of it) and the mesh "
        "does not pass through itself");
    cmd->add_flag("--json", o->json, "Print the report (as --report writes it) on stdout");
    cmd->add_flag("-q,--quiet", o->quiet, "No warnings and no progress on stderr");
    cmd->callback([o, &ctx]() {
        const std::filesystem::path in(o->input), out(o->output);
        for (const std::string* extra : {&o->labels, &o->segments, &o->report}) {
            std::error_code ec;
            if (!extra->empty() && (std::filesystem::equivalent(in, *extra, ec) ||
                                    std::filesystem::path(*extra) == out)) {
                print_error(*extra + " would overwrite the input or the output");
                ctx.exit_code = kExitUsage;
                return;
            }
            if (!extra->empty() && refuses_folder(*extra, ctx)) return;
        }
        auto healed = read_input(in, out, ctx, o->quiet);
        if (!healed) return;
        // After read_input(): an output refused (the input, a folder) gets no warning first.
        if (std::string ext = out.extension().string(); !o->quiet) {
            for (char& ch : ext)
                ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
            if (ext != ".step" && ext != ".stp") {
                print_warning(o->output +
                              ": written as STEP whatever its name; CAD systems look for "
                              ".step or .stp");
            }
        }
        const auto progress = terminal_progress(ctx, o->quiet);
        ReverseOptions ro;
        ro.method = o->method;
        ro.schema = o->schema;
        ro.unit = healed->report.unit;
        ro.product_name = in.stem().string();
        ro.progress = progress;
        ro.colors = !o->no_colors;
        ro.require_solid = o->require_solid;
        ro.heal = &healed->report.heal;
        ro.segment.tolerance = o->tolerance;
        ro.segment.surfaces = healed->surfaces;
        ro.segment.tools = healed->tools;
        ro.segment.use_surface_indices = !o->no_surfaces;
        ro.segment.snap = !o->no_snap;
        auto rev = reverse_to_step(healed->mesh, out, ro);
        if (!rev) {
            // A mesh with nothing to write is the input's fault: name the input.
            print_error(rev.error().code == ErrorCode::kEmpty
                            ? o->input + ": " + rev.error().message
                            : rev.error().describe());
            ctx.exit_code =
                rev.error().code == ErrorCode::kCannotWrite ? kExitCannotWrite : kExitNoResult;
            return;
        }
        if (rev->segmentation) {
            const SegmentResult& seg = *rev->segmentation;
            if (!o->labels.empty()) {
                const std::string text =
                    labels_text(input_labels(healed->mesh, seg, healed->report.input_facets));
                auto s = write_file_atomic(o->labels, std::as_bytes(std::span(text)));
                if (!s) {
                    print_error(s.error().describe());
                    ctx.exit_code = kExitCannotWrite;
                    return;
                }
            }
            if (!o->segments.empty()) {
                auto s = write_file_atomic(o->segments, encode_segments_ply(healed->mesh, seg));
                if (!s) {
                    print_error(s.error().describe());
                    ctx.exit_code = kExitCannotWrite;
                    return;
                }
            }
        }
        const std::string json = to_json(healed->report, *rev);
        if (!o->report.empty()) {
            const std::string text = json + "\n";
            auto s = write_file_atomic(o->report, std::as_bytes(std::span(text)));
            if (!s) {
                print_error(s.error().describe());
                ctx.exit_code = kExitCannotWrite;
                return;
            }
        }
        if (o->json) std::cout << json << '\n';
        if (!o->quiet) {
            for (const std::string& w : healed->report.warnings) print_warning(w);
            for (const std::string& w : rev->warnings) print_warning(w);
        }
        if (!rev->written) {
            print_error(
                o->input + ": no valid B-rep; nothing written" +
                (rev->warnings.empty() || o->quiet ? std::string() : " (see the warnings above)"));
            ctx.exit_code = kExitNoResult;
            return;
        }
        if (!o->json && !o->quiet) {
            std::string kinds;
            for (const auto& [kind, n] : rev->faces_by_kind) {
                kinds += (kinds.empty() ? "" : ", ") + std::to_string(n) + " " + kind;
            }
            std::string bodies =
                rev->bodies > 1
                    ? std::to_string(rev->bodies) + (rev->solid ? " closed solids" : " open shells")
                : rev->solid ? "closed solid"
                             : "open shell";
            if (rev->voids) {
                bodies += " with " + std::to_string(rev->voids) +
                          (rev->voids > 1 ? " cavities" : " cavity");
            }
            if (healed->report.heal.self_intersections > 0) bodies += " passing through itself";
            std::fprintf(stderr, "%s: %llu faces (%s), %llu edges, %llu vertices, %s, %llu bytes\n",
                         o->output.c_str(), static_cast<unsigned long long>(rev->faces),
                         kinds.c_str(), static_cast<unsigned long long>(rev->edges),
                         static_cast<unsigned long long>(rev->vertices), bodies.c_str(),
                         static_cast<unsigned long long>(rev->step_bytes));
        }
        ctx.exit_code = kExitOk;
    });
}

const bool kRegistered = register_command({30, add_reverse});

}  // namespace
}  // namespace ncrev::cli
