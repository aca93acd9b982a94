// `ncrev curvature INPUT -o OUTPUT.ply [--json]`: curvature, shape index, curvedness, the ten
// surface types and the high-curvature points of every vertex, as a colored PLY.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <numbers>

#include "commands.h"
#include "ncrev/curvature.h"
#include "ncrev/report.h"

namespace ncrev::cli {
namespace {

struct CurvatureCliOptions {
    std::string input, output;
    CurvatureOptions curvature;  ///< the library's defaults, overridden by the options
    double sharp_degrees = -1;
    bool json = false;
    bool quiet = false;
};

void add_curvature(CLI::App& app, Context& ctx) {
    auto o = std::make_shared<CurvatureCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "curvature",
        "Estimate the curvature at every vertex of a mesh (STL or SRE): principal curvatures "
        "k1 >= k2 (positive where the part is convex), shape index, curvedness, one of ten "
        "surface types (0 plane, 1 cup, 2 trough, 3 rut, 4 saddle rut, 5 saddle, 6 saddle ridge, "
        "7 ridge, 8 dome, 9 cap) and whether it is a high-curvature point (on a sharp edge or a "
        "fillet narrower than the mesh resolves). Writes a binary PLY whose vertices carry "
        "x y z k1 k2 shape_index curvedness (float), type high (uchar) and red green blue "
        "colored by type, so a viewer such as MeshLab shows the types at once. Curvature is in "
        "1/unit of the file (STL: mm assumed).");
    cmd->add_option("INPUT", o->input, "Mesh file: .stl (ASCII or binary) or .sre")->required();
    cmd->add_option("-o,--output", o->output, "PLY file to write (atomically)")->required();
    const std::map<std::string, CurvatureEstimator> estimators{
        {"plain", CurvatureEstimator::kPlain}, {"weighted", CurvatureEstimator::kWeighted}};
    cmd->add_option("--estimator", o->curvature.estimator,
                    "plain: the normal-cycle shape operator (default); weighted: with the "
                    "paper's per-edge weights (less accurate, see docs/curvature.md)")
        ->transform(keywords(estimators))
        ->option_text("plain|weighted");
    std::map<std::string, Neighbourhood> neighbourhoods;
    for (const Neighbourhood n : {Neighbourhood::kSmoothed, Neighbourhood::kKernel,
                                  Neighbourhood::kRings, Neighbourhood::kGeodesic}) {
        neighbourhoods.emplace(to_string(n), n);
    }
    cmd->add_option("--neighbourhood", o->curvature.neighbourhood,
                    "smoothed (default): three rounds of neighbour averaging under a smooth "
                    "kernel of about three edges, never beyond a small arc of the surface; "
                    "kernel: the same kernel summed exactly (slower); rings: the cells of the "
                    "--rings ring; geodesic: the cells within --radius along edges")
        ->transform(keywords(neighbourhoods))
        ->option_text("smoothed|kernel|rings|geodesic");
    cmd->add_option("--rings", o->curvature.rings, "Rings of the 'rings' neighbourhood")
        ->capture_default_str()
        ->check(CLI::Range(1, 16));
    cmd->add_option("--radius", o->curvature.radius,
                    "Radius of the 'geodesic' neighbourhood, in the file's unit")
        ->check(kPositive);
    cmd->add_option("--planar-curvedness", o->curvature.planar_curvedness,
                    "Curvedness (1/unit) below which a vertex is planar (default: from the "
                    "model size and the coordinate precision; the value used is reported)")
        ->check(kNonNegative);
    cmd->add_option(
           "--sharp-angle", o->sharp_degrees,
           "Dihedral angle in degrees from which an edge is sharp (default " +
               std::to_string(kDefaultSharpEdgeAngle * 180 / std::numbers::pi).substr(0, 4) + ")")
        ->check(CLI::Range(0.0, 180.0));
    cmd->add_flag("--json", o->json,
                  "Print one JSON object on stdout: input, healing, mesh, and curvature "
                  "(thresholds used, vertices per type, high-curvature points, seconds)");
    cmd->add_flag("-q,--quiet", o->quiet, "No warnings and no progress on stderr");
    cmd->callback([o, cmd, &ctx]() {
        const std::filesystem::path in(o->input), out(o->output);
        CurvatureOptions co = o->curvature;
        if (co.neighbourhood == Neighbourhood::kGeodesic && co.radius <= 0) {
            print_error("--neighbourhood geodesic needs --radius");
            ctx.exit_code = kExitUsage;
            return;
        }
        if (co.neighbourhood != Neighbourhood::kGeodesic && cmd->count("--radius") > 0) {
            print_error("--radius applies to --neighbourhood geodesic only");
            ctx.exit_code = kExitUsage;
            return;
        }
        auto healed = read_input(in, out, ctx, o->quiet);
        if (!healed) return;
        const auto progress = terminal_progress(ctx, o->quiet);
        if (healed->mesh.num_faces() == 0) {
            print_error(o->input + ": no facet left after healing; nothing to estimate");
            ctx.exit_code = kExitNoResult;
            return;
        }
        if (o->sharp_degrees >= 0) co.sharp_edge_angle = o->sharp_degrees * std::numbers::pi / 180;
        if (progress) progress("curvature", 0.0);
        const auto t0 = std::chrono::steady_clock::now();
        const CurvatureResult result = compute_curvature(healed->mesh, co);
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (progress) progress("curvature", 1.0);
        const std::vector<std::byte> ply = encode_curvature_ply(healed->mesh, result);
        if (auto s = write_file_atomic(out, ply); !s) {
            print_error(s.error().describe());
            ctx.exit_code = kExitCannotWrite;
            return;
        }
        if (o->json) {
            std::cout << to_json(healed->report, result, seconds) << '\n';
        } else {
            std::cout << to_text(healed->report) << to_text(result, healed->report.unit);
        }
        if (!o->quiet) {
            for (const std::string& w : healed->report.warnings) print_warning(w);
        }
        ctx.exit_code = kExitOk;
    });
}

const bool kRegistered = register_command({25, add_curvature});

}  // namespace
}  // namespace ncrev::cli
