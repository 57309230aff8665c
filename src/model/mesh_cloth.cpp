// A cloth made from a triangle mesh (cloth.mesh): its particles, areas,
// springs and neighbour lists (build_mesh_cloth), and the general kernels the
// step runs on it where the grid runs its stencil kernels. docs/model.md
// section 1 gives the rules; docs/guide.md how a scene uses them.
//
// The grid is a mesh cloth of one kind: an OBJ file of the grid's quads makes
// the same particles, areas, springs and constants (tests/model/test_mesh_cloth.cpp).
// The grid keeps its own kernels, which are faster; a mesh cloth runs on one
// thread, so the thread count never changes its result.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <sstream>
#include <tuple>

#include "detail.hpp"
#include "geometry/mesh_io.hpp"
#include "wetcloth/motion.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {

namespace {

Vec3 at(const TriangleMesh& mesh, int k) {
  return {mesh.position[k][0], mesh.position[k][1], mesh.position[k][2]};
}

// The file's quadrilaterals among its triangles: read_obj splits quad
// {a, b, c, d} into {a, b, c}, {a, c, d}, in the file's order.
std::vector<int> quad_of_triangle(const TriangleMesh& mesh) {
  std::vector<int> quad(mesh.triangles.size(), -1);
  std::size_t q = 0;
  for (std::size_t t = 0; t + 1 < mesh.triangles.size() && q < mesh.quads.size(); ++t) {
    const auto& d = mesh.quads[q];
    if (mesh.triangles[t] == std::array<int, 3>{d[0], d[1], d[2]} &&
        mesh.triangles[t + 1] == std::array<int, 3>{d[0], d[2], d[3]}) {
      quad[t] = quad[t + 1] = static_cast<int>(q++);
      ++t;
    }
  }
  return quad;
}

void push(SpringSet& s, int a, int b, double rest, double k, double damping) {
  s.a.push_back(a);
  s.b.push_back(b);
  s.rest.push_back(rest);
  s.k.push_back(k);
  s.damping.push_back(damping);
}

// Lists (CSR) from pairs: each pair's ends list each other.
void lists(int n, const std::vector<std::array<int, 2>>& pairs, std::vector<int>& start,
           std::vector<int>& entries) {
  std::vector<std::vector<int>> by(n);
  for (const auto& [a, b] : pairs) {
    by[a].push_back(b);
    by[b].push_back(a);
  }
  start.assign(n + 1, 0);
  entries.clear();
  for (int k = 0; k < n; ++k) {
    std::sort(by[k].begin(), by[k].end());
    by[k].erase(std::unique(by[k].begin(), by[k].end()), by[k].end());
    entries.insert(entries.end(), by[k].begin(), by[k].end());
    start[k + 1] = static_cast<int>(entries.size());
  }
}

}  // namespace

std::vector<Vec3> mesh_cloth_positions(const Params& p, const TriangleMesh& mesh) {
  if (p.cloth.placed()) {
    // As obstacles are placed, from the file's own origin (a garment made
    // around a body keeps its place on it): up, scale, rotate, translate.
    ObstacleParams as;
    as.up = p.cloth.up;
    as.translate = p.cloth.translate;
    as.rotate = p.cloth.rotate;
    for (int c = 0; c < 3; ++c) as.scale[c] = p.cloth.scale[c] * p.cloth.mesh_scale;
    std::vector<Vec3> x(mesh.position.size());
    for (std::size_t k = 0; k < x.size(); ++k)
      x[k] = place_obstacle_point(as, at(mesh, static_cast<int>(k)));
    return x;
  }
  Vec3 lo = Vec3::Constant(detail::kInf), hi = Vec3::Constant(-detail::kInf);
  for (std::size_t k = 0; k < mesh.position.size(); ++k) {
    lo = lo.cwiseMin(at(mesh, static_cast<int>(k)));
    hi = hi.cwiseMax(at(mesh, static_cast<int>(k)));
  }
  const Vec3 mid = 0.5 * (lo + hi);
  const Eigen::AngleAxisd tilt(p.cloth.tilt * std::numbers::pi / 180, Vec3::UnitX());
  std::vector<Vec3> x(mesh.position.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Vec3 f = p.cloth.mesh_scale * (at(mesh, static_cast<int>(k)) - mid);
    // As the grid: vertical turns the xy plane into the xz plane, y down.
    const Vec3 flat = p.cloth.orientation == Orientation::Vertical ? Vec3(f.x(), f.z(), -f.y()) : f;
    x[k] = to_vec(p.cloth.center) + (p.cloth.tilt != 0 ? Vec3(tilt * flat) : flat);
  }
  return x;
}

namespace {

// A cloth mesh being built: its faces, rest positions and areas.
struct ClothMesh {
  const TriangleMesh& mesh;
  const std::vector<Vec3>& x;
  std::vector<int> quad;  // each triangle's quad, or -1 (quad_of_triangle)
  double quad_area(int q) const {
    const auto& d = mesh.quads[q];
    return 0.5 * (x[d[2]] - x[d[0]]).cross(x[d[3]] - x[d[1]]).norm();
  }
  double triangle_area(int t) const {
    const auto& d = mesh.triangles[t];
    return 0.5 * (x[d[1]] - x[d[0]]).cross(x[d[2]] - x[d[0]]).norm();
  }
};

// The polygon edges (the quads' sides, the lone triangles' edges), each
// with the faces beside it: its share of their area (a quad's half, a
// triangle's two thirds: an isotropic stretch then stores the grid's
// energy) and, for a triangle, the corner across it.
struct Edge {
  double share = 0;
  int faces = 0;
  int triangles = 0;
  std::array<int, 2> across{-1, -1};
  std::array<double, 2> across_area{0, 0};
};
struct Edges {
  std::map<std::pair<int, int>, Edge> by_ends;
  std::vector<std::pair<int, int>> order;  // as first met: the springs' order
};

// Texture coordinates: the file's, else the xy bounding box of its
// vertices; and which particles the wind region holds.
void place_texture(Model& m, const Params& p, const TriangleMesh& mesh) {
  const int n = m.n;
  m.uv.resize(n);
  if (!mesh.uv.empty()) {
    m.uv = mesh.uv;
  } else {
    double lo[2] = {detail::kInf, detail::kInf}, hi[2] = {-detail::kInf, -detail::kInf};
    for (const auto& q : mesh.position)
      for (int c = 0; c < 2; ++c) {
        lo[c] = std::min(lo[c], q[c]);
        hi[c] = std::max(hi[c], q[c]);
      }
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 2; ++c)
        m.uv[k][c] = hi[c] > lo[c] ? (mesh.position[k][c] - lo[c]) / (hi[c] - lo[c]) : 0.0;
  }
  for (int k = 0; k < n; ++k) {
    const auto& w = p.wind;
    m.in_wind[k] = m.uv[k][0] >= w.region_min[0] && m.uv[k][0] <= w.region_max[0] &&
                   m.uv[k][1] >= w.region_min[1] && m.uv[k][1] <= w.region_max[1];
  }
}

// Areas: a quarter of each quad's and a third of each lone triangle's to
// each corner (on a grid of quads, the grid's Voronoi areas: l², l²/2 on
// the border, l²/4 at a corner).
void add_areas(Model& m, const ClothMesh& c) {
  const TriangleMesh& mesh = c.mesh;
  const auto& quad = c.quad;
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (const int k : mesh.quads[q]) m.area[k] += c.quad_area(static_cast<int>(q)) / 4;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (quad[t] < 0)
      for (const int k : mesh.triangles[t]) m.area[k] += c.triangle_area(static_cast<int>(t)) / 3;
}

Edges polygon_edges(const ClothMesh& c) {
  const TriangleMesh& mesh = c.mesh;
  const auto& quad = c.quad;
  Edges edges;
  const auto meet = [&](int a, int b, double share, int across, double area) {
    const std::pair key{std::min(a, b), std::max(a, b)};
    auto [it, fresh] = edges.by_ends.try_emplace(key);
    if (fresh) edges.order.push_back(key);
    Edge& e = it->second;
    e.share += share;
    ++e.faces;
    if (across >= 0 && e.triangles < 2) {
      e.across[e.triangles] = across;
      e.across_area[e.triangles++] = area;
    }
  };
  std::vector<std::uint8_t> quad_met(mesh.quads.size(), 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (quad[t] >= 0) {
      const int q = quad[t];
      if (quad_met[q]) continue;
      quad_met[q] = 1;
      const auto& d = mesh.quads[q];
      const double a = c.quad_area(q);
      for (int k = 0; k < 4; ++k) meet(d[k], d[(k + 1) % 4], a / 2, -1, 0);
      continue;
    }
    const auto& d = mesh.triangles[t];
    const double a = c.triangle_area(static_cast<int>(t));
    for (int k = 0; k < 3; ++k) meet(d[k], d[(k + 1) % 3], 2 * a / 3, d[(k + 2) % 3], a);
  }
  return edges;
}

// A spring constant of [springs] where a scene sets it, else the material's.
double constant(const std::optional<double>& set, double from_material) {
  return set.value_or(from_material);
}

// Structural and shear springs (docs/model.md section 1, "a mesh cloth"); the
// cloth's edges and the strain limiter's springs as pairs.
void add_stretch_springs(Model& m, const Params& p, const ClothMesh& c, Edges& edges,
                         std::vector<std::array<int, 2>>& edge_pairs,
                         std::vector<std::array<int, 2>>& strain_pairs) {
  const TriangleMesh& mesh = c.mesh;
  const auto& x = c.x;
  const auto& mat = p.material;
  const auto& sp = p.springs;
  // Structural: k = k_s A_e / l², A_e = the edge's shares, doubled on the
  // border (as if the cloth went on past it): on a grid, k_s dv / du.
  for (const auto& key : edges.order) {
    const Edge& e = edges.by_ends[key];
    const double rest = (x[key.second] - x[key.first]).norm();
    const double a = 2 * e.share / e.faces, scale = a / (rest * rest);
    push(m.structural, key.first, key.second, rest,
         constant(sp.structural_k, mat.stretch_stiffness * scale),
         constant(sp.structural_damping, mat.stretch_damping * scale));
    if (e.faces == 1) m.on_border[key.first] = m.on_border[key.second] = 1;
    edge_pairs.push_back({key.first, key.second});
  }
  // Shear: both diagonals of each quad, k = k_shear 2 A_q / l² (on a grid,
  // k_shear 2 du dv / (du² + dv²)).
  for (std::size_t q = 0; q < mesh.quads.size(); ++q) {
    const auto& d = mesh.quads[q];
    for (const auto& [a, b] : {std::pair{d[0], d[2]}, std::pair{d[1], d[3]}}) {
      const double rest = (x[b] - x[a]).norm();
      const double scale = 2 * c.quad_area(static_cast<int>(q)) / (rest * rest);
      push(m.shear, a, b, rest, constant(sp.shear_k, mat.shear_stiffness * scale),
           constant(sp.shear_damping, mat.shear_damping * scale));
    }
  }
  for (std::size_t e = 0; e < m.structural.size(); ++e)
    strain_pairs.push_back({m.structural.a[e], m.structural.b[e]});
  for (std::size_t e = 0; e < m.shear.size(); ++e)
    strain_pairs.push_back({m.shear.a[e], m.shear.b[e]});
}

// Bending: k = B ā / h⁴ (h half the spring's rest length, ā the mean area
// of the faces it bends across), 4 B ā / h⁴ along a quad diagonal: on a
// grid, the grid's B dv / du³ and 4 B du dv / (du² + dv²)².
void add_bending_springs(Model& m, const Params& p, const ClothMesh& c, Edges& edges,
                         const std::vector<std::array<int, 2>>& edge_pairs) {
  const TriangleMesh& mesh = c.mesh;
  const auto& x = c.x;
  const int n = m.n;
  const auto& mat = p.material;
  const auto& sp = p.springs;
  const auto bend = [&](int a, int b, double mean_area, double factor) {
    const double rest = (x[b] - x[a]).norm(), h = rest / 2;
    const double scale = factor * mean_area / (h * h * h * h);
    push(m.bending, a, b, rest, constant(sp.bending_k, mat.bending_rigidity * scale),
         constant(sp.bending_damping, mat.bending_damping * scale));
  };
  // Across each edge between two triangles: their corners across it.
  for (const auto& key : edges.order) {
    const Edge& e = edges.by_ends[key];
    if (e.faces == 2 && e.triangles == 2 && e.across[0] != e.across[1])
      bend(e.across[0], e.across[1], 0.5 * (e.across_area[0] + e.across_area[1]), 1.0);
  }
  // In a quad region, along the quads' lines through each regular vertex
  // (four quads around it, or two on the border), as the grid's (i ± 2, j),
  // (i, j ± 2) and (i ± 2, j ± 2).
  std::vector<std::vector<int>> quads_at(n);
  for (std::size_t q = 0; q < mesh.quads.size(); ++q)
    for (const int k : mesh.quads[q]) quads_at[k].push_back(static_cast<int>(q));
  std::vector<std::vector<int>> neighbours(n);
  for (const auto& [a, b] : edge_pairs) {
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  }
  for (int v = 0; v < n; ++v) {
    const auto& around = quads_at[v];
    const std::size_t valence = neighbours[v].size();
    const bool inner = !m.on_border[v] && around.size() == 4 && valence == 4;
    const bool rim = m.on_border[v] && around.size() == 2 && valence == 3;
    if (!inner && !rim) continue;
    double mean = 0;
    for (const int q : around) mean += c.quad_area(q) / around.size();
    const auto corner = [&](int q) {
      const auto& d = mesh.quads[q];
      return static_cast<int>(std::find(d.begin(), d.end(), v) - d.begin());
    };
    const auto in_quad = [&](int q, int k) {
      const auto& d = mesh.quads[q];
      return std::find(d.begin(), d.end(), k) != d.end();
    };
    // Two sides through v are in line when no quad holds both.
    for (const int a : neighbours[v])
      for (const int b : neighbours[v]) {
        if (b <= a) continue;
        if (std::any_of(around.begin(), around.end(),
                        [&](int q) { return in_quad(q, a) && in_quad(q, b); }))
          continue;
        if (rim && !(m.on_border[a] && m.on_border[b])) continue;
        bend(a, b, mean, 1.0);
      }
    // Two diagonals through v are in line when their quads share no side.
    if (inner)
      for (std::size_t i = 0; i < around.size(); ++i)
        for (std::size_t j = i + 1; j < around.size(); ++j) {
          const auto& qi = mesh.quads[around[i]];
          const auto& qj = mesh.quads[around[j]];
          const int ci = corner(around[i]), cj = corner(around[j]);
          const bool share =
              in_quad(around[j], qi[(ci + 1) % 4]) || in_quad(around[j], qi[(ci + 3) % 4]);
          if (!share) bend(qi[(ci + 2) % 4], qj[(cj + 2) % 4], mean, 4.0);
        }
  }
}

// Neighbour lists: the edges (contact border, air pockets, handles' patch),
// the structural and shear springs (strain limiting's order and queue), and
// self-collision's exclusion.
void build_neighbour_lists(Model& m, Topology& t, const Params& p,
                           const std::vector<std::array<int, 2>>& edge_pairs,
                           const std::vector<std::array<int, 2>>& strain_pairs) {
  const int n = m.n;
  lists(n, edge_pairs, t.edge_start, t.edge_neighbour);
  {
    std::vector<std::vector<int>> by(n);
    for (std::size_t e = 0; e < strain_pairs.size(); ++e)
      for (const int k : strain_pairs[e]) by[k].push_back(static_cast<int>(e));
    t.strain_start.assign(n + 1, 0);
    t.strain_spring.clear();
    for (int k = 0; k < n; ++k) {
      t.strain_spring.insert(t.strain_spring.end(), by[k].begin(), by[k].end());
      t.strain_start[k + 1] = static_cast<int>(t.strain_spring.size());
    }
  }
  // Self-collision's exclusion: within `reach` steps along the structural
  // and shear springs (the grid's Chebyshev distance in grid steps), reach =
  // max(2, ⌈d_t / the mean edge⌉).
  double total = 0;
  for (const double l : m.structural.rest) total += l;
  m.spacing = m.structural.size() ? total / m.structural.size() : 0.0;
  std::vector<int> strain_list_start, strain_list;
  lists(n, strain_pairs, strain_list_start, strain_list);
  const int reach = std::max(
      2, m.spacing > 0 ? static_cast<int>(std::ceil(p.self_collision.distance / m.spacing)) : 2);
  t.ring_start.assign(n + 1, 0);
  t.ring.clear();
  std::vector<int> depth(n, -1), seen;
  for (int k = 0; k < n; ++k) {
    seen.assign(1, k);
    depth[k] = 0;
    for (std::size_t q = 0; q < seen.size(); ++q) {
      const int a = seen[q];
      if (depth[a] == reach) continue;
      for (int e = strain_list_start[a]; e < strain_list_start[a + 1]; ++e)
        if (const int b = strain_list[e]; depth[b] < 0) {
          depth[b] = depth[a] + 1;
          seen.push_back(b);
        }
    }
    for (const int a : seen) depth[a] = -1;
    std::sort(seen.begin(), seen.end());
    t.ring.insert(t.ring.end(), seen.begin(), seen.end());
    t.ring_start[k + 1] = static_cast<int>(t.ring.size());
  }
}

}  // namespace

void build_mesh_cloth(Model& m, Topology& t, const Params& p) {
  const TriangleMesh mesh = load_scene_mesh(p, "cloth.mesh", p.cloth.mesh);
  const int n = static_cast<int>(mesh.position.size());
  m.grid = false;
  m.n = m.nu = n;
  m.nv = 1;
  m.threads = 1;
  m.rest_position = mesh_cloth_positions(p, mesh);
  m.area.assign(n, 0.0);
  m.on_border.assign(n, 0);
  m.in_wind.assign(n, 0);
  m.driven.assign(n, 0);
  m.triangles = mesh.triangles;
  place_texture(m, p, mesh);
  // Faces: the file's quads, and the triangles of no quad.
  const ClothMesh c{mesh, m.rest_position, quad_of_triangle(mesh)};
  add_areas(m, c);
  Edges edges = polygon_edges(c);
  std::vector<std::array<int, 2>> edge_pairs, strain_pairs;
  add_stretch_springs(m, p, c, edges, edge_pairs, strain_pairs);
  if (p.material.bending == BendingModel::Provot) add_bending_springs(m, p, c, edges, edge_pairs);
  build_neighbour_lists(m, t, p, edge_pairs, strain_pairs);
  // As a grid's particles along its longer side (xpbd_substeps).
  double longest = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double lo = detail::kInf, hi = -detail::kInf;
    for (const auto& q : mesh.position) lo = std::min(lo, q[axis]), hi = std::max(hi, q[axis]);
    longest = std::max(longest, p.cloth.mesh_scale * (hi - lo));
  }
  t.along = m.spacing > 0 ? static_cast<int>(std::lround(longest / m.spacing)) + 1 : 0;
}

ClothMeshSize cloth_mesh_size(const Params& p) {
  const TriangleMesh mesh = load_scene_mesh(p, "cloth.mesh", p.cloth.mesh);
  // The structural springs' edges: the quads' sides, the lone triangles' edges.
  std::map<std::pair<int, int>, double> edges;
  const auto edge = [&](int a, int b) {
    edges[{std::min(a, b), std::max(a, b)}] = (at(mesh, b) - at(mesh, a)).norm();
  };
  for (const auto& d : mesh.quads)
    for (int c = 0; c < 4; ++c) edge(d[c], d[(c + 1) % 4]);
  const std::vector<int> quad = quad_of_triangle(mesh);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (quad[t] < 0)
      for (int c = 0; c < 3; ++c) edge(mesh.triangles[t][c], mesh.triangles[t][(c + 1) % 3]);
  double total = 0;
  for (const auto& [unused, l] : edges) total += l;
  return {static_cast<long long>(mesh.position.size()),
          static_cast<long long>(mesh.triangles.size()),
          edges.empty() ? 0.0 : p.cloth.mesh_scale * total / static_cast<double>(edges.size())};
}

void check_cloth_mesh(const Params& p, const std::string& source) {
  if (p.cloth.mesh.empty()) return;
  TriangleMesh mesh;
  try {
    mesh = load_scene_mesh(p, "cloth.mesh", p.cloth.mesh);
  } catch (const SceneError& e) {
    // The path's faults are named against the scene's key ("Params: cloth.mesh: ..."):
    // here the scene file is known.
    const std::string what = e.what(), lead = "Params: ";
    throw SceneError(what.rfind(lead, 0) == 0 ? source + ": " + what.substr(lead.size())
                                              : source + ": cloth.mesh: " + what);
  }
  // A vertex in no face has no spring and no area: its mass is zero, and the
  // first step divides by it.
  std::vector<char> used(mesh.position.size(), 0);
  for (const auto& t : mesh.triangles)
    for (const int v : t) used[v] = 1;
  if (const auto it = std::find(used.begin(), used.end(), 0); it != used.end())
    throw SceneError(source + ": cloth.mesh: " + mesh.source + ": vertex " +
                     std::to_string(it - used.begin() + 1) +
                     " is in no face: a cloth's every vertex must be (remove it from the file)");
  const std::vector<Vec3> x = mesh_cloth_positions(p, mesh);
  for (const auto& [kind, name, on] : {std::tuple{SurfaceKind::Table, "table", p.table.enabled},
                                       std::tuple{SurfaceKind::Ball, "ball", p.ball.enabled}}) {
    if (!on) continue;
    double deepest = 0;
    SurfacePoses at_start;  // a moving ball where it is at t = 0
    if (p.ball.enabled) at_start.ball = ball_pose(p, 0.0);
    for (const Vec3& q : x)
      deepest = std::min(deepest, detail::query_surface(p, at_start, kind, q).distance);
    if (deepest < -1e-9) {
      char mm[32];
      std::snprintf(mm, sizeof mm, "%.3g", -deepest * 1000);
      throw SceneError(
          source + ": cloth.center: the cloth of cloth.mesh = \"" + p.cloth.mesh + "\" starts " +
          mm + " mm inside the " + name + " (cloth.center, cloth.mesh_scale, cloth.tilt, " +
          (kind == SurfaceKind::Table ? "table.height" : "ball.center, ball.radius") + ")");
    }
  }
}

std::vector<int> handle_vertex_indices(const Params& p, const std::string& name, int n) {
  const VertexList& list = p.handles.at(name).vertices;
  const std::string key = "handle." + name + ".vertices";
  const auto out_of_range = [&](long long i) {
    return "index " + std::to_string(i) + " is out of range: the cloth has " + std::to_string(n) +
           " particles (0 to " + std::to_string(n - 1) + ")";
  };
  std::vector<int> picked;
  if (list.file.empty()) {
    for (const long long i : list.indices) {
      if (i < 0 || i >= n) throw SceneError("Params: " + key + ": " + out_of_range(i));
      picked.push_back(static_cast<int>(i));
    }
  } else {
    // Whitespace-separated 0-based indices; # starts a comment. An error
    // names the file and the line.
    const std::string text = scene_file_text(p, key, list.file);
    const std::string source = p.scene_dir == "builtin:"
                                   ? "scenes/" + list.file
                                   : resolve_scene_path(p, key, list.file).string();
    std::istringstream lines(text);
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
      std::istringstream words(line.substr(0, line.find('#')));
      std::string word;
      while (words >> word) {
        const auto where = source + ":" + std::to_string(number) + ": " + key + ": ";
        long long i = -1;
        const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), i);
        if (error != std::errc() || end != word.data() + word.size() || i < 0)
          throw SceneError(where + "'" + word + "' is not a particle index (an integer from 0)");
        if (i >= n) throw SceneError(where + out_of_range(i));
        picked.push_back(static_cast<int>(i));
      }
    }
    if (picked.empty()) throw SceneError(source + ": " + key + ": the file names no particle");
  }
  std::sort(picked.begin(), picked.end());
  picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
  return picked;
}

void check_handle_vertices(const Params& p, const std::string& source) {
  int n = static_cast<int>(p.cloth.resolution[0] * p.cloth.resolution[1]);
  bool any = false;
  for (const auto& [name, h] : p.handles) any = any || !h.vertices.empty();
  if (!any) return;
  if (!p.cloth.mesh.empty())
    n = static_cast<int>(load_scene_mesh(p, "cloth.mesh", p.cloth.mesh).position.size());
  for (const auto& [name, h] : p.handles) {
    if (h.vertices.empty()) continue;
    try {
      handle_vertex_indices(p, name, n);
    } catch (const SceneError& e) {
      // The file's faults name it; the scene's own keys the scene file.
      const std::string what = e.what(), lead = "Params: ";
      throw SceneError(what.rfind(lead, 0) == 0 ? source + ": " + what.substr(lead.size()) : what);
    }
  }
}

// A handle on a mesh cloth, placed by the texture coordinates: span zero,
// the particle nearest to `at`; else every particle in the box from `at` to
// `at + span` (the nearest to its middle if none is), then `patch` rings of
// neighbours along the structural and shear springs around them (on the
// grid, grid steps).
std::vector<int> mesh_handle_particles(const Model& m, const HandleParams& h) {
  const double u0 = std::min(h.at[0], h.at[0] + h.span[0]),
               u1 = std::max(h.at[0], h.at[0] + h.span[0]);
  const double v0 = std::min(h.at[1], h.at[1] + h.span[1]),
               v1 = std::max(h.at[1], h.at[1] + h.span[1]);
  std::vector<int> picked;
  if (h.span[0] != 0 || h.span[1] != 0) {
    constexpr double kSlack = 1e-9;
    for (int k = 0; k < m.n; ++k)
      if (m.uv[k][0] >= u0 - kSlack && m.uv[k][0] <= u1 + kSlack && m.uv[k][1] >= v0 - kSlack &&
          m.uv[k][1] <= v1 + kSlack)
        picked.push_back(k);
  }
  if (picked.empty()) {
    const double cu = 0.5 * (u0 + u1), cv = 0.5 * (v0 + v1);
    int best = 0;
    double best_d = detail::kInf;
    for (int k = 0; k < m.n; ++k) {
      const double d = std::hypot(m.uv[k][0] - cu, m.uv[k][1] - cv);
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    picked.push_back(best);
  }
  std::vector<int> ring_of(m.n, -1);
  for (const int k : picked) ring_of[k] = 0;
  for (std::size_t q = 0; q < picked.size(); ++q) {
    const int a = picked[q];
    if (ring_of[a] >= h.patch) continue;
    for (int s = m.topology->strain_start[a]; s < m.topology->strain_start[a + 1]; ++s) {
      const int e = m.topology->strain_spring[s];
      const SpringSet& set = e < static_cast<int>(m.structural.size()) ? m.structural : m.shear;
      const std::size_t i = e < static_cast<int>(m.structural.size()) ? e : e - m.structural.size();
      const int b = set.a[i] == a ? set.b[i] : set.a[i];
      if (ring_of[b] >= 0) continue;
      ring_of[b] = ring_of[a] + 1;
      picked.push_back(b);
    }
  }
  std::sort(picked.begin(), picked.end());
  return picked;
}

namespace detail {

// Eq. 1 over every spring, each added at both ends, in the springs' order.
void add_spring_forces_mesh(const Model& m, const State& s, Workspace& w, bool damped) {
  for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
    for (std::size_t e = 0; e < set->size(); ++e) {
      const int a = set->a[e], b = set->b[e];
      const Vec3 d = s.x[b] - s.x[a];
      const double len = d.norm();
      if (!(len > 0)) continue;
      const Vec3 u = d / len;
      double f = set->k[e] * (len - set->rest[e]);
      if (damped) f += set->damping[e] * u.dot(s.v[b] - s.v[a]);
      add(w.force[a], f * u);
      sub(w.force[b], f * u);
    }
}

// Eq. 1's damping over a step h, implicitly, one spring at a time
// (Gauss-Seidel): each spring's impulse λ u from the velocities so far,
// λ = c u·(v_b − v_a) / (1 + c (w_a + w_b)), c = h k_d, takes out of its
// ends' relative velocity along it at most what backward Euler would. Equal
// and opposite, so momentum is conserved; never overshooting, so stable at
// any h.
void apply_spring_damping_mesh(const Model& m, State& s, double h) {
  for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
    for (std::size_t e = 0; e < set->size(); ++e) {
      if (set->damping[e] <= 0) continue;
      const int a = set->a[e], b = set->b[e];
      const Vec3 d = s.x[b] - s.x[a];
      const double len = d.norm();
      if (!(len > 0)) continue;
      const Vec3 u = d / len;
      const double c = h * set->damping[e], wa = m.inv_mass[a], wb = m.inv_mass[b];
      const double lambda = c * u.dot(s.v[b] - s.v[a]) / (1 + c * (wa + wb));
      add(s.v[a], (wa * lambda) * u);
      sub(s.v[b], (wb * lambda) * u);
    }
}

// Area-weighted normals: each triangle's cross product at its corners.
void compute_normals_mesh(const Model& m, const double* X, Vec3Array& normal) {
  const int n = m.n;
  const double *x = X, *y = X + n, *z = X + 2 * std::size_t(n);
  for (int k = 0; k < n; ++k) put(normal[k], Vec3::Zero());
  for (const auto& t : m.triangles) {
    const Vec3 a(x[t[0]], y[t[0]], z[t[0]]);
    const Vec3 u = Vec3(x[t[1]], y[t[1]], z[t[1]]) - a, v = Vec3(x[t[2]], y[t[2]], z[t[2]]) - a;
    const Vec3 c = u.cross(v);
    for (const int k : t) add(normal[k], c);
  }
  for (int k = 0; k < n; ++k) {
    const Vec3 c = normal[k];
    const double len = c.norm();
    put(normal[k], len > 0 ? Vec3(c / len) : Vec3::UnitZ());
  }
}

// The contact region's border: contact particles on the cloth's border or
// next to a lifted particle along an edge.
void contact_border_mesh(const Model& m, const State& s, Workspace& w) {
  for (int k = 0; k < m.n; ++k) {
    bool border = m.on_border[k];
    for (int e = m.topology->edge_start[k]; e < m.topology->edge_start[k + 1] && !border; ++e)
      border = !s.contact[m.topology->edge_neighbour[e]];
    w.border[k] = s.contact[k] && border;
  }
}

}  // namespace detail

}  // namespace wetcloth
