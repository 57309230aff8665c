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

std::string cloth_obj(const Model& m, const State& s) {
  Vec3Array normal(m.n);
  compute_normals(m, s.x, normal);
  std::string o;
  o.reserve(static_cast<std::size_t>(m.n) * 80);
  o += "# wetcloth cloth t=" + format_number(s.time) + "\n";
  char line[128];
  for (int i = 0; i < m.n; ++i) {
    const Vec3 x = s.x[i];
    std::snprintf(line, sizeof line, "v %.7g %.7g %.7g\n", x.x(), x.y(), x.z());
    o += line;
  }
  for (const auto& n : normal) {
    std::snprintf(line, sizeof line, "vn %.5f %.5f %.5f\n", n.x(), n.y(), n.z());
    o += line;
  }
  for (const auto& t : m.triangles) {
    std::snprintf(line, sizeof line, "f %d//%d %d//%d %d//%d\n", t[0] + 1, t[0] + 1, t[1] + 1,
                  t[1] + 1, t[2] + 1, t[2] + 1);
    o += line;
  }
  return o;
}

std::string obstacles_obj(const Model& m) {
  const Params& p = m.params;
  std::ostringstream o;
  o << "# wetcloth obstacles\n";
  int base = 1;
  if (p.table.enabled) {
    const double h = std::max(p.cloth.size[0], p.cloth.size[1]) * 2, z = p.table.height;
    const double cx = p.cloth.center[0], cy = p.cloth.center[1];
    o << "o table\n";
    for (auto [sx, sy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
      o << "v " << cx + sx * h << " " << cy + sy * h << " " << z << "\n";
    o << "f 1 2 3\nf 1 3 4\n";
    base += 4;
  }
  if (p.ball.enabled) {
    const int rings = 24, segs = 48;
    const Vec3 c = to_vec(p.ball.center);
    o << "o ball\n";
    for (int r = 0; r <= rings; ++r) {
      const double th = std::numbers::pi * r / rings;
      for (int s = 0; s < segs; ++s) {
        const double ph = 2 * std::numbers::pi * s / segs;
        const Vec3 x = c + p.ball.radius * Vec3(std::sin(th) * std::cos(ph),
                                                std::sin(th) * std::sin(ph), std::cos(th));
        o << "v " << x.x() << " " << x.y() << " " << x.z() << "\n";
      }
    }
    for (int r = 0; r < rings; ++r)
      for (int s = 0; s < segs; ++s) {
        const int a = base + r * segs + s, b = base + r * segs + (s + 1) % segs;
        const int c2 = a + segs, d = b + segs;
        o << "f " << a << " " << c2 << " " << d << "\nf " << a << " " << d << " " << b << "\n";
      }
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
