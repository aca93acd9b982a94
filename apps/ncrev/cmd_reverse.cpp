// `ncrev reverse INPUT -o OUTPUT.step --method facets|planar`: the mesh as a STEP solid.
#include <cstdio>
#include <iostream>
#include <map>

#include "commands.h"
#include "ncrev/brep.h"
#include "ncrev/report.h"

namespace ncrev::cli {
namespace {

struct ReverseCliOptions {
    std::string input, output, report;
    ReverseMethod method = ReverseMethod::kPlanar;
    StepSchema schema = StepSchema::kAP214;
    bool require_solid = false;
    bool json = false;
    bool quiet = false;
};

void add_reverse(CLI::App& app, Context& ctx) {
    auto o = std::make_shared<ReverseCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "reverse",
        "Rebuild a CAD solid from a mesh (STL or SRE) and write it as STEP. Methods: 'facets' "
        "gives one planar face per facet (the paper's method 1); 'planar' (default) merges "
        "coplanar neighbours into one planar face with its outer and inner wires, so a "
        "prismatic part comes back with its true faces. A closed mesh gives a solid; an open "
        "one a shell (a surface model) and a warning.");
    cmd->add_option("INPUT", o->input, "Mesh file: .stl (ASCII or binary) or .sre")->required();
    cmd->add_option("-o,--output", o->output, "STEP file to write (atomically)")->required();
    const std::map<std::string, ReverseMethod> methods{{"facets", ReverseMethod::kFacets},
                                                       {"planar", ReverseMethod::kPlanar}};
    cmd->add_option("--method", o->method,
                    "facets: one planar face per facet; planar: coplanar facets merged (default)")
        ->transform(CLI::CheckedTransformer(methods, CLI::ignore_case))
        ->option_text("facets|planar");
    const std::map<std::string, StepSchema> schemas{{"ap214", StepSchema::kAP214},
                                                    {"ap203", StepSchema::kAP203},
                                                    {"ap242", StepSchema::kAP242}};
    cmd->add_option("--schema", o->schema, "STEP application protocol (default ap214)")
        ->transform(CLI::CheckedTransformer(schemas, CLI::ignore_case))
        ->option_text("ap214|ap203|ap242");
    cmd->add_option("--report", o->report,
                    "Write a JSON report: stages with timings, healing, faces by kind, edges, "
                    "vertices, whether the result is a closed valid solid, volumes and areas");
    cmd->add_flag("--require-solid", o->require_solid,
                  "Fail (exit 3, nothing written) unless the result is a closed solid");
    cmd->add_flag("--json", o->json, "Print the report (as --report writes it) on stdout");
    cmd->add_flag("-q,--quiet", o->quiet, "No warnings and no progress on stderr");
    cmd->callback([o, &ctx]() {
        const std::filesystem::path in(o->input), out(o->output);
        auto healed = read_input(in, out, ctx, o->quiet);
        if (!healed) return;
        const auto progress = terminal_progress(ctx, o->quiet);
        if (o->require_solid && !healed->report.mesh.closed) {
            print_error(o->input + ": the mesh is open (" +
                        std::to_string(healed->report.mesh.boundary_loops) +
                        " boundary loops): no solid, nothing written (--require-solid)");
            ctx.exit_code = kExitNoResult;
            return;
        }
        ReverseOptions ro;
        ro.method = o->method;
        ro.schema = o->schema;
        ro.unit = healed->report.unit;
        ro.product_name = in.stem().string();
        ro.progress = progress;
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
            print_error(o->input + ": the B-rep is not a valid shape; nothing written");
            ctx.exit_code = kExitNoResult;
            return;
        }
        if (!o->json && !o->quiet) {
            std::fprintf(stderr, "%s: %llu faces, %llu edges, %llu vertices, %s, %llu bytes\n",
                         o->output.c_str(), static_cast<unsigned long long>(rev->faces),
                         static_cast<unsigned long long>(rev->edges),
                         static_cast<unsigned long long>(rev->vertices),
                         rev->solid ? "closed solid" : "open shell",
                         static_cast<unsigned long long>(rev->step_bytes));
        }
        ctx.exit_code = kExitOk;
    });
}

const bool kRegistered = register_command({30, add_reverse});

}  // namespace
}  // namespace ncrev::cli
