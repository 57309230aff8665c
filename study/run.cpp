// A run and many runs: the one frame loop (include/wetcloth/run.hpp).
#include "wetcloth/run.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "wetcloth/caches.hpp"
#include "wetcloth/checkpoint.hpp"
#include "wetcloth/output.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace fs = std::filesystem;

namespace {

nlohmann::json metrics_json(const Metrics& m) {
  nlohmann::json j;
  const auto cols = metrics_columns();
  const auto vals = metrics_values(m);
  for (std::size_t i = 0; i < cols.size(); ++i) j[cols[i]] = vals[i];
  return j;
}

// The output folder's lock: held (flock) while a run writes into it, released
// by the system however the process ends, and the empty file removed when the
// run ends. A run that locked a file another removed meanwhile takes the lock
// again on the file now there.
class OutputLock {
 public:
  explicit OutputLock(const fs::path& out) : path_(out / ".wetcloth.lock") {
    for (int attempt = 0;; ++attempt) {
      fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
      if (fd_ < 0) throw_output_error(path_, "cannot create the lock file", errno);
      if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
        const int e = errno;
        ::close(fd_);
        if (e == EWOULDBLOCK)
          throw SceneError("--out " + out.string() + ": another wetcloth run is writing into it (" +
                           path_.string() + " is locked); wait for it, or choose another --out");
        throw_output_error(path_, "cannot lock", e);
      }
      struct stat held {
      }, named{};
      if (::fstat(fd_, &held) == 0 && ::stat(path_.c_str(), &named) == 0 &&
          held.st_ino == named.st_ino && held.st_dev == named.st_dev)
        return;
      ::close(fd_);
      if (attempt == 100) throw_output_error(path_, "cannot lock", EAGAIN);
    }
  }
  ~OutputLock() {
    ::unlink(path_.c_str());  // before the lock goes: no other run holds this file
    ::close(fd_);
  }
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  fs::path path_;
  int fd_ = -1;
};

// Removes the frames (frames/frame_NNNNN.obj, vtk/cloth_NNNNN.vtp) from
// `first` on: a resumed run writes them again.
void remove_frames_from(const fs::path& out, long long first) {
  std::error_code ec;
  for (const auto& [folder, prefix] : {std::pair{"frames", "frame_"},
                                       {"vtk", "cloth_"},
                                       {"frames", "obstacles_"},
                                       {"vtk", "obstacles_"}}) {
    const fs::path dir = out / folder;
    if (!fs::is_directory(dir, ec)) continue;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      const std::string p = prefix;
      if (name.rfind(p, 0) != 0 || name.size() < p.size() + 5) continue;
      char* endp = nullptr;
      const long long index = std::strtoll(name.c_str() + p.size(), &endp, 10);
      if (endp == name.c_str() + p.size() || index < first) continue;
      if (std::string(endp) != (std::string(folder) == "frames" ? ".obj" : ".vtp")) continue;
      if (std::error_code rec; fs::remove(it->path(), rec), rec)
        throw_output_error(it->path(), "cannot remove", rec.value());
    }
    if (ec) throw_output_error(dir, "cannot list", ec.value());
  }
}

std::string read_file(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw SceneError(path.string() + ": cannot read");
  std::ostringstream buf;
  buf << f.rdbuf();
  return buf.str();
}

// The first metric that is not a number, or empty: such a row is not written.
std::string non_finite_metric(const Metrics& m) {
  const auto cols = metrics_columns();
  const auto vals = metrics_values(m);
  for (std::size_t i = 0; i < vals.size(); ++i)
    if (!std::isfinite(vals[i])) return cols[i] + " = " + format_number(vals[i]);
  return {};
}

const char* signal_name(int sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal";
}

// A run's scene.toml runs from its folder: the files the scene names go to
// OUT/meshes/ (meshes), OUT/maps/ (cloth.humidity_map) and OUT/lists/
// (handles' vertex lists), a built-in scene's from the copies in the program,
// and its keys name them there. P with those paths; with `files`, each file's
// path in OUT and its bytes. One file named twice is copied once; two files
// of one name in one folder become NAME and 2-NAME.
Params with_output_files(const Params& p,
                         std::vector<std::pair<std::string, std::string>>* files = nullptr) {
  Params q = p;
  std::vector<std::pair<std::string, std::string>> placed;  // the scene's path, the new one
  const auto place = [&](const std::string& folder, const std::string& key, std::string& path) {
    if (path.empty()) return;
    const std::string from = fs::path(path).lexically_normal().generic_string();
    for (const auto& [source, to] : placed)
      if (source == from) {
        path = to;
        return;
      }
    const std::string name = fs::path(from).filename().string();
    std::string to = folder + "/" + name;
    for (int k = 2;
         std::any_of(placed.begin(), placed.end(), [&](const auto& e) { return e.second == to; });
         ++k)
      to = folder + "/" + std::to_string(k) + "-" + name;
    placed.emplace_back(from, to);
    if (files) files->emplace_back(to, scene_file_text(p, key, path));
    path = to;
  };
  place("meshes", "cloth.mesh", q.cloth.mesh);
  for (auto& [name, o] : q.obstacles) place("meshes", "obstacle." + name + ".mesh", o.mesh);
  place("maps", "cloth.humidity_map", q.cloth.humidity_map);
  for (auto& [name, h] : q.handles) place("lists", "handle." + name + ".vertices", h.vertices.file);
  // Obstacles' caches to OUT/caches/: a PC2 file, or each file of an OBJ
  // sequence (its # pattern then names them there).
  for (auto& [name, o] : q.obstacles) {
    const std::string key = "obstacle." + name + ".cache";
    if (o.cache.empty()) continue;
    if (o.cache.find('#') == std::string::npos) {
      place("caches", key, o.cache);
      continue;
    }
    for (const std::string& frame : obstacle_cache_files(p, name))
      if (files)
        files->emplace_back("caches/" + fs::path(frame).filename().string(),
                            scene_file_text(p, key, frame));
    o.cache = "caches/" + fs::path(o.cache).filename().string();
  }
  return q;
}

// The folders and files with_output_files(p) copies into a run's folder,
// each folder (ending in '/') before its files: for the manifest.
std::vector<std::string> output_copies(const Params& p) {
  const Params q = with_output_files(p);
  std::vector<std::string> paths;
  const auto add = [&](const std::string& path) {
    if (!path.empty() && std::find(paths.begin(), paths.end(), path) == paths.end())
      paths.push_back(path);
  };
  add(q.cloth.mesh);
  for (const auto& [name, o] : q.obstacles) add(o.mesh);
  add(q.cloth.humidity_map);
  for (const auto& [name, h] : q.handles) add(h.vertices.file);
  for (const auto& [name, o] : p.obstacles) {
    if (o.cache.empty()) continue;
    for (const std::string& frame : obstacle_cache_files(p, name))
      add("caches/" + fs::path(frame).filename().string());
  }
  std::vector<std::string> out;
  for (const char* folder : {"meshes/", "maps/", "lists/", "caches/"}) {
    bool first = true;
    for (const std::string& path : paths)
      if (path.rfind(folder, 0) == 0) {
        if (first) out.push_back(folder);
        first = false;
        out.push_back(path);
      }
  }
  return out;
}

std::string frame_file(const char* folder, const char* prefix, long long f, const char* extension) {
  char name[64];
  std::snprintf(name, sizeof name, "%s/%s%05lld%s", folder, prefix, f, extension);
  return name;
}

// Every file (and, ending in '/', folder) a run of P may write in its folder,
// relative to it: its manifest. Its frames are known from the start.
std::vector<std::string> run_outputs(const Params& p) {
  std::vector<std::string> files = {"metrics.csv", "summary.json", "scene.toml", "obstacles.obj",
                                    "checkpoint.state"};
  const std::vector<std::string> copies = output_copies(p);
  files.insert(files.end(), copies.begin(), copies.end());
  const long long last = last_frame_index(p.run.duration, p.run.fps);
  // Moving obstacles: their pose each frame, in each output that has frames.
  const std::vector<std::string> moving = moving_obstacle_files(p);
  if (p.run.meshes) {
    files.push_back("frames/");
    for (long long f = 0; f <= last; ++f) {
      files.push_back(frame_file("frames", "frame_", f, ".obj"));
      if (!moving.empty()) files.push_back(frame_file("frames", "obstacles_", f, ".obj"));
    }
  }
  const ExportFormats formats = parse_export_formats(p.run.exports);
  if (formats.pc2) {
    files.insert(files.end(), {"cloth.pc2", "cloth_fields.pc2", "cloth_rest.obj"});
    for (const std::string& name : moving)
      files.insert(files.end(), {"obstacle_" + name + ".pc2", "obstacle_" + name + "_rest.obj"});
  }
  if (formats.vtk) {
    files.insert(files.end(), {"cloth.pvd", "vtk/", "vtk/obstacles.vtp"});
    if (!moving.empty()) files.push_back("obstacles.pvd");
    for (long long f = 0; f <= last; ++f) {
      files.push_back(frame_file("vtk", "cloth_", f, ".vtp"));
      if (!moving.empty()) files.push_back(frame_file("vtk", "obstacles_", f, ".vtp"));
    }
  }
  if (formats.usd) {
    files.insert(files.end(), {"cloth.usda", ".cloth.usda.samples/"});
    for (const char* a : {"points", "normals", "extent", "contact", "pressure", "adhesion",
                          "humidity", "velocities", "deficit"})
      files.push_back(std::string(".cloth.usda.samples/") + a);
    for (const std::string& name : obstacle_usd_samples(p))
      files.push_back(".cloth.usda.samples/" + name);
  }
  return files;
}

// Throws SceneError naming the first output that the checkpoint of a resumed
// run says was written and that is not there (as a file: no link).
void check_resume_outputs(const Params& p, const fs::path& out, long long frames,
                          const fs::path& checkpoint) {
  std::vector<std::string> files = {"scene.toml", "obstacles.obj"};
  for (const std::string& copy : output_copies(p))
    if (copy.back() != '/') files.push_back(copy);
  const ExportFormats formats = parse_export_formats(p.run.exports);
  const std::vector<std::string> moving = moving_obstacle_files(p);
  if (formats.pc2) files.push_back("cloth_rest.obj");
  if (formats.pc2)
    for (const std::string& name : moving) files.push_back("obstacle_" + name + "_rest.obj");
  if (formats.vtk) files.push_back("vtk/obstacles.vtp");
  for (long long f = 0; f < frames; ++f) {
    if (p.run.meshes) files.push_back(frame_file("frames", "frame_", f, ".obj"));
    if (formats.vtk) files.push_back(frame_file("vtk", "cloth_", f, ".vtp"));
    if (moving.empty()) continue;
    if (p.run.meshes) files.push_back(frame_file("frames", "obstacles_", f, ".obj"));
    if (formats.vtk) files.push_back(frame_file("vtk", "obstacles_", f, ".vtp"));
  }
  for (const std::string& rel : files) {
    struct stat st {};
    if (::lstat((out / rel).c_str(), &st) != 0 || !S_ISREG(st.st_mode))
      throw SceneError((out / rel).string() + ": " +
                       (::lstat((out / rel).c_str(), &st) != 0 ? "missing" : "not a file") +
                       ", where " + checkpoint.string() + " continues a run that wrote it (" +
                       std::to_string(frames) +
                       " frames): the outputs are not whole; run the scene again (wetcloth run " +
                       (out / "scene.toml").string() + " --out " + out.string() + ")");
  }
}

}  // namespace

ResourceEstimate estimate_resources(const Params& p) {
  ResourceEstimate e;
  // A mesh cloth's particles are its vertices (cloth.resolution is not used).
  const bool grid = p.cloth.mesh.empty();
  const ClothMeshSize mesh = grid ? ClothMeshSize{} : cloth_mesh_size(p);
  const double n = grid ? static_cast<double>(p.cloth.resolution[0]) * p.cloth.resolution[1]
                        : static_cast<double>(mesh.vertices);
  const double triangles = grid ? 2 * n : static_cast<double>(mesh.triangles);
  // Measured: peak RSS 8 MB + 1.5 kB a particle (hang, one thread, at 201 x
  // 201 and 401 x 401: 67 and 245 MB), 1.5 to 1.7 kB over whole runs at 401 x
  // 401 and 1001 x 1001, self-collision's pair lists included (they hold the
  // pairs near now, not every pair within reach).
  e.memory_bytes = kBaseBytes + n * kBytesPerParticle;
  const double frames = static_cast<double>(last_frame_index(p.run.duration, p.run.fps)) + 1;
  // An OBJ frame: a position and a normal a particle (70 bytes), a triangle 35.
  e.disk_bytes = frames * (300 + (p.run.meshes ? 70 * n + 35 * triangles : 0)) + 1e5;
  return e;
}

namespace {

std::string gigabytes(double bytes) {
  char b[32];
  std::snprintf(b, sizeof b, bytes < 1e9 ? "%.0f MB" : "%.1f GB",
                bytes < 1e9 ? bytes / 1e6 : bytes / 1e9);
  return b;
}

// MemAvailable, or the cgroup's limit, or what the address space limit
// (ulimit -v) leaves, where lower; < 0: unknown.
double available_memory() {
  double avail = -1;
  std::FILE* f = std::fopen("/proc/meminfo", "r");
  if (f) {
    char line[256];
    while (std::fgets(line, sizeof line, f))
      if (unsigned long long kb; std::sscanf(line, "MemAvailable: %llu kB", &kb) == 1)
        avail = static_cast<double>(kb) * 1024;
    std::fclose(f);
  }
  if (std::FILE* g = std::fopen("/sys/fs/cgroup/memory.max", "r")) {
    if (unsigned long long limit; std::fscanf(g, "%llu", &limit) == 1) {
      double used = 0;
      if (std::FILE* c = std::fopen("/sys/fs/cgroup/memory.current", "r")) {
        if (unsigned long long u; std::fscanf(c, "%llu", &u) == 1) used = static_cast<double>(u);
        std::fclose(c);
      }
      const double left = static_cast<double>(limit) - used;
      if (avail < 0 || left < avail) avail = left;
    }
    std::fclose(g);
  }
  if (rlimit r{}; ::getrlimit(RLIMIT_AS, &r) == 0 && r.rlim_cur != RLIM_INFINITY) {
    double used = 0;  // the address space this process already takes
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (unsigned long long pages; std::fscanf(f, "%llu", &pages) == 1)
        used = static_cast<double>(pages) * static_cast<double>(::sysconf(_SC_PAGESIZE));
      std::fclose(f);
    }
    const double left = static_cast<double>(r.rlim_cur) - used;
    if (avail < 0 || left < avail) avail = left;
  }
  return avail;
}

}  // namespace

void check_resources(const Params& p, const fs::path& out, const std::string& source) {
  const ResourceEstimate e = estimate_resources(p);
  const double mem = available_memory();
  const std::string force = "; --force runs it all the same";
  if (mem >= 0 && e.memory_bytes > mem)
    throw SceneError(
        source + ": " +
        (p.cloth.mesh.empty() ? "cloth.resolution = [" + std::to_string(p.cloth.resolution[0]) +
                                    ", " + std::to_string(p.cloth.resolution[1]) + "]"
                              : "cloth.mesh = \"" + p.cloth.mesh + "\" (" +
                                    std::to_string(cloth_mesh_size(p).vertices) + " vertices)") +
        " needs about " + gigabytes(e.memory_bytes) +
        " of memory (an estimate: " + format_number(kBytesPerParticle / 1000) +
        " kB a particle, as measured), more than the " + gigabytes(mem) + " available" + force);
  fs::path at = fs::absolute(out);
  std::error_code ec;
  while (!fs::exists(at, ec) && at.has_parent_path() && at != at.parent_path())
    at = at.parent_path();
  struct statvfs st {};
  if (::statvfs(at.c_str(), &st) == 0 && st.f_blocks > 0) {  // /proc has none: not a disk
    const double free = static_cast<double>(st.f_bavail) * static_cast<double>(st.f_frsize);
    if (e.disk_bytes > free)
      throw SceneError(source + ": the outputs (" +
                       std::to_string(last_frame_index(p.run.duration, p.run.fps) + 1) +
                       " frames of run.duration = " + format_number(p.run.duration) +
                       " s at run.fps = " + format_number(p.run.fps) +
                       (p.run.meshes ? ", with run.meshes" : "") + ") need about " +
                       gigabytes(e.disk_bytes) + ", more than the " + gigabytes(free) +
                       " free in " + at.string() + force);
  }
}

bool run_ended_whole(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir / "checkpoint.state", ec)) return false;
  std::ifstream f(dir / "summary.json");
  if (!f) return false;
  const auto j = nlohmann::json::parse(f, nullptr, false);
  return !j.is_discarded() && j.is_object() && j.value("status", "") == "ok";
}

ResumePoint load_resume_point(const fs::path& dir) {
  ResumePoint rp;
  rp.file = dir / "checkpoint.state";
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw SceneError("--resume " + dir.string() + ": not a folder of a run");
  if (!fs::exists(rp.file, ec))
    throw SceneError(rp.file.string() +
                     ": no checkpoint to resume from (a run writes one every "
                     "--checkpoint-every S of simulated time, and when SIGINT or SIGTERM stops "
                     "it; a run that ended whole removes it)");
  Checkpoint c = load_checkpoint(rp.file);
  if (c.run.empty())
    throw SceneError(rp.file.string() +
                     ": a state without its run's record (saved by the viewer, Python's "
                     "Simulation.save or an older wetcloth): `run --resume` continues only a "
                     "checkpoint that `wetcloth run` wrote");
  // The folder's scene.toml is the scene its outputs came from.
  const fs::path scene = dir / "scene.toml";
  if (!fs::exists(scene, ec))
    throw SceneError(scene.string() + ": missing, so the outputs of " + dir.string() +
                     " cannot be matched with " + rp.file.string());
  // What --resume may set (the step's threads, the checkpoints' interval)
  // changes no result: not compared.
  const Params folder = load_scene(scene.string());
  Params compared = c.params;
  compared.integrator.threads = folder.integrator.threads;
  compared.run.checkpoint_every = folder.run.checkpoint_every;
  // scene.toml names the files it copied (or, from an older run, the scene's).
  const std::string mine = to_toml(with_output_files(compared)), theirs = to_toml(folder);
  if (mine != theirs && to_toml(compared) != theirs) {
    std::istringstream a(mine), b(theirs);
    std::string la, lb;
    while (std::getline(a, la) && std::getline(b, lb) && la == lb) {
    }
    throw SceneError(rp.file.string() + ": a checkpoint of another scene than " + scene.string() +
                     " (the checkpoint's `" + la + "`, scene.toml's `" + lb + "`)");
  }
  rp.params = std::move(c.params);
  // A folder whose scene.toml names its own copies runs from them: it resumes
  // wherever the scene's files have gone (the same bytes, so the same bits).
  if (mine == theirs) {
    rp.params = with_output_files(rp.params);
    rp.params.scene_dir = folder.scene_dir;
  }
  rp.state = std::move(c.state);
  rp.record = std::move(c.run);
  return rp;
}

namespace {

// Where the outputs stand after the last frame that a resumed run keeps.
struct OutputsAt {
  long long next_frame = 0;     // the frame a resumed run writes first
  long long metrics_bytes = 0;  // metrics.csv's header and rows up to it
  CachePosition cache;
  bool any_row = false;
  nlohmann::json first, final;  // metrics of the first and last rows kept
  double time_to_5cm_s = -1, frame_peak_deficit_pa = 0;
};

nlohmann::json record_json(const OutputsAt& at, long long substeps, double wall) {
  return {{"next_frame", at.next_frame},
          {"metrics_bytes", at.metrics_bytes},
          {"cache",
           {{"frames", at.cache.frames},
            {"last_code", at.cache.last_code},
            {"samples_bytes", at.cache.samples_bytes}}},
          {"any_row", at.any_row},
          {"first", at.first},
          {"final", at.final},
          {"time_to_5cm_s", at.time_to_5cm_s},
          {"frame_peak_deficit_pa", at.frame_peak_deficit_pa},
          {"substeps", substeps},
          {"wall_seconds", wall}};
}

OutputsAt record_outputs(const ResumePoint& rp, long long& substeps, double& wall) {
  try {
    const auto j = nlohmann::json::parse(rp.record);
    OutputsAt at;
    at.next_frame = j.at("next_frame").get<long long>();
    at.metrics_bytes = j.at("metrics_bytes").get<long long>();
    at.cache.frames = j.at("cache").at("frames").get<long long>();
    at.cache.last_code = j.at("cache").at("last_code").get<double>();
    at.cache.samples_bytes = j.at("cache").at("samples_bytes").get<std::vector<long long>>();
    at.any_row = j.at("any_row").get<bool>();
    at.first = j.at("first");
    at.final = j.at("final");
    at.time_to_5cm_s = j.at("time_to_5cm_s").get<double>();
    at.frame_peak_deficit_pa = j.at("frame_peak_deficit_pa").get<double>();
    substeps = j.at("substeps").get<long long>();
    wall = j.at("wall_seconds").get<double>();
    if (at.next_frame < 0 || at.metrics_bytes < 0 ||
        (!at.cache.samples_bytes.empty() && at.cache.frames != at.next_frame))
      throw std::invalid_argument("its frames do not agree");
    return at;
  } catch (const std::exception& e) {
    throw SceneError(rp.file.string() + ": its run record is damaged (" + e.what() + ")");
  }
}

// The times of the rows of metrics.csv a resumed run keeps (its first
// `bytes`: the header and `rows` whole rows); SceneError where the file does
// not hold them.
std::vector<double> kept_row_times(const fs::path& path, long long bytes, long long rows,
                                   const fs::path& checkpoint) {
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw SceneError(path.string() + ": missing; " + checkpoint.string() + " continues it");
  const std::string text = read_file(path);
  const std::string why = path.string() + ": not the metrics.csv " + checkpoint.string() +
                          " continues (" + std::to_string(rows) + " rows, " +
                          std::to_string(bytes) + " bytes): ";
  if (static_cast<long long>(text.size()) < bytes)
    throw SceneError(why + "only " + std::to_string(text.size()) + " bytes");
  const std::string kept = text.substr(0, static_cast<std::size_t>(bytes));
  const std::string header = metrics_csv_header();
  if (kept.rfind(header, 0) != 0) throw SceneError(why + "another header");
  std::vector<double> times;
  for (std::size_t at = header.size(); at < kept.size();) {
    const std::size_t end = kept.find('\n', at);
    if (end == std::string::npos) throw SceneError(why + "a row cut short");
    times.push_back(std::strtod(kept.c_str() + at, nullptr));
    at = end + 1;
  }
  if (static_cast<long long>(times.size()) != rows)
    throw SceneError(why + std::to_string(times.size()) + " rows");
  return times;
}

// What a run writes to, and where its outputs stand after the last whole frame.
struct RunOutputs {
  std::optional<CacheWriter> caches;
  std::optional<MetricsFile> metrics;
  OutputsAt at;
  long long substeps_before = 0;  // a resumed run's, before the checkpoint
  double wall_before = 0;
};

// A new run's outputs started, or a resumed one's taken back to where its
// checkpoint left them.
void open_outputs(const Params& p, const fs::path& out, const Simulation& sim,
                  const ResumePoint* resume, RunOutputs& o, RunResult& r) {
  const UpAxis up = p.run.up;
  const ExportFormats formats = parse_export_formats(p.run.exports);
  auto& caches = o.caches;
  auto& metrics = o.metrics;
  auto& at = o.at;
  // Nothing is written through a link; what the run before wrote goes, and
  // only that; the manifest lists this run's files before they are written.
  const std::vector<std::string> files = run_outputs(p);
  refuse_links(out, files);
  if (!resume) {
    // The copies read first: a run of DIR/scene.toml into DIR reads its own.
    std::vector<std::pair<std::string, std::string>> copies;
    const Params written = with_output_files(p, &copies);
    remove_outputs(out, earlier_outputs(out));
    write_manifest(out, files);
    if (p.run.meshes)
      if (std::error_code ec; fs::create_directories(out / "frames", ec), ec)
        throw_output_error(out / "frames", "cannot make the folder", ec.value());
    for (const auto& [path, bytes] : copies) {
      const fs::path folder = (out / path).parent_path();
      if (std::error_code ec; fs::create_directories(folder, ec), ec)
        throw_output_error(folder, "cannot make the folder", ec.value());
      write_file_atomic(out / path, bytes);
    }
    write_file_atomic(out / "scene.toml", "# resolved by wetcloth " WETCLOTH_VERSION
                                          "; `wetcloth run` this file to reproduce the run\n" +
                                              to_toml(written));
    write_file_atomic(out / "obstacles.obj", obstacles_obj(sim.model(), up, sim.state().time));
    if (formats.any()) caches.emplace(out, sim, formats, up, p.run.fps);
    metrics.emplace(out / "metrics.csv");
    at.metrics_bytes = metrics->size();
    if (caches) at.cache = caches->position(false);
  } else {
    at = record_outputs(*resume, o.substeps_before, o.wall_before);
    check_resume_outputs(p, out, at.next_frame, resume->file);
    const std::vector<double> times =
        kept_row_times(out / "metrics.csv", at.metrics_bytes, at.next_frame, resume->file);
    if (formats.any()) {
      at.cache.frames = at.next_frame;  // a cache has a frame a row
      caches.emplace(out, sim, formats, up, p.run.fps, at.cache, times);
    }
    metrics.emplace(out / "metrics.csv", at.metrics_bytes);
    // The folder as it stood at the checkpoint: nothing after it, no summary yet.
    if (std::error_code ec; fs::remove(out / "summary.json", ec), ec)
      throw_output_error(out / "summary.json", "cannot remove", ec.value());
    remove_frames_from(out, at.next_frame);
    write_manifest(out, files);  // a run of a wetcloth that wrote none has one now
    if (p.run.meshes)
      if (std::error_code ec; fs::create_directories(out / "frames", ec), ec)
        throw_output_error(out / "frames", "cannot make the folder", ec.value());
    r.time_to_5cm_s = at.time_to_5cm_s;
    r.frame_peak_deficit_pa = at.frame_peak_deficit_pa;
  }
}

// Frame f's row, mesh and cache frame; the run's first and last rows, its
// peak deficit and time to 5 cm follow them.
void write_frame(const Params& p, const fs::path& out, const Simulation& sim, const Metrics& m,
                 long long f, RunOutputs& o, RunResult& r, nlohmann::json& first_json,
                 nlohmann::json& final_json) {
  if (o.metrics) o.metrics->append(m);
  if (first_json.is_null()) {
    first_json = metrics_json(m);
    r.first = m;
  }
  r.final = m;
  final_json = metrics_json(m);
  r.frame_peak_deficit_pa = std::max(r.frame_peak_deficit_pa, p.air.p_atm - m.inner_pressure_pa);
  if (p.run.meshes && !out.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05lld.obj", f);
    write_file_atomic(out / "frames" / name, cloth_obj(sim.model(), sim.state(), p.run.up));
    if (obstacles_move(p)) {  // beside it, the obstacles where they are then
      std::snprintf(name, sizeof name, "obstacles_%05lld.obj", f);
      write_file_atomic(out / "frames" / name,
                        obstacles_obj(sim.model(), p.run.up, sim.state().time));
    }
  }
  // A frame on the frame rate has its number as its USD time code; the last
  // one, where the duration falls between two, its time × fps.
  const bool between =
      frame_time(f, p.run.duration, p.run.fps) < static_cast<double>(f) / p.run.fps;
  if (o.caches) o.caches->add_frame(sim, between ? -1 : static_cast<double>(f));
  // Time to 5 cm is a pulled handle's: a pin (measured when there are only
  // pins) sits at its height from the start.
  const bool pulled = sim.model().measures_a_pull();
  if (pulled && r.time_to_5cm_s < 0 && m.handle_height_m >= 0.05) r.time_to_5cm_s = m.time_s;
}

// Where the outputs stand after whole frame f, for a checkpoint.
void mark_whole_frame(long long f, RunOutputs& o, const RunResult& r,
                      const nlohmann::json& first_json, const nlohmann::json& final_json) {
  OutputsAt& at = o.at;
  at.next_frame = f + 1;
  if (o.metrics) at.metrics_bytes = o.metrics->size();
  if (o.caches) at.cache = o.caches->position(false);
  at.any_row = true;
  at.first = first_json;
  at.final = final_json;
  at.time_to_5cm_s = r.time_to_5cm_s;
  at.frame_peak_deficit_pa = r.frame_peak_deficit_pa;
}

// summary.json: how the run ended, its size and speed, the last row; its text.
std::string write_summary(const fs::path& out, const Params& p, const Simulation& sim,
                          const RunResult& r, const nlohmann::json& final_json,
                          long long substeps_before, const ResumePoint* resume) {
  const bool interrupted = r.code > 128;
  nlohmann::json s;
  s["scene"] = p.name;
  s["version"] = WETCLOTH_VERSION;
  s["status"] = r.code == kOk ? "ok" : interrupted ? "interrupted" : "blew up";
  s["interrupted"] = interrupted;
  if (interrupted) s["signal"] = signal_name(r.code - 128);
  if (r.code != kOk) s["message"] = r.message;
  s["steps"] = r.steps;
  // More than steps where implicit Euler halved some.
  s["substeps"] = substeps_before + sim.stats().substeps;
  s["particles"] = sim.model().n;
  // The count asked for (0: chosen as it ran), always a number; beside it how
  // the choice went, or the count used (at most one thread per 1024 particles).
  s["threads"] = p.integrator.threads;
  if (const StepStats c = sim.stats(); c.threads_chosen)
    s["thread_choice"] = {{"most", c.most_threads},
                          {"steps_on_1", c.steps_on_one},
                          {"steps_on_most", c.steps_on_most}};
  else
    s["threads_used"] = sim.model().threads;
  s["simulated_seconds"] = sim.state().time;
  s["wall_seconds"] = r.wall_seconds;
  s["realtime_factor"] = r.wall_seconds > 0 ? sim.state().time / r.wall_seconds : 0.0;
  s["peak_pressure_deficit_pa"] = r.peak_deficit_pa;
  s["final"] = final_json;  // the last row's (JSON has no inf: a row never has one)
  if (resume) s["resumed_at_s"] = resume->state.time;
  std::string text = s.dump(2) + "\n";
  write_file_atomic(out / "summary.json", text);
  return text;
}

// The run's end: the outputs closed, the result's totals, summary.json, and
// on success the checkpoint removed. wrote_a_row: this run wrote a row;
// start: when it started.
void finish_run(const Params& p, const fs::path& out, const Simulation& sim,
                const ResumePoint* resume, bool wrote_a_row,
                std::chrono::steady_clock::time_point start, RunOutputs& o, RunResult& r,
                nlohmann::json& first_json, nlohmann::json& final_json) {
  if (o.metrics) o.metrics->close();
  if (o.caches) o.caches->finish();
  if (first_json.is_null()) {
    r.first = r.final = sim.metrics();
    first_json = final_json = metrics_json(r.first);
  } else if (!wrote_a_row) {
    r.final = sim.metrics();  // a resumed run that had no frame left: the state's
  }
  r.peak_deficit_pa = sim.state().peak_deficit;
  r.steps = sim.state().steps;
  r.wall_seconds = o.wall_before +
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.simulated_seconds = sim.state().time;
  const bool interrupted = r.code > 128;
  if (interrupted)
    r.message = std::string("interrupted by ") + signal_name(r.code - 128) +
                " at t = " + format_number(sim.state().time) + " s";
  if (out.empty()) return;  // no folder: nothing to write or remove
  r.summary = write_summary(out, p, sim, r, final_json, o.substeps_before, resume);
  // Whole: nothing to resume. The checkpoint goes once cloth.usda and
  // summary.json are written, the USD samples after it: a run killed at any
  // moment either resumes from its checkpoint or has ended whole.
  if (r.code == kOk) {
    if (std::error_code ec; fs::remove(out / "checkpoint.state", ec), ec)
      throw_output_error(out / "checkpoint.state", "cannot remove", ec.value());
    if (o.caches) o.caches->remove_samples();
  }
}

// The stop hook's answer, held once it asks: the run stops at that step's end.
struct Stop {
  const std::function<int()>& hook;
  int sig = 0;
  int operator()() {
    if (sig == 0 && hook) sig = hook();
    return sig;
  }
};

// Steps until `target`, a step at a time (Simulation::advance_to): a stop
// ends the run at the end of the step it arrived in, a blow-up at once.
void advance_to_step(Simulation& sim, long long target, Stop& stop) {
  while (sim.state().steps < target && stop() == 0) {
    sim.step();
    if (!sim.blow_up_reason().empty()) break;
  }
}

// A run's frames, from where its outputs stand to the last: the simulation,
// what it writes, and its clock (from `start`, the wall time before a resume
// added to it).
struct FrameLoop {
  const Params& p;
  const fs::path& out;
  Simulation& sim;
  RunOutputs& o;
  RunResult& r;
  const RunHooks& hooks;
  Stop stop{hooks.stop};
  nlohmann::json first_json, final_json;  // the first and last rows' metrics
  long long written_at_step = -1;         // the step of the last row written
  const std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

  double wall() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  long long target_step(long long f) const {
    return std::llround(frame_time(f, p.run.duration, p.run.fps) / p.integrator.dt);
  }
  // The checkpoint: this state, and the outputs as they stood after the last
  // whole frame (a row at a step between two frames is written again).
  void save() {
    if (out.empty()) return;  // no folder: no checkpoint
    o.metrics->sync();
    if (o.caches) o.caches->position(true);  // on the disk
    const nlohmann::json rec =
        record_json(o.at, o.substeps_before + sim.stats().substeps, o.wall_before + wall());
    save_checkpoint(out / "checkpoint.state", p, sim.state(), rec.dump());
  }
  // Frame f: the steps to it, its row, mesh and cache frame. False where the
  // run ends there (a signal, a blow-up), r saying why.
  bool frame(long long f);
  void run();
};

bool FrameLoop::frame(long long f) {
  const long long target = target_step(f);
  advance_to_step(sim, target, stop);
  const bool ok = sim.blow_up_reason().empty();
  const int sig = stop();
  if (sig != 0 && sim.state().steps == written_at_step) {  // the last row is this state's
    r.code = 128 + sig;
    save();
    return false;
  }
  const Metrics m = sim.metrics();
  if (const std::string bad = non_finite_metric(m); !bad.empty()) {
    r.code = kBlowUp;
    r.message =
        "the simulation left the range of numbers at t = " + format_number(sim.state().time) +
        " s (" + bad + "; not written to metrics.csv). " +
        (ok ? "Look at positions and sizes far from the origin (cloth.center, "
              "ball.center, table.height, cloth.size) and the forces."
            : sim.blow_up_reason());
    return false;
  }
  write_frame(p, out, sim, m, f, o, r, first_json, final_json);
  written_at_step = sim.state().steps;
  if (hooks.progress) hooks.progress(sim.state().time, p.run.duration, o.wall_before + wall());
  if (!ok) {
    r.code = kBlowUp;
    r.message = sim.blow_up_reason();
    return false;
  }
  // A whole frame: a resumed run goes on after it.
  if (sim.state().steps == target) mark_whole_frame(f, o, r, first_json, final_json);
  if (sig != 0) {
    r.code = 128 + sig;
    save();
    return false;
  }
  return true;
}

void FrameLoop::run() {
  const long long frames = last_frame_index(p.run.duration, p.run.fps);
  const double every = p.run.checkpoint_every;
  const auto next_checkpoint_after = [&](double t) {
    return every > 0 ? (std::floor(t / every + 1e-9) + 1) * every
                     : std::numeric_limits<double>::infinity();
  };
  double next_checkpoint = next_checkpoint_after(sim.state().time);
  for (long long f = o.at.next_frame; f <= frames; ++f) {
    if (!frame(f)) break;
    // Every run.checkpoint_every, at a whole frame with steps to the next
    // (a row right after a restore is the next step's).
    if (sim.state().time >= next_checkpoint - 1e-9 * every && f < frames &&
        target_step(f + 1) > target_step(f)) {
      save();
      next_checkpoint = next_checkpoint_after(sim.state().time);
    }
  }
}

}  // namespace

RunResult run_scene(const Params& p, const fs::path& out, const RunHooks& hooks,
                    const ResumePoint* resume) {
  RunResult r;
  Simulation sim(p);
  if (resume) try {
      sim.restore(resume->state);
    } catch (const std::invalid_argument& e) {
      throw SceneError(resume->file.string() + ": " + e.what());
    }
  RunOutputs o;
  std::optional<OutputLock> lock;
  if (!out.empty()) {
    if (std::error_code ec; fs::create_directories(out, ec), ec)
      throw_output_error(out, "cannot make the folder", ec.value());
    lock.emplace(out);
    open_outputs(p, out, sim, resume, o, r);
  }
  r.started = true;
  FrameLoop loop{p, out, sim, o, r, hooks, {hooks.stop}, o.at.first, o.at.final};
  loop.run();
  finish_run(p, out, sim, resume, loop.written_at_step >= 0, loop.start, o, r, loop.first_json,
             loop.final_json);
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
                               const RunHooks& hooks,
                               const std::function<void(std::size_t, const RunResult&)>& done) {
  std::vector<RunResult> results(runs.size());
  std::atomic<std::size_t> next{0};
  std::mutex lock;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < runs.size();) {
      if (const int sig = hooks.stop ? hooks.stop() : 0; sig != 0) {  // interrupted: no case starts
        results[i].code = 128 + sig;
        results[i].message = std::string("not run: interrupted by ") + signal_name(sig);
      } else
        try {  // an exception must not end the process from a worker thread
          results[i] = run_scene(runs[i].first, runs[i].second, {hooks.stop, nullptr});
        } catch (const std::exception& e) {
          results[i].code = dynamic_cast<const SceneError*>(&e)    ? kBadInput
                            : dynamic_cast<const OutputError*>(&e) ? kOutputError
                                                                   : kError;
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

void prepare_run(const Params& p, const fs::path& out, bool force, const std::string& source,
                 const std::string& option) {
  if (!force) check_resources(p, out, source);
  check_output_folder(out, option);
  refuse_system_folder(out, option);
  if (!force) refuse_foreign_folder(out, option);
  make_output_folder(out, option);
}

std::optional<ResumePoint> resume_run(const fs::path& dir, std::optional<unsigned> threads,
                                      std::optional<double> checkpoint_every, bool force) {
  if (run_ended_whole(dir)) {
    // Killed in its last moment, between removing the checkpoint and
    // the USD samples: the samples go now.
    std::error_code ec;
    fs::remove_all(dir / ".cloth.usda.samples", ec);
    return std::nullopt;
  }
  ResumePoint resume = load_resume_point(dir);
  if (threads) resume.params.integrator.threads = *threads;
  if (checkpoint_every) resume.params.run.checkpoint_every = *checkpoint_every;
  if (!force) check_resources(resume.params, dir, resume.file.string());
  return resume;
}

bool overrides_key(const std::vector<std::string>& sets, const std::string& key) {
  for (const auto& s : sets)
    if (s.rfind(key + "=", 0) == 0) return true;
  return false;
}

Params load_on_grid(const std::string& scene, const std::vector<std::string>& sets,
                    std::optional<long long> grid, const std::string& option, IntegratorTier tier) {
  Params p = load_scene(scene, sets, tier);
  if (!grid) return p;
  const double dt = p.integrator.dt;
  try {
    p = at_resolution(p, *grid);
  } catch (const SceneError& e) {
    throw SceneError(option + ": " + e.what());
  }
  if (overrides_key(sets, "integrator.dt")) p.integrator.dt = dt;
  // What the scaling made of the scene (a handle's patch in grid steps) is
  // checked here, so that the error names the option before anything runs.
  try {
    validate(p);
  } catch (const SceneError& e) {
    std::string what = e.what();
    if (what.rfind("Params: ", 0) == 0) what = what.substr(8);
    throw SceneError(option + " " + std::to_string(*grid) + ": " + what);
  }
  return p;
}

}  // namespace wetcloth
