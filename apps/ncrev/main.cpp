// ncrev: machined-part meshes (STL, SRE) back to CAD solids (STEP). The subcommands live in
// cmd_*.cpp; this file only assembles them and maps failures to exit codes.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.h"

namespace ncrev::cli {

std::vector<Command>& registered_commands() {
    static std::vector<Command> commands;
    return commands;
}

bool register_command(Command command) {
    registered_commands().push_back(std::move(command));
    return true;
}

std::function<void(std::string_view, double)> terminal_progress(const Context& ctx, bool quiet) {
    if (quiet || !ctx.stderr_is_tty) return {};
    struct State {
        std::chrono::steady_clock::time_point start;
    };
    auto state = std::make_shared<State>();
    return [state](std::string_view stage, double fraction) {
        const auto now = std::chrono::steady_clock::now();
        if (fraction <= 0.0) {
            state->start = now;
            std::fprintf(stderr, "ncrev: %.*s ...", static_cast<int>(stage.size()), stage.data());
        } else if (fraction >= 1.0) {
            std::fprintf(stderr, " %.2f s\n",
                         std::chrono::duration<double>(now - state->start).count());
        }
        std::fflush(stderr);
    };
}

std::string labels_text(const std::vector<std::int32_t>& labels) {
    std::string s;
    s.reserve(labels.size() * 4);
    for (const std::int32_t l : labels) {
        s += std::to_string(l);
        s += '\n';
    }
    return s;
}

namespace {
CLI::Validator number_at_least(bool zero_too) {
    const char* what = zero_too ? "a number of at least 0" : "a positive number";
    return CLI::Validator(
        [zero_too, what](std::string& text) -> std::string {
            double v = 0;
            if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) ||
                (zero_too ? v < 0 : v <= 0)) {
                return std::string("must be ") + what + ", got '" + text + "'";
            }
            return {};
        },
        zero_too ? "NONNEGATIVE" : "POSITIVE");
}
}  // namespace

const CLI::Validator kPositive = number_at_least(false);
const CLI::Validator kNonNegative = number_at_least(true);

void print_error(const std::string& message) {
    std::fprintf(stderr, "error: %s\n", message.c_str());
}

bool refuses_folder(const std::filesystem::path& path, Context& ctx) {
    std::error_code ec;
    if (!std::filesystem::is_directory(path, ec)) return false;
    print_error(path.string() + ": is a directory; give the path of a file to write");
    ctx.exit_code = kExitCannotWrite;
    return true;
}
std::optional<HealedMesh> read_input(const std::filesystem::path& input,
                                     const std::filesystem::path& output, Context& ctx,
                                     bool quiet) {
    std::error_code ec;
    if (std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec)) {
        print_error(output.string() + ": is the input; ncrev never overwrites its input");
        ctx.exit_code = kExitUsage;
        return std::nullopt;
    }
    if (refuses_folder(output, ctx)) return std::nullopt;
    auto healed = read_and_heal(input, {}, terminal_progress(ctx, quiet));
    if (!healed) {
        print_error(healed.error().describe());
        ctx.exit_code = kExitBadInput;
        return std::nullopt;
    }
    return std::move(healed).value();
}

void print_warning(const std::string& message) {
    std::fprintf(stderr, "warning: %s\n", message.c_str());
}

}  // namespace ncrev::cli

int main(int argc, char** argv) {
    using namespace ncrev::cli;
    CLI::App app{
        "ncrev turns the triangle mesh of a machined part (STL, or the NC simulator's SRE) back "
        "into a CAD solid.\nLengths: STL has no unit and is read as millimetres; SRE states its "
        "unit.\nExit codes: 0 ok (warnings allowed), 1 usage, 2 unreadable or invalid input, 3 "
        "no valid result, 4 cannot write output.",
        "ncrev"};
    app.set_version_flag("--version", "ncrev 0.1.0");
    app.require_subcommand(1);
    Context ctx;
    ctx.stderr_is_tty = ::isatty(2) == 1;
    auto& commands = registered_commands();
    std::stable_sort(commands.begin(), commands.end(),
                     [](const Command& a, const Command& b) { return a.order < b.order; });
    for (const Command& c : commands) c.add(app, ctx);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return kExitUsage;
    }
    return ctx.exit_code;
}
