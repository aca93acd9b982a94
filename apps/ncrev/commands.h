// The ncrev command-line tool: each subcommand lives in its own cmd_<name>.cpp and registers
// itself here. The CLI is thin: it parses options, calls the library, prints, and maps
// failures to exit codes (0 ok, 1 usage, 2 invalid input, 3 no valid result, 4 cannot write).
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ncrev/report.h"

namespace ncrev::cli {

enum ExitCode : int {
    kExitOk = 0,
    kExitUsage = 1,
    kExitBadInput = 2,
    kExitNoResult = 3,
    kExitCannotWrite = 4,
};

/// Shared state of one run: the exit code the chosen subcommand sets.
struct Context {
    int exit_code = kExitOk;
    bool stderr_is_tty = false;
};

/// A subcommand: `order` sorts them in --help; `add` creates the CLI11 subcommand on `app`
/// and sets its callback (which stores its exit code in the context).
struct Command {
    int order = 0;
    std::function<void(CLI::App& app, Context& ctx)> add;
};

/// Registers a subcommand (called from a static initialiser in cmd_<name>.cpp).
bool register_command(Command command);
std::vector<Command>& registered_commands();

/// Progress on the terminal: one line per stage on stderr ("ncrev: weld ... 0.12 s") when
/// stderr is a terminal and not `quiet`; otherwise a no-op callback.
std::function<void(std::string_view stage, double fraction)> terminal_progress(const Context& ctx,
                                                                               bool quiet);

/// CLI11's PositiveNumber and NonNegativeNumber with messages a user can read: "must be a
/// positive number, got -1", not the range up to DBL_MAX written out in full. Finite only.
extern const CLI::Validator kPositive;
extern const CLI::Validator kNonNegative;

/// A keyword option's transform: the text, in any case, must be a key of `choices` and becomes
/// its value; any other text is refused with "'x' is not one of: a, b, c" (CLI11's own
/// CheckedTransformer would print its whole map, values as numbers).
template <class T>
CLI::Validator keywords(const std::map<std::string, T>& choices) {
    std::string list;
    for (const auto& entry : choices) list += (list.empty() ? "" : ", ") + entry.first;
    const CLI::Validator convert = CLI::CheckedTransformer(choices, CLI::ignore_case);
    return CLI::Validator(
        [choices, list, convert](std::string& text) -> std::string {
            for (const auto& entry : choices) {
                if (CLI::ignore_case(entry.first) == CLI::ignore_case(text)) return convert(text);
            }
            return "'" + text + "' is not one of: " + list;
        },
        "", "KEYWORD");
}

/// Prints "error: <message>" to stderr.
void print_error(const std::string& message);

/// True, with the error printed and exit 4 set, when `path` is a directory: an output refused
/// before any work, not when the result is renamed into place after it.
bool refuses_folder(const std::filesystem::path& path, Context& ctx);

/// One label per line, in input facet order (`--labels` files).
std::string labels_text(const std::vector<std::int32_t>& labels);
/// Prints "warning: <message>" to stderr.
void print_warning(const std::string& message);

/// The start of every command that turns an input mesh into an output file: refuses an output
/// that is the input (exit 1) or a directory (exit 4), then reads and heals the input (exit 2 on a
/// reader error, with the error printed). Empty when the command must stop; ctx.exit_code is then
/// set.
std::optional<HealedMesh> read_input(const std::filesystem::path& input,
                                     const std::filesystem::path& output, Context& ctx, bool quiet);

}  // namespace ncrev::cli
