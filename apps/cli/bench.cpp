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

#include "cli.hpp"
#include "common/scene_options.hpp"
#ifdef WETCLOTH_BULLET
#include "bullet_peer.hpp"
#endif
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
  std::string out;   // default out/bench.json, with a peer out/bench_<peer>.json
  std::string peer;  // "bullet": time the same cloth in Bullet beside ours
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
    const StepStats before = sim.stats();
    const long long substeps = before.substeps, solves = before.solves,
                    iterations = before.cg_iterations_total;
    const auto start = std::chrono::steady_clock::now();
    for (long long k = 0; k < g.steps; ++k) sim.step();
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    // Implicit Euler's step control may take a step in substeps, and throw
    // solves away; the other integrators take one substep and no solve.
    const StepStats w = sim.stats();
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
    r["springs"] = spring_count(m, SpringKind::Structural) + spring_count(m, SpringKind::Shear) +
                   spring_count(m, SpringKind::Bending);
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

// bench.json's first keys, the same beside a peer: the run and the machine.
json doc_head(const Options& o, const Params& p0, unsigned threads, unsigned cores,
              const std::string& cpu) {
  return {{"version", WETCLOTH_VERSION},
          {"scene", p0.name},
          {"integrator", to_string(p0.integrator.type)},
          {"dt_s", p0.integrator.dt},
          {"threads", threads},
          {"duration_s", o.duration},
          {"repetitions", o.repetitions},
          {"machine", {{"cores", cores}, {"cpu", cpu}}}};
}

// The scene at each grid, and the steps that take --duration there.
std::vector<Grid> load_grids(const Options& o, unsigned threads) {
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
  return grids;
}

void print_bench_header(const Options& o, const Params& p0, unsigned threads, unsigned cores,
                        const std::string& cpu) {
  std::printf(
      "wetcloth %s bench: scene %s, integrator %s, dt %g s (first grid), %g s simulated per run, "
      "%d repetitions, "
      "%u threads\nmachine: %u cores, %s\n\n",
      WETCLOTH_VERSION, p0.name.c_str(), to_string(p0.integrator.type).c_str(), p0.integrator.dt,
      o.duration, o.repetitions, threads, cores, cpu.c_str());
  std::printf(
      " grid  particles  springs  dt µs   steps  substeps/step    wall s    µs/step  "
      "ns/particle-step  real-time ×  peak MB  B/particle\n");
}

// A grid's measurements (measure()'s) as its row of the table and its entry
// in bench.json, with the medians over the repetitions.
json report_grid(const Grid& g, const json& r) {
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
  return {{"grid", g.size},
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
          {"bytes_per_particle", per_particle}};
}

int run_peer(const Options& o, const std::vector<Grid>& grids, unsigned threads,
             const fs::path& out);

int run_bench(const Options& o) {
#ifndef WETCLOTH_BULLET
  if (o.peer == "bullet") {
    std::fprintf(stderr,
                 "wetcloth: error: --peer bullet: this wetcloth was built without Bullet "
                 "(libbullet-dev was not found when the build was configured); install it "
                 "(make deps) and configure again\n");
    return kError;
  }
#endif
  // Every input is checked, and every grid's scene loaded, before anything runs.
  if (o.repetitions < 1) throw SceneError("--repetitions: must be at least 1");
  if (!(o.duration > 0)) throw SceneError("--duration: must be positive");
  const std::string out_name = !o.out.empty()   ? o.out
                               : o.peer.empty() ? "out/bench.json"
                                                : "out/bench_" + o.peer + ".json";
  const fs::path out(out_name);
  if (fs::is_directory(out))
    throw SceneError("--out " + out_name + ": is a folder; give a file name");
  check_output_folder(out.parent_path(), "--out");
  // All the cores by default, as a fixed count: a bench times a number of
  // threads, not the choice integrator.threads = 0 makes as it runs (which
  // --threads 0 times). Beside a peer, one thread, as Bullet's soft bodies
  // step on one.
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const unsigned threads = o.threads.value_or(o.peer.empty() ? cores : 1);
  const std::vector<Grid> grids = load_grids(o, threads);
  if (!o.peer.empty()) return run_peer(o, grids, threads, out);

  const Params& p0 = grids.front().params;
  const std::string cpu = cpu_model();
  print_bench_header(o, p0, threads, cores, cpu);
  json doc = doc_head(o, p0, threads, cores, cpu);
  doc["grids"] = json::array();
  for (const Grid& g : grids) {
    const json r = measure_in_child(g, o.repetitions);
    if (r.contains("blow_up")) {
      std::fprintf(stderr, "wetcloth: grid %lld: %s\nnothing written\n", g.size,
                   r["blow_up"].get<std::string>().c_str());
      return kBlowUp;
    }
    doc["grids"].push_back(report_grid(g, r));
  }
  if (out.has_parent_path()) fs::create_directories(out.parent_path());
  write_file_atomic(out, doc.dump(2) + "\n");
  std::printf("\nmedians over %d repetitions; results in %s\n", o.repetitions, out_name.c_str());
  return kOk;
}

#ifdef WETCLOTH_BULLET
constexpr double kPeerDt = 1.0 / 600.0;  // Bullet's step

// Our cloth's mean height and highest point, m.
std::pair<double, double> heights(const Simulation& sim) {
  const double* z = sim.state().x.column(2);
  const int n = sim.model().n;
  double sum = 0, top = z[0];
  for (int k = 0; k < n; ++k) {
    sum += z[k];
    top = std::max(top, z[k]);
  }
  return {sum / n, top};
}

// One grid's rounds: each simulator's wall times, and where each ended.
struct PeerRounds {
  std::vector<double> ours_wall, peer_wall, ratio;
  std::pair<double, double> ours_end, peer_end;  // mean and highest height, m
  int links = 0, faces = 0;
  double peer_mass = 0, ours_time = 0, peer_time = 0;
};

// Ours from t = 0: one untimed step, then the grid's steps timed. False
// (said on stderr) when it blew up.
bool time_ours(const Grid& g, PeerRounds& r) {
  Simulation sim(g.params);
  sim.step();
  const auto start = std::chrono::steady_clock::now();
  for (long long k = 0; k < g.steps; ++k) sim.step();
  r.ours_wall.push_back(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (const std::string why = sim.blow_up_reason(); !why.empty()) {
    std::fprintf(stderr, "wetcloth: grid %lld: %s\nnothing written\n", g.size, why.c_str());
    return false;
  }
  r.ours_end = heights(sim);
  r.ours_time = sim.state().time;
  return true;
}

// Bullet's the same way, on the cloth made plain.
bool time_bullet(const Grid& g, const Model& model, long long peer_steps, PeerRounds& r) {
  BulletCloth peer(model, kPeerDt);
  peer.step();
  const auto start = std::chrono::steady_clock::now();
  for (long long k = 0; k < peer_steps; ++k) peer.step();
  r.peer_wall.push_back(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!peer.finite()) {
    std::fprintf(stderr, "wetcloth: grid %lld: Bullet's cloth blew up\nnothing written\n", g.size);
    return false;
  }
  r.peer_end = {peer.mean_z(), peer.max_z()};
  r.links = peer.links();
  r.faces = peer.faces();
  r.peer_mass = peer.mass();
  r.peer_time = peer.time();
  return true;
}

// The rounds of a grid, the two taking turns going first; false when either blew up.
bool time_rounds(const Options& o, const Grid& g, const Model& model, long long peer_steps,
                 PeerRounds& r) {
  for (int round = 0; round < o.repetitions; ++round) {
    for (int turn = 0; turn < 2; ++turn) {
      const bool ours = (turn == 0) == (round % 2 == 0);
      if (!(ours ? time_ours(g, r) : time_bullet(g, model, peer_steps, r))) return false;
    }
    r.ratio.push_back((g.steps * g.params.integrator.dt / r.ours_wall.back()) /
                      (peer_steps * kPeerDt / r.peer_wall.back()));
  }
  return true;
}

void print_peer_header(const Options& o, const Params& p0, unsigned threads, unsigned cores,
                       const std::string& cpu, const std::string& version) {
  std::printf(
      "wetcloth %s bench --peer bullet: ours and Bullet %s's btSoftBody on the same cloth, "
      "in turn in this process, %d rounds of %g s simulated\n"
      "ours:   scene %s, integrator %s, %u thread%s, dt %g s (first grid)\n"
      "Bullet: the scene's cloth, plain (dry mass, gravity, table, ball, handles; no air, "
      "adhesion, self-collision, wind or damping), dt 1/600 s, Bullet's defaults otherwise, "
      "one thread\nmachine: %u cores, %s\n\n",
      WETCLOTH_VERSION, version.c_str(), o.repetitions, o.duration, p0.name.c_str(),
      to_string(p0.integrator.type).c_str(), threads, threads == 1 ? "" : "s", p0.integrator.dt,
      cores, cpu.c_str());
  std::printf(
      "       ------------------- ours -------------------   ------------- Bullet --------------\n"
      " grid  particles  springs  dt µs   µs/step  real-time ×    "
      "links  dt µs  µs/step  real-time ×  ours/Bullet\n");
  std::fflush(stdout);
}

// A grid's row of the table, its lines for the end (where each cloth ended)
// and its entry in bench.json.
json report_peer_grid(const Options& o, const Grid& g, const Model& model, long long peer_steps,
                      const PeerRounds& r, std::vector<std::string>& lines) {
  const double dt = g.params.integrator.dt;
  const auto real_time = [](const std::vector<double>& walls, double simulated) {
    std::vector<double> rt;
    for (double w : walls) rt.push_back(simulated / w);
    return median(rt);
  };
  const double ours_rt = real_time(r.ours_wall, g.steps * dt);
  const double peer_rt = real_time(r.peer_wall, peer_steps * kPeerDt);
  const double ours_us = 1e6 * median(r.ours_wall) / g.steps;
  const double peer_us = 1e6 * median(r.peer_wall) / peer_steps;
  const double ratio_median = median(r.ratio);
  const long long springs = spring_count(model, SpringKind::Structural) +
                            spring_count(model, SpringKind::Shear) +
                            spring_count(model, SpringKind::Bending);
  double area = 0;
  for (double a : model.area) area += a;
  std::printf("%5lld  %9d  %7lld  %5.2f  %8.1f  %11.4f  %7d  %5.0f  %7.1f  %11.4f  %11.3f\n",
              g.size, model.n, springs, 1e6 * dt, ours_us, ours_rt, r.links, 1e6 * kPeerDt, peer_us,
              peer_rt, ratio_median);
  std::fflush(stdout);
  char line[512];
  std::snprintf(line, sizeof line,
                "grid %lld: ours/Bullet real-time factor %.3f (ours %.4f x real time, Bullet "
                "%.4f x; median of %d rounds)\n"
                "  at the end (ours at %.4g s, Bullet at %.4g s): mean height ours %.4f m, "
                "Bullet %.4f m; highest ours %.4f m, Bullet %.4f m\n",
                g.size, ratio_median, ours_rt, peer_rt, o.repetitions, r.ours_time, r.peer_time,
                r.ours_end.first, r.peer_end.first, r.ours_end.second, r.peer_end.second);
  lines.push_back(line);
  return {{"grid", g.size},
          {"ours",
           {{"particles", model.n},
            {"springs", springs},
            {"dry_mass_kg", g.params.cloth.areal_density * area},
            {"dt_s", dt},
            {"steps", g.steps},
            {"wall_s", r.ours_wall},
            {"median", {{"us_per_step", ours_us}, {"realtime_factor", ours_rt}}},
            {"end", {{"mean_z_m", r.ours_end.first}, {"max_z_m", r.ours_end.second}}}}},
          {"bullet",
           {{"nodes", model.n},
            {"links", r.links},
            {"faces", r.faces},
            {"mass_kg", r.peer_mass},
            {"dt_s", kPeerDt},
            {"steps", peer_steps},
            {"wall_s", r.peer_wall},
            {"median", {{"us_per_step", peer_us}, {"realtime_factor", peer_rt}}},
            {"end", {{"mean_z_m", r.peer_end.first}, {"max_z_m", r.peer_end.second}}}}},
          {"ratio_per_round", r.ratio},
          {"ratio_median", ratio_median}};
}

// `bench --peer bullet`: per grid, rounds of ours (the scene, as run_bench
// times it) and Bullet's btSoftBody on the same cloth made plain
// (bullet_peer.hpp), each from t = 0 in a fresh world, one untimed step, then
// the same simulated time; the two take turns going first. The ratio is the
// median of each round's ratio of real-time factors.
int run_peer(const Options& o, const std::vector<Grid>& grids, unsigned threads,
             const fs::path& out) {
  const long long peer_steps = std::llround(o.duration / kPeerDt);
  if (peer_steps < 1)
    throw SceneError("--duration " + format_number(o.duration) +
                     " s is shorter than one of Bullet's steps (1/600 s)");
  const Params& p0 = grids.front().params;
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::string cpu = cpu_model(), version = bullet_version();
  print_peer_header(o, p0, threads, cores, cpu, version);
  json doc = doc_head(o, p0, threads, cores, cpu);
  doc["peer"] = {{"name", "bullet"}, {"version", version}, {"dt_s", kPeerDt}};
  doc["grids"] = json::array();
  std::vector<std::string> lines;
  for (const Grid& g : grids) {
    const Model model = build_model(g.params);
    PeerRounds r;
    if (!time_rounds(o, g, model, peer_steps, r)) return kBlowUp;
    doc["grids"].push_back(report_peer_grid(o, g, model, peer_steps, r, lines));
  }
  std::printf("\n");
  for (const std::string& line : lines) std::fputs(line.c_str(), stdout);
  if (out.has_parent_path()) fs::create_directories(out.parent_path());
  write_file_atomic(out, doc.dump(2) + "\n");
  std::printf("ratio: our real-time factor over Bullet's; results in %s\n", out.c_str());
  return kOk;
}
#else
int run_peer(const Options&, const std::vector<Grid>&, unsigned, const fs::path&) {
  return kError;  // not reached: run_bench said so first
}
#endif

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
  cmd->add_option("--out", o->out,
                  "the results as JSON (default out/bench.json; with --peer, out/bench_PEER.json)")
      ->check(a_path());
  cmd->add_option("--peer", o->peer,
                  "time the same cloth in another simulator beside ours, in turn in this process, "
                  "and print the ratio of real-time factors: bullet (Bullet's btSoftBody; "
                  "only in a build that found libbullet-dev)")
      ->check(CLI::IsMember({"bullet"}));
  cmd->footer(
      "Each grid runs in a process of its own (its peak memory is its own); each repetition "
      "builds\n"
      "the simulation afresh, takes one untimed step, then times round(duration / dt) steps.\n"
      "Writes FILE (every repetition's wall time, the medians, the machine).\n"
      "--peer bullet: per grid, rounds of ours and of Bullet's btSoftBody on the same cloth,\n"
      "plain (no air, adhesion, self-collision), at dt 1/600 s and Bullet's defaults, taking\n"
      "turns; ours on one thread unless --threads; no memory column.\n"
      "Exit codes: 0 ok, 1 --peer bullet in a build without Bullet, 2 bad input (nothing\n"
      "written), 3 the simulation blew up (nothing written).");
  return [cmd, o]() -> int { return *cmd ? run_bench(*o) : -1; };
}

}  // namespace wetcloth::cli
