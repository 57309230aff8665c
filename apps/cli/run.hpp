// Running scenes into output folders: one (`run`), or many at once (`sweep`, `converge`).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "wetcloth/params.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth::cli {

// 128 + the signal where one stopped a run (130 SIGINT, 143 SIGTERM).
enum ExitCode { kOk = 0, kError = 1, kBadInput = 2, kBlowUp = 3, kOutputError = 4 };

struct RunResult {
  int code = kOk;
  std::string message;               // why it stopped, when it failed
  Metrics first, final;              // the first and last frames
  double peak_deficit_pa = 0;        // p_atm - p_in at any step
  double frame_peak_deficit_pa = 0;  // over the output frames, as the plots show it
  double time_to_5cm_s = -1;         // first time the handle is 5 cm up; -1: never
  long long steps = 0;
  double wall_seconds = 0;
  double simulated_seconds = 0;
  bool started = false;  // its folder was made and written into (a signal may skip a case)
};

// SIGINT and SIGTERM ask runs to stop at the end of the step they are in
// (run_scene then writes that state's row and frame, and summary.json says
// "interrupted"); a second signal ends the process at once, removing the
// temporary file being written. Exit 128 + the signal.
void install_stop_handlers();

// What a run of P will take: memory from the resolution (and self-collision's
// reach), disk from the frames (and their meshes).
struct ResourceEstimate {
  double memory_bytes = 0, disk_bytes = 0;
};
// Peak memory measured a particle (the high end: 1.5 to 1.7 kB), and the
// program's own (estimate_resources).
constexpr double kBytesPerParticle = 1700, kBaseBytes = 32e6;
ResourceEstimate estimate_resources(const Params& p);
// Throws SceneError, naming SOURCE and the estimate, where P would need more
// memory than is available or more disk than is free where OUT is.
void check_resources(const Params& p, const std::filesystem::path& out, const std::string& source);
int stop_signal();  // the signal that asked to stop, or 0

// What `run --resume DIR` continues from: DIR/checkpoint.state, a checkpoint
// written by run_scene (its scene, its state, and where the outputs stood).
struct ResumePoint {
  std::filesystem::path file;  // DIR/checkpoint.state
  Params params;               // the checkpoint's scene
  State state;
  std::string record;  // where the outputs stood (JSON)
};
// Throws SceneError naming the file and what is wrong: no checkpoint, not a
// checkpoint, another format, damaged, one without a run's record, or one of
// another scene than DIR/scene.toml.
ResumePoint load_resume_point(const std::filesystem::path& dir);
// DIR holds a run that ended whole (summary.json "ok", no checkpoint): a
// resume has nothing to do.
bool run_ended_whole(const std::filesystem::path& dir);

// Runs P into OUT (made if missing, locked while the run writes: a second run
// into it throws SceneError). Throws OutputError where a file cannot be written.
// With run.checkpoint_every, and when a signal stops it, writes
// OUT/checkpoint.state (removed when the run ends whole). With `resume` (P its
// scene, but for the step's threads and run.checkpoint_every), continues the
// run OUT holds from that checkpoint: metrics.csv and the caches cut back to
// it, the frames after it removed, with the same bits as a run never stopped.
RunResult run_scene(const Params& p, const std::filesystem::path& out, bool progress,
                    const ResumePoint* resume = nullptr);

// The override that shares the cores between `jobs` runs at once, put first
// in `sets` unless the user chose the step's threads (more threads than cores
// only wait).
void share_cores(std::vector<std::string>& sets, unsigned jobs);

// Runs every (params, folder) `jobs` at a time; done(i) is called for each as
// it ends, one call at a time. Returns the results in the order given.
std::vector<RunResult> run_all(const std::vector<std::pair<Params, std::filesystem::path>>& runs,
                               unsigned jobs,
                               const std::function<void(std::size_t, const RunResult&)>& done);

}  // namespace wetcloth::cli
