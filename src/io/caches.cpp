#include "wetcloth/caches.hpp"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace fs = std::filesystem;

ExportFormats parse_export_formats(const std::string& list) {
  ExportFormats f;
  std::istringstream in(list);
  for (std::string word; std::getline(in, word, ',');) {
    const auto first = word.find_first_not_of(" \t"), last = word.find_last_not_of(" \t");
    word = first == std::string::npos ? "" : word.substr(first, last - first + 1);
    if (word == "usd")
      f.usd = true;
    else if (word == "pc2")
      f.pc2 = true;
    else if (word == "vtk")
      f.vtk = true;
    else if (!word.empty())
      throw std::invalid_argument("'" + word + "' is not a cache format (usd, pc2, vtk)");
  }
  return f;
}

CacheFrame cache_frame(const Simulation& sim, UpAxis up) {
  const Model& m = sim.model();
  const State& s = sim.state();
  Vec3Array normal(m.n);
  compute_normals(m, s.x, normal);
  CacheFrame f;
  f.time = s.time;
  f.humidity.assign(m.n, static_cast<float>(m.params.cloth.humidity));
  f.points.resize(m.n);
  f.normals.resize(m.n);
  f.velocities.resize(m.n);
  f.contact.resize(m.n);
  f.pressure.assign(m.n, static_cast<float>(m.params.air.p_atm));
  f.adhesion.assign(m.n, 0.0f);
  const bool pressure = s.pocket_pressure.size() == std::size_t(m.n);
  const bool adhesion = sim.adhesion().size() == std::size_t(m.n);
  for (int i = 0; i < m.n; ++i) {
    f.points[i] = to_up(s.x[i], up);
    f.normals[i] = to_up(normal[i], up);
    f.velocities[i] = to_up(s.v[i], up);
    f.contact[i] = s.contact[i] ? 1.0f : 0.0f;
    if (pressure) f.pressure[i] = static_cast<float>(s.pocket_pressure[i]);
    if (adhesion) f.adhesion[i] = static_cast<float>(sim.adhesion()[i]);
    if (s.humidity.size() == std::size_t(m.n)) f.humidity[i] = static_cast<float>(s.humidity[i]);
  }
  return f;
}

namespace {

// Text of a float as USD and VTK read it back (9 significant digits: exact).
void put(std::string& o, double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9g", v);
  o += b;
}

template <class T>
std::string join(const std::vector<T>& v, const char* sep = " ") {
  std::string o;
  o.reserve(v.size() * 12);
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) o += sep;
    put(o, static_cast<double>(v[i]));
  }
  return o;
}

std::string tuples(const std::vector<Vec3>& v) {  // USD: (x, y, z), ...
  std::string o;
  o.reserve(v.size() * 36);
  for (std::size_t i = 0; i < v.size(); ++i) {
    o += i ? ", (" : "(";
    put(o, v[i].x());
    o += ", ";
    put(o, v[i].y());
    o += ", ";
    put(o, v[i].z());
    o += ")";
  }
  return o;
}

std::string usd_matrix(const Eigen::Matrix4d& M) {  // ( (a, b, c, d), ... )
  std::string o = "(";
  for (int r = 0; r < 4; ++r) {
    o += r ? ", (" : "(";
    for (int c = 0; c < 4; ++c) {
      if (c) o += ", ";
      put(o, M(r, c));
    }
    o += ")";
  }
  return o + ")";
}

std::vector<Vec3> uvs(const Model& m) {  // (u, v, 0): the grid's own coordinates, or the mesh's
  std::vector<Vec3> uv;
  uv.reserve(m.n);
  for (const auto& t : m.uv) uv.emplace_back(t[0], t[1], 0.0);
  return uv;
}

// A VTK XML file's arrays in binary, zlib-compressed and appended after the
// XML (a frame at 31 x 31 was 94 kB of ASCII, 92 kB raw): each array's tag
// gives its offset into the appended block, where VTK's compression header
// (UInt64: blocks, block size, last block's size, each block's compressed
// size) and the compressed little-endian values follow, in one block.
class VtkArrays {
 public:
  template <class T>
  std::string add(const char* type, const char* name, int components, const std::vector<T>& v) {
    std::string tag = std::string("<DataArray type=\"") + type + "\"" +
                      (name ? std::string(" Name=\"") + name + "\"" : std::string()) +
                      " NumberOfComponents=\"" + std::to_string(components) +
                      "\" format=\"appended\" offset=\"" + std::to_string(blob_.size()) + "\"/>\n";
    const auto raw = static_cast<uLong>(v.size() * sizeof(T));
    uLongf packed = compressBound(raw);
    std::string data(packed, '\0');
    if (compress2(reinterpret_cast<Bytef*>(data.data()), &packed,
                  reinterpret_cast<const Bytef*>(v.data()), raw, 6) != Z_OK)
      throw std::runtime_error("zlib: cannot compress a VTK array");
    data.resize(packed);
    const std::uint64_t header[4] = {1, raw, raw, packed};
    blob_.append(reinterpret_cast<const char*>(header), sizeof header);
    blob_ += data;
    return tag;
  }
  std::string appended() const {
    return "<AppendedData encoding=\"raw\">\n_" + blob_ + "\n</AppendedData>\n";
  }

 private:
  std::string blob_;
};

template <class T>
std::vector<T> components(const std::vector<Vec3>& v) {  // x y z x y z ...
  std::vector<T> o;
  o.reserve(3 * v.size());
  for (const Vec3& x : v)
    for (int q = 0; q < 3; ++q) o.push_back(static_cast<T>(x[q]));
  return o;
}

// A PolyData of `points` and `tris`; `point_data` the <PointData> element,
// its arrays already in `arrays`.
std::string polydata(const std::vector<Vec3>& points, const std::vector<std::array<int, 3>>& tris,
                     const std::string& point_data, VtkArrays& arrays) {
  std::vector<std::int32_t> connectivity, offsets;
  for (std::size_t k = 0; k < tris.size(); ++k) {
    connectivity.insert(connectivity.end(), tris[k].begin(), tris[k].end());
    offsets.push_back(static_cast<std::int32_t>(3 * (k + 1)));
  }
  std::string o =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n<PolyData>\n<Piece "
      "NumberOfPoints=\"" +
      std::to_string(points.size()) + "\" NumberOfPolys=\"" + std::to_string(tris.size()) +
      "\">\n" + point_data + "<Points>\n" +
      arrays.add("Float64", nullptr, 3, components<double>(points)) + "</Points>\n<Polys>\n" +
      arrays.add("Int32", "connectivity", 1, connectivity) +
      arrays.add("Int32", "offsets", 1, offsets) + "</Polys>\n</Piece>\n</PolyData>\n";
  return o + arrays.appended() + "</VTKFile>\n";
}

std::string mesh_topology(const std::vector<std::array<int, 3>>& tris, const std::string& indent) {
  std::string counts, indices;
  for (std::size_t k = 0; k < tris.size(); ++k) {
    counts += k ? ", 3" : "3";
    for (int q = 0; q < 3; ++q) indices += (k || q ? ", " : "") + std::to_string(tris[k][q]);
  }
  return indent + "int[] faceVertexCounts = [" + counts + "]\n" + indent +
         "int[] faceVertexIndices = [" + indices + "]\n";
}

// USD names, [A-Za-z_][A-Za-z0-9_]*, each once and never "cloth": the
// obstacles' prims, and the names of their files.
std::vector<std::string> prim_names(const std::vector<std::string>& names) {
  std::vector<std::string> prims;
  for (std::string prim : names) {
    for (char& c : prim)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    if (prim.empty() || std::isdigit(static_cast<unsigned char>(prim[0]))) prim = "_" + prim;
    while (std::find(prims.begin(), prims.end(), prim) != prims.end() || prim == "cloth")
      prim += "_";
    prims.push_back(prim);
  }
  return prims;
}

// The names obstacle_meshes gives, in its order, from the parameters alone.
std::vector<std::string> obstacle_names(const Params& p) {
  std::vector<std::string> names;
  if (p.table.enabled) names.emplace_back("table");
  if (p.ball.enabled) names.emplace_back("ball");
  for (const auto& [name, unused] : p.obstacles) names.push_back(name);
  return names;
}

std::string vtk_obstacles_name(long long k) {
  char name[32];
  std::snprintf(name, sizeof name, "obstacles_%05lld.vtp", k);
  return name;
}

constexpr const char* kPc2 = "cloth.pc2";
constexpr const char* kPc2Fields = "cloth_fields.pc2";

void write_pc2_header(std::fstream& f, int points, long long samples) {
  char header[32] = "POINTCACHE2";
  const std::int32_t version = 1, n = points, count = static_cast<std::int32_t>(samples);
  const float start = 0.0f, rate = 1.0f;  // sample k is frame k
  std::memcpy(header + 12, &version, 4);
  std::memcpy(header + 16, &n, 4);
  std::memcpy(header + 20, &start, 4);
  std::memcpy(header + 24, &rate, 4);
  std::memcpy(header + 28, &count, 4);
  f.seekp(0);
  f.write(header, sizeof header);
}

// Which of obstacle_meshes' obstacles deform (a cache), in its order.
std::vector<bool> deforming(const Params& p) {
  std::vector<bool> d;
  if (p.table.enabled) d.push_back(false);
  if (p.ball.enabled) d.push_back(false);
  for (const auto& [name, o] : p.obstacles) d.push_back(!o.cache.empty());
  return d;
}

}  // namespace

std::vector<std::string> moving_obstacle_files(const Params& p) {
  std::vector<std::string> files;
  const std::vector<std::string> prims = prim_names(obstacle_names(p));
  const std::vector<RigidPose> poses = obstacle_poses(p, 0);
  const std::vector<bool> deforms = deforming(p);
  for (std::size_t k = 0; k < prims.size(); ++k)
    if (poses[k].moving || deforms[k]) files.push_back(prims[k]);
  return files;
}

std::vector<std::string> obstacle_usd_samples(const Params& p) {
  std::vector<std::string> files;
  const std::vector<std::string> prims = prim_names(obstacle_names(p));
  const std::vector<RigidPose> poses = obstacle_poses(p, 0);
  const std::vector<bool> deforms = deforming(p);
  for (std::size_t k = 0; k < prims.size(); ++k) {
    if (poses[k].moving) files.push_back("xform_" + prims[k]);
    if (deforms[k]) files.push_back("points_" + prims[k]);
  }
  return files;
}

// A USD attribute's time samples, "code: value,\n" each, kept in a file of
// .cloth.usda.samples/ until the stage is written.
struct CacheWriter::Spool {
  std::string declaration;  // e.g. "point3f[] points"
  fs::path path;
  std::FILE* file = nullptr;
  ~Spool() {
    if (file) std::fclose(file);
  }
  void add(double code, const std::string& value) {
    std::string line = "            ";
    put(line, code);
    line += ": " + value + ",\n";
    if (std::fwrite(line.data(), 1, line.size(), file) != line.size())
      throw_output_error(path, "cannot write", errno);
  }
};

namespace {

const fs::path kSamples = ".cloth.usda.samples";
constexpr const char* kAttributes[][2] = {{"point3f[] points", "points"},
                                          {"normal3f[] normals", "normals"},
                                          {"float3[] extent", "extent"},
                                          {"float[] primvars:contact", "contact"},
                                          {"float[] primvars:pressure", "pressure"},
                                          {"float[] primvars:adhesion", "adhesion"},
                                          {"float[] primvars:humidity", "humidity"},
                                          {"vector3f[] velocities", "velocities"},
                                          {"float[] primvars:pressure_deficit", "deficit"}};

}  // namespace

void CacheWriter::open_usd_samples(const CachePosition* at) {
  const fs::path folder = dir_ / kSamples;
  if (std::error_code ec; fs::create_directories(folder, ec), ec)
    throw_output_error(folder, "cannot make the folder", ec.value());
  // The cloth's attributes, then each moving obstacle's transform.
  std::vector<std::pair<std::string, std::string>> attributes;
  for (const auto& [declaration, file] : kAttributes) attributes.emplace_back(declaration, file);
  xform_spool_.assign(moving_.size(), -1);
  points_spool_.assign(moving_.size(), -1);
  const std::vector<RigidPose> poses = obstacle_poses(model_.params, 0);
  for (std::size_t q = 0; q < moving_.size(); ++q) {
    const std::size_t k = moving_[q];
    if (poses[k].moving) {
      xform_spool_[q] = static_cast<int>(attributes.size());
      attributes.emplace_back("matrix4d xformOp:transform", "xform_" + prims_[k]);
    }
    if (meshes_[k].deforming) {
      points_spool_[q] = static_cast<int>(attributes.size());
      attributes.emplace_back("point3f[] points", "points_" + prims_[k]);
    }
  }
  if (at && at->samples_bytes.size() != attributes.size())
    throw SceneError(folder.string() + ": the checkpoint does not say where its samples end");
  for (std::size_t a = 0; a < attributes.size(); ++a) {
    auto spool = std::make_unique<Spool>();
    spool->declaration = attributes[a].first;
    spool->path = folder / attributes[a].second;
    if (at) {
      std::error_code ec;
      const auto size = fs::file_size(spool->path, ec);
      if (ec || static_cast<long long>(size) < at->samples_bytes[a])
        throw SceneError(spool->path.string() + ": " +
                         (ec ? ec.message() : "shorter than the checkpoint says") +
                         ": the USD samples the checkpoint continues are not there");
      fs::resize_file(spool->path, static_cast<std::uintmax_t>(at->samples_bytes[a]), ec);
      if (ec) throw_output_error(spool->path, "cannot cut back", ec.value());
    }
    if (!at) ::unlink(spool->path.c_str());  // a new file, not one a link names
    spool->file = std::fopen(spool->path.c_str(), at ? "ab+" : "wb+");
    if (!spool->file || std::fseek(spool->file, 0, SEEK_END) != 0)
      throw_output_error(spool->path, "cannot open", errno);
    spools_.push_back(std::move(spool));
  }
}

CacheWriter::CacheWriter(const fs::path& dir, const Simulation& sim, ExportFormats formats,
                         UpAxis up, double fps)
    : dir_(dir), formats_(formats), up_(up), fps_(fps), model_(sim.model()) {
  const Model& m = model_;
  find_moving_obstacles();
  const std::vector<RigidPose> poses = obstacle_poses(m.params, sim.state().time);
  if (formats.pc2) {
    write_file_atomic(dir / "cloth_rest.obj", cloth_obj(m, sim.state(), up));
    for (auto [file, name] : {std::pair{&pc2_, kPc2}, std::pair{&pc2_fields_, kPc2Fields}}) {
      ::unlink((dir / name).c_str());  // a new file, not one a link names
      file->open(dir / name, std::ios::binary | std::ios::in | std::ios::out | std::ios::trunc);
      if (!*file) throw_output_error(dir / name, "cannot write", errno);
      write_pc2_header(*file, m.n, 0);
    }
    // A moving obstacle's own point cache over its own rest OBJ, as the cloth's.
    for (const std::size_t k : moving_) {
      const NamedMesh& mesh = meshes_[k];
      std::ostringstream o;
      o << "# wetcloth obstacle " << mesh.name << ", " << (up == UpAxis::Z ? "z" : "y")
        << " up, metres; obstacle_" << prims_[k] << ".pc2 moves it\no " << prims_[k] << "\n";
      for (const Vec3& x0 : mesh.points_at(sim.state().time)) {
        const Vec3 x = to_up(poses[k].to_world(x0), up);
        o << "v " << x.x() << " " << x.y() << " " << x.z() << "\n";
      }
      for (const auto& t : mesh.triangles)
        o << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
      write_file_atomic(dir / ("obstacle_" + prims_[k] + "_rest.obj"), o.str());
      const fs::path path = dir / ("obstacle_" + prims_[k] + ".pc2");
      ::unlink(path.c_str());
      auto file = std::make_unique<std::fstream>(
          path, std::ios::binary | std::ios::in | std::ios::out | std::ios::trunc);
      if (!*file) throw_output_error(path, "cannot write", errno);
      write_pc2_header(*file, static_cast<int>(mesh.points.size()), 0);
      obstacle_pc2_.push_back(std::move(file));
    }
  }
  if (formats.vtk) {
    if (std::error_code ec; fs::create_directories(dir / "vtk", ec), ec)
      throw_output_error(dir / "vtk", "cannot make the folder", ec.value());
    write_vtk_obstacles(dir / "vtk" / "obstacles.vtp", poses, sim.state().time);
  }
  if (formats.usd) open_usd_samples(nullptr);
}

void CacheWriter::find_moving_obstacles() {
  meshes_ = obstacle_meshes(model_);
  std::vector<std::string> names;
  for (const NamedMesh& mesh : meshes_) names.push_back(mesh.name);
  prims_ = prim_names(names);
  const std::vector<RigidPose> poses = obstacle_poses(model_.params, 0);
  for (std::size_t k = 0; k < poses.size(); ++k)
    if (poses[k].moving || meshes_[k].deforming) moving_.push_back(k);
}

void CacheWriter::write_vtk_obstacles(const fs::path& path, const std::vector<RigidPose>& poses,
                                      double t) {
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> tris;
  for (std::size_t k = 0; k < meshes_.size(); ++k) {
    const int base = static_cast<int>(points.size());
    for (const Vec3& x : meshes_[k].points_at(t))
      points.push_back(to_up(poses[k].to_world(x), up_));
    for (const auto& t : meshes_[k].triangles)
      tris.push_back({base + t[0], base + t[1], base + t[2]});
  }
  VtkArrays arrays;
  write_file_atomic(path, polydata(points, tris, "", arrays));
}

CacheWriter::CacheWriter(const fs::path& dir, const Simulation& sim, ExportFormats formats,
                         UpAxis up, double fps, const CachePosition& at,
                         const std::vector<double>& frame_times)
    : dir_(dir), formats_(formats), up_(up), fps_(fps), model_(sim.model()) {
  frames_ = at.frames;
  last_code_ = at.last_code;
  find_moving_obstacles();
  // A point cache cut back to the checkpoint's frames.
  const auto reopen = [&](std::fstream& file, const fs::path& path, int points) {
    const auto bytes = static_cast<std::uintmax_t>(32 + at.frames * 3LL * points * 4);
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec || size < bytes)
      throw SceneError(
          path.string() + ": " + (ec ? ec.message() : "shorter than the checkpoint says") +
          ": the " + std::to_string(at.frames) + " frames the checkpoint continues are not there");
    if (fs::resize_file(path, bytes, ec); ec)
      throw_output_error(path, "cannot cut back", ec.value());
    file.open(path, std::ios::binary | std::ios::in | std::ios::out);
    if (!file) throw_output_error(path, "cannot write", errno);
    write_pc2_header(file, points, at.frames);
    if (!file.flush()) throw_output_error(path, "cannot write", errno);
  };
  if (formats.pc2) {
    for (auto [file, name] : {std::pair{&pc2_, kPc2}, std::pair{&pc2_fields_, kPc2Fields}})
      reopen(*file, dir / name, model_.n);
    for (const std::size_t k : moving_) {
      obstacle_pc2_.push_back(std::make_unique<std::fstream>());
      reopen(*obstacle_pc2_.back(), dir / ("obstacle_" + prims_[k] + ".pc2"),
             static_cast<int>(meshes_[k].points.size()));
    }
  }
  if (formats.vtk) {
    if (static_cast<long long>(frame_times.size()) != at.frames)
      throw std::logic_error("CacheWriter: a frame time a frame kept");
    vtk_times_ = frame_times;
    write_pvd();
  }
  if (formats.usd) open_usd_samples(&at);
}

CachePosition CacheWriter::position(bool durable) {
  CachePosition p;
  p.frames = frames_;
  p.last_code = last_code_;
  if (formats_.pc2)
    for (auto [file, name] : {std::pair{&pc2_, kPc2}, std::pair{&pc2_fields_, kPc2Fields}}) {
      if (!file->flush()) throw_output_error(dir_ / name, "cannot write", errno);
      if (durable) sync_file(dir_ / name);
    }
  for (std::size_t q = 0; q < obstacle_pc2_.size(); ++q) {
    const fs::path path = dir_ / ("obstacle_" + prims_[moving_[q]] + ".pc2");
    if (!obstacle_pc2_[q]->flush()) throw_output_error(path, "cannot write", errno);
    if (durable) sync_file(path);
  }
  for (const auto& spool : spools_) {
    if (std::fflush(spool->file) != 0) throw_output_error(spool->path, "cannot write", errno);
    if (durable && ::fsync(fileno(spool->file)) != 0)
      throw_output_error(spool->path, "cannot write", errno);
    const long size = std::ftell(spool->file);
    if (size < 0) throw_output_error(spool->path, "cannot tell its size", errno);
    p.samples_bytes.push_back(size);
  }
  return p;
}

void CacheWriter::write_pvd() {
  // cloth.pvd; with moving obstacles, obstacles.pvd their frames the same way.
  for (const char* what : {"cloth", "obstacles"}) {
    const bool cloth = what[0] == 'c';
    if (!cloth && moving_.empty()) break;
    std::string pvd =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (std::size_t q = 0; q < vtk_times_.size(); ++q) {
      char line[128];
      std::snprintf(line, sizeof line, "<DataSet timestep=\"%.9g\" file=\"vtk/%s_%05zu.vtp\"/>\n",
                    vtk_times_[q], what, q);
      pvd += line;
    }
    write_file_atomic(dir_ / (std::string(what) + ".pvd"), pvd + "</Collection>\n</VTKFile>\n");
  }
}

CacheWriter::~CacheWriter() = default;

void CacheWriter::add_frame(const Simulation& sim, double frame_code) {
  if (finished_) throw std::logic_error("CacheWriter: a frame after finish()");
  const CacheFrame f = cache_frame(sim, up_);
  const long long k = frames_++;
  const std::vector<RigidPose> poses =
      moving_.empty() ? std::vector<RigidPose>{} : obstacle_poses(model_.params, f.time);
  if (formats_.pc2) {
    // cloth.pc2 the points; cloth_fields.pc2, its side file, each point's
    // (humidity ω, contact 0 or 1, pressure deficit p_atm - P_in in Pa).
    std::vector<float> xyz(3 * f.points.size()), fields(3 * f.points.size());
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      for (int q = 0; q < 3; ++q) xyz[3 * i + q] = static_cast<float>(f.points[i][q]);
      fields[3 * i] = f.humidity[i];
      fields[3 * i + 1] = f.contact[i];
      fields[3 * i + 2] = static_cast<float>(model_.params.air.p_atm - f.pressure[i]);
    }
    for (auto [file, name, values] :
         {std::tuple{&pc2_, kPc2, &xyz}, std::tuple{&pc2_fields_, kPc2Fields, &fields}}) {
      file->seekp(32 + k * static_cast<long long>(values->size() * sizeof(float)));
      file->write(reinterpret_cast<const char*>(values->data()),
                  static_cast<std::streamsize>(values->size() * sizeof(float)));
      write_pc2_header(*file, static_cast<int>(f.points.size()), k + 1);
      if (!file->flush()) throw_output_error(dir_ / name, "cannot write", errno);
    }
    for (std::size_t q = 0; q < moving_.size(); ++q) {
      const std::size_t o = moving_[q];
      std::vector<float> points;
      points.reserve(3 * meshes_[o].points.size());
      for (const Vec3& x0 : meshes_[o].points_at(f.time)) {
        const Vec3 x = to_up(poses[o].to_world(x0), up_);
        points.insert(points.end(), {static_cast<float>(x.x()), static_cast<float>(x.y()),
                                     static_cast<float>(x.z())});
      }
      std::fstream& file = *obstacle_pc2_[q];
      file.seekp(32 + k * static_cast<long long>(points.size() * sizeof(float)));
      file.write(reinterpret_cast<const char*>(points.data()),
                 static_cast<std::streamsize>(points.size() * sizeof(float)));
      write_pc2_header(file, static_cast<int>(meshes_[o].points.size()), k + 1);
      if (!file.flush())
        throw_output_error(dir_ / ("obstacle_" + prims_[o] + ".pc2"), "cannot write", errno);
    }
  }
  if (formats_.vtk) {
    if (!moving_.empty()) write_vtk_obstacles(dir_ / "vtk" / vtk_obstacles_name(k), poses, f.time);
    char name[32];
    std::snprintf(name, sizeof name, "cloth_%05lld.vtp", k);
    VtkArrays arrays;
    const std::string fields =
        "<PointData Scalars=\"contact\" Normals=\"normals\" TCoords=\"uv\">\n" +
        arrays.add("Float32", "normals", 3, components<float>(f.normals)) +
        arrays.add("Float32", "uv", 3, components<float>(uvs(model_))) +
        arrays.add("Float32", "contact", 1, f.contact) +
        arrays.add("Float32", "pressure_pa", 1, f.pressure) +
        arrays.add("Float32", "adhesion_n", 1, f.adhesion) +
        arrays.add("Float32", "humidity", 1, f.humidity) + "</PointData>\n";
    write_file_atomic(dir_ / "vtk" / name, polydata(f.points, model_.triangles, fields, arrays));
    vtk_times_.push_back(f.time);
    write_pvd();
  }
  if (formats_.usd) {
    Vec3 lo = f.points[0], hi = f.points[0];
    for (const Vec3& x : f.points) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const double code = frame_code >= 0 ? frame_code : f.time * fps_;
    last_code_ = code;
    spools_[0]->add(code, "[" + tuples(f.points) + "]");
    spools_[1]->add(code, "[" + tuples(f.normals) + "]");
    spools_[2]->add(code, "[" + tuples({lo, hi}) + "]");
    spools_[3]->add(code, "[" + join(f.contact, ", ") + "]");
    spools_[4]->add(code, "[" + join(f.pressure, ", ") + "]");
    spools_[5]->add(code, "[" + join(f.adhesion, ", ") + "]");
    spools_[6]->add(code, "[" + join(f.humidity, ", ") + "]");
    spools_[7]->add(code, "[" + tuples(f.velocities) + "]");
    std::vector<float> deficit(f.pressure.size());
    for (std::size_t i = 0; i < deficit.size(); ++i)
      deficit[i] = static_cast<float>(model_.params.air.p_atm - f.pressure[i]);
    spools_[8]->add(code, "[" + join(deficit, ", ") + "]");
    for (std::size_t q = 0; q < moving_.size(); ++q) {
      if (xform_spool_[q] >= 0)
        spools_[xform_spool_[q]]->add(code, usd_matrix(up_matrix(poses[moving_[q]], up_)));
      if (points_spool_[q] >= 0) {  // a deforming one's points, before its transform
        std::vector<Vec3> points;
        for (const Vec3& x : meshes_[moving_[q]].points_at(f.time)) points.push_back(to_up(x, up_));
        spools_[points_spool_[q]]->add(code, "[" + tuples(points) + "]");
      }
    }
  }
}

void CacheWriter::finish() {
  if (finished_) return;
  finished_ = true;
  if (!formats_.usd) return;
  const Model& m = model_;
  std::string o = "#usda 1.0\n(\n    defaultPrim = \"wetcloth\"\n    metersPerUnit = 1\n";
  o += std::string("    upAxis = \"") + (up_ == UpAxis::Z ? "Z" : "Y") + "\"\n";
  o += "    startTimeCode = 0\n    endTimeCode = ";
  // The last frame's time code (a run's last frame may fall between two).
  put(o, last_code_);
  o += "\n    timeCodesPerSecond = ";
  put(o, fps_);
  o += "\n    framesPerSecond = ";
  put(o, fps_);
  o += "\n    doc = \"wetcloth " WETCLOTH_VERSION ": " + m.params.name + "\"\n)\n\n";
  o += "def Xform \"wetcloth\"\n{\n    def Mesh \"cloth\"\n    {\n";
  o += "        uniform bool doubleSided = 1\n        uniform token subdivisionScheme = \"none\"\n";
  o += "        uniform token orientation = \"rightHanded\"\n";
  o += mesh_topology(m.triangles, "        ");
  std::string st;
  for (const Vec3& uv : uvs(m)) {
    st += st.empty() ? "(" : ", (";
    put(st, uv.x());
    st += ", ";
    put(st, uv.y());
    st += ")";
  }
  o += "        texCoord2f[] primvars:st = [" + st +
       "] (\n            interpolation = \"vertex\"\n        )\n";
  o += "        normal3f[] normals (\n            interpolation = \"vertex\"\n        )\n";
  // Each field's unit in its doc, as USD tools show it.
  for (const auto& [name, doc] :
       {std::pair{"contact", "1 where the vertex is within the liquid bridge of the surface"},
        {"pressure", "the trapped air's pressure under the vertex, Pa (p_atm where none)"},
        {"pressure_deficit", "p_atm - pressure: the suction under the vertex, Pa"},
        {"adhesion", "the liquid bridge's adhesion force on the vertex, N"},
        {"humidity", "the water saturation ω of the cloth at the vertex, 0 to 1"}})
    o += std::string("        float[] primvars:") + name + " (\n            doc = \"" + doc +
         "\"\n            interpolation = \"vertex\"\n        )\n";
  o += "        vector3f[] velocities (\n            doc = \"m/s\"\n        )\n";
  const fs::path path = dir_ / "cloth.usda", tmp = path.string() + ".tmp";
  const TemporaryFile record(tmp.string());  // a second signal removes it
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << o;
    for (std::size_t a = 0; a < std::size(kAttributes); ++a) {
      const auto& spool = spools_[a];
      out << "        " << spool->declaration << ".timeSamples = {\n";
      std::rewind(spool->file);
      char buf[1 << 16];
      for (std::size_t got; (got = std::fread(buf, 1, sizeof buf, spool->file)) > 0;)
        out.write(buf, static_cast<std::streamsize>(got));
      out << "        }\n";
    }
    out << "    }\n";
    // The obstacles: still ones where they stand; a moving one at its
    // placement before the motion, moved by its time-sampled transform
    // (written as the cloth's samples are, one a frame).
    std::size_t q = 0;
    for (std::size_t k = 0; k < meshes_.size(); ++k) {
      const NamedMesh& mesh = meshes_[k];
      std::vector<Vec3> points;
      for (const Vec3& x : mesh.points) points.push_back(to_up(x, up_));
      out << "\n    def Mesh \"" << prims_[k] << "\"\n    {\n"
          << mesh_topology(mesh.triangles, "        ") << "        point3f[] points = ["
          << tuples(points) << "]\n        uniform token subdivisionScheme = \"none\"\n";
      if (q < moving_.size() && moving_[q] == k) {
        for (const int a : {points_spool_[q], xform_spool_[q]}) {
          if (a < 0) continue;
          const Spool& spool = *spools_[a];
          out << "        " << spool.declaration << ".timeSamples = {\n";
          std::rewind(spool.file);
          char buf[1 << 16];
          for (std::size_t got; (got = std::fread(buf, 1, sizeof buf, spool.file)) > 0;)
            out.write(buf, static_cast<std::streamsize>(got));
          out << "        }\n";
        }
        if (xform_spool_[q] >= 0)
          out << "        uniform token[] xformOpOrder = [\"xformOp:transform\"]\n";
        ++q;
      }
      out << "    }\n";
    }
    out << "}\n";
    if (!out.flush()) {
      const int error = errno;
      out.close();
      fs::remove(tmp);
      throw_output_error(path, "cannot write", error);
    }
  }
  if (std::error_code ec; fs::rename(tmp, path, ec), ec) {
    fs::remove(tmp, ec);
    throw_output_error(path, "cannot rename " + tmp.string() + " to it", ec.value());
  }
}

void CacheWriter::remove_samples() {
  spools_.clear();
  if (std::error_code ec; fs::remove_all(dir_ / kSamples, ec), ec)
    throw_output_error(dir_ / kSamples, "cannot remove", ec.value());
}

}  // namespace wetcloth
