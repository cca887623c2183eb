// Subcommands of the `caustica` binary. Each registers its options on the CLI11 app and
// returns the process exit code when run: 0 success, 1 runtime failure, 2 bad input. Under
// mpirun every rank runs the command; only rank 0 writes files and prints progress.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

#include "render/ranks.h"

namespace caustica::cli {

using Runner = std::function<int(Ranks& ranks)>;

Runner add_render_command(CLI::App& app);
Runner add_scenes_command(CLI::App& app);
Runner add_integrators_command(CLI::App& app);

// One line per integrator of the registry: "name: description", for option help.
std::string integrator_help();
Runner add_reference_command(CLI::App& app);
Runner add_compare_command(CLI::App& app);
Runner add_bench_command(CLI::App& app);

// "a,b,,c" -> {"a", "b", "c"}.
std::vector<std::string> split_list(const std::string& s);

// Parses a name against a list; on failure prints "unknown <what> 'x'; valid: a, b" and
// returns false.
bool check_name(const std::string& what, const std::string& value,
                const std::vector<std::string>& valid);

}  // namespace caustica::cli
