// `wetcloth run`: one scene into an output folder, or a stopped run resumed
// from its checkpoint.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace wetcloth::cli {

// Registers the subcommand; the returned callable runs it when it was chosen
// (returns -1 when it was not).
std::function<int()> add_run_command(CLI::App& app);

}  // namespace wetcloth::cli
