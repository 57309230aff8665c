#include "run.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>
#include <nlohmann/json.hpp>
#include <thread>

#include "scene_options.hpp"
#include "wetcloth/caches.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth::cli {

namespace fs = std::filesystem;

namespace {

void print_progress(double t, double duration, double wall) {
  const int width = 30;
  const double frac = duration > 0 ? std::min(1.0, t / duration) : 1.0;
  const int fill = static_cast<int>(frac * width);
  std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%  sim %.3f s  wall %.1f s  %.2fx real time ", fill,
               "##############################", width - fill, "", 100 * frac, t, wall,
               wall > 0 ? t / wall : 0.0);
  std::fflush(stderr);
}

nlohmann::json metrics_json(const Metrics& m) {
  nlohmann::json j;
  const auto cols = metrics_columns();
  const auto vals = metrics_values(m);
  for (std::size_t i = 0; i < cols.size(); ++i) j[cols[i]] = vals[i];
  return j;
}

// Clears what an earlier run left, so a folder never mixes two runs.
void clear_outputs(const fs::path& out) {
  for (const char* f : {"metrics.csv", "summary.json", "scene.toml", "obstacles.obj"})
    fs::remove(out / f);
  if (fs::exists(out / "frames"))
    for (const auto& e : fs::directory_iterator(out / "frames"))
      if (e.path().extension() == ".obj") fs::remove(e.path());
}

}  // namespace

RunResult run_scene(const Params& p, const fs::path& out, bool progress) {
  RunResult r;
  Simulation sim(p);
  fs::create_directories(out);
  clear_outputs(out);
  if (p.run.meshes) fs::create_directories(out / "frames");
  write_file_atomic(out / "scene.toml", "# resolved by wetcloth " WETCLOTH_VERSION
                                        "; `wetcloth run` this file to reproduce the run\n" +
                                            to_toml(p));
  const UpAxis up = p.run.up;
  write_file_atomic(out / "obstacles.obj", obstacles_obj(sim.model(), up));
  const ExportFormats formats = parse_export_formats(p.run.exports);
  std::optional<CacheWriter> caches;
  if (formats.any()) caches.emplace(out, sim, formats, up, p.run.fps);

  MetricsTable table;
  const long long frames = last_frame_index(p.run.duration, p.run.fps);
  const auto start = std::chrono::steady_clock::now();
  auto wall = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  // Time to 5 cm is a pulled handle's: a pin (measured when there are only
  // pins) sits at its height from the start.
  const bool pulled = sim.model().measures_a_pull();
  for (long long f = 0; f <= frames; ++f) {
    const double t = frame_time(f, p.run.duration, p.run.fps);
    const bool ok = sim.advance_to(t);
    const Metrics m = sim.metrics();
    table.add(m);
    write_file_atomic(out / "metrics.csv", table.csv());
    if (p.run.meshes) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05lld.obj", f);
      write_file_atomic(out / "frames" / name, cloth_obj(sim.model(), sim.state(), up));
    }
    if (caches) caches->add_frame(sim);
    if (pulled && r.time_to_5cm_s < 0 && m.handle_height_m >= 0.05) r.time_to_5cm_s = m.time_s;
    if (progress) print_progress(sim.state().time, p.run.duration, wall());
    if (!ok) {
      r.code = kBlowUp;
      r.message = sim.blow_up_reason();
      break;
    }
  }
  if (progress) std::fprintf(stderr, "\n");
  if (caches) caches->finish();
  r.first = table.rows().front();
  r.final = table.rows().back();
  r.peak_deficit_pa = sim.state().peak_deficit;
  for (const Metrics& row : table.rows())
    r.frame_peak_deficit_pa =
        std::max(r.frame_peak_deficit_pa, p.air.p_atm - row.inner_pressure_pa);
  r.steps = sim.state().steps;
  r.wall_seconds = wall();

  nlohmann::json s;
  s["scene"] = p.name;
  s["version"] = WETCLOTH_VERSION;
  s["status"] = r.code == kOk ? "ok" : "blew up";
  if (r.code != kOk) s["message"] = r.message;
  s["steps"] = r.steps;
  s["substeps"] = sim.stats().substeps;  // more than steps where implicit Euler halved some
  s["particles"] = sim.model().n;
  // The count asked for (0: chosen as it ran), always a number; beside it how
  // the choice went, or the count used (at most one thread per 1024 particles).
  s["threads"] = p.integrator.threads;
  if (const auto& c = sim.thread_choice(); c.automatic)
    s["thread_choice"] = {
        {"most", c.most}, {"steps_on_1", c.steps_on_one}, {"steps_on_most", c.steps_on_most}};
  else
    s["threads_used"] = sim.model().threads;
  s["simulated_seconds"] = sim.state().time;
  s["wall_seconds"] = r.wall_seconds;
  s["realtime_factor"] = r.wall_seconds > 0 ? sim.state().time / r.wall_seconds : 0.0;
  s["peak_pressure_deficit_pa"] = r.peak_deficit_pa;
  s["final"] = metrics_json(r.final);
  write_file_atomic(out / "summary.json", s.dump(2) + "\n");
  return r;
}

void share_cores(std::vector<std::string>& sets, unsigned jobs) {
  if (overrides_key(sets, "integrator.threads")) return;
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  // One run at a time takes all the cores as the step finds them free (0).
  const unsigned each = jobs <= 1 ? 0 : std::max(1u, cores / jobs);
  sets.insert(sets.begin(), "integrator.threads=" + std::to_string(each));
}

std::vector<RunResult> run_all(const std::vector<std::pair<Params, fs::path>>& runs, unsigned jobs,
                               const std::function<void(std::size_t, const RunResult&)>& done) {
  std::vector<RunResult> results(runs.size());
  std::atomic<std::size_t> next{0};
  std::mutex lock;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < runs.size();) {
      try {  // an exception must not end the process from a worker thread
        results[i] = run_scene(runs[i].first, runs[i].second, false);
      } catch (const std::exception& e) {
        results[i].code = dynamic_cast<const SceneError*>(&e) ? kBadInput : kError;
        results[i].message = e.what();
      }
      std::lock_guard<std::mutex> hold(lock);
      done(i, results[i]);
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t t = 0; t < std::min<std::size_t>(std::max(1u, jobs), runs.size()); ++t)
    pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  return results;
}

}  // namespace wetcloth::cli
