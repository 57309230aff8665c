// Writing results: meshes as OBJ, metrics as CSV, every file written whole under a
// temporary name and then renamed, so that a reader never sees half a file.
#pragma once

#include <algorithm>
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "wetcloth/simulation.hpp"

namespace wetcloth {

void write_file_atomic(const std::filesystem::path& path, const std::string& contents);

// The files' up axis (run.up): y turns (x, y, z) -> (x, z, -y), as Houdini, Maya
// and Blender's OBJ importer expect by default.
inline Vec3 to_up(const Vec3& x, UpAxis up) {
  return up == UpAxis::Z ? x : Vec3(x.x(), x.z(), -x.y());
}

// The cloth: positions, texture coordinates (u, v) = (i, j) / (nu - 1, nv - 1),
// normals, triangles.
std::string cloth_obj(const Model& m, const State& s, UpAxis up = UpAxis::Z);

// An obstacle as a triangle mesh: the table (a square around the cloth), the ball.
struct NamedMesh {
  std::string name;
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> triangles;  // 0-based
};
std::vector<NamedMesh> obstacle_meshes(const Model& m);
std::string obstacles_obj(const Model& m, UpAxis up = UpAxis::Z);

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
