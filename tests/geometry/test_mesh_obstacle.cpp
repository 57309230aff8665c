// Mesh obstacles (docs/model.md section 3, docs/guide.md "Obstacles"): the CGAL
// tree's distances against the analytic ball, contact and air on a mesh
// contact surface, no penetration, Coulomb's threshold on a mesh incline,
// threads and restores, the scene keys and their errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "common.hpp"
#include "detail.hpp"
#include "geometry/mesh_obstacle.hpp"

using namespace wetcloth;
namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kXpbd = {"integrator.type=xpbd",
                                        "integrator.dt=0.004166666666666667"};

std::vector<std::string> with(std::vector<std::string> sets, const std::vector<std::string>& more) {
  sets.insert(sets.end(), more.begin(), more.end());
  return sets;
}

struct Obj {
  std::vector<Vec3> v;
  std::vector<std::array<int, 3>> f;
  std::string text() const {
    std::ostringstream o;
    o.precision(17);
    for (const Vec3& x : v) o << "v " << x.x() << " " << x.y() << " " << x.z() << "\n";
    for (const auto& t : f) o << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    return o.str();
  }
};

// A UV sphere of radius r about c, counter-clockwise seen from outside.
Obj uv_sphere(const Vec3& c, double r, int rings, int segments) {
  Obj o;
  o.v.push_back(c + Vec3(0, 0, r));
  for (int k = 1; k < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const double th = std::numbers::pi * k / rings, ph = 2 * std::numbers::pi * s / segments;
      o.v.push_back(
          c + r * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  o.v.push_back(c - Vec3(0, 0, r));
  const int south = static_cast<int>(o.v.size()) - 1;
  const auto at = [&](int k, int s) { return 1 + (k - 1) * segments + s % segments; };
  for (int s = 0; s < segments; ++s) o.f.push_back({0, at(1, s), at(1, s + 1)});
  for (int k = 1; k < rings - 1; ++k)
    for (int s = 0; s < segments; ++s) {
      o.f.push_back({at(k, s), at(k + 1, s), at(k + 1, s + 1)});
      o.f.push_back({at(k, s), at(k + 1, s + 1), at(k, s + 1)});
    }
  for (int s = 0; s < segments; ++s) o.f.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
  return o;
}

// A square of side 2 half in the xy plane: an open mesh.
Obj square(double half) {
  Obj o;
  o.v = {Vec3(-half, -half, 0), Vec3(half, -half, 0), Vec3(half, half, 0), Vec3(-half, half, 0)};
  o.f = {{0, 1, 2}, {0, 2, 3}};
  return o;
}

using test::TempDir;

// Params with one obstacle, the contact surface, from `dir`.
void add_contact_obstacle(Params& p, const TempDir& dir, const std::string& file) {
  p.scene_dir = dir.path.string();
  ObstacleParams o;
  o.mesh = file;
  o.contact = true;
  p.obstacles["mesh"] = o;
  p.contact.surface = SurfaceChoice::Obstacle;
}

// The closest a triangle of the sphere comes to its centre: R minus it is the
// chord error, the most the mesh's distance may differ from the ball's.
double chord_error(const Obj& o, const Vec3& c, double r) {
  double nearest = r;
  for (const auto& t : o.f) {
    const Vec3 a = o.v[t[0]], b = o.v[t[1]], d = o.v[t[2]];
    const Vec3 n = (b - a).cross(d - a).normalized();
    nearest =
        std::min(nearest, std::abs((c - a).dot(n)));  // the plane: its nearest point is inside
  }
  return r - nearest;
}

}  // namespace

// A finely triangulated sphere gives the ball's distance within the chord
// error, inside and out, with the ball's normal within the facets' angle.
TEST(MeshObstacle, SphereMeshGivesTheBallsDistanceWithinTheChordError) {
  TempDir dir("mesh_obstacle_sphere");
  const Vec3 c(0.01, -0.02, 0.08);
  const double r = 0.08;
  const Obj sphere = uv_sphere(c, r, 96, 192);
  dir.write("meshes/sphere.obj", sphere.text());
  Params p;
  add_contact_obstacle(p, dir, "meshes/sphere.obj");
  const auto o = build_mesh_obstacle(p, "mesh");
  EXPECT_TRUE(o->closed);
  const double chord = chord_error(sphere, c, r);
  EXPECT_LT(chord, 1e-4);
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    // Directions over the sphere (a Fibonacci lattice), depths from 2 cm in to 5 cm out.
    const double z = 1 - 2 * (k + 0.5) / 400, ph = k * std::numbers::pi * (3 - std::sqrt(5.0));
    const Vec3 dir_k(std::sqrt(1 - z * z) * std::cos(ph), std::sqrt(1 - z * z) * std::sin(ph), z);
    for (const double off : {-0.02, -1e-3, -1e-5, 0.0, 1e-5, 5e-4, 1e-3, 0.01, 0.05}) {
      const Vec3 x = c + (r + off) * dir_k;
      const MeshObstacle::Hit h = o->query(x);
      ASSERT_NEAR(h.distance, off, chord + 1e-12) << "direction " << k << ", offset " << off;
      if (std::abs(off) >= 1e-3) {
        EXPECT_GT(h.normal.dot(dir_k), std::cos(0.05));
      }
      // A bounded search gives the same bits.
      const MeshObstacle::Hit b = o->query_within(x, h.unsigned_distance * 1.001 + 1e-9);
      ASSERT_EQ(b.distance, h.distance);
      ASSERT_EQ(b.normal, h.normal);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 3600);
  // The same sphere with every face turned inward: turned back, the same answers.
  Obj inverted = sphere;
  for (auto& t : inverted.f) std::swap(t[1], t[2]);
  dir.write("meshes/inverted.obj", inverted.text());
  p.obstacles["mesh"].mesh = "meshes/inverted.obj";
  const auto flipped = build_mesh_obstacle(p, "mesh");
  for (const Vec3& x : {Vec3(c + Vec3(0, 0, r + 0.003)), Vec3(c + Vec3(0.02, 0.01, 0.0))}) {
    EXPECT_EQ(flipped->query(x).distance, o->query(x).distance);
    EXPECT_EQ(flipped->query(x).normal, o->query(x).normal);
  }
}

// The same cloth dropped on the ball and on a sphere mesh in its place lands
// alike: contact area and the air under it within a few percent.
TEST(MeshObstacle, ClothOnASphereMeshTouchesAsOnTheBall) {
  TempDir dir("mesh_obstacle_drop");
  const Params ball = test::coarse("drop-ball", kXpbd);
  Params mesh = ball;
  const Obj sphere = uv_sphere(to_vec(ball.ball.center), ball.ball.radius, 48, 96);
  dir.write("meshes/ball.obj", sphere.text());
  mesh.ball.enabled = false;
  add_contact_obstacle(mesh, dir, "meshes/ball.obj");
  Simulation a(ball), b(mesh);
  // At the start: the air under the cloth, from the distance along the normal.
  EXPECT_NEAR(b.state().air_volume, a.state().air_volume, 0.01 * a.state().air_volume);
  ASSERT_TRUE(a.advance_to(0.6)) << a.blow_up_reason();
  ASSERT_TRUE(b.advance_to(0.6)) << b.blow_up_reason();
  const Metrics ma = a.metrics(), mb = b.metrics();
  EXPECT_GT(ma.contact_area_m2, 0.002);
  EXPECT_NEAR(mb.contact_area_m2, ma.contact_area_m2, 0.1 * ma.contact_area_m2);
  EXPECT_NEAR(mb.air_volume_m3, ma.air_volume_m3, 0.1 * ma.air_volume_m3);
  EXPECT_NEAR(mb.max_height_m, ma.max_height_m, 2e-3);
}

// Air pockets over a mesh: the pressure force on lifted particles is along
// the mesh's normal (the ball's, within the facets' angle) and suction
// points into the surface.
TEST(MeshObstacle, AirPressesAlongTheMeshNormal) {
  TempDir dir("mesh_obstacle_air");
  Params p = test::coarse("drape-ball", with({"air.model=\"sealed\""}, kXpbd));
  const Obj sphere = uv_sphere(to_vec(p.ball.center), p.ball.radius, 48, 96);
  dir.write("meshes/ball.obj", sphere.text());
  p.ball.enabled = false;
  add_contact_obstacle(p, dir, "meshes/ball.obj");
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(0.4)) << sim.blow_up_reason();
  const Model& m = sim.model();
  const State& s = detail::state(sim);
  Workspace& w = detail::workspace(sim);
  EXPECT_GT(s.air_volume, 0);
  int pushed = 0;
  for (int i = 0; i < m.n; ++i) {
    if (w.air_direction[i].norm() == 0) continue;
    const Vec3 radial = (s.x[i] - to_vec(p.ball.center)).normalized();
    EXPECT_GT((w.air_direction[i] / m.area[i]).dot(radial), std::cos(0.05)) << i;
    ++pushed;
  }
  EXPECT_GT(pushed, 0);
}

// No particle ever ends a step inside a closed mesh: the mannequin, hit hard.
TEST(MeshObstacle, AClosedMeshIsNeverPenetrated) {
  for (const auto& integrator : std::vector<std::vector<std::string>>{
           kXpbd, {"integrator.type=symplectic-euler", "integrator.dt=5e-5"}}) {
    Simulation sim(
        test::coarse("mannequin-drape", with({"forces.gravity=[0, 0, -40]"}, integrator)));
    const MeshObstacle& torso = *sim.model().obstacles.at(0);
    const double dt = sim.model().params.integrator.dt;
    const int steps = static_cast<int>(std::lround(0.12 / dt));
    double deepest = 0;
    int touching = 0;
    for (int k = 0; k < steps; ++k) {
      sim.step();
      ASSERT_TRUE(sim.blow_up_reason().empty()) << sim.blow_up_reason();
      // Within 1 cm of the surface each step (a particle inside is that near
      // it, or it went deeper in one step than it could), the whole tree at the end.
      for (int i = 0; i < sim.model().n; ++i)
        deepest = std::min(deepest, torso.query_within(sim.state().x[i], 0.01).distance);
    }
    for (int i = 0; i < sim.model().n; ++i) {
      touching += sim.state().contact[i];
      deepest = std::min(deepest, torso.query(sim.state().x[i]).distance);
    }
    EXPECT_GT(touching, 20) << integrator[0];
    EXPECT_GT(deepest, -1e-9) << integrator[0];
  }
}

// Coulomb's threshold on an incline made as a mesh (an open square, a
// shell 2 mm thick), as on the tilted table (Xpbd.DryClothHolds...): a dry
// cloth holds when tan θ < μ and slides at g (sin θ - μ cos θ) above.
TEST(MeshObstacle, DryClothHoldsOnAMeshInclineBelowTheFrictionAngleAndSlidesAbove) {
  TempDir dir("mesh_obstacle_incline");
  dir.write("meshes/incline.obj", square(1.0).text());
  const double mu = Params{}.friction.mu;
  for (const double degrees : {12.0, 30.0}) {
    const double th = degrees * std::numbers::pi / 180;
    Params p =
        test::coarse("pull-straight", with({"cloth.humidity=0", "air.model=\"off\""}, kXpbd));
    p.handles.clear();
    p.table.enabled = false;
    add_contact_obstacle(p, dir, "meshes/incline.obj");
    p.obstacles["mesh"].thickness = 0.002;
    p.obstacles["mesh"].rotate = {degrees, 0, 0};
    const Vec3 normal(0, -std::sin(th), std::cos(th)), downhill(0, -std::cos(th), -std::sin(th));
    const Vec3 c = 0.0012 * normal;  // 0.2 mm above the shell
    p.cloth.center = {c.x(), c.y(), c.z()};
    p.cloth.tilt = degrees;
    Simulation sim(p);
    const auto mean = [&] {
      Vec3 sum = Vec3::Zero();
      for (int i = 0; i < sim.model().n; ++i) sum += sim.state().x[i];
      return Vec3(sum / sim.model().n);
    };
    const Vec3 start = mean();
    ASSERT_TRUE(sim.advance_to(0.5)) << sim.blow_up_reason();
    const double slid = (mean() - start).dot(downhill);
    if (std::tan(th) < mu) {
      EXPECT_LT(std::abs(slid), 1e-3) << degrees << "°";
    } else {
      const double a = 9.81 * (std::sin(th) - mu * std::cos(th));
      EXPECT_NEAR(slid, 0.5 * a * 0.25, 0.1 * 0.5 * a * 0.25) << degrees << "°";
    }
  }
}

// The queries are per particle: the same bits on one thread and on two, and a
// restored state continues with the same bits (the searches' cache bounds
// the search, never the answer).
TEST(MeshObstacle, SameBitsOnAnyThreadCountAndAfterARestore) {
  std::vector<Simulation> sims;
  for (const char* threads : {"integrator.threads=1", "integrator.threads=2"})
    sims.emplace_back(load_scene("mannequin-drape", {threads}));
  ASSERT_EQ(sims[1].model().threads, 2);
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.125)) << sim.blow_up_reason();
  const State middle = sims[0].state();
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.2)) << sim.blow_up_reason();
  Simulation restored(load_scene("mannequin-drape", {"integrator.threads=1"}));
  restored.restore(middle);
  ASSERT_TRUE(restored.advance_to(0.2)) << restored.blow_up_reason();
  int touching = 0;
  for (int i = 0; i < sims[0].model().n; ++i) {
    ASSERT_EQ(sims[0].state().x[i], sims[1].state().x[i]) << "particle " << i;
    ASSERT_EQ(sims[0].state().v[i], sims[1].state().v[i]) << "particle " << i;
    ASSERT_EQ(sims[0].state().x[i], restored.state().x[i]) << "particle " << i;
    touching += sims[0].state().contact[i];
  }
  EXPECT_GT(touching, 0);
}

// The keys: a scene's obstacles read back from its resolved TOML; the
// contact surface and the obstacle must agree; a bad mesh, an open one with
// no thickness, or a path out of the scene's folder is an error naming the
// file and the key.
TEST(MeshObstacle, SceneKeysAndTheirErrors) {
  const Params p = load_scene("bowl-drape");
  ASSERT_EQ(p.obstacles.size(), 1u);
  EXPECT_EQ(p.obstacles.at("bowl").mesh, "meshes/bowl.obj");
  EXPECT_TRUE(p.obstacles.at("bowl").contact);
  const Params back = parse_scene(to_toml(p), "resolved.toml");
  EXPECT_EQ(back.obstacles.at("bowl").mesh, "meshes/bowl.obj");
  EXPECT_EQ(back.obstacles.at("bowl").scale, p.obstacles.at("bowl").scale);
  const auto error = [](const std::string& text, const std::vector<std::string>& sets = {}) {
    try {
      parse_scene(text, "x.toml", sets);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string obstacle = "[obstacle.box]\nmesh = \"m.obj\"\n";
  EXPECT_NE(error(obstacle + "contact = true\n").find("obstacle.box.contact"), std::string::npos);
  EXPECT_NE(error("[contact]\nsurface = \"obstacle\"\n" + obstacle).find("contact.surface"),
            std::string::npos);
  EXPECT_NE(error("[obstacle.box]\nscale = [1, 1, 1]\n").find("obstacle.box.mesh"),
            std::string::npos);
  EXPECT_NE(error(obstacle + "mseh = 1\n").find("did you mean obstacle.box.mesh"),
            std::string::npos);
  EXPECT_NE(error(obstacle, {"obstacle.other.mesh=\"x.obj\""}).find("no such obstacle"),
            std::string::npos);

  TempDir dir("mesh_obstacle_errors");
  dir.write("meshes/open.obj", square(0.5).text());
  dir.write("meshes/bad.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  const auto load_error = [&](const std::string& text) {
    dir.write("scene.toml", text);
    try {
      load_scene((dir.path / "scene.toml").string());
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string open = load_error("[obstacle.plate]\nmesh = \"meshes/open.obj\"\n");
  EXPECT_NE(open.find("obstacle.plate.thickness"), std::string::npos) << open;
  EXPECT_NE(open.find("open.obj"), std::string::npos) << open;
  const std::string bad = load_error("[obstacle.plate]\nmesh = \"meshes/bad.obj\"\n");
  EXPECT_NE(bad.find("obstacle.plate.mesh"), std::string::npos) << bad;
  EXPECT_NE(bad.find("bad.obj"), std::string::npos) << bad;
  const std::string out = load_error("[obstacle.plate]\nmesh = \"../open.obj\"\n");
  EXPECT_NE(out.find("obstacle.plate.mesh"), std::string::npos) << out;
  EXPECT_NE(out.find("leaves the scene file's folder"), std::string::npos) << out;
  const std::string inside = load_error(
      "[cloth]\ncenter = [0, 0, 0.05]\n[obstacle.plate]\nmesh = \"meshes/open.obj\"\n"
      "thickness = 0.2\n");
  EXPECT_NE(inside.find("inside obstacle.plate"), std::string::npos) << inside;
  EXPECT_EQ(load_error("[obstacle.plate]\nmesh = \"meshes/open.obj\"\nthickness = 0.002\n"
                       "translate = [0, 0, -0.01]\n"),
            "no error");
}

// sleeve-pull's claim (docs/guide.md "A garment"): the cuff pulled along the
// arm with 0.1 N slides a dry sleeve off the arm's end, and a wet one, held
// by adhesion's load on friction, barely moves. Measured at 0.4 s: dry, the
// centroid 0.40 m along and nothing in contact; wet, 0.11 mm along and
// 0.057 m² in contact.
TEST(MeshObstacle, AWetSleeveClingsWhereADrySleeveSlidesOff) {
  const auto pull = [](const std::string& humidity) {
    Simulation sim(load_scene("sleeve-pull", {"cloth.humidity=" + humidity}));
    const double x0 = sim.metrics().centroid_x_m;
    EXPECT_TRUE(sim.advance_to(0.4)) << sim.blow_up_reason();
    const Metrics m = sim.metrics();
    return std::pair{m.centroid_x_m - x0, m.contact_area_m2};
  };
  const auto [wet, wet_contact] = pull("1");
  const auto [dry, dry_contact] = pull("0");
  EXPECT_LT(std::abs(wet), 0.002);
  EXPECT_GT(wet_contact, 0.04);  // of the sleeve's 0.061 m²
  EXPECT_GT(dry, 0.3);           // the sleeve is 0.24 m long, its cuff 0.08 m from the end
  EXPECT_LT(dry_contact, 0.005);
}
