// Obstacles made of triangle meshes: read, transformed, checked, and queried
// for the signed distance through a CGAL AABB tree (docs/model.md section 3).
#include "geometry/mesh_obstacle.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

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

}  // namespace

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

void check_obstacle_meshes(const Params& p, const std::string& source) {
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
      throw SceneError(source + ": " + what);
    }
    // A cloth that starts inside the obstacle would be flung out at the first
    // step: where a moving one is at t = 0, in its body frame.
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
          (p.obstacles.at(name).motion.moves() ? ", obstacle." + name + ".motion" : "") + ")" +
          axis);
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
    const double dx = x.x() - cache->x[i], dy = x.y() - cache->y[i], dz = x.z() - cache->z[i];
    const double moved = std::sqrt(dx * dx + dy * dy + dz * dz) + kMargin;
    lo = cache->lo[i] - moved;
    hi = cache->hi[i] + moved;
  }
  MeshObstacle::Hit capped;
  capped.distance = reach;
  if (lo >= reach) return capped;  // certainly `reach` or more outside
  MeshObstacle::Hit h = o.query_within(x, std::isfinite(hi) ? hi : MeshObstacle::kWhole);
  if (!std::isfinite(h.unsigned_distance)) h = o.query(x);  // (rounding beyond the margin)
  if (cache) {
    cache->x[i] = x.x(), cache->y[i] = x.y(), cache->z[i] = x.z();
    cache->lo[i] = h.distance;
    cache->hi[i] = h.unsigned_distance;
  }
  return h.distance >= reach ? capped : h;
}

}  // namespace detail

}  // namespace wetcloth
