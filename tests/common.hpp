// What the tests share: small scenes built in code, and results compared bit
// for bit.
#pragma once

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "wetcloth/scene.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth::test {

// A cloth with no forces at all: each test switches on what it checks.
inline Params bare(int n = 2) {
  Params p;
  p.cloth.resolution = {n, n};
  p.cloth.size = {0.01 * (n - 1), 0.01 * (n - 1)};
  p.cloth.center = {0, 0, 1};
  // Spring constants set directly (200/20/20 N/m at any spacing), undamped:
  // Provot's bending springs, whose constant is a spring's.
  p.material.bending = BendingModel::Provot;
  p.springs.structural_k = 200;
  p.springs.shear_k = 20;
  p.springs.bending_k = 20;
  p.springs.structural_damping = p.springs.shear_damping = p.springs.bending_damping = 0;
  p.forces.gravity = {0, 0, 0};
  p.forces.viscous_damping = 0;
  p.wind.k = 0;
  p.strain_limit.enabled = false;
  p.table.enabled = false;
  p.contact.surface = SurfaceChoice::None;
  p.air.model = AirModel::Off;
  p.self_collision.enabled = false;
  return p;
}

// Pins each of `particles` of a grid cloth where it starts, with a pin handle
// of its own from t = 0: the model's driven particles, as a scene makes them.
inline void pin_particles(Params& p, const std::vector<int>& particles) {
  const auto [nu, nv] = p.cloth.resolution;
  for (const int k : particles) {
    HandleParams pin;
    pin.type = HandleType::Pin;
    pin.at = {double(k % nu) / double(nu - 1), double(k / nu) / double(nv - 1)};
    p.handles["pin" + std::to_string(k)] = pin;
  }
}

// A built-in scene at a coarser grid, with the physics unchanged.
inline Params coarse(const std::string& scene, std::vector<std::string> sets = {}) {
  sets.insert(sets.begin(), "cloth.resolution=[25,25]");
  return load_scene(scene, sets);
}

// The same bits in every component (NaNs and signed zeros too).
inline bool same_bits(const Vec3Array& a, const Vec3Array& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int q = 0; q < 3; ++q) {
      const double x = a[i][q], y = b[i][q];
      if (std::memcmp(&x, &y, sizeof x) != 0) return false;
    }
  return true;
}

// A file's whole contents.
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream o;
  o << in.rdbuf();
  return o.str();
}

// Every number in a text, in order (a cache read back).
inline std::vector<double> numbers(const std::string& text) {
  std::vector<double> v;
  static const std::regex number(R"([-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)");
  for (std::sregex_iterator it(text.begin(), text.end(), number), end; it != end; ++it)
    v.push_back(std::stod(it->str()));
  return v;
}

// A folder of its own for a test's files (with meshes/ in it), removed at the end.
struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() /
             ("wetcloth_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path / "meshes");
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  // Writes `text` to the folder's `file`; returns its path.
  std::filesystem::path write(const std::string& file, const std::string& text) const {
    std::ofstream(path / file) << text;
    return path / file;
  }
};

}  // namespace wetcloth::test
