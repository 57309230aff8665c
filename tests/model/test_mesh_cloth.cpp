// A cloth from a triangle mesh (cloth.mesh, src/model/mesh_cloth.cpp): the grid's
// own quads read from a file make the grid's particles, areas and springs and
// run as it does; a mesh that is no grid (a disc of triangles) conserves
// momentum, drops onto the table and settles, and takes air and adhesion.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <tuple>

#include "common.hpp"
#include "detail.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("wetcloth_mesh_cloth_" + name);
  fs::create_directories(d);
  return d;
}

// The grid of p (its cloth at the origin, flat) as an OBJ of quads: vertex
// j nu + i, texture coordinates (i, j) / (nu - 1, nv - 1), and each quad
// starting at the corner its grid triangulation splits from (model.cpp's
// chequerboard), so that the file's triangles are the grid's.
std::string grid_obj(const Params& p) {
  Params flat = p;
  flat.cloth.center = {0, 0, 0};
  flat.cloth.tilt = 0;
  flat.cloth.orientation = Orientation::Horizontal;
  const auto [nu, nv] = p.cloth.resolution;
  std::string o;
  char line[256];
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const Vec3 x = cloth_start_position(flat, i, j);
      std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", x.x(), x.y(), x.z());
      o += line;
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      std::snprintf(line, sizeof line, "vt %.17g %.17g\n", double(i) / double(nu - 1),
                    double(j) / double(nv - 1));
      o += line;
    }
  for (int j = 0; j + 1 < nv; ++j)
    for (int i = 0; i + 1 < nu; ++i) {
      const long long a = j * nu + i + 1, b = a + 1, c = a + nu + 1, d = a + nu;
      const auto [q0, q1, q2, q3] =
          (i + j) % 2 == 0 ? std::tuple{a, b, c, d} : std::tuple{b, c, d, a};
      std::snprintf(line, sizeof line, "f %lld/%lld %lld/%lld %lld/%lld %lld/%lld\n", q0, q0, q1,
                    q1, q2, q2, q3, q3);
      o += line;
    }
  return o;
}

// A disc of radius r in rings of triangles (ring k has 6 k vertices), as
// tools/make_cloth_meshes.py makes scenes/meshes/cloth_disc.obj.
std::string disc_obj(double r, int rings) {
  std::vector<std::array<double, 2>> v{{0, 0}};
  std::vector<int> first{0};
  for (int k = 1; k <= rings; ++k) {
    first.push_back(static_cast<int>(v.size()));
    for (int q = 0; q < 6 * k; ++q) {
      const double a = 2 * std::numbers::pi * q / (6 * k);
      v.push_back({r * k / rings * std::cos(a), r * k / rings * std::sin(a)});
    }
  }
  std::vector<std::array<int, 3>> t;
  for (int q = 0; q < 6; ++q) t.push_back({0, first[1] + q, first[1] + (q + 1) % 6});
  for (int k = 1; k < rings; ++k) {
    const int in = first[k], out = first[k + 1], n_in = 6 * k, n_out = 6 * (k + 1);
    int i = 0, j = 0;
    while (i < n_in || j < n_out) {
      const double a_in = double(i + 1) / n_in, a_out = double(j + 1) / n_out;
      if (j < n_out && (i >= n_in || a_out <= a_in)) {
        t.push_back({in + i % n_in, out + j, out + (j + 1) % n_out});
        ++j;
      } else {
        t.push_back({in + i % n_in, out + j % n_out, in + (i + 1) % n_in});
        ++i;
      }
    }
  }
  std::string o;
  char line[256];
  for (const auto& p : v) {
    std::snprintf(line, sizeof line, "v %.17g %.17g 0\nvt %.17g %.17g\n", p[0], p[1],
                  0.5 + p[0] / (2 * r), 0.5 + p[1] / (2 * r));
    o += line;
  }
  for (const auto& f : t) {
    std::snprintf(line, sizeof line, "f %d/%d %d/%d %d/%d\n", f[0] + 1, f[0] + 1, f[1] + 1,
                  f[1] + 1, f[2] + 1, f[2] + 1);
    o += line;
  }
  return o;
}

// p with its cloth from `text`, written as `name` into a folder of its own.
Params with_mesh(Params p, const std::string& name, const std::string& text) {
  const fs::path dir = temp_dir(name);
  std::ofstream(dir / (name + ".obj")) << text;
  p.cloth.mesh = name + ".obj";
  p.scene_dir = dir.string();
  return p;
}

// A spring set as {ends} -> (rest, k, damping), for comparing two models.
std::map<std::pair<int, int>, std::array<double, 3>> springs_of(const SpringSet& s) {
  std::map<std::pair<int, int>, std::array<double, 3>> r;
  for (std::size_t e = 0; e < s.size(); ++e)
    r[{std::min(s.a[e], s.b[e]), std::max(s.a[e], s.b[e])}] = {s.rest[e], s.k[e], s.damping[e]};
  return r;
}

void expect_same_springs(const SpringSet& grid, const SpringSet& mesh, const char* kind) {
  const auto g = springs_of(grid), m = springs_of(mesh);
  ASSERT_EQ(g.size(), m.size()) << kind;
  for (const auto& [ends, c] : g) {
    const auto it = m.find(ends);
    ASSERT_NE(it, m.end()) << kind << " spring " << ends.first << "-" << ends.second;
    for (int q = 0; q < 3; ++q) EXPECT_NEAR(it->second[q], c[q], 1e-9 * std::abs(c[q])) << kind;
  }
}

// A non-square grid, so that u and v constants differ.
Params grid_scene() {
  return load_scene("pull-straight", {"cloth.resolution=[15,11]", "cloth.size=[0.3,0.2]"});
}

TEST(MeshCloth, TheGridsQuadsMakeTheGridsModel) {
  const Params p = grid_scene();
  const Model grid = build_model(p);
  const Model mesh = build_model(with_mesh(p, "grid", grid_obj(p)));
  EXPECT_TRUE(grid.grid);
  EXPECT_FALSE(mesh.grid);
  ASSERT_EQ(mesh.n, grid.n);
  for (int k = 0; k < grid.n; ++k) {
    EXPECT_NEAR((mesh.rest_position[k] - grid.rest_position[k]).norm(), 0, 1e-15);
    EXPECT_NEAR(mesh.area[k], grid.area[k], 1e-12 * grid.area[k]) << k;
    EXPECT_EQ(mesh.on_border[k], grid.on_border[k]) << k;
    EXPECT_NEAR(mesh.mass[k], grid.mass[k], 1e-12 * grid.mass[k]) << k;
    // (tinyobjloader's number parser is not correctly rounded: within an ulp or two.)
    for (int c = 0; c < 2; ++c) EXPECT_NEAR(mesh.uv[k][c], grid.uv[k][c], 1e-15) << k;
  }
  EXPECT_EQ(grid.structural.size() + grid.shear.size() + grid.bending.size(), 0u);  // the stencil's
  for (const auto& [kind, name] :
       {std::pair{SpringKind::Structural, "structural"}, std::pair{SpringKind::Shear, "shear"},
        std::pair{SpringKind::Bending, "bending"}}) {
    expect_same_springs(spring_set(grid, kind), spring_set(mesh, kind), name);
    EXPECT_EQ(spring_count(grid, kind), spring_set(mesh, kind).size()) << name;
  }
  ASSERT_EQ(mesh.handles.size(), grid.handles.size());
  for (std::size_t h = 0; h < grid.handles.size(); ++h)
    EXPECT_EQ(mesh.handles[h].particles, grid.handles[h].particles);
  // The same triangles (each a rotation of the grid's corners).
  auto sorted = [](std::vector<std::array<int, 3>> t) {
    for (auto& f : t) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    std::sort(t.begin(), t.end());
    return t;
  };
  EXPECT_EQ(sorted(mesh.triangles), sorted(grid.triangles));
}

// The step's defaults from the mesh as from the grid it is: xpbd's substeps
// by the particles along the longer side (131: 13 substeps, where a mesh
// cloth had the default grid's 10), the explicit step's limit by the stiffest
// springs and the lightest particle.
TEST(MeshCloth, StepDefaultsComeFromTheMesh) {
  const Params p =
      load_scene("pull-straight", {"cloth.resolution=[131,11]", "cloth.size=[0.39,0.03]",
                                   "integrator.type=xpbd", "integrator.dt=0.004166666666666667"});
  const Model grid = build_model(p);
  const Model mesh = build_model(with_mesh(p, "long", grid_obj(p)));
  EXPECT_EQ(xpbd_substeps(p), 13);
  EXPECT_EQ(xpbd_substeps(grid), 13);
  EXPECT_EQ(mesh.topology->along, 131);
  EXPECT_EQ(xpbd_substeps(mesh), 13);
  // The springs' limit exactly as the grid's (Provot's bending springs too);
  // the quadratic bending's bound from the mesh's own Q, where the grid's is
  // a formula (explicit_step_limit(Params)): within 2 %.
  Params provot = p;
  provot.material.bending = BendingModel::Provot;
  EXPECT_NEAR(explicit_step_limit(build_model(with_mesh(provot, "long", grid_obj(provot)))),
              explicit_step_limit(provot), 1e-9 * explicit_step_limit(provot));
  EXPECT_EQ(explicit_step_limit(build_model(provot)), explicit_step_limit(provot));
  EXPECT_NEAR(explicit_step_limit(mesh), explicit_step_limit(p), 0.02 * explicit_step_limit(p));
  EXPECT_NEAR(explicit_step_limit(grid), explicit_step_limit(mesh), 0.01 * explicit_step_limit(p));
  // Set substeps win, as on the grid.
  Params set = with_mesh(p, "long", grid_obj(p));
  set.integrator.substeps = 4;
  EXPECT_EQ(xpbd_substeps(build_model(set)), 4);
}

// The grid read from a file runs the general kernels (mesh_cloth.cpp), the
// built-in grid its stencil's: the same physics, summed in another order, and
// the springs' damping by one Gauss-Seidel sweep where the grid solves it by
// operator splitting. Close, not bit-identical.
TEST(MeshCloth, TheGridFromAFileRunsAsTheGrid) {
  for (const char* integrator : {"symplectic-euler", "implicit-euler", "xpbd"}) {
    Params p = grid_scene();
    p = load_scene("pull-straight",
                   {"cloth.resolution=[15,11]", "cloth.size=[0.3,0.2]",
                    std::string("integrator.type=\"") + integrator + "\"",
                    std::string(integrator) == "symplectic-euler" ? "integrator.dt=5e-5"
                                                                  : "integrator.dt=0.002"});
    Simulation grid(p), mesh(with_mesh(p, "grid_run", grid_obj(p)));
    ASSERT_TRUE(grid.advance_to(0.4));
    ASSERT_TRUE(mesh.advance_to(0.4));
    const Metrics g = grid.metrics(), m = mesh.metrics();
    SCOPED_TRACE(integrator);
    EXPECT_NEAR(m.handle_height_m, g.handle_height_m, 0.01 * g.handle_height_m);
    EXPECT_NEAR(m.max_height_m, g.max_height_m, 0.01 * g.max_height_m);
    EXPECT_NEAR(m.contact_area_m2, g.contact_area_m2, 0.03 * g.contact_area_m2 + 1e-4);
    EXPECT_NEAR(m.centroid_x_m, g.centroid_x_m, 1e-3);
    EXPECT_NEAR(m.centroid_y_m, g.centroid_y_m, 1e-3);
    double worst = 0;
    for (int k = 0; k < grid.model().n; ++k)
      worst = std::max(worst, (mesh.state().x[k] - grid.state().x[k]).norm());
    EXPECT_LT(worst, 5e-4);
    std::printf("%s: handle %.6f / %.6f m, contact %.6f / %.6f m², largest gap %.3g m\n",
                integrator, m.handle_height_m, g.handle_height_m, m.contact_area_m2,
                g.contact_area_m2, worst);
  }
}

Params disc_scene(std::vector<std::string> sets = {}) {
  Params p = load_scene("drop-table", sets);
  return with_mesh(p, "disc", disc_obj(0.1, 10));
}

// F = ma for a free mesh cloth: a force on a patch in the middle, no gravity,
// no drag, no surface; springs, their damping and the strain limit are
// internal, so Σ m v = F t.
TEST(MeshCloth, AFreeMeshClothAcceleratesAsFOverM) {
  Params p = test::bare();
  p.springs = {};  // from the material
  p.strain_limit.enabled = true;
  p.self_collision.enabled = true;
  p = with_mesh(p, "disc_free", disc_obj(0.1, 10));
  HandleParams h;
  h.type = HandleType::Force;
  h.at = {0.3, 0.5};
  h.patch = 1;
  h.force = {0.002, 0, 0.01};
  p.handles["pull"] = h;
  Simulation sim(p);
  const Model& m = sim.model();
  EXPECT_FALSE(m.grid);
  EXPECT_GT(m.handles[0].particles.size(), 3u);
  double mass = 0;
  for (double x : m.mass) mass += x;
  const double t = 0.05;
  ASSERT_TRUE(sim.advance_to(t));
  Vec3 momentum = Vec3::Zero();
  for (int k = 0; k < m.n; ++k) momentum += m.mass[k] * sim.state().v[k];
  const Vec3 expected = Vec3(0.002, 0, 0.01) * sim.state().time;
  EXPECT_NEAR((momentum - expected).norm(), 0, 1e-9 * expected.norm()) << momentum.transpose();
  // The cloth's area and mass are the disc's (a polygon of 60 sides inscribed).
  double area = 0;
  for (double a : m.area) area += a;
  EXPECT_NEAR(area, 0.5 * 60 * 0.01 * std::sin(2 * std::numbers::pi / 60), 1e-12);
  (void)mass;
}

// Dropped onto the table, a mesh cloth lands, stays above it and comes to rest,
// with every integrator.
TEST(MeshCloth, AMeshClothDropsOntoTheTableAndSettles) {
  for (const auto& [integrator, dt] :
       {std::pair{"symplectic-euler", "5e-5"}, std::pair{"implicit-euler", "0.002"},
        std::pair{"xpbd", "0.004166666666666667"}}) {
    SCOPED_TRACE(integrator);
    Params p = disc_scene({std::string("integrator.type=\"") + integrator + "\"",
                           std::string("integrator.dt=") + dt, "cloth.center=[0,0,0.03]",
                           "cloth.humidity=0.3"});
    Simulation sim(p);
    ASSERT_TRUE(sim.advance_to(1.0));
    const Metrics r = sim.metrics();
    double area = 0;
    for (double a : sim.model().area) area += a;
    for (int k = 0; k < sim.model().n; ++k) EXPECT_GE(sim.state().x[k].z(), -1e-9);
    EXPECT_GT(r.contact_area_m2, 0.9 * area);
    EXPECT_LT(r.max_height_m, 5e-3);
    EXPECT_LT(r.kinetic_energy_j, 1e-6);
  }
}

// A mesh that is no grid takes the wet model: lifted by its middle on a wet
// table it holds a tent of trapped air under suction, its contact region
// feels eq. 13's adhesion exactly, and with `vented` its pockets follow the
// mesh's edges.
TEST(MeshCloth, ANonGridMeshTakesAirAndAdhesion) {
  for (const char* air : {"exchange", "vented"}) {
    SCOPED_TRACE(air);
    Params p = disc_scene(
        {"cloth.humidity=0.7", "cloth.center=[0,0,0]", std::string("air.model=\"") + air + "\""});
    HandleParams h;
    h.type = HandleType::Move;
    h.at = {0.5, 0.5};
    h.patch = 1;
    h.velocity = {0, 0, 0.1};
    h.max_travel = 0.04;
    p.handles["lift"] = h;
    Simulation sim(p);
    ASSERT_TRUE(sim.advance_to(0.5));
    const Metrics r = sim.metrics();
    EXPECT_GT(r.contact_area_m2, 0);
    EXPECT_GT(r.lifted_area_m2, 0);
    EXPECT_GT(r.air_volume_m3, 0);
    EXPECT_GT(r.max_height_m, 0.01);
    // `exchange`: one pocket under the cloth, under suction. `vented`: this tent
    // reaches the cloth's border, so it is open to the room.
    if (std::string(air) == "exchange") {
      EXPECT_LT(r.inner_pressure_pa, sim.model().params.air.p_atm - 1);
    } else {
      EXPECT_NEAR(r.inner_pressure_pa, sim.model().params.air.p_atm, 1e-6);
    }
    // Pockets are flooded along the mesh's edges: two lifted neighbours
    // share theirs.
    const Model& m = sim.model();
    for (int k = 0; k < m.n; ++k)
      for (int e = m.topology->edge_start[k]; e < m.topology->edge_start[k + 1]; ++e) {
        const int o = m.topology->edge_neighbour[e];
        if (!sim.state().contact[k] && !sim.state().contact[o] && sim.state().pocket[k] >= 0 &&
            sim.state().pocket[o] >= 0) {
          EXPECT_EQ(sim.state().pocket[k], sim.state().pocket[o]);
        }
      }
    double sum = 0;
    for (double f : sim.adhesion()) sum += f;
    EXPECT_NEAR(sum, adhesion_total(sim.model().params, r.contact_area_m2), 1e-9 * sum);
    // The lifted particles sit in pockets, the contact ones in none.
    int in_pocket = 0;
    for (int k = 0; k < sim.model().n; ++k) {
      if (std::string(air) == "vented" && sim.state().contact[k]) {
        EXPECT_LT(sim.state().pocket[k], 0);
      }
      in_pocket += sim.state().pocket[k] >= 0;
    }
    std::printf("%s: contact %.4f m², lifted %.4f m², P_in %.1f Pa, V_sum %.3g m³, peak %.3g m\n",
                air, r.contact_area_m2, r.lifted_area_m2, r.inner_pressure_pa, r.air_volume_m3,
                r.max_height_m);
    EXPECT_GT(in_pocket, 0);
    // Border of the contact region: only contact particles, and some.
    const auto& border = detail::workspace(sim).border;
    int on_border = 0;
    for (int k = 0; k < sim.model().n; ++k) {
      if (border[k]) {
        EXPECT_TRUE(sim.state().contact[k]);
      }
      on_border += border[k];
    }
    EXPECT_GT(on_border, 0);
  }
}

// A mesh cloth's result does not depend on the thread count (it runs on one).
TEST(MeshCloth, ThreadsChangeNoBit) {
  Params p = disc_scene({"cloth.humidity=0.7", "cloth.center=[0,0,0.01]"});
  Params q = p;
  q.integrator.threads = 2;
  Simulation a(p), b(q);
  ASSERT_TRUE(a.advance_to(0.05));
  ASSERT_TRUE(b.advance_to(0.05));
  EXPECT_EQ(a.state().x, b.state().x);
  EXPECT_EQ(a.state().v, b.state().v);
}

// The built-in scene with a mesh cloth loads and steps; its mesh is the
// script's (tools/make_cloth_meshes.py).
TEST(MeshCloth, TheBuiltInDiscDrapes) {
  const Params p = load_scene("drape-disc");
  Simulation sim(p);
  EXPECT_FALSE(sim.model().grid);
  EXPECT_EQ(sim.model().n, 1951);
  ASSERT_TRUE(sim.advance_to(0.01));
}

TEST(MeshCloth, BadMeshesAreRefusedNamingTheFile) {
  const fs::path dir = temp_dir("bad");
  std::ofstream(dir / "scene.toml") << "[cloth]\nmesh = \"flat.obj\"\n";
  std::ofstream(dir / "flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
  try {
    load_scene((dir / "scene.toml").string());
    ADD_FAILURE() << "a degenerate mesh loaded";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("flat.obj"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("degenerate"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "scene.toml", std::ios::trunc) << "[cloth]\nmesh = \"missing.obj\"\n";
  try {
    load_scene((dir / "scene.toml").string());
    ADD_FAILURE() << "a missing mesh loaded";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.toml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cloth.mesh"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace wetcloth
