// Running one scene into an output folder (shared by `run` and `sweep`).
#pragma once

#include <filesystem>
#include <string>

#include "wetcloth/params.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth::cli {

enum ExitCode { kOk = 0, kError = 1, kBadInput = 2, kBlowUp = 3 };

struct RunResult {
  int code = kOk;
  std::string message;      // why it stopped, when it failed
  Metrics final;
  double peak_deficit_pa = 0;
  double time_to_5cm_s = -1;  // first time the handle is 5 cm up; -1: never
  long long steps = 0;
  double wall_seconds = 0;
};

RunResult run_scene(const Params& p, const std::filesystem::path& out, bool progress);

}  // namespace wetcloth::cli
