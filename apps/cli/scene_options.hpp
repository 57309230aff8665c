// The options every scene-running command takes: SCENE, --set, --humidity,
// --duration, --threads, --grid.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth::cli {

// Whether one of the KEY=VALUE overrides sets `key`.
inline bool overrides_key(const std::vector<std::string>& sets, const std::string& key) {
  for (const auto& s : sets)
    if (s.rfind(key + "=", 0) == 0) return true;
  return false;
}

// SCENE with the overrides; with a grid, the same cloth that many particles
// wide (wetcloth::at_resolution), keeping a time step the overrides set.
// `option` names the grid in an error.
inline Params load_on_grid(const std::string& scene, const std::vector<std::string>& sets,
                           std::optional<long long> grid, const std::string& option = "--grid") {
  Params p = load_scene(scene, sets);
  if (!grid) return p;
  const double dt = p.integrator.dt;
  try {
    p = at_resolution(p, *grid);
  } catch (const SceneError& e) {
    throw SceneError(option + ": " + e.what());
  }
  if (overrides_key(sets, "integrator.dt")) p.integrator.dt = dt;
  return p;
}

struct SceneOptions {
  std::string scene;
  std::vector<std::string> sets;
  std::optional<double> humidity, duration;
  std::optional<unsigned> threads;
  std::optional<long long> grid;
  bool all_cores = false;  // with add_to: no --threads means all cores

  void add_to(CLI::App* app, bool scene_required = true) {
    auto* s = app->add_option("scene", scene, "scene: a TOML file, or a built-in name (wetcloth scenes)");
    if (scene_required) s->required();
    app->add_option("--set", sets,
                    "override a parameter, KEY=VALUE in TOML syntax, e.g. "
                    "--set cloth.resolution=[101,101] (repeatable; wetcloth params lists the keys)")
        ->allow_extra_args(false);
    app->add_option("--humidity", humidity, "cloth humidity ω in [0, 1] (= --set cloth.humidity=W)");
    app->add_option("--duration", duration, "simulated time, s (= --set run.duration=S)");
    app->add_option("--threads", threads,
                    "threads of the step (default: all cores; = --set integrator.threads=N, "
                    "which comes after it)");
    add_grid_to(app);
    all_cores = true;
  }

  void add_grid_to(CLI::App* app) {
    app->add_option("--grid", grid,
                    "the same scene on a cloth G particles wide: handle patches keep their size "
                    "in metres, and an explicit time step shrinks with the spacing unless --set "
                    "integrator.dt is given");
  }

  std::vector<std::string> overrides() const {
    std::vector<std::string> all;
    if (threads || all_cores) all.push_back("integrator.threads=" + std::to_string(threads.value_or(0)));
    all.insert(all.end(), sets.begin(), sets.end());
    if (humidity) all.push_back("cloth.humidity=" + format_number(*humidity));
    if (duration) all.push_back("run.duration=" + format_number(*duration));
    return all;
  }

  Params load() const { return load_on_grid(scene, overrides(), grid); }
};

}  // namespace wetcloth::cli
