#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "cli.hpp"
#include "common/convergence.hpp"
#include "common/scene_options.hpp"
#include "wetcloth/output.hpp"

namespace wetcloth::cli {

namespace fs = std::filesystem;

namespace {

struct Options {
  SceneOptions scene;
  std::vector<double> dts;  // default: the scene's step, halved and halved again
  std::string out;
  unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
  bool quiet = false, force = false;
};

struct Case {
  double dt = 0;
  std::string name;
  Params params;
  RunResult result;
};

// The measurements the table shows (all of them go to converge.csv). The
// slide is how far the cloth's centroid moved in the plane from the first
// frame to the last.
constexpr const char* kShown[] = {"handle_height_m", "contact_area_m2", "base_diagonal_m",
                                  "max_height_m", "slide_m"};
constexpr int kDigits = 5;  // significant digits of the table's values
// A limit is trusted at an order of a half or more: below, the differences
// shrink too slowly with the step for the extrapolation to mean much.
constexpr double kLeastOrder = 0.5;

// A time as people write it: 1.5, not 1.5000000000000002.
std::string format_time(double t) {
  char s[32];
  std::snprintf(s, sizeof s, "%.6g", t);
  return s;
}

void add_converge_options(CLI::App* cmd, Options& o) {
  cmd->add_option("scene", o.scene.scene, "scene: a TOML file, or a built-in name")->required();
  cmd->add_option("--dt", o.dts, "time steps, s (default: the scene's, its half and its quarter)")
      ->delimiter(',')
      ->check(in_range_of("integrator.dt"));
  cmd->add_option("--set", o.scene.sets, "override a parameter, KEY=VALUE (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--humidity", o.scene.humidity, "cloth humidity ω in [0, 1]")
      ->check(in_range_of("cloth.humidity"));
  cmd->add_option("--duration", o.scene.duration, "simulated time per run, s")
      ->check(in_range_of("run.duration"));
  o.scene.add_grid_to(cmd);
  cmd->add_option("--out", o.out, "output folder (default out/<scene>-converge)")->check(a_path());
  cmd->add_option("--jobs", o.jobs, "runs at once (default: all cores)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--quiet", o.quiet, "print nothing but errors");
  cmd->add_flag("--force", o.force,
                "write into DIR even where it holds files of no wetcloth convergence study");
  cmd->footer(
      "Writes DIR/dt_<dt>/ (the outputs of `run`) for every step and DIR/converge.csv (one row\n"
      "per step: its final measurements, and slide_m, how far the cloth's centroid moved from\n"
      "the first frame). With three steps or more, each a constant ratio apart, the three\n"
      "smallest give each measurement's observed order p and its limit as the step goes to 0\n"
      "(Richardson), and the table shows every run's error against it. A measurement that\n"
      "prints the same at every step is converged to its digits: \"same at every dt\".");
}

// The steps to run, largest first: --dt, or the scene's, its half and its quarter.
std::vector<double> time_steps(const Options& o) {
  std::vector<double> dts = o.dts;
  if (dts.empty()) {
    const double dt = load_on_grid(o.scene.scene, o.scene.overrides(), o.scene.grid).integrator.dt;
    dts = {dt, dt / 2, dt / 4};
  }
  std::sort(dts.rbegin(), dts.rend());
  return dts;
}

// A case per step, its scene loaded: every case is checked before anything is written.
std::vector<Case> load_cases(const Options& o, const std::vector<double>& dts) {
  std::vector<Case> cases;
  for (const double dt : dts) {
    Case c;
    c.dt = dt;
    c.name = "dt_" + format_number(dt);
    std::vector<std::string> sets = o.scene.overrides();
    share_cores(sets, o.jobs);
    sets.push_back("integrator.dt=" + format_number(dt));
    c.params = load_on_grid(o.scene.scene, sets, o.scene.grid);
    cases.push_back(std::move(c));
  }
  return cases;
}

void run_cases(const Options& o, std::vector<Case>& cases, const fs::path& out) {
  std::vector<std::pair<Params, fs::path>> runs;
  for (const auto& c : cases) runs.emplace_back(c.params, out / c.name);
  run_all(runs, o.jobs, run_hooks(false), [&](std::size_t i, const RunResult& r) {
    cases[i].result = r;
    if (o.quiet) return;
    std::printf("dt %-10s %s  (%.1f s wall)\n", format_number(cases[i].dt).c_str(),
                r.code == kOk ? "ok" : "BLEW UP", r.wall_seconds);
    std::fflush(stdout);
  });
}

// Every run's final measurements (metrics_columns() and slide_m), and its
// slide to the nanometre (a cloth that stays put moves its centroid by
// rounding errors, 1e-16 m).
std::vector<std::vector<double>> final_values(const std::vector<Case>& cases) {
  std::vector<std::vector<double>> values;
  for (const auto& c : cases) {
    values.push_back(metrics_values(c.result.final));
    const Metrics &a = c.result.first, &b = c.result.final;
    const double slide =
        std::hypot(b.centroid_x_m - a.centroid_x_m, b.centroid_y_m - a.centroid_y_m);
    values.back().push_back(std::round(slide * 1e9) / 1e9);
  }
  return values;
}

void write_converge_csv(const fs::path& out, const std::vector<Case>& cases,
                        const std::vector<std::string>& columns,
                        const std::vector<std::vector<double>>& values) {
  std::string csv = "dt_s,status,wall_s";
  for (const auto& c : columns) csv += "," + c;
  csv += "\n";
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto& c = cases[i];
    csv += format_number(c.dt) + "," + (c.result.code == kOk ? "ok" : "blew_up") + "," +
           format_number(c.result.wall_seconds);
    for (double v : values[i]) csv += "," + format_number(v);
    csv += "\n";
  }
  write_file_atomic(out / "converge.csv", csv);
}

// What the table shows of each kShown measurement: where it sits among the
// columns, whether it prints the same at every step (converged to the digits
// shown: no order to find), and its Richardson fit from the three smallest
// steps when they are a constant ratio apart (ratio 0 where they are not).
struct Analysis {
  double ratio = 0;
  std::vector<std::size_t> at;
  std::vector<bool> same;
  std::vector<Extrapolation> fits;

  bool trusted(std::size_t q) const {
    return !same[q] && std::isfinite(fits[q].limit) && fits[q].limit != 0 &&
           fits[q].order >= kLeastOrder;
  }
  bool any_same() const { return std::find(same.begin(), same.end(), true) != same.end(); }
};

Analysis analyse(const std::vector<Case>& cases, const std::vector<std::string>& columns,
                 const std::vector<std::vector<double>>& values) {
  Analysis a;
  const std::size_t k = cases.size();
  if (k >= 3) {
    const double r1 = cases[k - 3].dt / cases[k - 2].dt, r2 = cases[k - 2].dt / cases[k - 1].dt;
    if (std::abs(r1 - r2) <= 1e-9 * r2) a.ratio = r2;
  }
  for (const char* name : kShown) {
    a.at.push_back(std::find(columns.begin(), columns.end(), name) - columns.begin());
    std::vector<double> column;
    for (const auto& v : values) column.push_back(v[a.at.back()]);
    a.same.push_back(same_to_digits(column, kDigits));
  }
  for (const std::size_t q : a.at)
    a.fits.push_back(a.ratio > 0
                         ? richardson(values[k - 3][q], values[k - 2][q], values[k - 1][q], a.ratio)
                         : Extrapolation{});
  return a;
}

// The final values at every step, each with its error against the limit where trusted.
void print_values(const std::vector<Case>& cases, const std::vector<std::vector<double>>& values,
                  const Analysis& a) {
  std::printf("\nfinal values at t = %s s", format_time(cases.front().result.final.time_s).c_str());
  if (a.ratio > 0)
    std::printf("; in brackets, the error against the limit as dt -> 0, where trusted");
  std::printf("\n%-14s", "dt s");
  for (const char* name : kShown) std::printf("  %-24s", name);
  std::printf("\n");
  for (std::size_t i = 0; i < cases.size(); ++i) {
    std::printf("%-14s", format_number(cases[i].dt).c_str());
    for (std::size_t q = 0; q < a.at.size(); ++q) {
      const double v = values[i][a.at[q]], limit = a.fits[q].limit;
      char cell[64];
      if (a.trusted(q))
        std::snprintf(cell, sizeof cell, "%.*g (%+.1f %%)", kDigits, v, 100 * (v / limit - 1));
      else
        std::snprintf(cell, sizeof cell, "%.*g", kDigits, v == 0 ? 0.0 : v);
      std::printf("  %-24s", cell);
    }
    std::printf("\n");
  }
}

// The rows of order p and limit, with notes on the cells that need them.
void print_order_and_limit(const std::vector<double>& finest, const Analysis& a) {
  bool any_nan = false;
  std::printf("%-14s", "order p");
  for (std::size_t q = 0; q < a.at.size(); ++q) {
    if (a.same[q]) {
      std::printf("  %-24s", "same at every dt");
    } else {
      any_nan = any_nan || std::isnan(a.fits[q].order);
      std::printf("  %-24.2f", a.fits[q].order);
    }
  }
  std::printf("\n%-14s", "limit dt->0");
  bool any_untrusted = false;
  for (std::size_t q = 0; q < a.at.size(); ++q) {
    const double v = finest[a.at[q]];
    // A finite limit of too low an order (a nan one says so itself).
    const bool untrusted = !a.same[q] && !a.trusted(q) && std::isfinite(a.fits[q].limit);
    any_untrusted = any_untrusted || untrusted;
    char cell[64];
    std::snprintf(cell, sizeof cell, "%.*g%s", kDigits,
                  a.same[q] ? (v == 0 ? 0.0 : v) : a.fits[q].limit, untrusted ? " ?" : "");
    std::printf("  %-24s", cell);
  }
  std::printf("\n");
  if (any_untrusted)
    std::printf(
        "(?: an order under %.1f, or a limit of 0: the differences shrink too slowly with the "
        "step to trust the limit; the spread of the values is the better error bar)\n",
        kLeastOrder);
  if (a.any_same())
    std::printf(
        "(same at every dt: the value is the same, to the digits shown, at every step: "
        "converged)\n");
  if (any_nan)
    std::printf("(nan: the differences do not shrink with the step, so no order shows)\n");
}

// Without an order: which measurements are converged, and why there is no order.
void print_without_order(const Analysis& a) {
  if (a.any_same()) {
    std::printf("(the same, to the digits shown, at every step: converged:");
    for (std::size_t q = 0; q < std::size(kShown); ++q)
      if (a.same[q]) std::printf(" %s", kShown[q]);
    std::printf(")\n");
  }
  std::printf(
      "(an order and a limit need three steps or more, the smallest three a constant ratio "
      "apart)\n");
}

int run_converge(const Options& o) {
  const std::vector<double> dts = time_steps(o);
  if (std::adjacent_find(dts.begin(), dts.end()) != dts.end()) {
    std::fprintf(stderr, "wetcloth converge: error: --dt: a time step is given twice\n");
    return kBadInput;
  }
  std::vector<Case> cases = load_cases(o, dts);
  const fs::path out =
      o.out.empty() ? fs::path("out") / (cases.front().params.name + "-converge") : fs::path(o.out);
  if (!o.force) {  // an earlier study's folder holds its table or its runs
    std::vector<std::string> marks = {"converge.csv"};
    for (const Case& c : cases) marks.push_back(c.name);
    refuse_system_folder(out);
    refuse_foreign_folder(out, "--out", "convergence study", marks);
  }
  make_output_folder(out);
  run_cases(o, cases, out);

  std::vector<std::string> columns = metrics_columns();
  columns.push_back("slide_m");
  const std::vector<std::vector<double>> values = final_values(cases);
  write_converge_csv(out, cases, columns, values);

  int code = kOk;
  for (const auto& c : cases)
    if (c.result.code != kOk) {
      std::fprintf(stderr, "wetcloth: %s: %s\n", c.name.c_str(), c.result.message.c_str());
      code = kBlowUp;
    }
  if (o.quiet || code != kOk) return code;

  const Analysis a = analyse(cases, columns, values);
  print_values(cases, values, a);
  if (a.ratio > 0)
    print_order_and_limit(values.back(), a);
  else
    print_without_order(a);
  std::printf(
      "(slide_m: how far the cloth's centroid moved from the first frame, m, to the "
      "nanometre)\n");
  std::printf("results: %s (converge.csv)\n", out.c_str());
  return code;
}

}  // namespace

std::function<int()> add_converge_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* cmd =
      app.add_subcommand("converge", "run a scene at several time steps: is the result converged?");
  add_converge_options(cmd, *o);
  return [cmd, o]() -> int { return *cmd ? run_converge(*o) : -1; };
}

}  // namespace wetcloth::cli
