// `wetcloth bench`: times the step of a scene at several grid sizes and writes
// the medians, with each grid's peak memory, as a table and as bench.json.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace wetcloth::cli {

// Registers the subcommand; the returned callable runs it when it was chosen
// (returns -1 when it was not).
std::function<int()> add_bench_command(CLI::App& app);

}  // namespace wetcloth::cli
