// `wetcloth run`, and what the program's runs share: the stop signals and the
// progress bar around the library's run (wetcloth/run.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

#include "wetcloth/run.hpp"

namespace wetcloth::cli {

// Registers the subcommand; the returned callable runs it when it was chosen
// (returns -1 when it was not).
std::function<int()> add_run_command(CLI::App& app);

// SIGINT and SIGTERM ask runs to stop at the end of the step they are in
// (the run then writes that state's row and frame, and summary.json says
// "interrupted"); a second signal ends the process at once, removing the
// temporary file being written. Exit 128 + the signal.
void install_stop_handlers();
int stop_signal();  // the signal that asked to stop, or 0

// The hooks of a run from the program: stop_signal, and with `progress` a
// progress bar on stderr.
RunHooks run_hooks(bool progress);

}  // namespace wetcloth::cli
