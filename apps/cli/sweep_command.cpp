#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "cli.hpp"
#include "common/scene_options.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/sweep.hpp"
#ifdef WETCLOTH_VIEWER
#include "../viewer/commands.hpp"
#endif

namespace wetcloth::cli {

namespace fs = std::filesystem;

namespace {

// Runs the plotting script on DIR; false (said on stderr) when it failed.
bool plot(const fs::path& out) {
  std::string cmdline;
  if (sweep::plot(out, &cmdline)) return true;
  std::fprintf(stderr, "wetcloth: the plots failed (%s)\n", cmdline.c_str());
  return false;
}

// `--gather DIR`: sweep.csv (and the plots) from the case folders that have
// finished, in the sweep's order; the missing ones listed. 0 when none is
// missing, 1 otherwise.
int gather(const fs::path& dir, bool no_plots, bool quiet) {
  const sweep::Gathered g = sweep::gather(dir);
  if (!quiet)
    std::printf("gathered %zu of %zu cases into %s\n", g.found, g.total,
                (dir / "sweep.csv").c_str());
  if (!g.missing.empty()) {
    std::fprintf(stderr, "wetcloth: missing %zu of %zu cases (index and name):\n", g.missing.size(),
                 g.total);
    for (const auto& m : g.missing) std::fprintf(stderr, "  %s\n", m.c_str());
  }
  bool plots_ok = true;
  if (!no_plots) plots_ok = plot(dir);
  return g.missing.empty() && plots_ok ? kOk : kError;
}

// The line `sweep` keeps on a terminal while cases run: done, running, time left.
class ProgressLine {
 public:
  ProgressLine(std::size_t total, unsigned jobs, bool on) : total_(total), jobs_(jobs), on_(on) {
    if (on_)
      ticker_ = std::thread([this] {
        std::unique_lock<std::mutex> hold(lock_);
        while (!stop_) {
          draw();
          wake_.wait_for(hold, std::chrono::seconds(1));
        }
      });
  }
  ~ProgressLine() {
    if (!on_) return;
    {
      std::lock_guard<std::mutex> hold(lock_);
      stop_ = true;
    }
    wake_.notify_all();
    ticker_.join();
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  // Before a case's line is printed: the progress line is cleared.
  void case_done() {
    if (!on_) return;
    std::lock_guard<std::mutex> hold(lock_);
    ++done_;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  void redraw() {
    if (!on_) return;
    std::lock_guard<std::mutex> hold(lock_);
    draw();
  }

 private:
  void draw() {
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const std::size_t running = std::min<std::size_t>(jobs_, total_ - done_);
    char left[64] = "?";
    if (done_ > 0) std::snprintf(left, sizeof left, "%.0f s", wall / done_ * (total_ - done_));
    std::fprintf(stderr,
                 "\r\033[Ksweep: %zu/%zu cases done, %zu running, %.0f s wall, time left ~%s",
                 done_, total_, running, wall, left);
    std::fflush(stderr);
  }
  std::size_t total_, done_ = 0;
  unsigned jobs_;
  bool on_, stop_ = false;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::mutex lock_;
  std::condition_variable wake_;
  std::thread ticker_;
};

struct Options {
  SceneOptions scene;
  std::vector<double> humidities;
  std::vector<std::string> air_models, vary;
  std::string out, gather;
  std::optional<long long> case_index;
  unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
  bool render = false, quiet = false, no_plots = false, list = false, force = false;
};

// What varies from case to case: SCENE's parameters, with --set in every case.
void add_case_options(CLI::App* cmd, Options& o) {
  cmd->add_option("scene", o.scene.scene, "scene: a TOML file, or a built-in name");
  cmd->add_option(
         "--vary", o.vary,
         "KEY=V1,V2,...: run every value of the parameter KEY (TOML values; repeatable: the "
         "cartesian product), e.g. --vary material.stretch_stiffness=100,200 --vary "
         "cloth.resolution=[25,25],[51,51]")
      ->allow_extra_args(false);
  cmd->add_option("--humidity", o.humidities,
                  "humidities ω to run, e.g. 0,0.3,0.5,0.7,1 (= --vary cloth.humidity=...)")
      ->delimiter(',')
      ->check(in_range_of("cloth.humidity"));
  cmd->add_option(
         "--air-models", o.air_models,
         "air models to compare, e.g. exchange,sealed (paper Fig. 8; = --vary air.model=...)")
      ->delimiter(',')
      ->check(CLI::IsMember(std::vector<std::string>(ChoiceNames<AirModel>::names.begin(),
                                                     ChoiceNames<AirModel>::names.end())));
  cmd->add_option("--set", o.scene.sets,
                  "override a parameter in every case, KEY=VALUE (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--duration", o.scene.duration, "simulated time per case, s")
      ->check(in_range_of("run.duration"));
  cmd->add_option(
         "--threads", o.scene.threads,
         "threads of each case's step (default: the cores shared between --jobs; 0: chosen "
         "as it runs)")
      ->check(in_range_of("integrator.threads"));
  o.scene.add_grid_to(cmd);
}

// Where the cases go and how they run: all at once, or one task of a job
// array at a time; then what is made of them.
void add_output_options(CLI::App* cmd, Options& o) {
  cmd->add_option("--out", o.out, "output folder (default out/<scene>-sweep)")->check(a_path());
  cmd->add_option("--jobs", o.jobs, "cases run at once (default: all cores)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--list", o.list,
                "print the cases, one a line: index, folder name, overrides; run nothing");
  cmd->add_option(
      "--case", o.case_index,
      "run case I alone (from --list; 0-based) into DIR/<case>: one task of a job array. "
      "`--gather DIR` makes sweep.csv once they have run");
  cmd->add_option("--gather", o.gather,
                  "make DIR/sweep.csv and the plots from the case folders of DIR that have run "
                  "(--case), and list the missing ones (exit 1 if any)")
      ->check(a_path());
  cmd->add_flag("--render", o.render,
                "also render a contact sheet of the last frames (contact_sheet.png)");
  cmd->add_flag("--no-plots", o.no_plots, "skip the plots");
  cmd->add_flag("--quiet", o.quiet, "print nothing but errors");
  cmd->add_flag("--force", o.force,
                "write into DIR even where it holds files of no wetcloth sweep (a user's)");
  cmd->footer(
      "Writes DIR/<case>/ (the outputs of `run`, and its row of sweep.csv) for every case, named\n"
      "from its values (omega_0.70, sealed_omega_0.70, omega_0.70_stretch_stiffness=100),\n"
      "DIR/cases.csv (the cases in order), DIR/sweep.csv (one row per case: a column per varied "
      "key\n"
      "besides air_model and humidity, final metrics, peak pressure deficit at any step and over "
      "the\n"
      "output frames, time until the handle first reaches 5 cm)\n"
      "and the plots that mean something for the scene: fig7 (pulled height and base diagonal\n"
      "against humidity), pressure, contact_area and handle_height over time (for a driven\n"
      "handle handle_force, against how far it has moved), and fig8 with several air models\n"
      "(PNG and SVG). On a cluster: --list, then --case I per task, then --gather DIR.");
}

// The keys the cases vary, from --air-models, --humidity and --vary in turn.
std::vector<sweep::Varied> varied_keys(const Options& o) {
  std::vector<sweep::Varied> varied;
  if (!o.air_models.empty()) varied.push_back({"air.model", o.air_models, "--air-models"});
  if (!o.humidities.empty()) {
    sweep::Varied h{"cloth.humidity", {}, "--humidity"};
    for (double w : o.humidities) h.values.push_back(format_number(w));
    varied.push_back(h);
  }
  for (const auto& v : o.vary) varied.push_back(sweep::parse_vary(v));
  return varied;
}

// `--list`: a case a line, index, folder name and overrides, tab-separated.
void print_cases(const sweep::Plan& plan) {
  for (std::size_t i = 0; i < plan.cases.size(); ++i) {
    std::string sets;
    for (const auto& s : plan.cases[i].sets) sets += " " + s;
    std::printf("%zu\t%s\t%s\n", i, plan.cases[i].name.c_str(), sets.c_str() + 1);
  }
}

// A finished case's line of the table. Both peaks: the plots show the
// frames', and a step between frames can go higher (up to the breakthrough
// cap as a peel starts).
void print_case(const std::string& name, const RunResult& r) {
  std::printf(
      "%-22s %s  handle %.4f m  contact %.5f m²  peak deficit (any step) %.1f Pa, "
      "over frames %.1f Pa  (%.1f s wall)\n",
      name.c_str(),
      r.code == kOk  ? "ok     "
      : r.code > 128 ? "STOPPED"
                     : "BLEW UP",
      r.final.handle_height_m, r.final.contact_area_m2, r.peak_deficit_pa, r.frame_peak_deficit_pa,
      r.wall_seconds);
}

// Every case's result and its row of sweep.csv (empty where it did not run),
// by index in the plan.
struct Ran {
  std::vector<RunResult> results;
  std::vector<std::string> rows;
};

// Runs the chosen cases `jobs` at a time into OUT/<case>; each writes its row
// of sweep.csv into its folder as it ends.
Ran run_cases(const Options& o, const sweep::Plan& plan, const std::vector<std::size_t>& chosen,
              const fs::path& out, unsigned jobs) {
  Ran ran{std::vector<RunResult>(plan.cases.size()), std::vector<std::string>(plan.cases.size())};
  // Cases end in any order; each is printed once those before it in the
  // list have been, so that the table reads in the order asked for.
  std::vector<bool> ended(plan.cases.size(), false);
  std::size_t printed = 0;
  ProgressLine progress(chosen.size(), jobs, !o.quiet && isatty(STDERR_FILENO));
  install_stop_handlers();  // SIGINT / SIGTERM: every case stops at a step's end
  sweep::run_cases(plan, chosen, out, jobs, run_hooks(false),
                   [&](std::size_t i, const RunResult& r, const std::string& row) {
                     ran.results[i] = r;
                     ran.rows[i] = row;
                     ended[i] = true;
                     progress.case_done();
                     for (; printed < chosen.size() && ended[chosen[printed]]; ++printed)
                       if (!o.quiet)
                         print_case(plan.cases[chosen[printed]].name, ran.results[chosen[printed]]);
                     std::fflush(stdout);
                     progress.redraw();
                   });
  return ran;
}

// --render: the contact sheet of the cases' last frames; false (said on
// stderr) when it could not be made.
bool render_sheet(const std::vector<sweep::Varied>& varied, const sweep::Plan& plan,
                  const fs::path& out) {
#ifdef WETCLOTH_VIEWER
  std::vector<std::pair<std::string, fs::path>> tiles;
  const bool several = std::any_of(varied.begin(), varied.end(), [](const auto& v) {
    return v.key == "air.model" && v.values.size() > 1;
  });
  for (const auto& c : plan.cases) {
    // "omega", spelt out: the sheet's font is ASCII, it drew ω as 'w'.
    char label[96];
    std::snprintf(label, sizeof label, "%s%somega = %.3g", several ? c.air_model.c_str() : "",
                  several ? ", " : "", c.humidity);
    tiles.emplace_back(plan.extra_keys.empty() ? std::string(label) : c.name, out / c.name);
  }
  std::string error;
  if (viewer::render_contact_sheet(tiles, out / "contact_sheet.png", 480, 360, &error)) return true;
  std::fprintf(stderr, "wetcloth: contact sheet: %s\n", error.c_str());
  return false;
#else
  (void)varied, (void)plan, (void)out;
  std::fprintf(stderr, "wetcloth: --render needs the viewer (build with WETCLOTH_VIEWER=ON)\n");
  return false;
#endif
}

// The whole sweep's end: sweep.csv, the plots, the contact sheet, and every
// file made listed (the contact sheet is listed nowhere else).
int finish_sweep(const Options& o, const std::vector<sweep::Varied>& varied,
                 const sweep::Plan& plan, const Ran& ran, const fs::path& out, int code) {
  std::string csv = sweep::csv_header(plan);
  for (const auto& r : ran.rows) csv += r;
  write_file_atomic(out / "sweep.csv", csv);
  if (stop_signal() != 0) return 128 + stop_signal();  // what finished is in sweep.csv
  if (!o.no_plots && !plot(out) && code == kOk) code = kError;
  bool sheet = false;
  if (o.render) {
    sheet = render_sheet(varied, plan, out);
    if (!sheet && code == kOk) code = kError;
  }
  if (!o.quiet) {
    std::vector<std::string> made{"sweep.csv"};
    if (!o.no_plots) made.push_back("the plots listed above");
    if (sheet) made.push_back("contact_sheet.png");
    std::string list = made[0];
    for (std::size_t k = 1; k < made.size(); ++k)
      list += (k + 1 == made.size() ? " and " : ", ") + made[k];
    std::printf("results: %s (%s)\n", out.c_str(), list.c_str());
  }
  return code;
}

int run_sweep(const Options& o) {
  if (!o.gather.empty()) {
    if (!o.scene.scene.empty() || o.case_index || o.list || !o.vary.empty() ||
        !o.humidities.empty() || !o.air_models.empty())
      throw SceneError("--gather DIR takes no scene and no cases (it reads DIR/cases.csv)");
    return gather(o.gather, o.no_plots, o.quiet);
  }
  if (o.scene.scene.empty()) throw SceneError("sweep: a SCENE is required (or --gather DIR)");
  // Every case is checked before anything is written.
  const std::vector<sweep::Varied> varied = varied_keys(o);
  const unsigned jobs = o.case_index ? 1u : o.jobs;
  std::vector<std::string> base = o.scene.overrides();
  share_cores(base, jobs);
  const Params scene = o.scene.load();
  const sweep::Plan plan = sweep::plan(varied, [&](const std::vector<std::string>& sets) {
    std::vector<std::string> all = base;
    all.insert(all.end(), sets.begin(), sets.end());
    return load_on_grid(o.scene.scene, all, o.scene.grid);
  });
  const std::size_t n = plan.cases.size();
  if (o.list) {
    print_cases(plan);
    return kOk;
  }
  if (o.case_index && (*o.case_index < 0 || static_cast<std::size_t>(*o.case_index) >= n))
    throw SceneError("--case " + std::to_string(*o.case_index) + ": the sweep has " +
                     std::to_string(n) + " cases, 0 to " + std::to_string(n - 1) +
                     " (--list prints them)");
  const fs::path out =
      o.out.empty() ? fs::path("out") / folder_name(scene.name + "-sweep") : fs::path(o.out);
  if (!o.force) {  // an earlier sweep's folder holds its cases or their list
    std::vector<std::string> marks = {sweep::kCasesFile, "sweep.csv"};
    for (const auto& c : plan.cases) marks.push_back(c.name);
    refuse_system_folder(out);
    refuse_foreign_folder(out, "--out", "sweep", marks);
  }
  make_output_folder(out);
  sweep::write_shared(out / sweep::kCasesFile, sweep::cases_csv(plan));

  std::vector<std::size_t> chosen;
  for (std::size_t i = 0; i < n; ++i)
    if (!o.case_index || static_cast<long long>(i) == *o.case_index) chosen.push_back(i);
  const Ran ran = run_cases(o, plan, chosen, out, jobs);
  int code = kOk;
  for (std::size_t i : chosen)
    if (ran.results[i].code != kOk) {
      std::fprintf(stderr, "wetcloth: %s: %s\n", plan.cases[i].name.c_str(),
                   ran.results[i].message.c_str());
      code = kBlowUp;
    }
  if (o.case_index) {
    if (!o.quiet) std::printf("results: %s\n", (out / plan.cases[chosen[0]].name).c_str());
    return stop_signal() != 0 ? 128 + stop_signal() : code;
  }
  return finish_sweep(o, varied, plan, ran, out, code);
}

}  // namespace

std::function<int()> add_sweep_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("sweep",
                                 "run a scene over the cartesian product of parameter values, in "
                                 "parallel or one case at a time");
  add_case_options(cmd, *o);
  add_output_options(cmd, *o);
  return [cmd, o]() -> int { return *cmd ? run_sweep(*o) : -1; };
}

}  // namespace wetcloth::cli
