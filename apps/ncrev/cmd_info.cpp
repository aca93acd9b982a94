// `ncrev info FILE [--json]`: what was read and what healing did.
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "ncrev/report.h"

namespace ncrev::cli {
namespace {

struct InfoOptions {
    std::string path;
    bool json = false;
    bool quiet = false;
    double tolerance = -1;
    bool keep_holes = false;
};

void add_info(CLI::App& app, Context& ctx) {
    auto opts = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand(
        "info",
        "Read a mesh (STL ASCII or binary, SRE), heal it, and report what was read and what "
        "healing did: welded vertices, degenerate, duplicate and flipped facets, non-manifold "
        "edges and vertices, holes closed, components, cavities, parts that cross each other, "
        "facets that cross (the mesh passing through itself, and where), boundary loops "
        "(holes), Euler characteristic, area, volume, bounding box.");
    cmd->add_option("FILE", opts->path, "Mesh file: .stl (ASCII or binary) or .sre")->required();
    cmd->add_flag("--json", opts->json,
                  "Print one JSON object (input, healing, mesh, timing, warnings) on stdout");
    cmd->add_option("--tolerance", opts->tolerance,
                    "Weld distance in model units (default: 1e-6 x bounding-box diagonal, at "
                    "least 8 float32 ulps of the largest coordinate; 0: exact weld only)")
        ->check(kNonNegative);
    cmd->add_flag("--keep-holes", opts->keep_holes,
                  "Leave the mesh's holes open: by default cracks along T-junctions are closed by "
                  "splitting facets, and small holes (up to 64 edges, a perimeter up to half the "
                  "part's size) get new facets");
    cmd->add_flag("-q,--quiet", opts->quiet,
                  "No warnings and no progress on stderr (progress is only shown on a terminal)");
    cmd->callback([opts, &ctx]() {
        HealOptions heal;
        heal.weld_tolerance = opts->tolerance;
        heal.fill_holes = !opts->keep_holes;
        auto report = inspect_file(opts->path, heal, terminal_progress(ctx, opts->quiet));
        if (!report) {
            print_error(report.error().describe());
            ctx.exit_code = kExitBadInput;
            return;
        }
        if (opts->json) {
            std::cout << to_json(*report) << '\n';
        } else {
            std::cout << to_text(*report);
        }
        if (!opts->quiet) {
            for (const std::string& w : report->warnings) print_warning(w);
        }
        ctx.exit_code = kExitOk;
    });
}

const bool kRegistered = register_command({10, add_info});

}  // namespace
}  // namespace ncrev::cli
