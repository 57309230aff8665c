// Writing results: meshes as OBJ, metrics as CSV, every file written whole under a
// temporary name and then renamed, so that a reader never sees half a file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "wetcloth/simulation.hpp"

namespace wetcloth {

void write_file_atomic(const std::filesystem::path& path, const std::string& contents);

// The cloth: positions, normals, triangles.
std::string cloth_obj(const Model& m, const State& s);
// The table (a square around the cloth) and the ball.
std::string obstacles_obj(const Model& m);

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

}  // namespace wetcloth
