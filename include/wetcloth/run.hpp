// A run: a scene into an output folder (metrics.csv, frames, caches,
// checkpoints and their resume, summary.json), the checks before it (memory
// and disk, the folder), and many runs at once. The one frame loop: the
// command line's run, sweep and converge, and Python's wetcloth.run and
// wetcloth.sweep call it (docs/guide.md, Outputs).
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "wetcloth/output_folder.hpp"
#include "wetcloth/params.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

// How a run ended, as the programs exit with it: 128 + the signal where one
// stopped it (130 SIGINT, 143 SIGTERM).
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
  std::string summary;   // summary.json as written (JSON; empty where no folder)
};

// What a run asks of its caller. stop is polled after every step: a signal
// number (SIGINT, SIGTERM) stops the run at the end of that step, whole (its
// row and frame written, a checkpoint, summary.json "interrupted"); once
// given, it holds. progress is called after each frame written.
struct RunHooks {
  std::function<int()> stop;
  std::function<void(double t, double duration, double wall_seconds)> progress;
};

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

// A new run of P into OUT, checked before anything is written and its folder
// made: the memory and disk it needs (unless force; SOURCE names the scene in
// the error), OUT not a file nor a system folder, nor (unless force) a folder
// of someone else's files.
void prepare_run(const Params& p, const std::filesystem::path& out, bool force,
                 const std::string& source, const std::string& option = "--out");

// --- resume ------------------------------------------------------------------

// What a resumed run continues from: DIR/checkpoint.state, a checkpoint
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
// The run in DIR to continue, with what may change on resuming (the step's
// threads, the checkpoints' interval), its resources checked unless force;
// nothing where it ended whole (then the USD samples a run killed in its last
// moment left are removed).
std::optional<ResumePoint> resume_run(const std::filesystem::path& dir,
                                      std::optional<unsigned> threads,
                                      std::optional<double> checkpoint_every, bool force);

// --- running -----------------------------------------------------------------

// Runs P into OUT (made if missing, locked while the run writes: a second run
// into it throws SceneError). Throws OutputError where a file cannot be written.
// With run.checkpoint_every, and when a stop hook stops it, writes
// OUT/checkpoint.state (removed when the run ends whole). With `resume` (P its
// scene, but for the step's threads and run.checkpoint_every), continues the
// run OUT holds from that checkpoint: metrics.csv and the caches cut back to
// it, the frames after it removed, with the same bits as a run never stopped.
// An empty OUT writes nothing: the run's measurements alone (a sweep's case
// in memory).
RunResult run_scene(const Params& p, const std::filesystem::path& out, const RunHooks& hooks = {},
                    const ResumePoint* resume = nullptr);

// The override that shares the cores between `jobs` runs at once, put first
// in `sets` unless the user chose the step's threads (more threads than cores
// only wait).
void share_cores(std::vector<std::string>& sets, unsigned jobs);

// Runs every (params, folder) `jobs` at a time; done(i) is called for each as
// it ends, one call at a time. Once hooks.stop asks, no run starts (its code
// 128 + the signal). Returns the results in the order given.
std::vector<RunResult> run_all(const std::vector<std::pair<Params, std::filesystem::path>>& runs,
                               unsigned jobs, const RunHooks& hooks,
                               const std::function<void(std::size_t, const RunResult&)>& done);

// --- scenes as the programs load them ------------------------------------------

// Whether one of the KEY=VALUE overrides sets `key`.
bool overrides_key(const std::vector<std::string>& sets, const std::string& key);

// SCENE with the overrides; with a grid, the same cloth that many particles
// wide (wetcloth::at_resolution), keeping a time step the overrides set.
// `option` names the grid in an error.
Params load_on_grid(const std::string& scene, const std::vector<std::string>& sets,
                    std::optional<long long> grid, const std::string& option = "--grid",
                    IntegratorTier tier = IntegratorTier::Accurate);

}  // namespace wetcloth
