#include "wetcloth/output.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace wetcloth {

void write_file_atomic(const std::filesystem::path& path, const std::string& contents) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << contents;
    if (!out.flush()) throw std::runtime_error(tmp.string() + ": cannot write");
  }
  std::filesystem::rename(tmp, path);
}

long long last_frame_index(double duration, double fps) {
  const auto whole = static_cast<long long>(std::floor(duration * fps + 1e-9));
  return whole + (duration > (static_cast<double>(whole) + 1e-9) / fps ? 1 : 0);
}

std::string format_number(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string cloth_obj(const Model& m, const State& s, UpAxis up) {
  Vec3Array normal(m.n);
  compute_normals(m, s.x, normal);
  std::string o;
  o.reserve(static_cast<std::size_t>(m.n) * 110);
  o += "# wetcloth cloth t=" + format_number(s.time) + std::string(", ") +
       (up == UpAxis::Z ? "z" : "y") + " up, metres\n";
  char line[128];
  for (int i = 0; i < m.n; ++i) {
    const Vec3 x = to_up(s.x[i], up);
    std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", x.x(), x.y(), x.z());
    o += line;
  }
  for (int j = 0; j < m.nv; ++j)
    for (int i = 0; i < m.nu; ++i) {
      std::snprintf(line, sizeof line, "vt %.7g %.7g\n", double(i) / (m.nu - 1),
                    double(j) / (m.nv - 1));
      o += line;
    }
  for (const auto& n0 : normal) {
    const Vec3 n = to_up(n0, up);
    std::snprintf(line, sizeof line, "vn %.5f %.5f %.5f\n", n.x(), n.y(), n.z());
    o += line;
  }
  for (const auto& t : m.triangles) {
    const int a = t[0] + 1, b = t[1] + 1, c = t[2] + 1;
    std::snprintf(line, sizeof line, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, b, b, b, c, c, c);
    o += line;
  }
  return o;
}

std::vector<NamedMesh> obstacle_meshes(const Model& m) {
  const Params& p = m.params;
  std::vector<NamedMesh> meshes;
  if (p.table.enabled) {
    const double h = std::max(p.cloth.size[0], p.cloth.size[1]) * 2, z = p.table.height;
    const double cx = p.cloth.center[0], cy = p.cloth.center[1];
    NamedMesh t{"table", {}, {{0, 1, 2}, {0, 2, 3}}};
    for (auto [sx, sy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
      t.points.emplace_back(cx + sx * h, cy + sy * h, z);
    meshes.push_back(std::move(t));
  }
  if (p.ball.enabled) {
    const int rings = 24, segs = 48;
    const Vec3 c = to_vec(p.ball.center);
    NamedMesh b{"ball", {}, {}};
    for (int r = 0; r <= rings; ++r) {
      const double th = std::numbers::pi * r / rings;
      for (int s = 0; s < segs; ++s) {
        const double ph = 2 * std::numbers::pi * s / segs;
        b.points.push_back(c + p.ball.radius * Vec3(std::sin(th) * std::cos(ph),
                                                    std::sin(th) * std::sin(ph), std::cos(th)));
      }
    }
    for (int r = 0; r < rings; ++r)
      for (int s = 0; s < segs; ++s) {
        const int a = r * segs + s, d = r * segs + (s + 1) % segs;
        b.triangles.push_back({a, a + segs, d + segs});
        b.triangles.push_back({a, d + segs, d});
      }
    meshes.push_back(std::move(b));
  }
  return meshes;
}

std::string obstacles_obj(const Model& m, UpAxis up) {
  std::ostringstream o;
  o << "# wetcloth obstacles, " << (up == UpAxis::Z ? "z" : "y") << " up, metres\n";
  int base = 1;
  for (const NamedMesh& mesh : obstacle_meshes(m)) {
    o << "o " << mesh.name << "\n";
    for (const Vec3& x0 : mesh.points) {
      const Vec3 x = to_up(x0, up);
      o << "v " << x.x() << " " << x.y() << " " << x.z() << "\n";
    }
    for (const auto& t : mesh.triangles)
      o << "f " << base + t[0] << " " << base + t[1] << " " << base + t[2] << "\n";
    base += static_cast<int>(mesh.points.size());
  }
  return o.str();
}

std::string MetricsTable::csv() const {
  std::string o;
  const auto cols = metrics_columns();
  for (std::size_t i = 0; i < cols.size(); ++i) o += (i ? "," : "") + cols[i];
  o += "\n";
  for (const auto& r : rows_) {
    const auto vals = metrics_values(r);
    for (std::size_t i = 0; i < vals.size(); ++i) o += (i ? "," : "") + format_number(vals[i]);
    o += "\n";
  }
  return o;
}

}  // namespace wetcloth
