#include "wetcloth/output.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "geometry/mesh_obstacle.hpp"

namespace wetcloth {

namespace {

// The temporary files being written now, for remove_temporary_files (a signal
// handler): a fixed table, no allocation, slots taken with an atomic flag.
constexpr int kTempSlots = 64;
constexpr std::size_t kTempPath = 4096;
struct TempSlot {
  std::atomic<bool> used{false};
  std::atomic<bool> ready{false};
  char path[kTempPath];
};
TempSlot g_temp[kTempSlots];

// WETCLOTH_FAIL_AFTER_BYTES: bytes left before writes fail; < 0: no fault.
std::atomic<long long>& fault_budget() {
  static std::atomic<long long> budget = [] {
    const char* v = std::getenv("WETCLOTH_FAIL_AFTER_BYTES");
    return v && *v ? std::atoll(v) : -1LL;
  }();
  return budget;
}

// Writes all of `data` to fd; false with errno set where it could not.
bool write_all(int fd, const char* data, std::size_t size) {
  std::size_t allowed = size;
  bool fault = false;
  if (auto& b = fault_budget(); b.load() >= 0) {
    const long long left = b.fetch_sub(static_cast<long long>(size));
    allowed = left <= 0 ? 0 : std::min<std::size_t>(size, static_cast<std::size_t>(left));
    fault = allowed < size;
  }
  while (allowed > 0) {
    const ssize_t w = ::write(fd, data, allowed);
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += w;
    allowed -= static_cast<std::size_t>(w);
    size -= static_cast<std::size_t>(w);
  }
  if (fault) {
    errno = ENOSPC;
    return false;
  }
  return true;
}

}  // namespace

TemporaryFile::TemporaryFile(const std::string& path) {
  if (path.size() >= kTempPath) return;
  for (int i = 0; i < kTempSlots; ++i) {
    bool expected = false;
    if (g_temp[i].used.compare_exchange_strong(expected, true)) {
      std::memcpy(g_temp[i].path, path.c_str(), path.size() + 1);
      g_temp[i].ready = true;
      slot_ = i;
      return;
    }
  }
}

TemporaryFile::~TemporaryFile() {
  if (slot_ < 0) return;
  g_temp[slot_].ready = false;
  g_temp[slot_].used = false;
}

bool write_fault_injected() { return fault_budget().load() >= 0; }

void throw_output_error(const std::filesystem::path& path, const std::string& doing,
                        int error_number) {
  throw OutputError(path.string() + ": " + doing + ": " + std::strerror(error_number));
}

void remove_temporary_files() noexcept {
  for (auto& t : g_temp)
    if (t.ready.load()) ::unlink(t.path);
}

namespace {

// fsync of the folder holding PATH: its new entry (a rename) is on the disk.
void sync_folder(const std::filesystem::path& path) {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw_output_error(dir, "cannot open the folder", errno);
  if (::fsync(fd) != 0 && errno != EINVAL) {  // EINVAL: a file system that cannot
    const int e = errno;
    ::close(fd);
    throw_output_error(dir, "cannot sync the folder", e);
  }
  ::close(fd);
}

}  // namespace

void sync_file(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw_output_error(path, "cannot open", errno);
  if (::fsync(fd) != 0) {
    const int e = errno;
    ::close(fd);
    throw_output_error(path, "cannot write", e);
  }
  ::close(fd);
  sync_folder(path);
}

void write_file_atomic(const std::filesystem::path& path, const std::string& contents,
                       Durability durability) {
  const std::string tmp = path.string() + ".tmp";
  TemporaryFile record(tmp);
  // A new file, never one a link points to: whatever is at PATH.tmp goes first
  // (a link itself, not what it names).
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) throw_output_error(tmp, "cannot create", errno);
  if (!write_all(fd, contents.data(), contents.size())) {
    const int e = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw_output_error(path, "cannot write", e);
  }
  if (durability == Durability::kSynced && ::fsync(fd) != 0) {
    const int e = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw_output_error(path, "cannot write", e);
  }
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw_output_error(path, "cannot write", e);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw_output_error(path, "cannot rename " + tmp + " to it", e);
  }
  if (durability == Durability::kSynced) sync_folder(path);
}

std::string metrics_csv_header() {
  std::string o;
  const auto cols = metrics_columns();
  for (std::size_t i = 0; i < cols.size(); ++i) o += (i ? "," : "") + cols[i];
  return o + "\n";
}

// The time to 12 digits: a frame's time is a whole number of steps of a dt
// of few digits, which in binary prints as 0.033350000000000005 (667 x 5e-5);
// 12 digits give it as it is, 0.03335. The values in their shortest exact form.
std::string metrics_csv_row(const Metrics& m) {
  const auto vals = metrics_values(m);
  char buf[32];
  const auto time = std::to_chars(buf, buf + sizeof buf, vals[0], std::chars_format::general, 12);
  std::string o(buf, time.ptr);
  for (std::size_t i = 1; i < vals.size(); ++i) o += "," + format_number(vals[i]);
  return o + "\n";
}

MetricsFile::MetricsFile(const std::filesystem::path& path) : path_(path) {
  const std::string header = metrics_csv_header();
  write_file_atomic(path, header);
  fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_NOFOLLOW | O_CLOEXEC);
  if (fd_ < 0) throw_output_error(path, "cannot open", errno);
  size_ = static_cast<long long>(header.size());
}

MetricsFile::MetricsFile(const std::filesystem::path& path, long long keep_bytes) : path_(path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_NOFOLLOW | O_CLOEXEC);
  if (fd_ < 0) throw_output_error(path, "cannot open", errno);
  if (::ftruncate(fd_, static_cast<off_t>(keep_bytes)) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw_output_error(path, "cannot cut back", e);
  }
  size_ = keep_bytes;
}

void MetricsFile::sync() {
  if (fd_ >= 0 && ::fsync(fd_) != 0) throw_output_error(path_, "cannot write", errno);
}

MetricsFile::~MetricsFile() {
  if (fd_ >= 0) ::close(fd_);
}

void MetricsFile::append(const Metrics& m) {
  if (fd_ < 0) throw_output_error(path_, "cannot write", EBADF);
  const std::string row = metrics_csv_row(m);
  if (!write_all(fd_, row.data(), row.size())) {
    const int e = errno;
    // A row written in part is taken back: the file ends with a whole row.
    if (::ftruncate(fd_, static_cast<off_t>(size_)) != 0) {
    }
    throw_output_error(path_, "cannot write", e);
  }
  size_ += static_cast<long long>(row.size());
}

void MetricsFile::close() {
  if (fd_ < 0) return;
  const int fd = fd_;
  fd_ = -1;
  if (::fsync(fd) != 0) {
    const int e = errno;
    ::close(fd);
    throw_output_error(path_, "cannot write", e);
  }
  if (::close(fd) != 0) throw_output_error(path_, "cannot write", errno);
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
  for (const auto& uv : m.uv) {
    std::snprintf(line, sizeof line, "vt %.7g %.7g\n", uv[0], uv[1]);
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

namespace {
// The table and the ball as meshes.
std::vector<NamedMesh> analytic_meshes(const Params& p) {
  std::vector<NamedMesh> meshes;
  if (p.table.enabled) {
    const double h = std::max(p.cloth.size[0], p.cloth.size[1]) * 2, z = p.table.height;
    const double cx = p.cloth.center[0], cy = p.cloth.center[1];
    NamedMesh t{"table", {}, {{0, 1, 2}, {0, 2, 3}}, nullptr};
    for (auto [sx, sy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
      t.points.emplace_back(cx + sx * h, cy + sy * h, z);
    meshes.push_back(std::move(t));
  }
  if (p.ball.enabled) {
    const int rings = 24, segs = 48;
    const Vec3 c = to_vec(p.ball.center);
    NamedMesh b{"ball", {}, {}, nullptr};
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
}  // namespace

std::vector<Vec3> NamedMesh::points_at(double t) const {
  if (!deforming) return points;
  std::vector<Vec3> x, v;
  sample_cache(*deforming->cache, t, x, v);
  return x;
}

std::vector<NamedMesh> obstacle_meshes(const Model& m) {
  std::vector<NamedMesh> meshes = analytic_meshes(m.params);
  for (const auto& o : m.obstacles)
    meshes.push_back({o->name, o->points, o->triangles, o->cache ? o : nullptr});
  return meshes;
}

std::vector<NamedMesh> obstacle_meshes(const Params& p) {
  std::vector<NamedMesh> meshes = analytic_meshes(p);
  for (const auto& [name, unused] : p.obstacles) {
    const auto o = build_mesh_obstacle(p, name);
    meshes.push_back({o->name, o->points, o->triangles, o->cache ? o : nullptr});
  }
  return meshes;
}

std::vector<RigidPose> obstacle_poses(const Params& p, double t) {
  std::vector<RigidPose> poses;
  if (p.table.enabled) poses.emplace_back();  // the table stands still
  if (p.ball.enabled) poses.push_back(ball_pose(p, t));
  for (const auto& [name, unused] : p.obstacles) poses.push_back(obstacle_pose(p, name, t));
  return poses;
}

bool obstacles_move(const Params& p) {
  for (const RigidPose& pose : obstacle_poses(p, 0))
    if (pose.moving) return true;
  for (const auto& [name, o] : p.obstacles)
    if (!o.cache.empty()) return true;
  return false;
}

std::string obstacles_obj(const Model& m, UpAxis up, double t) {
  std::ostringstream o;
  o << "# wetcloth obstacles, " << (up == UpAxis::Z ? "z" : "y") << " up, metres";
  const std::vector<RigidPose> poses = obstacle_poses(m.params, t);
  if (obstacles_move(m.params)) o << ", at t = " << format_number(t) << " s";
  o << "\n";
  int base = 1;
  std::size_t k = 0;
  for (const NamedMesh& mesh : obstacle_meshes(m)) {
    const RigidPose& pose = poses[k++];
    o << "o " << mesh.name << "\n";
    for (const Vec3& x0 : mesh.points_at(t)) {
      const Vec3 x = to_up(pose.to_world(x0), up);
      o << "v " << x.x() << " " << x.y() << " " << x.z() << "\n";
    }
    for (const auto& tri : mesh.triangles)
      o << "f " << base + tri[0] << " " << base + tri[1] << " " << base + tri[2] << "\n";
    base += static_cast<int>(mesh.points.size());
  }
  return o.str();
}

Eigen::Matrix4d up_matrix(const RigidPose& pose, UpAxis up) {
  // x -> R x + (pivot + shift - R pivot), conjugated by the up axis' turn C:
  // C R C^T on C x. USD multiplies row vectors: the transpose, translation last.
  Mat3 C = Mat3::Identity();
  if (up == UpAxis::Y) C << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  const Mat3 R = pose.moving ? pose.rotation : Mat3::Identity();
  const Vec3 t = pose.to_world(Vec3::Zero());
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = (C * R * C.transpose()).transpose();
  M.block<1, 3>(3, 0) = (C * t).transpose();
  return M;
}

std::string MetricsTable::csv() const {
  std::string o = metrics_csv_header();
  for (const auto& r : rows_) o += metrics_csv_row(r);
  return o;
}

}  // namespace wetcloth
