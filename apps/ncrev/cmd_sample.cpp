// `ncrev sample NAME|all -o DIR`: machined sample parts with ground truth (mesh, solid,
// labels, face parameters), built with OpenCASCADE. See docs/samples.md.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "ncrev/sample.h"

namespace ncrev::cli {
namespace {

struct SampleCliOptions {
    std::string name;
    std::string out;
    double deflection = 0;
    double angular = kSampleAngularDeflection;
    std::uint64_t seed = 0;
    bool list = false;
    bool quiet = false;
    bool json = false;
};

std::string part_names() {
    std::string s;
    for (const SamplePartInfo& p : sample_parts()) {
        if (!s.empty()) s += ", ";
        s += p.name;
    }
    return s;
}

void print_list(bool json) {
    if (json) {
        nlohmann::ordered_json parts = nlohmann::ordered_json::array();
        for (const SamplePartInfo& p : sample_parts()) {
            parts.push_back({{"name", p.name}, {"description", p.description}});
        }
        std::cout << nlohmann::ordered_json{{"parts", parts}}.dump(2) << '\n';
        return;
    }
    std::size_t width = 0;
    for (const SamplePartInfo& p : sample_parts()) width = std::max(width, p.name.size());
    for (const SamplePartInfo& p : sample_parts()) {
        std::cout << p.name << std::string(width + 2 - p.name.size(), ' ') << p.description << '\n';
    }
}

int run_sample(const SampleCliOptions& o) {
    if (o.list) {
        print_list(o.json);
        return kExitOk;
    }
    if (o.name.empty()) {
        print_error("sample: name a part or 'all' (parts: " + part_names() + ")");
        return kExitUsage;
    }
    if (o.out.empty()) {
        print_error("sample: -o DIR is required");
        return kExitUsage;
    }
    std::vector<std::string_view> names;
    if (o.name == "all") {
        for (const SamplePartInfo& p : sample_parts()) names.push_back(p.name);
    } else if (is_sample_part(o.name)) {
        names.push_back(o.name);
    } else {
        print_error("sample: unknown part '" + o.name + "' (parts: " + part_names() + ", all)");
        return kExitUsage;
    }

    SampleOptions options;
    options.seed = o.seed;
    options.deflection = o.deflection;
    options.angular_deflection = o.angular;
    nlohmann::ordered_json written = nlohmann::ordered_json::array();
    int exit_code = kExitOk;
    const auto t_all = std::chrono::steady_clock::now();
    for (const std::string_view name : names) {
        const auto t0 = std::chrono::steady_clock::now();
        Result<SamplePart> part = make_sample_part(name, options);
        if (!part) {
            print_error(part.error().describe());
            exit_code =
                part.error().code == ErrorCode::kCannotWrite ? kExitCannotWrite : kExitNoResult;
            if (exit_code == kExitCannotWrite) break;
            continue;
        }
        Result<SampleFiles> files = write_sample_part(*part, o.out);
        if (!files) {
            print_error(files.error().describe());
            exit_code = kExitCannotWrite;
            break;
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (part->weld.float32_mismatches != 0 && !o.quiet) {
            print_warning(std::string(name) + ": " + std::to_string(part->weld.float32_mismatches) +
                          " shared mesh nodes differ in float32 between faces (merged anyway)");
        }
        if (o.json) {
            written.push_back({{"name", part->name},
                               {"seed", part->seed},
                               {"deflection", part->deflection},
                               {"angular_deflection", part->angular_deflection},
                               {"facets", part->mesh.num_facets()},
                               {"vertices", part->mesh.points.size()},
                               {"faces", part->faces.size()},
                               {"volume", part->solid.volume},
                               {"folder", files->folder.string()},
                               {"files",
                                {{"stl", files->stl.string()},
                                 {"sre", files->sre.string()},
                                 {"step", files->step.string()},
                                 {"labels", files->labels.string()},
                                 {"truth", files->truth.string()}}},
                               {"seconds", seconds}});
        } else if (!o.quiet) {
            std::printf("%-24s %8zu facets  %4zu faces  %s\n", part->name.c_str(),
                        part->mesh.num_facets(), part->faces.size(),
                        files->folder.string().c_str());
        }
    }
    if (o.json) {
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t_all).count();
        std::cout << nlohmann::ordered_json{{"output", o.out},
                                            {"ok", exit_code == kExitOk},
                                            {"parts", written},
                                            {"seconds", seconds}}
                         .dump(2)
                  << '\n';
    }
    std::fflush(stdout);
    return exit_code;
}

void add_sample(CLI::App& app, Context& ctx) {
    auto opts = std::make_shared<SampleCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "sample",
        "Write machined sample parts with ground truth: for each part DIR/NAME/ holds NAME.stl "
        "(binary), NAME.sre (per facet: tool color, cut = face index, analytic surface), "
        "NAME.step (the exact solid, AP214, mm), NAME.labels (the true face index of every "
        "facet, one per line) and NAME.truth.json (faces, surface parameters, areas, volume, "
        "dimensions). The same name, seed and options give byte-identical files.");
    cmd->add_option("NAME", opts->name, "Part name, or 'all' (see --list)");
    cmd->add_option("-o,--output", opts->out, "Output folder (created if missing)");
    cmd->add_option("--deflection", opts->deflection,
                    "Chordal deflection in mm (default: 0.0005 x the part's bounding-box "
                    "diagonal, about 0.06 mm for a 100 mm part)")
        ->check(kPositive);
    cmd->add_option("--angular", opts->angular,
                    "Angular deflection in radians (default 0.35, about 20 degrees)")
        ->check(kPositive);
    cmd->add_option("--seed", opts->seed,
                    "Dimension variant: 0 = nominal dimensions, other values vary them "
                    "deterministically");
    cmd->add_flag("--list", opts->list, "List the parts with a one-line description");
    cmd->add_flag("-q,--quiet", opts->quiet, "Print nothing but errors");
    cmd->add_flag("--json", opts->json, "Print one JSON document summarising what was written");
    cmd->callback([opts, &ctx]() { ctx.exit_code = run_sample(*opts); });
}

const bool kRegistered = register_command({20, add_sample});

}  // namespace
}  // namespace ncrev::cli
