// `wetcloth sweep`: one run per (air model, humidity), in parallel, then a table
// and the paper's plots.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace wetcloth::cli {

// Registers the subcommand; the returned callable runs it when it was chosen
// (returns -1 when it was not).
std::function<int()> add_sweep_command(CLI::App& app);

}  // namespace wetcloth::cli
