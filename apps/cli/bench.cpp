#include "bench.hpp"

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "run.hpp"
#include "scene_options.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth::cli {

namespace fs = std::filesystem;
// Keys in the order written, so that bench.json reads top-down.
using json = nlohmann::ordered_json;

namespace {

struct Options {
  std::string scene = "pull-straight";
  std::vector<long long> grids{51};
  double duration = 0.05;
  std::optional<unsigned> threads;
  std::string integrator;
  int repetitions = 5;
  std::vector<std::string> sets;
  std::string out = "out/bench.json";
};

struct Grid {
  long long size = 0, steps = 0;
  Params params;
};

// This process's peak resident memory so far, bytes (Linux gives KiB).
long long peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<long long>(u.ru_maxrss) * 1024;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const auto start = line.find_first_not_of(" \t:", line.find(':'));
      if (start != std::string::npos) return line.substr(start);
    }
  return "unknown";
}

// One grid's repetitions, each on a fresh Simulation: one untimed step (first
// touches of the memory, lazy set-up), then the timed steps.
json measure(const Grid& g, int repetitions) {
  json r;
  const long long base = peak_rss_bytes();
  std::vector<double> wall;
  for (int rep = 0; rep < repetitions; ++rep) {
    Simulation sim(g.params);
    sim.step();
    const Workspace& w = sim.workspace();
    const long long substeps = w.substeps, solves = w.solves, iterations = w.cg_iterations_total;
    const auto start = std::chrono::steady_clock::now();
    for (long long k = 0; k < g.steps; ++k) sim.step();
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    // Implicit Euler's step control may take a step in substeps, and throw
    // solves away; the other integrators take one substep and no solve.
    r["substeps_per_step"] = static_cast<double>(w.substeps - substeps) / g.steps;
    r["solves_per_step"] = static_cast<double>(w.solves - solves) / g.steps;
    r["cg_iterations_per_solve"] = w.solves > solves
                                       ? static_cast<double>(w.cg_iterations_total - iterations) /
                                             static_cast<double>(w.solves - solves)
                                       : 0.0;
    // Checked after the clock stops: the check costs a pass over the particles.
    if (const std::string why = sim.blow_up_reason(); !why.empty()) return {{"blow_up", why}};
    const Model& m = sim.model();
    r["particles"] = m.n;
    r["springs"] = m.structural.size() + m.shear.size() + m.bending.size();
  }
  r["wall_s"] = wall;
  r["peak_bytes"] = peak_rss_bytes();
  r["base_bytes"] = base;
  return r;
}

// Runs measure() in a child process so that ru_maxrss is this grid's own peak:
// a forked child's high-water mark starts from its own (near-empty) resident
// set, not from the parent's or an earlier grid's peak (checked on Linux 6.x
// against VmHWM in /proc/self/status). The result comes back as JSON on a pipe.
json measure_in_child(const Grid& g, int repetitions) {
  int fd[2];
  if (pipe(fd) != 0) throw std::runtime_error("bench: pipe failed");
  std::fflush(nullptr);  // else the child would inherit, and repeat, buffered output
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("bench: fork failed");
  if (pid == 0) {
    close(fd[0]);
    std::string msg;
    try {
      msg = measure(g, repetitions).dump();
    } catch (const std::exception& e) {
      msg = json{{"error", e.what()}}.dump();
    }
    for (std::size_t done = 0; done < msg.size();) {
      const ssize_t k = write(fd[1], msg.data() + done, msg.size() - done);
      if (k <= 0) _exit(1);
      done += static_cast<std::size_t>(k);
    }
    _exit(0);  // no exit handlers, nothing of the parent's flushed twice
  }
  close(fd[1]);
  std::string msg;
  char buf[4096];
  for (ssize_t k; (k = read(fd[0], buf, sizeof buf)) > 0;)
    msg.append(buf, static_cast<std::size_t>(k));
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || msg.empty())
    throw std::runtime_error(
        "bench: the process timing grid " + std::to_string(g.size) + " died" +
        (WIFSIGNALED(status) ? " (signal " + std::to_string(WTERMSIG(status)) + ")" : ""));
  json r = json::parse(msg);
  if (r.contains("error")) throw std::runtime_error(r["error"].get<std::string>());
  return r;
}

int run_bench(const Options& o) {
  // Every input is checked, and every grid's scene loaded, before anything runs.
  if (o.repetitions < 1) throw SceneError("--repetitions: must be at least 1");
  if (!(o.duration > 0)) throw SceneError("--duration: must be positive");
  const fs::path out(o.out);
  if (fs::is_directory(out)) throw SceneError("--out " + o.out + ": is a folder; give a file name");
  check_output_folder(out.parent_path(), "--out");
  // All the cores by default, as a fixed count: a bench times a number of
  // threads, not the choice integrator.threads = 0 makes as it runs (which
  // --threads 0 times).
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const unsigned threads = o.threads.value_or(cores);
  std::vector<Grid> grids;
  for (long long size : o.grids) {
    std::vector<std::string> sets;
    sets.push_back("integrator.threads=" + std::to_string(threads));
    if (!o.integrator.empty()) sets.push_back("integrator.type=\"" + o.integrator + "\"");
    sets.insert(sets.end(), o.sets.begin(), o.sets.end());
    // The same cloth at each grid, unless the user chose the time step.
    Grid grid{size, 0, load_on_grid(o.scene, sets, size, "--grids")};
    grid.steps = std::llround(o.duration / grid.params.integrator.dt);
    if (grid.steps < 1)
      throw SceneError("--duration " + format_number(o.duration) +
                       " s is shorter than one step (integrator.dt = " +
                       format_number(grid.params.integrator.dt) + " s)");
    grids.push_back(std::move(grid));
  }

  const Params& p0 = grids.front().params;
  const double dt = p0.integrator.dt;
  const std::string cpu = cpu_model();
  std::printf(
      "wetcloth %s bench: scene %s, integrator %s, dt %g s (first grid), %g s simulated per run, "
      "%d repetitions, "
      "%u threads\nmachine: %u cores, %s\n\n",
      WETCLOTH_VERSION, p0.name.c_str(), p0.integrator.type.c_str(), dt, o.duration, o.repetitions,
      threads, cores, cpu.c_str());
  std::printf(
      " grid  particles  springs  dt µs   steps  substeps/step    wall s    µs/step  "
      "ns/particle-step  real-time ×  peak MB  B/particle\n");

  json doc = {{"version", WETCLOTH_VERSION},
              {"scene", p0.name},
              {"integrator", p0.integrator.type},
              {"dt_s", dt},
              {"threads", threads},
              {"duration_s", o.duration},
              {"repetitions", o.repetitions},
              {"machine", {{"cores", cores}, {"cpu", cpu}}},
              {"grids", json::array()}};
  for (const Grid& g : grids) {
    const json r = measure_in_child(g, o.repetitions);
    if (r.contains("blow_up")) {
      std::fprintf(stderr, "wetcloth: grid %lld: %s\nnothing written\n", g.size,
                   r["blow_up"].get<std::string>().c_str());
      return kBlowUp;
    }
    const auto walls = r["wall_s"].get<std::vector<double>>();
    const long long n = r["particles"], springs = r["springs"];
    std::vector<double> us_step, ns_particle, realtime;
    for (double w : walls) {
      us_step.push_back(1e6 * w / g.steps);
      ns_particle.push_back(1e9 * w / (static_cast<double>(g.steps) * n));
      realtime.push_back(g.steps * g.params.integrator.dt / w);
    }
    const double peak_mb = r["peak_bytes"].get<double>() / 1e6;
    // What the grid's simulations added to the process: bytes per particle.
    const double per_particle = (r["peak_bytes"].get<double>() - r["base_bytes"].get<double>()) / n;
    const double substeps = r["substeps_per_step"];  // the last repetition's: the same in each
    std::printf(
        "%5lld  %9lld  %7lld  %5.2f  %6lld  %13.2f  %8.3f  %9.1f  %16.1f  %11.4f  %7.1f  %10.0f\n",
        g.size, n, springs, 1e6 * g.params.integrator.dt, g.steps, substeps, median(walls),
        median(us_step), median(ns_particle), median(realtime), peak_mb, per_particle);
    const double solves = r["solves_per_step"], iterations = r["cg_iterations_per_solve"];
    if (solves > 0)
      std::printf(
          "       implicit Euler: %.2f solves a step, %.1f conjugate-gradient iterations a solve\n",
          solves, iterations);
    std::fflush(stdout);
    doc["grids"].push_back({{"grid", g.size},
                            {"particles", n},
                            {"springs", springs},
                            {"dt_s", g.params.integrator.dt},
                            {"steps", g.steps},
                            {"substeps_per_step", substeps},
                            {"solves_per_step", solves},
                            {"cg_iterations_per_solve", iterations},
                            {"wall_s", walls},
                            {"median",
                             {{"wall_s", median(walls)},
                              {"us_per_step", median(us_step)},
                              {"ns_per_particle_step", median(ns_particle)},
                              {"realtime_factor", median(realtime)}}},
                            {"peak_memory_mb", peak_mb},
                            {"bytes_per_particle", per_particle}});
  }
  if (out.has_parent_path()) fs::create_directories(out.parent_path());
  write_file_atomic(out, doc.dump(2) + "\n");
  std::printf("\nmedians over %d repetitions; results in %s\n", o.repetitions, o.out.c_str());
  return kOk;
}

}  // namespace

std::function<int()> add_bench_command(CLI::App& app) {
  auto o = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "bench", "time the step of a scene at several grid sizes, with peak memory");
  cmd->add_option("--scene", o->scene, "scene: a TOML file, or a built-in name")
      ->capture_default_str();
  cmd->add_option("--grids", o->grids, "cloth grids G (G x G particles), e.g. 51,101,201")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--duration", o->duration, "simulated time timed per repetition, s")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads,
                  "threads of the step (default: all cores; = --set integrator.threads=N)");
  cmd->add_option("--integrator", o->integrator, "integrator.type (default: the scene's)");
  cmd->add_option("--repetitions", o->repetitions, "timed runs per grid; the table shows medians")
      ->capture_default_str();
  cmd->add_option("--set", o->sets, "override a parameter, KEY=VALUE (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--out", o->out, "the results as JSON")->capture_default_str()->check(a_path());
  cmd->footer(
      "Each grid runs in a process of its own (its peak memory is its own); each repetition "
      "builds\n"
      "the simulation afresh, takes one untimed step, then times round(duration / dt) steps.\n"
      "Writes FILE (every repetition's wall time, the medians, the machine).\n"
      "Exit codes: 0 ok, 2 bad input (nothing written), 3 the simulation blew up (nothing "
      "written).");
  return [cmd, o]() -> int { return *cmd ? run_bench(*o) : -1; };
}

}  // namespace wetcloth::cli
