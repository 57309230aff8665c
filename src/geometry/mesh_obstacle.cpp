// Obstacles made of triangle meshes: read, transformed, checked, and queried
// for the signed distance through a CGAL AABB tree (docs/model.md section 3).
#include "geometry/mesh_obstacle.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "detail.hpp"
#include "geometry/mesh_io.hpp"
#include "wetcloth/motion.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace {
using K = CGAL::Simple_cartesian<double>;
using Triangle3 = K::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Triangle3>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
}  // namespace

struct MeshObstacle::Geometry {
  std::vector<Triangle3> cgal_triangles;  // the tree points into it: never moved
  Tree tree;
  std::vector<Vec3> face_normal, edge_normal, vertex_normal;  // unit pseudo-normals
  std::vector<std::array<int, 3>> face_edges;  // edge e of a triangle: vertices e, e + 1
};

namespace {

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw SceneError(key + ": " + what);
}

// The point of triangle (a, b, c) closest to x, after Ericson (Real-Time
// Collision Detection, 5.1.5), and where it lies: on a vertex (0, 1, 2), an
// edge (3 + e for the edge from corner e to e + 1) or inside (6). On an edge
// or a vertex the point is computed from the edge's or vertex's own points,
// in index order, so that both triangles that share it give the same bits.
struct Closest {
  Vec3 point;
  int feature = 6;
};
Closest closest_on_triangle(const Vec3& x, const std::array<int, 3>& t,
                            const std::vector<Vec3>& pts) {
  const Vec3 &a = pts[t[0]], &b = pts[t[1]], &c = pts[t[2]];
  const auto on_edge = [&](int e) {
    int i = t[e], j = t[(e + 1) % 3];
    if (i > j) std::swap(i, j);
    const Vec3 d = pts[j] - pts[i];
    const double s = std::clamp((x - pts[i]).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return Closest{pts[i] + s * d, 3 + e};
  };
  const Vec3 ab = b - a, ac = c - a, ap = x - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, 0};
  const Vec3 bp = x - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return on_edge(0);
  const Vec3 cp = x - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return on_edge(2);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return on_edge(1);
  const double denom = 1 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), 6};
}

}  // namespace

MeshObstacle::Hit MeshObstacle::query_within(const Vec3& x, double bound) const {
  const Geometry& g = *geometry;
  const K::Point_3 q(x.x(), x.y(), x.z());
  // The hint: a point `bound` away that is on no triangle, with the first
  // triangle: the search keeps only triangles strictly nearer.
  const K::Point_3 hint(x.x() + bound, x.y(), x.z());
  const auto found = g.tree.closest_point_and_primitive(q, {hint, g.cgal_triangles.begin()});
  Hit h;
  if (found.first == hint) return h;  // nothing within the bound
  const int t = static_cast<int>(found.second - g.cgal_triangles.begin());
  const Closest c = closest_on_triangle(x, triangles[t], points);
  const Vec3 away = x - c.point;
  const double u = away.norm();
  h.unsigned_distance = u;
  h.triangle = t;
  h.point = c.point;
  if (!closed) {
    h.distance = u - half_thickness;
    h.normal = u > 0 ? Vec3(away / u) : g.face_normal[t];
    return h;
  }
  const Vec3& pseudo = c.feature < 3   ? g.vertex_normal[triangles[t][c.feature]]
                       : c.feature < 6 ? g.edge_normal[g.face_edges[t][c.feature - 3]]
                                       : g.face_normal[t];
  const bool inside = away.dot(pseudo) < 0;
  h.distance = inside ? -u : u;
  h.normal = u > 0 ? Vec3((inside ? -1.0 : 1.0) * away / u) : pseudo;
  return h;
}

namespace {

// Whether the mesh is closed (no edge on one triangle only), its faces turned
// outward if it is; throws where its faces disagree on their orientation or
// its thickness does not suit it.
void check_orientation(MeshObstacle& o, const ObstacleParams& op, const std::string& name,
                       const std::string& key, const std::string& source) {
  // Edges: each triangle's, with the triangles on them and their direction.
  std::map<std::pair<int, int>, std::vector<std::pair<int, bool>>> edges;  // (t, from low)
  for (std::size_t t = 0; t < o.triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const int a = o.triangles[t][e], b = o.triangles[t][(e + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({static_cast<int>(t), a < b});
    }
  std::size_t open_edges = 0;
  for (const auto& [ends, on] : edges) {
    if (on.size() == 1) ++open_edges;
    if (on.size() == 2 && on[0].second == on[1].second)
      fail(key, source + ": triangles " + std::to_string(on[0].first + 1) + " and " +
                    std::to_string(on[1].first + 1) +
                    " face opposite ways across their shared edge (vertices " +
                    std::to_string(ends.first + 1) + " and " + std::to_string(ends.second + 1) +
                    "): orient the mesh's faces consistently");
  }
  o.closed = open_edges == 0;
  const std::string thickness_key = "obstacle." + name + ".thickness";
  if (!o.closed && op.thickness <= 0)
    fail(thickness_key, source + " is open (" + std::to_string(open_edges) +
                            " edges on one triangle only): it has no inside, so give it a "
                            "thickness > 0 (a shell about the surface), or close the mesh");
  if (o.closed && op.thickness > 0)
    fail(thickness_key, source +
                            " is closed: its inside is the obstacle, and a thickness would do "
                            "nothing (set it to 0)");
  o.half_thickness = op.thickness / 2;
  if (o.closed) {  // outward: a positive volume, or every triangle turned
    double volume = 0;
    for (const auto& t : o.triangles)
      volume += o.points[t[0]].dot(o.points[t[1]].cross(o.points[t[2]])) / 6;
    if (volume < 0)
      for (auto& t : o.triangles) std::swap(t[1], t[2]);
  }
}

// The face normals, the angle-weighted vertex normals; throws on a triangle
// with no area.
void add_normals(const MeshObstacle& o, MeshObstacle::Geometry& g, const std::string& name,
                 const std::string& key, const std::string& source) {
  const std::size_t nt = o.triangles.size();
  g.face_normal.resize(nt);
  g.vertex_normal.assign(o.points.size(), Vec3::Zero());
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tr = o.triangles[t];
    const Vec3 &a = o.points[tr[0]], &b = o.points[tr[1]], &c = o.points[tr[2]];
    const Vec3 n = (b - a).cross(c - a);
    if (!(n.norm() > 0))
      fail(key, source + ": triangle " + std::to_string(t + 1) +
                    " has no area once transformed (obstacle." + name + ".scale)");
    g.face_normal[t] = n.normalized();
    for (int e = 0; e < 3; ++e) {  // angle-weighted vertex normals
      const Vec3 u = (o.points[tr[(e + 1) % 3]] - o.points[tr[e]]).normalized();
      const Vec3 v = (o.points[tr[(e + 2) % 3]] - o.points[tr[e]]).normalized();
      g.vertex_normal[tr[e]] += std::acos(std::clamp(u.dot(v), -1.0, 1.0)) * g.face_normal[t];
    }
  }
  for (auto& n : g.vertex_normal) n.normalize();
}

// The pseudo-normals of a reshaped mesh (the edges as they were): a
// triangle that has lost its area keeps its last normal.
void renew_normals(const MeshObstacle& o, MeshObstacle::Geometry& g) {
  std::fill(g.vertex_normal.begin(), g.vertex_normal.end(), Vec3::Zero());
  std::fill(g.edge_normal.begin(), g.edge_normal.end(), Vec3::Zero());
  for (std::size_t t = 0; t < o.triangles.size(); ++t) {
    const auto& tr = o.triangles[t];
    const Vec3 &a = o.points[tr[0]], &b = o.points[tr[1]], &c = o.points[tr[2]];
    const Vec3 n = (b - a).cross(c - a);
    if (n.norm() > 0) g.face_normal[t] = n.normalized();
    for (int e = 0; e < 3; ++e) {
      const Vec3 u = (o.points[tr[(e + 1) % 3]] - o.points[tr[e]]).normalized();
      const Vec3 v = (o.points[tr[(e + 2) % 3]] - o.points[tr[e]]).normalized();
      g.vertex_normal[tr[e]] += std::acos(std::clamp(u.dot(v), -1.0, 1.0)) * g.face_normal[t];
      g.edge_normal[g.face_edges[t][e]] += g.face_normal[t];
    }
  }
  for (auto& n : g.vertex_normal) n.normalize();
  for (auto& n : g.edge_normal) n.normalize();
}

// Each triangle's edges, and each edge's normal: the mean of its faces'.
void add_edge_normals(const MeshObstacle& o, MeshObstacle::Geometry& g) {
  const std::size_t nt = o.triangles.size();
  std::map<std::pair<int, int>, int> edge_index;
  g.face_edges.resize(nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int e = 0; e < 3; ++e) {
      const int a = o.triangles[t][e], b = o.triangles[t][(e + 1) % 3];
      const auto [it, fresh] = edge_index.emplace(std::pair{std::min(a, b), std::max(a, b)},
                                                  static_cast<int>(g.edge_normal.size()));
      if (fresh) g.edge_normal.push_back(Vec3::Zero());
      g.edge_normal[it->second] += g.face_normal[t];
      g.face_edges[t][e] = it->second;
    }
  for (auto& n : g.edge_normal) n.normalize();
}

// obstacle.NAME.cache: a PC2 file (Blender's, Houdini's: "POINTCACHE2\0",
// version 1, points, start frame, sample rate in frames, samples; then
// float32 x, y, z per point per sample) or an OBJ sequence, every frame as
// many vertices as `rest` (and a sequence's files its faces), placed as the
// mesh's points.
std::shared_ptr<MeshObstacle::Cache> load_cache(const Params& p, const ObstacleParams& op,
                                                const std::string& name, const TriangleMesh& rest) {
  const std::string key = "obstacle." + name + ".cache";
  const std::size_t n = rest.position.size();
  auto c = std::make_shared<MeshObstacle::Cache>();
  const auto place = [&](const auto& file_points) {
    std::vector<Vec3> frame;
    frame.reserve(n);
    for (const auto& q : file_points) frame.push_back(place_obstacle_point(op, to_vec(q)));
    c->frames.push_back(std::move(frame));
  };
  const auto count_error = [&](const std::string& file, std::size_t has) {
    fail(key, file + " has " + std::to_string(has) + " vertices a frame, and obstacle." + name +
                  ".mesh (" + rest.source + ") has " + std::to_string(n) +
                  ": a cache moves the mesh's own vertices, in its order");
  };
  const std::string& path = op.cache;
  const std::size_t hash = path.find('#');
  if (hash == std::string::npos) {  // a PC2 file
    const std::filesystem::path where = resolve_scene_path(p, key, path);
    const std::string file = where.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(where, ec)) fail(key, file + ": no such file");
    std::ifstream in(where, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    const std::string data = bytes.str();
    if (data.size() < 32 || std::memcmp(data.data(), "POINTCACHE2", 12) != 0)
      fail(key, file + ": not a PC2 file (it does not start with POINTCACHE2)");
    // (Its start frame is not used: cache_start says when sample 0 is.)
    std::int32_t points, samples;
    float rate;
    std::memcpy(&points, data.data() + 16, 4);
    std::memcpy(&rate, data.data() + 24, 4);
    std::memcpy(&samples, data.data() + 28, 4);
    if (points < 0 || static_cast<std::size_t>(points) != n)
      count_error(file, static_cast<std::size_t>(std::max(points, 0)));
    if (samples < 1) fail(key, file + ": holds no frames");
    if (!(rate > 0) || !std::isfinite(rate))
      fail(key, file + ": its sample rate is not a number of frames above 0");
    const std::size_t want = 32 + 12 * n * static_cast<std::size_t>(samples);
    if (data.size() != want)
      fail(key, file + ": " + std::to_string(data.size()) + " bytes where its header (" +
                    std::to_string(points) + " points, " + std::to_string(samples) +
                    " samples) says " + std::to_string(want));
    c->source = file;
    c->step = static_cast<double>(rate) / op.cache_fps;
    for (std::int32_t k = 0; k < samples; ++k) {
      std::vector<std::array<double, 3>> frame(n);
      for (std::size_t i = 0; i < n; ++i) {
        float x[3];
        std::memcpy(x, data.data() + 32 + (static_cast<std::size_t>(k) * n + i) * 12, 12);
        for (int q = 0; q < 3; ++q) {
          if (!std::isfinite(x[q]))
            fail(key, file + ": sample " + std::to_string(k) + ", point " + std::to_string(i) +
                          " is not finite");
          frame[i][static_cast<std::size_t>(q)] = x[q];
        }
      }
      place(frame);
    }
  } else {  // an OBJ sequence
    const std::vector<std::string> files = obstacle_cache_files(p, name);
    for (std::size_t k = 0; k < files.size(); ++k) {
      const TriangleMesh frame = load_scene_mesh(p, key, files[k], MeshRules{false});
      if (frame.position.size() != n) count_error(frame.source, frame.position.size());
      if (frame.triangles != rest.triangles)
        fail(key, frame.source + ": its faces are not obstacle." + name + ".mesh's (" +
                      rest.source + "): a cache moves the mesh's vertices, not its faces");
      if (k == 0) c->source = frame.source;
      place(frame.position);
    }
    c->step = 1 / op.cache_fps;
  }
  c->start = op.cache_start;
  return c;
}

}  // namespace

std::vector<std::string> obstacle_cache_files(const Params& p, const std::string& name) {
  const std::string key = "obstacle." + name + ".cache";
  const std::string& path = p.obstacles.at(name).cache;
  const std::size_t hash = path.find('#');
  if (hash == std::string::npos) return {path};
  const std::size_t width = path.find_first_not_of('#', hash) - hash;
  const std::string head = path.substr(0, hash), tail = path.substr(hash + width);
  const std::filesystem::path pattern = resolve_scene_path(p, key, path);
  const std::string file = pattern.filename().string();
  const std::string prefix = file.substr(0, file.find('#'));
  const std::string suffix = file.substr(file.find_last_of('#') + 1);
  const auto name_of = [&](long long k) {
    char digits[32];
    std::snprintf(digits, sizeof digits, "%0*lld", static_cast<int>(width), k);
    return head + digits + tail;
  };
  std::vector<long long> numbers;
  std::error_code ec;
  if (p.scene_dir != "builtin:")
    for (const auto& entry : std::filesystem::directory_iterator(pattern.parent_path(), ec)) {
      const std::string f = entry.path().filename().string();
      if (f.size() <= prefix.size() + suffix.size() || f.compare(0, prefix.size(), prefix) != 0 ||
          f.compare(f.size() - suffix.size(), suffix.size(), suffix) != 0)
        continue;
      const std::string digits = f.substr(prefix.size(), f.size() - prefix.size() - suffix.size());
      if (digits.size() > 12 || digits.find_first_not_of("0123456789") != std::string::npos)
        continue;
      const long long k = std::stoll(digits);
      if (name_of(k) == head + digits + tail) numbers.push_back(k);
    }
  std::sort(numbers.begin(), numbers.end());
  if (numbers.empty())
    fail(key, pattern.string() + ": no such files (# stands for the zero-padded frame number)");
  std::vector<std::string> files;
  for (std::size_t k = 0; k < numbers.size(); ++k) {
    const long long want = numbers[0] + static_cast<long long>(k);
    if (numbers[k] != want)
      fail(key, resolve_scene_path(p, key, name_of(want)).string() +
                    ": no such file, and the sequence goes on after it (frame " +
                    std::to_string(numbers[k]) + ")");
    files.push_back(name_of(want));
  }
  return files;
}

void sample_cache(const MeshObstacle::Cache& c, double t, std::vector<Vec3>& points,
                  std::vector<Vec3>& velocity) {
  const std::size_t last = c.frames.size() - 1, n = c.frames[0].size();
  const double s = (t - c.start) / c.step;  // in frames
  velocity.assign(n, Vec3::Zero());
  if (!(s > 0) || last == 0) {
    points = c.frames[0];
    return;
  }
  if (s >= static_cast<double>(last)) {
    points = c.frames[last];
    return;
  }
  const auto k = static_cast<std::size_t>(s);  // the interval [k, k + 1) that holds s
  const double f = s - static_cast<double>(k);
  const std::vector<Vec3>&a = c.frames[k], &b = c.frames[k + 1];
  points.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = b[i] - a[i];
    points[i] = a[i] + f * d;
    velocity[i] = d / c.step;
  }
}

std::shared_ptr<MeshObstacle> deformable_copy(const MeshObstacle& o) {
  auto copy = std::make_shared<MeshObstacle>(o);
  auto g = std::make_shared<MeshObstacle::Geometry>();
  g->cgal_triangles = o.geometry->cgal_triangles;
  g->face_normal = o.geometry->face_normal;
  g->edge_normal = o.geometry->edge_normal;
  g->vertex_normal = o.geometry->vertex_normal;
  g->face_edges = o.geometry->face_edges;
  g->tree.insert(g->cgal_triangles.begin(), g->cgal_triangles.end());
  g->tree.build();
  copy->geometry = std::move(g);
  return copy;
}

void reshape(MeshObstacle& o, double t) {
  if (!o.cache || o.time == t) return;
  std::vector<Vec3> points;
  sample_cache(*o.cache, t, points, o.velocity);
  double farthest = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    farthest = std::max(farthest, (points[i] - o.points[i]).norm());
  o.time = t;
  if (farthest == 0) return;  // held: the same shape
  o.travel += farthest;
  o.points = std::move(points);
  // The copy made its own geometry (deformable_copy): no one else reads it.
  auto& g = const_cast<MeshObstacle::Geometry&>(*o.geometry);
  renew_normals(o, g);
  o.lo = o.hi = o.points.front();
  for (const Vec3& x : o.points) o.lo = o.lo.cwiseMin(x), o.hi = o.hi.cwiseMax(x);
  for (std::size_t t3 = 0; t3 < o.triangles.size(); ++t3) {
    const auto pt = [&](int k) {
      const Vec3& x = o.points[o.triangles[t3][k]];
      return K::Point_3(x.x(), x.y(), x.z());
    };
    g.cgal_triangles[t3] = Triangle3(pt(0), pt(1), pt(2));
  }
  g.tree.clear();
  g.tree.insert(g.cgal_triangles.begin(), g.cgal_triangles.end());
  g.tree.build();
}

Vec3 surface_velocity_at(const MeshObstacle& o, const MeshObstacle::Hit& h) {
  if (o.velocity.empty() || h.triangle < 0) return Vec3::Zero();
  const auto& tr = o.triangles[h.triangle];
  const Vec3 &a = o.points[tr[0]], &b = o.points[tr[1]], &c = o.points[tr[2]];
  // Barycentric coordinates of the closest point (Ericson 3.4).
  const Vec3 v0 = b - a, v1 = c - a, v2 = h.point - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1);
  const double d20 = v2.dot(v0), d21 = v2.dot(v1), denom = d00 * d11 - d01 * d01;
  if (!(denom > 0)) return (o.velocity[tr[0]] + o.velocity[tr[1]] + o.velocity[tr[2]]) / 3;
  const double v = (d11 * d20 - d01 * d21) / denom, w = (d00 * d21 - d01 * d20) / denom;
  return (1 - v - w) * o.velocity[tr[0]] + v * o.velocity[tr[1]] + w * o.velocity[tr[2]];
}

std::shared_ptr<const MeshObstacle> build_mesh_obstacle(const Params& p, const std::string& name) {
  const ObstacleParams& op = p.obstacles.at(name);
  const std::string key = "obstacle." + name + ".mesh";
  TriangleMesh mesh;
  try {
    mesh = load_scene_mesh(p, key, op.mesh, MeshRules{true});
  } catch (const SceneError& e) {
    const std::string what = e.what();
    if (what.find(key) != std::string::npos) throw;
    fail(key, what);
  }
  auto o = std::make_shared<MeshObstacle>();
  o->name = name;
  o->source = mesh.source;
  // Where its keys place it: a moving obstacle's body frame (wetcloth/motion.hpp).
  for (const auto& q : mesh.position) o->points.push_back(place_obstacle_point(op, to_vec(q)));
  o->triangles = mesh.triangles;
  if (!op.cache.empty()) {
    const std::string cache_key = "obstacle." + name + ".cache";
    try {
      o->cache = load_cache(p, op, name, mesh);
    } catch (const SceneError& e) {  // a frame's own fault (read_obj's) names the key too
      std::string what = e.what();
      if (what.rfind("Params: ", 0) == 0) what.erase(0, 8);
      if (what.rfind(cache_key, 0) == 0) throw SceneError(what);
      fail(cache_key, what);
    }
  }
  check_orientation(*o, op, name, key, mesh.source);
  auto g = std::make_shared<MeshObstacle::Geometry>();
  add_normals(*o, *g, name, key, mesh.source);
  add_edge_normals(*o, *g);
  o->lo = o->hi = o->points.front();
  for (const Vec3& x : o->points) o->lo = o->lo.cwiseMin(x), o->hi = o->hi.cwiseMax(x);
  for (const auto& t : o->triangles) {
    const auto pt = [&](int k) {
      const Vec3& x = o->points[t[k]];
      return K::Point_3(x.x(), x.y(), x.z());
    };
    g->cgal_triangles.emplace_back(pt(0), pt(1), pt(2));
  }
  g->tree.insert(g->cgal_triangles.begin(), g->cgal_triangles.end());
  g->tree.build();  // now, not at the first query: queries run on many threads
  o->geometry = std::move(g);
  return o;
}

void check_obstacle_meshes(const Params& p, const std::string& source,
                           const std::function<std::string(const std::string&)>& line_of) {
  // Where the cloth starts: the grid's points, or a mesh cloth's vertices
  // (check_cloth_mesh has read its file).
  std::vector<Vec3> start, turned;  // turned: the mesh cloth read with the other up axis
  if (!p.obstacles.empty() && p.cloth.mesh.empty()) {
    for (int j = 0; j < p.cloth.resolution[1]; ++j)
      for (int i = 0; i < p.cloth.resolution[0]; ++i)
        start.push_back(cloth_start_position(p, i, j));
  } else if (!p.obstacles.empty()) {
    const TriangleMesh mesh = load_scene_mesh(p, "cloth.mesh", p.cloth.mesh);
    start = mesh_cloth_positions(p, mesh);
    Params other = p;
    other.cloth.up = p.cloth.up == UpAxis::Z ? UpAxis::Y : UpAxis::Z;
    turned = mesh_cloth_positions(other, mesh);
    if (!p.cloth.placed()) {  // placed by its bounding box's centre: that one's too
      Vec3 lo = turned.front(), hi = lo;
      for (const Vec3& x : turned) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
      const Vec3 shift = to_vec(p.cloth.center) - 0.5 * (lo + hi);
      for (Vec3& x : turned) x += shift;
    }
  }
  for (const auto& [name, op] : p.obstacles) {
    std::shared_ptr<const MeshObstacle> o;
    try {
      o = build_mesh_obstacle(p, name);
    } catch (const SceneError& e) {
      std::string what = e.what();
      if (what.rfind("Params: ", 0) == 0) what.erase(0, 8);
      const std::string cache_key = "obstacle." + name + ".cache";
      const std::string line =
          line_of && what.rfind(cache_key + ":", 0) == 0 ? line_of(cache_key) : "";
      throw SceneError(source + line + ": " + what);
    }
    // A cloth that starts inside the obstacle would be flung out at the first
    // step: where a moving one is at t = 0, in its body frame, a deforming
    // one in its shape then.
    if (o->cache) {
      auto shaped = deformable_copy(*o);
      reshape(*shaped, 0.0);
      o = shaped;
    }
    const RigidPose pose = obstacle_pose(p, name, 0.0);
    const auto deepest_of = [&](const std::vector<Vec3>& points) {
      double deepest = 0;
      for (const Vec3& x_world : points) {
        const Vec3 x = pose.to_body(x_world);
        if ((x.array() < o->lo.array() - o->half_thickness).any() ||
            (x.array() > o->hi.array() + o->half_thickness).any())
          continue;  // outside its box
        deepest = std::min(deepest, o->query(x).distance);
      }
      return deepest;
    };
    const double deepest = deepest_of(start);
    if (deepest < -1e-9) {
      char mm[32];
      std::snprintf(mm, sizeof mm, "%.3g", -deepest * 1000);
      // A garment from a y-up tool (Blender) lies on its side in a z-up
      // world: say so when the other up axis would have kept it outside.
      std::string axis;
      if (!turned.empty() && deepest_of(turned) >= -1e-9) {
        const char* other = p.cloth.up == UpAxis::Z ? "y" : "z";
        axis = std::string(". The file seems to be ") + other + "-up: with cloth.up = \"" + other +
               "\" the cloth would start outside it";
      }
      throw SceneError(
          source + ": cloth.center: the cloth starts " + std::string(mm) + " mm inside obstacle." +
          name + " (cloth.center, cloth.tilt, cloth.up, " + "cloth.translate, obstacle." + name +
          ".translate" +
          (p.obstacles.at(name).motion.moves() ? ", obstacle." + name + ".motion" : "") +
          (o->cache ? ", obstacle." + name + ".cache" : "") + ")" + axis);
    }
  }
}

namespace detail {

MeshObstacle::Hit query_mesh(const MeshObstacle& o, const Vec3& x, double reach,
                             MeshQueryCache* cache, int i) {
  constexpr double kMargin = 1e-9;  // m: more than the rounding of a distance
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo = -kInf, hi = kInf;
  if (cache) {
    // A deforming mesh has moved by at most its travel since: the bounds
    // were stored less (lo) or more (hi) the travel then.
    const double dx = x.x() - cache->x[i], dy = x.y() - cache->y[i], dz = x.z() - cache->z[i];
    const double moved = std::sqrt(dx * dx + dy * dy + dz * dz) + kMargin;
    lo = cache->lo[i] - o.travel - moved;
    hi = cache->hi[i] + o.travel + moved;
  }
  MeshObstacle::Hit capped;
  capped.distance = reach;
  if (lo >= reach) return capped;  // certainly `reach` or more outside
  MeshObstacle::Hit h = o.query_within(x, std::isfinite(hi) ? hi : MeshObstacle::kWhole);
  if (!std::isfinite(h.unsigned_distance)) h = o.query(x);  // (rounding beyond the margin)
  if (cache) {
    cache->x[i] = x.x(), cache->y[i] = x.y(), cache->z[i] = x.z();
    cache->lo[i] = h.distance + o.travel;
    cache->hi[i] = h.unsigned_distance - o.travel;
  }
  return h.distance >= reach ? capped : h;
}

}  // namespace detail

}  // namespace wetcloth
