// The options every scene-running command of the programs (the command line,
// the viewer) takes: SCENE, --set, --humidity, --duration, --threads, --grid,
// parsed with CLI11; what they load is the library's (wetcloth/run.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "wetcloth/output.hpp"
#include "wetcloth/run.hpp"  // load_on_grid, overrides_key
#include "wetcloth/scene.hpp"

namespace wetcloth::cli {

// A command-line value checked against the range of the scene parameter it
// sets, so that the error names the option the user typed:
// "--humidity: value 1.5 is out of range [0, 1] (cloth.humidity)".
inline CLI::Validator in_range_of(const std::string& key) {
  const ParamDef* def = nullptr;
  for (const ParamDef& d : param_defs())
    if (d.key == key) def = &d;
  if (def == nullptr || def->min > def->max) throw std::logic_error("no numeric parameter " + key);
  return CLI::Validator(
      [def](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return "not a number: " + text;
        if (v >= def->min && v <= def->max) return {};
        return "value " + text + " is out of range " + def->range_text() + " (" + def->key + ")";
      },
      def->range_text());
}

// A count such as --grid: digits that fit a long long, nothing else (CLI11
// reads '' as no value, and an overflow as its largest value).
inline CLI::Validator a_whole_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        long long v = 0;
        const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (text.empty() || error != std::errc() || end != text.data() + text.size() || v < 1)
          return "'" + text + "' is not a whole number of particles (e.g. 101)";
        return {};
      },
      "G");
}

// An --out that is empty (an unset shell variable) is a mistake, not "the default".
inline CLI::Validator a_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "an empty path" : ""; }, "");
}

struct SceneOptions {
  std::string scene;
  std::vector<std::string> sets;
  std::optional<double> humidity, duration;
  std::optional<unsigned> threads;
  std::optional<long long> grid;
  bool all_cores = false;  // with add_to: no --threads means 0, chosen as the step runs
  // The tier a scene that names no integrator runs with, and the flag that
  // sets the other over the scene's own (--live; the viewer's --accurate).
  IntegratorTier tier = IntegratorTier::Accurate;
  bool other_tier = false;

  void add_to(CLI::App* app, bool scene_required = true) {
    auto* s =
        app->add_option("scene", scene, "scene: a TOML file, or a built-in name (wetcloth scenes)");
    if (scene_required) s->required();
    app->add_option("--set", sets,
                    "override a parameter, KEY=VALUE in TOML syntax, e.g. "
                    "--set cloth.resolution=[101,101] (repeatable; wetcloth params lists the keys)")
        ->allow_extra_args(false);
    app->add_option("--humidity", humidity, "cloth humidity ω in [0, 1] (= --set cloth.humidity=W)")
        ->check(in_range_of("cloth.humidity"));
    app->add_option("--duration", duration, "simulated time, s (= --set run.duration=S)")
        ->check(in_range_of("run.duration"));
    app->add_option("--threads", threads,
                    "threads of the step (default 0: all cores, or one where that is faster, "
                    "timed as it runs; = --set integrator.threads=N, which comes after it)")
        ->check(in_range_of("integrator.threads"));
    add_grid_to(app);
    if (tier == IntegratorTier::Accurate)
      app->add_flag("--live", other_tier,
                    "the live integrator tier, the fastest, as the viewer runs (= --set "
                    "integrator.tier=live, before the --set options; its error against the "
                    "reference: docs/performance.md)");
    else
      app->add_flag("--accurate", other_tier,
                    "the accurate integrator tier, the default of run (= --set "
                    "integrator.tier=accurate, before the --set options)");
    all_cores = true;
  }

  void add_grid_to(CLI::App* app) {
    app->add_option("--grid", grid,
                    "the same scene on a cloth G particles wide: handle patches keep their size "
                    "in metres, and an explicit time step shrinks with the spacing unless --set "
                    "integrator.dt is given")
        ->check(a_whole_number());
  }

  std::vector<std::string> overrides() const {
    std::vector<std::string> all;
    if (threads || all_cores)
      all.push_back("integrator.threads=" + std::to_string(threads.value_or(0)));
    if (other_tier)
      all.push_back(std::string("integrator.tier=\"") +
                    (tier == IntegratorTier::Accurate ? "live" : "accurate") + "\"");
    all.insert(all.end(), sets.begin(), sets.end());
    if (humidity) all.push_back("cloth.humidity=" + format_number(*humidity));
    if (duration) all.push_back("run.duration=" + format_number(*duration));
    return all;
  }

  // The step's threads change no result and no check: set once the scene is
  // loaded, so that no message names a --set the user did not give.
  Params load() const {
    std::vector<std::string> given = overrides();
    const bool threads_set = threads || all_cores;
    if (threads_set) given.erase(given.begin());
    Params p = load_on_grid(scene, given, grid, "--grid", tier);
    if (threads_set && !overrides_key(given, "integrator.threads"))
      p.integrator.threads = threads.value_or(0);
    return p;
  }
};

}  // namespace wetcloth::cli
