// The command-line program's commands (main.cpp registers them in the order
// `wetcloth --help` lists them), and what its runs share: the stop signals and
// the progress bar around the library's run (wetcloth/run.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

#include "wetcloth/run.hpp"

namespace wetcloth::cli {

// Each registers its subcommand; the returned callable runs it when it was
// chosen (returns -1 when it was not).
// `wetcloth run` (run.cpp): one scene into an output folder, or a stopped run
// resumed from its checkpoint.
std::function<int()> add_run_command(CLI::App& app);
// `wetcloth sweep` (sweep_command.cpp): one run per case, in parallel or one case at a
// time, then sweep.csv and the plots.
std::function<int()> add_sweep_command(CLI::App& app);
// `wetcloth bench` (bench.cpp): times the step of a scene at several grid
// sizes and writes the medians, with each grid's peak memory, as a table and
// as bench.json.
std::function<int()> add_bench_command(CLI::App& app);
// `wetcloth converge` (converge.cpp): one run per time step, in parallel, then
// how the final measurements converge as the step shrinks (observed order,
// Richardson limit).
std::function<int()> add_converge_command(CLI::App& app);

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
