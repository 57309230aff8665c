#include "geometry/mesh_io.hpp"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "wetcloth/scene.hpp"

namespace wetcloth {

const std::vector<BuiltinScene>& builtin_mesh_texts();  // builtin_scenes.cpp, generated

namespace fs = std::filesystem;

namespace {

// A mesh file larger than this is not one a cloth scene means (a 1000 × 1000
// grid's OBJ is about 60 MB).
constexpr std::uintmax_t kMaxMeshBytes = 256u << 20;

double twice_area(const std::array<double, 3>& a, const std::array<double, 3>& b,
                  const std::array<double, 3>& c) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]};
  return std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

// Every edge is used by at most two triangles.
void check_manifold(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> uses;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const int a = m.triangles[t][e], b = m.triangles[t][(e + 1) % 3];
      if (++uses[{std::min(a, b), std::max(a, b)}] > 2)
        throw SceneError(m.source + ": not a manifold mesh: the edge between vertices " +
                         std::to_string(std::min(a, b) + 1) + " and " +
                         std::to_string(std::max(a, b) + 1) +
                         " is shared by more than two faces (face " + std::to_string(t + 1) + ")");
    }
}

}  // namespace

TriangleMesh read_obj(const std::string& text, const std::string& source, const MeshRules& rules) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // quads are kept, for their diagonals' shear springs
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(text, "", config))
    throw SceneError(source + ": not an OBJ file: " + reader.Error());
  const auto& attrib = reader.GetAttrib();
  TriangleMesh m;
  m.source = source;
  const std::size_t nv = attrib.vertices.size() / 3;
  m.position.resize(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) {
      m.position[i][k] = attrib.vertices[3 * i + k];
      if (!std::isfinite(m.position[i][k]))
        throw SceneError(source + ": vertex " + std::to_string(i + 1) +
                         " has a coordinate that is not a finite number");
    }
  }
  const std::size_t nt = attrib.texcoords.size() / 2;
  bool any_uv = false, all_uv = true;
  std::vector<std::uint8_t> has_uv(nv, 0);
  for (const auto& shape : reader.GetShapes()) {
    std::size_t at = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
      const int count = shape.mesh.num_face_vertices[f];
      const std::string face = "face " + std::to_string(m.triangles.size() + 1);
      if (count < 3) throw SceneError(source + ": " + face + " has fewer than three vertices");
      std::vector<int> vi(count);
      std::vector<std::array<double, 2>> vt(count, {0, 0});
      for (int c = 0; c < count; ++c) {
        const auto& idx = shape.mesh.indices[at + c];
        if (idx.vertex_index < 0 || static_cast<std::size_t>(idx.vertex_index) >= nv)
          throw SceneError(source + ": " + face + " names a vertex that is not in the file");
        vi[c] = idx.vertex_index;
        if (idx.texcoord_index >= 0 && static_cast<std::size_t>(idx.texcoord_index) < nt) {
          vt[c] = {attrib.texcoords[2 * idx.texcoord_index],
                   attrib.texcoords[2 * idx.texcoord_index + 1]};
          any_uv = true;
        } else {
          all_uv = false;
        }
      }
      at += count;
      if (count == 4) m.quads.push_back({vi[0], vi[1], vi[2], vi[3]});
      for (int c = 1; c + 1 < count; ++c) {  // a fan from the first corner
        const std::array<int, 3> t = {vi[0], vi[c], vi[c + 1]};
        const std::string name = "face " + std::to_string(f + 1);
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
          throw SceneError(source + ": " + name + " is degenerate: it repeats a vertex");
        if (!(twice_area(m.position[t[0]], m.position[t[1]], m.position[t[2]]) > 0))
          throw SceneError(source + ": " + name + " is degenerate: its area is zero");
        m.triangles.push_back(t);
        m.corner_uv.push_back({vt[0], vt[c], vt[c + 1]});
      }
      for (int c = 0; c < count; ++c) {
        if (has_uv[vi[c]]) continue;
        has_uv[vi[c]] = 1;
        if (m.uv.empty()) m.uv.assign(nv, {0, 0});
        m.uv[vi[c]] = vt[c];
      }
    }
  }
  if (m.triangles.empty())
    throw SceneError(source + ": no faces (is it an OBJ file with `f` lines?)");
  if (!any_uv || !all_uv) {  // partial coordinates are none
    m.uv.clear();
    m.corner_uv.clear();
  }
  if (rules.manifold) check_manifold(m);
  return m;
}

fs::path resolve_scene_path(const Params& p, const std::string& key, const std::string& path) {
  const auto fail = [&](const std::string& why) {
    throw SceneError("Params: " + key + ": \"" + path + "\" " + why);
  };
  if (path.empty()) fail("is empty: name a mesh file");
  const fs::path given(path);
  if (given.is_absolute()) fail("is absolute: a scene names its files relative to its own folder");
  const fs::path normal = given.lexically_normal();
  if (!normal.empty() && *normal.begin() == "..")
    fail("leaves the scene file's folder: a scene may only name files in its folder or below");
  if (p.scene_dir == "builtin:") return fs::path("builtin:") / normal;
  const fs::path dir = fs::weakly_canonical(fs::path(p.scene_dir));
  const fs::path full = fs::weakly_canonical(dir / normal);
  // Through a symbolic link out of the folder is leaving it too.
  const auto [d, f] = std::mismatch(dir.begin(), dir.end(), full.begin(), full.end());
  if (d != dir.end()) fail("leads out of the scene file's folder " + dir.string());
  return full;
}

std::string scene_file_text(const Params& p, const std::string& key, const std::string& path) {
  const fs::path where = resolve_scene_path(p, key, path);
  if (p.scene_dir == "builtin:") {
    const std::string name = fs::path(path).lexically_normal().generic_string();
    for (const auto& b : builtin_mesh_texts())
      if (b.name == name) return b.text;
    throw SceneError("Params: " + key + ": \"" + path + "\" is not a built-in mesh");
  }
  std::error_code ec;
  if (!fs::is_regular_file(where, ec))
    throw SceneError("Params: " + key + ": " + where.string() + ": no such file");
  if (fs::file_size(where, ec) > kMaxMeshBytes)
    throw SceneError("Params: " + key + ": " + where.string() + ": larger than " +
                     std::to_string(kMaxMeshBytes >> 20) + " MB: not a cloth scene's mesh");
  std::ifstream in(where, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw SceneError("Params: " + key + ": " + where.string() + ": cannot read the file");
  return text.str();
}

TriangleMesh load_scene_mesh(const Params& p, const std::string& key, const std::string& path,
                             const MeshRules& rules) {
  const std::string text = scene_file_text(p, key, path);
  if (p.scene_dir == "builtin:")
    return read_obj(text, "scenes/" + fs::path(path).lexically_normal().generic_string(), rules);
  return read_obj(text, resolve_scene_path(p, key, path).string(), rules);
}

}  // namespace wetcloth
