#include "sweep.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <thread>
#include <unistd.h>

#include "run.hpp"
#include "scene_options.hpp"
#include "wetcloth/output.hpp"
#ifdef WETCLOTH_VIEWER
#include "../viewer/commands.hpp"
#endif

namespace wetcloth::cli {

namespace fs = std::filesystem;

namespace {

struct Case {
  std::string name, air_model;
  double humidity = 0;
  Params params;
  RunResult result;
};

// Decimals that tell the humidities apart in case names: two, or as many as
// close ones need (an ensemble moves ω by 1e-7: 0.6999999, 0.7000000, ...).
int humidity_decimals(std::vector<double> omegas) {
  std::sort(omegas.begin(), omegas.end());
  if (const auto twice = std::adjacent_find(omegas.begin(), omegas.end()); twice != omegas.end())
    throw SceneError("--humidity: " + format_number(*twice) + " is given twice");
  const auto distinct = [&](int decimals) {
    char a[32], b[32];
    for (std::size_t k = 1; k < omegas.size(); ++k) {
      std::snprintf(a, sizeof a, "%.*f", decimals, omegas[k - 1]);
      std::snprintf(b, sizeof b, "%.*f", decimals, omegas[k]);
      if (std::strcmp(a, b) == 0) return false;
    }
    return true;
  };
  int decimals = 2;
  while (!distinct(decimals)) ++decimals;  // ends by 17: the doubles differ
  return decimals;
}

std::string case_name(double omega, int decimals, const std::string& air, bool several_air_models) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "omega_%.*f", decimals, omega);
  return several_air_models ? air + "_" + buf : buf;
}

// The plotting script: next to an installed program, or in the source tree.
fs::path plot_script() {
  if (const char* env = std::getenv("WETCLOTH_PLOT_SCRIPT")) return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path installed = exe.parent_path().parent_path() / "share/wetcloth/plot_sweep.py";
  if (!ec && fs::exists(installed)) return installed;
  return fs::path(WETCLOTH_SOURCE_DIR) / "tools/plot_sweep.py";
}

std::string sweep_csv(const std::vector<Case>& cases) {
  std::string o =
      "case,air_model,humidity,status,peak_deficit_pa,frame_peak_deficit_pa,time_to_5cm_s";
  for (const auto& c : metrics_columns()) o += "," + c;
  o += "\n";
  for (const auto& c : cases) {
    o += c.name + "," + c.air_model + "," + format_number(c.humidity) + "," +
         (c.result.code == kOk ? "ok" : c.result.code > 128 ? "interrupted" : "blew_up") + "," + format_number(c.result.peak_deficit_pa) +
         "," + format_number(c.result.frame_peak_deficit_pa) + "," +
         format_number(c.result.time_to_5cm_s);
    for (double v : metrics_values(c.result.final)) o += "," + format_number(v);
    o += "\n";
  }
  return o;
}

}  // namespace

std::function<int()> add_sweep_command(CLI::App& app) {
  struct Options {
    SceneOptions scene;
    std::vector<double> humidities;
    std::vector<std::string> air_models;
    std::string out;
    unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
    bool render = false, quiet = false, no_plots = false;
  };
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("sweep", "run a scene at several humidities (and air models), in parallel");
  cmd->add_option("scene", o->scene.scene, "scene: a TOML file, or a built-in name")->required();
  cmd->add_option("--humidity", o->humidities, "humidities ω to run, e.g. 0,0.3,0.5,0.7,1")
      ->delimiter(',')
      ->required()
      ->check(in_range_of("cloth.humidity"));
  cmd->add_option("--air-models", o->air_models, "air models to compare, e.g. exchange,sealed (paper Fig. 8)")
      ->delimiter(',')
      ->check(CLI::IsMember({"exchange", "sealed", "vented", "off"}));
  cmd->add_option("--set", o->scene.sets, "override a parameter, KEY=VALUE (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--duration", o->scene.duration, "simulated time per case, s")
      ->check(in_range_of("run.duration"));
  o->scene.add_grid_to(cmd);
  cmd->add_option("--out", o->out, "output folder (default out/<scene>-sweep)")->check(a_path());
  cmd->add_option("--jobs", o->jobs, "cases run at once (default: all cores)")->check(CLI::PositiveNumber);
  cmd->add_flag("--render", o->render, "also render a contact sheet of the last frames (contact_sheet.png)");
  cmd->add_flag("--no-plots", o->no_plots, "skip the plots");
  cmd->add_flag("--quiet", o->quiet, "print nothing but errors");
  cmd->footer(
      "Writes DIR/<case>/ (the outputs of `run`) for every case, DIR/sweep.csv (one row per case:\n"
      "humidity, final metrics, peak pressure deficit at any step and over the output frames,\n"
      "time until the handle first reaches 5 cm)\n"
      "and the plots that mean something for the scene: fig7 (pulled height and base diagonal\n"
      "against humidity), pressure, contact_area and handle_height over time (for a driven\n"
      "handle handle_force, against how far it has moved), and fig8 with several air models\n"
      "(PNG and SVG).");

  return [cmd, o]() -> int {
    if (!*cmd) return -1;
    // Every case is checked before anything is written.
    std::vector<Case> cases;
    const bool several = o->air_models.size() > 1;
    std::vector<std::string> airs = o->air_models;
    const Params base = o->scene.load();
    if (airs.empty()) airs.push_back(base.air.model);
    const int decimals = humidity_decimals(o->humidities);
    for (const auto& air : airs)
      for (double w : o->humidities) {
        Case c;
        c.name = case_name(w, decimals, air, several);
        c.air_model = air;
        c.humidity = w;
        std::vector<std::string> sets = o->scene.overrides();
        share_cores(sets, o->jobs);
        sets.push_back("cloth.humidity=" + format_number(w));
        sets.push_back("air.model=\"" + air + "\"");
        c.params = load_on_grid(o->scene.scene, sets, o->scene.grid);
        cases.push_back(std::move(c));
      }
    const fs::path out =
        o->out.empty() ? fs::path("out") / folder_name(base.name + "-sweep") : fs::path(o->out);
    make_output_folder(out);

    std::vector<std::pair<Params, fs::path>> runs;
    for (const auto& c : cases) runs.emplace_back(c.params, out / c.name);
    // Cases end in any order; each is printed once those before it in the
    // list have been, so that the table reads in the order asked for.
    std::vector<bool> ended(cases.size(), false);
    std::size_t printed = 0;
    install_stop_handlers();  // SIGINT / SIGTERM: every case stops at a step's end
    run_all(runs, o->jobs, [&](std::size_t i, const RunResult& r) {
      cases[i].result = r;
      ended[i] = true;
      for (; printed < cases.size() && ended[printed]; ++printed) {
        if (o->quiet) continue;
        const Case& c = cases[printed];
        // Both peaks: the plots show the frames', and a step between frames
        // can go higher (up to the breakthrough cap as a peel starts).
        std::printf(
            "%-22s %s  handle %.4f m  contact %.5f m²  peak deficit (any step) %.1f Pa, "
            "over frames %.1f Pa  (%.1f s wall)\n",
            c.name.c_str(), c.result.code == kOk ? "ok     " : c.result.code > 128 ? "STOPPED" : "BLEW UP",
            c.result.final.handle_height_m, c.result.final.contact_area_m2,
            c.result.peak_deficit_pa, c.result.frame_peak_deficit_pa, c.result.wall_seconds);
      }
      std::fflush(stdout);
    });
    write_file_atomic(out / "sweep.csv", sweep_csv(cases));

    int code = kOk;
    for (const auto& c : cases)
      if (c.result.code != kOk) {
        std::fprintf(stderr, "wetcloth: %s: %s\n", c.name.c_str(), c.result.message.c_str());
        code = kBlowUp;
      }
    if (stop_signal() != 0) return 128 + stop_signal();  // what finished is in sweep.csv
    if (!o->no_plots) {
      const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
      const std::string cmdline = python + " '" + plot_script().string() + "' '" + out.string() + "'";
      if (std::system(cmdline.c_str()) != 0) {
        std::fprintf(stderr, "wetcloth: the plots failed (%s)\n", cmdline.c_str());
        if (code == kOk) code = kError;
      }
    }
    bool sheet = false;
    if (o->render) {
#ifdef WETCLOTH_VIEWER
      std::vector<std::pair<std::string, fs::path>> tiles;
      for (const auto& c : cases) {
        // "omega", spelt out: the sheet's font is ASCII, it drew ω as 'w'.
        char label[64];
        std::snprintf(label, sizeof label, "%s%somega = %.*f", several ? c.air_model.c_str() : "",
                      several ? ", " : "", decimals, c.humidity);
        tiles.emplace_back(label, out / c.name);
      }
      std::string error;
      sheet = viewer::render_contact_sheet(tiles, out / "contact_sheet.png", 480, 360, &error);
      if (!sheet) {
        std::fprintf(stderr, "wetcloth: contact sheet: %s\n", error.c_str());
        if (code == kOk) code = kError;
      }
#else
      std::fprintf(stderr, "wetcloth: --render needs the viewer (build with WETCLOTH_VIEWER=ON)\n");
      if (code == kOk) code = kError;
#endif
    }
    if (!o->quiet) {
      // Every file the sweep made, the contact sheet too: it is listed nowhere else.
      std::vector<std::string> made{"sweep.csv"};
      if (!o->no_plots) made.push_back("the plots listed above");
      if (sheet) made.push_back("contact_sheet.png");
      std::string list = made[0];
      for (std::size_t k = 1; k < made.size(); ++k)
        list += (k + 1 == made.size() ? " and " : ", ") + made[k];
      std::printf("results: %s (%s)\n", out.c_str(), list.c_str());
    }
    return code;
  };
}

}  // namespace wetcloth::cli
