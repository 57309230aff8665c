#include "converge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "run.hpp"
#include "scene_options.hpp"
#include "wetcloth/convergence.hpp"
#include "wetcloth/output.hpp"

namespace wetcloth::cli {

namespace fs = std::filesystem;

namespace {

struct Case {
  double dt = 0;
  std::string name;
  Params params;
  RunResult result;
};

// The measurements the table shows (all of them go to converge.csv).
constexpr const char* kShown[] = {"handle_height_m", "contact_area_m2", "base_diagonal_m",
                                  "max_height_m"};

}  // namespace

std::function<int()> add_converge_command(CLI::App& app) {
  struct Options {
    SceneOptions scene;
    std::vector<double> dts{5e-5, 2.5e-5, 1.25e-5};
    std::string out;
    unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
    bool quiet = false;
  };
  auto o = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("converge", "run a scene at several time steps: is the result converged?");
  cmd->add_option("scene", o->scene.scene, "scene: a TOML file, or a built-in name")->required();
  cmd->add_option("--dt", o->dts, "time steps, s (default 5e-5,2.5e-5,1.25e-5)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  cmd->add_option("--set", o->scene.sets, "override a parameter, KEY=VALUE (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--humidity", o->scene.humidity, "cloth humidity ω in [0, 1]");
  cmd->add_option("--duration", o->scene.duration, "simulated time per run, s");
  o->scene.add_grid_to(cmd);
  cmd->add_option("--out", o->out, "output folder (default out/<scene>-converge)");
  cmd->add_option("--jobs", o->jobs, "runs at once (default: all cores)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--quiet", o->quiet, "print nothing but errors");
  cmd->footer(
      "Writes DIR/dt_<dt>/ (the outputs of `run`) for every step and DIR/converge.csv (one row\n"
      "per step: its final measurements). With three steps or more, each a constant ratio\n"
      "apart, the three smallest give each measurement's observed order p and its limit as\n"
      "the step goes to 0 (Richardson), and the table shows every run's error against it.");

  return [cmd, o]() -> int {
    if (!*cmd) return -1;
    std::vector<double> dts = o->dts;
    std::sort(dts.rbegin(), dts.rend());
    if (std::adjacent_find(dts.begin(), dts.end()) != dts.end()) {
      std::fprintf(stderr, "wetcloth converge: error: --dt: a time step is given twice\n");
      return kBadInput;
    }
    // Every case is checked before anything is written.
    std::vector<Case> cases;
    for (const double dt : dts) {
      Case c;
      c.dt = dt;
      c.name = "dt_" + format_number(dt);
      std::vector<std::string> sets = o->scene.overrides();
      share_cores(sets, o->jobs);
      sets.push_back("integrator.dt=" + format_number(dt));
      c.params = load_on_grid(o->scene.scene, sets, o->scene.grid);
      cases.push_back(std::move(c));
    }
    const fs::path out = o->out.empty()
                             ? fs::path("out") / (cases.front().params.name + "-converge")
                             : fs::path(o->out);
    fs::create_directories(out);

    std::vector<std::pair<Params, fs::path>> runs;
    for (const auto& c : cases) runs.emplace_back(c.params, out / c.name);
    run_all(runs, o->jobs, [&](std::size_t i, const RunResult& r) {
      cases[i].result = r;
      if (o->quiet) return;
      std::printf("dt %-10s %s  (%.1f s wall)\n", format_number(cases[i].dt).c_str(),
                  r.code == kOk ? "ok" : "BLEW UP", r.wall_seconds);
      std::fflush(stdout);
    });

    std::string csv = "dt_s,status,wall_s";
    for (const auto& c : metrics_columns()) csv += "," + c;
    csv += "\n";
    for (const auto& c : cases) {
      csv += format_number(c.dt) + "," + (c.result.code == kOk ? "ok" : "blew_up") + "," +
             format_number(c.result.wall_seconds);
      for (double v : metrics_values(c.result.final)) csv += "," + format_number(v);
      csv += "\n";
    }
    write_file_atomic(out / "converge.csv", csv);

    int code = kOk;
    for (const auto& c : cases)
      if (c.result.code != kOk) {
        std::fprintf(stderr, "wetcloth: %s: %s\n", c.name.c_str(), c.result.message.c_str());
        code = kBlowUp;
      }
    if (o->quiet || code != kOk) return code;

    // The three smallest steps give the order when they are a constant ratio apart.
    const std::size_t k = cases.size();
    double ratio = 0;
    if (k >= 3) {
      const double r1 = cases[k - 3].dt / cases[k - 2].dt, r2 = cases[k - 2].dt / cases[k - 1].dt;
      if (std::abs(r1 - r2) <= 1e-9 * r2) ratio = r2;
    }
    // Where each shown measurement sits among metrics_values' columns.
    const auto columns = metrics_columns();
    std::vector<std::size_t> at;
    for (const char* name : kShown)
      at.push_back(std::find(columns.begin(), columns.end(), name) - columns.begin());
    std::vector<std::vector<double>> values;
    for (const auto& c : cases) values.push_back(metrics_values(c.result.final));
    std::vector<Extrapolation> fits;
    for (const std::size_t q : at)
      fits.push_back(ratio > 0
                         ? richardson(values[k - 3][q], values[k - 2][q], values[k - 1][q], ratio)
                         : Extrapolation{});

    std::printf("\nfinal values at t = %s s",
                format_number(cases.front().result.final.time_s).c_str());
    if (ratio > 0) std::printf("; in brackets, the error against the limit as dt -> 0");
    std::printf("\n%-14s", "dt s");
    for (const char* name : kShown) std::printf("  %-24s", name);
    std::printf("\n");
    for (std::size_t i = 0; i < k; ++i) {
      std::printf("%-14s", format_number(cases[i].dt).c_str());
      for (std::size_t q = 0; q < at.size(); ++q) {
        const double v = values[i][at[q]], limit = fits[q].limit;
        char cell[64];
        if (std::isfinite(limit) && limit != 0)
          std::snprintf(cell, sizeof cell, "%.5g (%+.1f %%)", v, 100 * (v / limit - 1));
        else
          std::snprintf(cell, sizeof cell, "%.5g", v);
        std::printf("  %-24s", cell);
      }
      std::printf("\n");
    }
    if (ratio > 0) {
      std::printf("%-14s", "order p");
      for (const auto& f : fits) std::printf("  %-24.2f", f.order);
      std::printf("\n%-14s", "limit dt->0");
      for (const auto& f : fits) std::printf("  %-24.5g", f.limit);
      std::printf("\n(nan: the differences do not shrink with the step, so no order shows)\n");
    } else {
      std::printf(
          "(an order and a limit need three steps or more, the smallest three a constant ratio "
          "apart)\n");
    }
    std::printf("results: %s (converge.csv)\n", out.c_str());
    return code;
  };
}

}  // namespace wetcloth::cli
