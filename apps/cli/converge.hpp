// `wetcloth converge`: one run per time step, in parallel, then how the final
// measurements converge as the step shrinks (observed order, Richardson limit).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace wetcloth::cli {

// Registers the subcommand; the returned callable runs it when it was chosen
// (returns -1 when it was not).
std::function<int()> add_converge_command(CLI::App& app);

}  // namespace wetcloth::cli
