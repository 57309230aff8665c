#include "geometry/mesh_io.hpp"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>

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

// tinyobjloader reads `v 1,5 0 0` as 1, a face index `1.5` as 1 and
// 4294967297 as 1: every number of the v, vt, vn and f lines is read whole
// here first, and one that is not a number (or an index past an int) refused,
// named by its line.
void check_obj_numbers(const std::string& text, const std::string& source) {
  std::size_t line = 0;
  for (std::size_t at = 0; at < text.size();) {
    std::size_t end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    std::string_view rest(text.data() + at, end - at);
    at = end + 1;
    ++line;
    rest = rest.substr(0, rest.find('#'));
    std::vector<std::string_view> words;
    for (std::size_t i = 0; i < rest.size();) {
      if (rest[i] == ' ' || rest[i] == '\t' || rest[i] == '\r') {
        ++i;
        continue;
      }
      std::size_t j = i;
      while (j < rest.size() && rest[j] != ' ' && rest[j] != '\t' && rest[j] != '\r') ++j;
      words.push_back(rest.substr(i, j - i));
      i = j;
    }
    if (words.empty()) continue;
    const auto fail = [&](std::string_view word, const char* what) {
      throw SceneError(source + ":" + std::to_string(line) + ": `" + std::string(word) +
                       "` is not " + what);
    };
    if (words[0] == "v" || words[0] == "vt" || words[0] == "vn") {
      for (std::size_t w = 1; w < words.size(); ++w) {
        std::string_view word = words[w];
        if (word.size() > 1 && word[0] == '+') word.remove_prefix(1);
        double v = 0;
        const auto [ptr, error] = std::from_chars(word.data(), word.data() + word.size(), v);
        if (ptr != word.data() + word.size() || (error != std::errc() && ptr == word.data()))
          fail(words[w], "a number");
        if (error != std::errc()) fail(words[w], "a finite number");  // 1e999
      }
    } else if (words[0] == "f") {
      for (std::size_t w = 1; w < words.size(); ++w) {
        std::string_view corner = words[w];
        for (int part = 0; !corner.empty() || part == 0; ++part) {
          const std::size_t slash = corner.find('/');
          const std::string_view index = corner.substr(0, slash);
          corner = slash == std::string_view::npos ? std::string_view() : corner.substr(slash + 1);
          if (part > 2) fail(words[w], "a face corner (v, v/vt, v//vn or v/vt/vn)");
          if (index.empty() && part == 1) continue;  // v//vn
          int v = 0;
          const auto [ptr, error] = std::from_chars(index.data(), index.data() + index.size(), v);
          if (index.empty() || error != std::errc() || ptr != index.data() + index.size() || v == 0)
            fail(words[w], "a face corner of whole 1-based indices (v, v/vt, v//vn or v/vt/vn)");
          if (slash == std::string_view::npos) break;
        }
      }
    }
  }
}

}  // namespace

TriangleMesh read_obj(const std::string& text, const std::string& source, const MeshRules& rules) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // quads are kept, for their diagonals' shear springs
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  check_obj_numbers(text, source);
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
  // A link that loops (or a path too long) is the path's fault, named as such.
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(fs::path(p.scene_dir), ec);
  if (ec) fail("cannot be followed from the scene's folder (" + ec.message() + ")");
  const fs::path full = fs::weakly_canonical(dir / normal, ec);
  if (ec) fail("cannot be followed (" + ec.message() + ")");
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
  if (const auto st = fs::status(where, ec); !fs::is_regular_file(st))
    throw SceneError("Params: " + key + ": " + where.string() + ": " +
                     (fs::exists(st) ? "not a regular file (a folder, FIFO or device)"
                      : ec && ec != std::errc::no_such_file_or_directory ? ec.message()
                                                                         : "no such file"));
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
