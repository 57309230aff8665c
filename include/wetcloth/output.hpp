// Writing results: meshes as OBJ, metrics as CSV, every file written whole under a
// temporary name and then renamed, so that a reader never sees half a file.
#pragma once

#include <algorithm>
#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "wetcloth/motion.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

// An output file or folder that could not be written: the message names it and
// the system's reason ("out/x/metrics.csv: cannot write: No space left on
// device"). The CLI exits 4 on it.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
[[noreturn]] void throw_output_error(const std::filesystem::path& path, const std::string& doing,
                                     int error_number);

// Writes PATH.tmp, then renames it to PATH: a reader sees the old file or the
// new one, whole. On any failure the .tmp is removed and OutputError thrown.
// Durable: the file is on the disk (fsync) before the rename, and the rename
// too (the folder's fsync) before it returns.
enum class Durability { kCached, kSynced };
void write_file_atomic(const std::filesystem::path& path, const std::string& contents,
                       Durability durability = Durability::kCached);

// Makes a file's bytes, and its folder's entry, durable (fsync); OutputError
// naming it where that fails.
void sync_file(const std::filesystem::path& path);

// A temporary file being written, known to remove_temporary_files for as long
// as this lives (write_file_atomic takes one itself).
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& path);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

 private:
  int slot_ = -1;
};

// Removes the temporary files being written at this moment (by any thread).
// Async-signal-safe: a signal handler that ends the process calls it.
void remove_temporary_files() noexcept;

// A test hook: with WETCLOTH_FAIL_AFTER_BYTES=N in the environment, the
// output files (write_file_atomic, MetricsFile) take N bytes in all and then
// fail as a full disk does (ENOSPC), part way through a write.
bool write_fault_injected();

// metrics.csv grown a row at a time, so that a run's I/O is linear in its
// frames: the header is written whole (write_file_atomic), then each row is
// appended with one write; a write that fails part way is cut back, so that
// the file ends with a whole row. Only SIGKILL, which cannot be caught, can
// leave the start of a row at the end (Linux ends a write at a page boundary
// when it comes): `run --resume` cuts the file back to its checkpoint's bytes.
class MetricsFile {
 public:
  explicit MetricsFile(const std::filesystem::path& path);
  // Continues an existing metrics.csv: cut back to its first `keep_bytes`
  // (a header and whole rows), then appended to.
  MetricsFile(const std::filesystem::path& path, long long keep_bytes);
  ~MetricsFile();
  MetricsFile(const MetricsFile&) = delete;
  MetricsFile& operator=(const MetricsFile&) = delete;
  void append(const Metrics& m);
  void close();  // flushed to the disk (fsync); the destructor closes without
  void sync();   // the rows so far on the disk (fsync)
  long long size() const { return size_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  long long size_ = 0;
};
std::string metrics_csv_header();
std::string metrics_csv_row(const Metrics& m);

// The files' up axis (run.up): y turns (x, y, z) -> (x, z, -y), as Houdini, Maya
// and Blender's OBJ importer expect by default.
inline Vec3 to_up(const Vec3& x, UpAxis up) {
  return up == UpAxis::Z ? x : Vec3(x.x(), x.z(), -x.y());
}

// The cloth: positions, texture coordinates (the grid's (u, v) = (i, j) / (nu - 1, nv - 1),
// a mesh cloth's from its file),
// normals, triangles.
std::string cloth_obj(const Model& m, const State& s, UpAxis up = UpAxis::Z);

// An obstacle as a triangle mesh: the table (a square around the cloth), the
// ball, and each [obstacle.NAME] (named NAME) as the simulation has it.
struct NamedMesh {
  std::string name;
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> triangles;  // 0-based
  // A deforming obstacle (obstacle.NAME.cache): null for a rigid one.
  std::shared_ptr<const MeshObstacle> deforming;
  // Its points at time t before its pose: the cache's shape then, or `points`.
  std::vector<Vec3> points_at(double t) const;
};
std::vector<NamedMesh> obstacle_meshes(const Model& m);
// The same from a scene's parameters (its mesh files read again; throws
// SceneError as load_scene would), for a viewer that has no Model.
std::vector<NamedMesh> obstacle_meshes(const Params& p);
// Where each of obstacle_meshes' obstacles stands at time t, in the same
// order: a moving one's pose (its points x0 are at pose.to_world(x0)), the
// identity (moving false) for one that stands still.
std::vector<RigidPose> obstacle_poses(const Params& p, double t);
// Whether any obstacle moves or deforms: then the outputs carry the
// obstacles per frame.
bool obstacles_move(const Params& p);
// The obstacles as they stand at time t (obstacles.obj: at the start; with
// moving obstacles, frames/obstacles_NNNNN.obj: each frame's, the same
// vertices and faces every frame).
std::string obstacles_obj(const Model& m, UpAxis up = UpAxis::Z, double t = 0);
// A pose in the files' up axis as USD writes it: the row-vector matrix
// (points times it) taking a point of obstacle_meshes, in that axis, to
// where the pose has it.
Eigen::Matrix4d up_matrix(const RigidPose& pose, UpAxis up);

// metrics.csv, one row per output frame.
class MetricsTable {
 public:
  void add(const Metrics& m) { rows_.push_back(m); }
  const std::vector<Metrics>& rows() const { return rows_; }
  std::string csv() const;

 private:
  std::vector<Metrics> rows_;
};

std::string format_number(double v);  // shortest text that reads back to v

// Output frames over a run of `duration` s: at 0, 1/fps, 2/fps, ... and,
// where the duration falls between two, one more at the duration, so that a
// run covers the whole time asked for. Frame f is at frame_time(f, ...).
long long last_frame_index(double duration, double fps);
inline double frame_time(long long f, double duration, double fps) {
  return std::min(duration, static_cast<double>(f) / fps);
}

}  // namespace wetcloth
