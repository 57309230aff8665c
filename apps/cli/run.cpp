// `wetcloth run`: one scene into an output folder, or a stopped run resumed
// from its checkpoint. The run is the library's (wetcloth/run.hpp); here are
// its options, the stop signals and the progress bar.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "cli.hpp"
#include "common/scene_options.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth::cli {

namespace fs = std::filesystem;

namespace {

// The signal that asked the run to stop (0: none). A second one ends the
// process at once, removing the temporary file being written.
std::atomic<int> g_stop{0};

extern "C" void on_stop_signal(int sig) {
  if (g_stop.exchange(sig) != 0) {
    remove_temporary_files();
    constexpr char msg[] = "\nwetcloth: stopped at once (second signal)\n";
    [[maybe_unused]] const auto w = ::write(STDERR_FILENO, msg, sizeof msg - 1);
    ::_exit(128 + sig);
  }
  constexpr char msg[] = "\nwetcloth: stopping at the end of this step (again to stop at once)\n";
  [[maybe_unused]] const auto w = ::write(STDERR_FILENO, msg, sizeof msg - 1);
}

void print_progress(double t, double duration, double wall) {
  const int width = 30;
  const double frac = duration > 0 ? std::min(1.0, t / duration) : 1.0;
  const int fill = static_cast<int>(frac * width);
  std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  sim %.3f s  wall %.1f s  %.2fx real time ", fill,
               "##############################", width - fill, "", 100 * frac, t, wall,
               wall > 0 ? t / wall : 0.0);
  std::fflush(stderr);
}

struct RunOptions {
  SceneOptions scene;
  std::string out_dir, resume_dir;
  std::optional<double> checkpoint_every;
  std::optional<std::string> exports, up;
  bool quiet = false, force = false;
};

void add_run_options(CLI::App* run, RunOptions& o) {
  o.scene.add_to(run, false);  // no SCENE with --resume
  run->add_option("--checkpoint-every", o.checkpoint_every,
                  "write the whole state into DIR/checkpoint.state every S of simulated time, "
                  "for --resume (= --set run.checkpoint_every=S)")
      ->check(in_range_of("run.checkpoint_every"));
  run->add_option("--resume", o.resume_dir,
                  "continue the run in DIR from its checkpoint.state, with the same bits as a run "
                  "never stopped (no SCENE: it comes from the checkpoint; --threads and "
                  "--checkpoint-every may be given)")
      ->check(a_path());
  run->add_option("--out", o.out_dir, "output folder (default out/<scene name>)")->check(a_path());
  run->add_flag("--quiet", o.quiet, "no progress bar");
  run->add_option("--export", o.exports,
                  "animation caches, any of usd,pc2,vtk (= --set run.export=LIST): DIR/cloth.usda; "
                  "DIR/cloth.pc2 with DIR/cloth_rest.obj; DIR/vtk/*.vtp with DIR/cloth.pvd");
  run->add_option("--up", o.up,
                  "up axis of every file written, z (default) or y (= --set run.up=A)")
      ->check(CLI::IsMember({"z", "y"}));
  run->add_flag("--force", o.force,
                "run even where the memory or disk the run needs (estimated) is more than the "
                "machine has, or into a folder that holds files no wetcloth run wrote (they stay)");
  run->footer(
      "Writes DIR/metrics.csv (one row per frame, SI units in the header), DIR/frames/*.obj,\n"
      "DIR/obstacles.obj, DIR/scene.toml (every parameter, resolved) and DIR/summary.json,\n"
      "listed in DIR/.wetcloth.manifest: a run into DIR removes only what the last run listed.\n"
      "Exit codes: 0 ok, 2 bad input (nothing written; or DIR is in use by another run, a\n"
      "system folder, or holds files of no wetcloth run and --force is not given),\n"
      "3 the simulation blew up (outputs so far kept), 4 an output could not be written\n"
      "(full disk, read-only folder: the file and the reason named), 130 / 143 stopped by\n"
      "SIGINT / SIGTERM at the end of a step (outputs whole, summary.json \"interrupted\",\n"
      "DIR/checkpoint.state written: `wetcloth run --resume DIR` continues the run).");
}

// The scene is the checkpoint's: what would change it is refused.
void refuse_scene_changes(const RunOptions& o) {
  std::string given;
  const auto refuse = [&](bool set, const char* what) {
    if (set) given += (given.empty() ? "" : ", ") + std::string(what);
  };
  refuse(!o.scene.scene.empty(), "a SCENE");
  refuse(!o.scene.sets.empty(), "--set");
  refuse(o.scene.humidity.has_value(), "--humidity");
  refuse(o.scene.duration.has_value(), "--duration");
  refuse(o.scene.grid.has_value(), "--grid");
  refuse(o.exports.has_value(), "--export");
  refuse(o.up.has_value(), "--up");
  refuse(!o.out_dir.empty(), "--out");
  if (!given.empty())
    throw SceneError("--resume " + o.resume_dir +
                     ": the run continues in that folder with its checkpoint's scene; " + given +
                     " would change it (--threads, --checkpoint-every, --quiet and --force "
                     "may be given)");
}

// --resume DIR: the checkpoint's scene with the options that may change, or
// nothing when the run in DIR has ended whole.
std::optional<ResumePoint> resume_point(const RunOptions& o, fs::path& out) {
  refuse_scene_changes(o);
  out = o.resume_dir;
  std::optional<ResumePoint> resume = resume_run(out, o.scene.threads, o.checkpoint_every, o.force);
  if (!resume && !o.quiet)
    std::printf("%s: the run ended whole (summary.json); nothing to resume\n", out.c_str());
  return resume;
}

// A new run: SCENE with the options that stand for overrides, into a folder
// made for it.
void new_run(RunOptions o, Params& p, fs::path& out) {
  if (o.scene.scene.empty())
    throw SceneError(
        "run: a SCENE is needed (a TOML file or a built-in name: wetcloth scenes), or "
        "--resume DIR");
  if (o.exports) o.scene.sets.push_back("run.export=\"" + *o.exports + "\"");
  if (o.up) o.scene.sets.push_back("run.up=" + *o.up);
  if (o.checkpoint_every)
    o.scene.sets.push_back("run.checkpoint_every=" + format_number(*o.checkpoint_every));
  p = o.scene.load();
  out = o.out_dir.empty() ? fs::path("out") / folder_name(p.name) : fs::path(o.out_dir);
  prepare_run(p, out, o.force, o.scene.scene);
}

// How the run ended, on stderr when it failed, with where its results are.
int report(const RunResult& r, const Params& p, const fs::path& out, bool quiet) {
  if (r.code > 128) {
    std::fprintf(stderr,
                 "wetcloth: %s\nresults so far (whole): %s; `wetcloth run --resume %s` "
                 "continues the run\n",
                 r.message.c_str(), out.c_str(), out.c_str());
    return r.code;
  }
  if (r.code != kOk) {
    std::fprintf(stderr, "wetcloth: %s\nresults so far: %s\n", r.message.c_str(), out.c_str());
    return r.code;
  }
  if (!quiet)
    std::printf("%s: %lld steps in %.2f s wall (%.2fx real time); results in %s\n", p.name.c_str(),
                r.steps, r.wall_seconds, r.wall_seconds > 0 ? r.final.time_s / r.wall_seconds : 0.0,
                out.c_str());
  return kOk;
}

int run_command(const RunOptions& o) {
  Params p;
  fs::path out;
  std::optional<ResumePoint> resume;
  if (!o.resume_dir.empty()) {
    resume = resume_point(o, out);
    if (!resume) return kOk;  // it ended whole
    p = resume->params;
  } else {
    new_run(o, p, out);
  }
  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  install_stop_handlers();
  RunResult r;
  try {
    r = run_scene(p, out, run_hooks(progress), resume ? &*resume : nullptr);
  } catch (...) {
    if (progress) std::fprintf(stderr, "\n");  // the bar's line ended before the error
    throw;
  }
  if (progress) std::fprintf(stderr, "\n");
  return report(r, p, out, o.quiet);
}

}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int stop_signal() { return g_stop.load(); }

RunHooks run_hooks(bool progress) {
  RunHooks hooks;
  hooks.stop = stop_signal;
  if (progress) hooks.progress = print_progress;
  return hooks;
}

std::function<int()> add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand("run", "run a scene and write its results into a folder");
  add_run_options(cmd, *o);
  return [cmd, o]() -> int { return *cmd ? run_command(*o) : -1; };
}

}  // namespace wetcloth::cli
