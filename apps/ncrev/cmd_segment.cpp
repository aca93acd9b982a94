// `ncrev segment INPUT -o OUTPUT.ply [--method facets|paper] [--labels FILE] [--json]`: the
// mesh split into regions, one fitted surface each, as a PLY colored by region.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <numbers>

#include "commands.h"
#include "ncrev/report.h"
#include "ncrev/segment.h"

namespace ncrev::cli {
namespace {

struct SegmentCliOptions {
    std::string input, output, labels;
    SegmentOptions segment;
    double sharp_degrees = 0;
    bool no_surfaces = false;
    bool no_snap = false;
    bool json = false;
    bool quiet = false;
};

void add_segment(CLI::App& app, Context& ctx) {
    auto o = std::make_shared<SegmentCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "segment",
        "Split a mesh (STL or SRE) into regions, each described by one surface: plane, "
        "cylinder, cone, sphere, torus, shear cylinder, swept torus, or a B-spline where no "
        "simpler surface fits. Writes a binary PLY whose faces carry 'region' (int) and "
        "'red green blue' (one color per region). With SRE input the file's surface indices "
        "are kept and only the facets without one are segmented. The tolerance (how far a "
        "vertex may lie from its region's surface) and the mesh's chordal deflection are "
        "derived from the model and reported.");
    cmd->add_option("INPUT", o->input, "Mesh file: .stl (ASCII or binary) or .sre")->required();
    cmd->add_option("-o,--output", o->output, "PLY file to write (atomically)")->required();
    const std::map<std::string, SegmentMethod> methods{{"facets", SegmentMethod::kFacets},
                                                       {"paper", SegmentMethod::kPaper}};
    cmd->add_option("--method", o->segment.method,
                    "facets (default): sharp edges, then regions grown facet by facet while one "
                    "surface fits, merged, their borders refined; paper: the paper's vertex "
                    "method (curvature types, refining, connected regions, merging)")
        ->transform(keywords(methods))
        ->option_text("facets|paper");
    cmd->add_option("--labels", o->labels,
                    "Also write one region id per input facet, one per line, in input order "
                    "(-1 for a facet that healing removed)");
    cmd->add_option("--tolerance", o->segment.tolerance,
                    "Largest distance of a vertex from its region's surface, in the file's unit "
                    "(default: 1e-4 x the part's size, the diagonal of its smallest box, the same "
                    "in every pose; raised to six times the noise of a noisy mesh)")
        ->check(kPositive);
    cmd->add_option("--sharp-angle", o->sharp_degrees,
                    "Dihedral angle in degrees from which an edge is sharp (default " +
                        std::to_string(static_cast<int>(
                            std::lround(kDefaultSegmentSharpAngle * 180 / std::numbers::pi))) +
                        ")")
        ->check(CLI::Range(1.0, 179.0));
    cmd->add_flag("--no-surface-indices", o->no_surfaces,
                  "Segment every facet, ignoring the surface indices of an SRE file");
    cmd->add_flag("--no-snap", o->no_snap,
                  "Keep the fitted values: by default axes are made parallel, coaxial and along "
                  "the coordinate axes, and positions, radii and cone angles round, where the "
                  "points cannot tell them from the fit");
    cmd->add_flag(
        "--json", o->json,
        "Print one JSON object on stdout: input, healing, mesh, segment (method, "
        "tolerances, counts, seconds, each step's seconds) and regions (id, kind, params, "
        "facets, area, rms, max)");
    cmd->add_flag("-q,--quiet", o->quiet, "No warnings and no progress on stderr");
    cmd->callback([o, &ctx]() {
        const std::filesystem::path in(o->input), out(o->output);
        if (!o->labels.empty()) {
            std::error_code ec;
            if (std::filesystem::equivalent(in, o->labels, ec) ||
                std::filesystem::path(o->labels) == out) {
                print_error("--labels " + o->labels + " would overwrite the input or the output");
                ctx.exit_code = kExitUsage;
                return;
            }
            if (refuses_folder(o->labels, ctx)) return;
        }
        auto healed = read_input(in, out, ctx, o->quiet);
        if (!healed) return;
        if (healed->mesh.num_faces() == 0) {
            print_error(o->input + ": no facet left after healing; nothing to segment");
            ctx.exit_code = kExitNoResult;
            return;
        }
        SegmentOptions so = o->segment;
        if (o->sharp_degrees > 0) so.sharp_angle = o->sharp_degrees * std::numbers::pi / 180;
        so.surfaces = healed->surfaces;
        so.tools = healed->tools;
        so.use_surface_indices = !o->no_surfaces;
        so.snap = !o->no_snap;
        const auto progress = terminal_progress(ctx, o->quiet);
        Result<SegmentResult> r = segment(healed->mesh, so, progress);
        if (!r) {
            print_error(r.error().describe());
            ctx.exit_code = kExitUsage;
            return;
        }
        const std::vector<std::byte> ply = encode_segments_ply(healed->mesh, r.value());
        if (auto s = write_file_atomic(out, ply); !s) {
            print_error(s.error().describe());
            ctx.exit_code = kExitCannotWrite;
            return;
        }
        if (!o->labels.empty()) {
            const std::string text =
                labels_text(input_labels(healed->mesh, r.value(), healed->report.input_facets));
            const auto* bytes = reinterpret_cast<const std::byte*>(text.data());
            if (auto s = write_file_atomic(o->labels, {bytes, text.size()}); !s) {
                print_error(s.error().describe());
                ctx.exit_code = kExitCannotWrite;
                return;
            }
        }
        if (o->json) {
            std::cout << to_json(healed->report, r.value()) << '\n';
        } else {
            std::cout << to_text(healed->report) << to_text(r.value(), healed->report.unit);
        }
        if (!o->quiet) {
            for (const std::string& w : healed->report.warnings) print_warning(w);
        }
        ctx.exit_code = kExitOk;
    });
}

const bool kRegistered = register_command({27, add_segment});

}  // namespace
}  // namespace ncrev::cli
