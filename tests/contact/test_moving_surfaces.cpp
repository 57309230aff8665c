// Moving surfaces (docs/model.md section 3, "Moving surfaces"): contact and
// friction act on the cloth's velocity relative to the surface. A cloth on a
// plate sliding at constant velocity rides along with enough friction and
// stays put with none; a ball moving into a hanging cloth pushes it and never
// holds it inside; a moving scene keeps its bits on any thread count and
// across a restore.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>

#include "common.hpp"
#include "detail.hpp"
#include "wetcloth/motion.hpp"

using namespace wetcloth;
namespace fs = std::filesystem;

namespace {

using test::TempDir;

// A square plate of half-side 1 m in the xy plane (an open mesh, a shell 2 mm
// thick), sliding along x at `speed` from t = 0: a moving table.
Params on_sliding_plate(const TempDir& dir, double speed, const std::vector<std::string>& sets) {
  dir.write("meshes/plate.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n");
  std::vector<std::string> all = {"cloth.humidity=0", "air.model=\"off\""};
  all.insert(all.end(), sets.begin(), sets.end());
  Params p = test::coarse("pull-straight", all);
  p.handles.clear();
  p.table.enabled = false;
  p.scene_dir = dir.path.string();
  ObstacleParams o;
  o.mesh = "meshes/plate.obj";
  o.thickness = 0.002;
  o.contact = true;
  o.motion.keys = {{0, {0, 0, 0}, {0, 0, 0}}, {10, {10 * speed, 0, 0}, {0, 0, 0}}};
  p.obstacles["plate"] = o;
  p.contact.surface = SurfaceChoice::Obstacle;
  p.cloth.center = {0, 0, 0.0012};  // 0.2 mm above the shell
  return p;
}

Vec3 mean_of(const Vec3Array& a) {
  Vec3 sum = Vec3::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) sum += a[i];
  return sum / static_cast<double>(a.size());
}

const std::vector<std::string> kXpbd = {"integrator.type=xpbd",
                                        "integrator.dt=0.004166666666666667"};

}  // namespace

// Dry, on a plate that starts sliding at v: friction μ g accelerates the cloth
// until it moves with the plate (Coulomb: it slips v² / (2 μ g) meanwhile),
// then it rides along, its velocity relative to the plate zero. Both friction
// passes: the small steps' (constraints/friction.cpp) and xpbd's.
TEST(MovingSurfaces, ClothRidesAlongOnASlidingPlate) {
  TempDir dir("moving_ride");
  const double v = 0.1, t = 0.4, mu = Params{}.friction.mu;
  for (const bool xpbd : {false, true}) {
    Simulation sim(on_sliding_plate(dir, v, xpbd ? kXpbd : std::vector<std::string>{}));
    const Vec3 start = mean_of(sim.state().x);
    ASSERT_TRUE(sim.advance_to(t)) << sim.blow_up_reason();
    const Vec3 moved = mean_of(sim.state().x) - start;
    const double slip = v * v / (2 * mu * 9.81);  // 1.7 mm
    EXPECT_NEAR(moved.x(), v * t - slip, 0.1 * slip) << (xpbd ? "xpbd" : "symplectic");
    EXPECT_LT(std::abs(moved.y()), 1e-9);
    for (int i = 0; i < sim.model().n; ++i) {
      ASSERT_NEAR(sim.state().v[i].x(), v, 1e-3) << "particle " << i;
      ASSERT_TRUE(sim.state().contact[i]) << "particle " << i;
    }
  }
}

// Frictionless, the plate's motion along its own plane reaches the cloth
// through nothing: only the normal couples, and the cloth stays where it was
// (to the rounding of the projection: the closest point on a triangle is
// found to an ulp of its x and y).
TEST(MovingSurfaces, FrictionlessPlateSlidesUnderAClothThatStaysPut) {
  TempDir dir("moving_frictionless");
  for (const bool xpbd : {false, true}) {
    std::vector<std::string> sets = {"friction.mu=0"};
    if (xpbd) sets.insert(sets.end(), kXpbd.begin(), kXpbd.end());
    Simulation sim(on_sliding_plate(dir, 0.1, sets));
    const Vec3Array start = sim.state().x;
    ASSERT_TRUE(sim.advance_to(0.3)) << sim.blow_up_reason();
    for (int i = 0; i < sim.model().n; ++i) {
      ASSERT_NEAR(sim.state().x[i].x(), start[i].x(), 1e-12) << "particle " << i;
      ASSERT_NEAR(sim.state().x[i].y(), start[i].y(), 1e-12) << "particle " << i;
      ASSERT_TRUE(sim.state().contact[i]) << "particle " << i;
    }
  }
}

// A plate tilted by theta about x (its downhill direction -(0, cos, sin)),
// moving at the constant velocity V in its own plane, and a dry cloth lying
// on it (tilted with it) that starts with the plate's velocity.
Simulation on_moving_incline(const TempDir& dir, double theta_deg, const Vec3& V, bool xpbd) {
  // No air drag: the law has none.
  std::vector<std::string> sets = {"forces.viscous_damping=0"};
  if (xpbd) sets.insert(sets.end(), kXpbd.begin(), kXpbd.end());
  Params p = on_sliding_plate(dir, 0.0, sets);
  const double th = theta_deg * std::numbers::pi / 180;
  ObstacleParams& plate = p.obstacles["plate"];
  plate.rotate = {theta_deg, 0, 0};
  plate.motion.keys = {{0, {0, 0, 0}, {0, 0, 0}},
                       {10, {10 * V.x(), 10 * V.y(), 10 * V.z()}, {0, 0, 0}}};
  const Vec3 normal(0, -std::sin(th), std::cos(th));
  const Vec3 c = 0.0012 * normal;  // 0.2 mm above the shell, as on the flat plate
  p.cloth.center = {c.x(), c.y(), c.z()};
  p.cloth.tilt = theta_deg;
  Simulation sim(p);
  sim.set_velocities(Vec3Array(static_cast<std::size_t>(sim.model().n), V));
  return sim;
}

// The moving incline (issue 39's check): a constant velocity changes nothing
// (Galilean), so relative to the plate a dry cloth does what it does on a
// still incline. Below Coulomb's threshold (tan θ < μ) it does not slip: it
// moves with the plate. Above it, it slides down the plate at
// a = g (sin θ - μ cos θ), within 5 %.
TEST(MovingSurfaces, ClothOnAMovingInclineSlipsAboveCoulombsThresholdOnly) {
  TempDir dir("moving_incline");
  const double mu = Params{}.friction.mu, g = 9.81, T = 0.3;
  for (const bool xpbd : {false, true}) {
    for (const double theta : {10.0, 30.0}) {
      const double th = theta * std::numbers::pi / 180;
      const Vec3 downhill(0, -std::cos(th), -std::sin(th));
      const Vec3 V = 0.2 * Vec3::UnitX() - 0.1 * downhill;  // across and up the slope
      Simulation sim = on_moving_incline(dir, theta, V, xpbd);
      const Vec3 start = mean_of(sim.state().x);
      ASSERT_TRUE(sim.advance_to(T)) << sim.blow_up_reason();
      const double t = sim.state().time;
      // Relative to the plate, along it (the cloth settles the 0.2 mm onto it).
      const Vec3 normal(0, -std::sin(th), std::cos(th));
      Vec3 slip = mean_of(sim.state().x) - start - V * t;
      slip -= slip.dot(normal) * normal;
      const Vec3 rate = mean_of(sim.state().v) - V;
      const std::string what =
          std::string(xpbd ? "xpbd" : "symplectic") + " at " + std::to_string(theta) + " deg";
      for (int i = 0; i < sim.model().n; ++i)
        ASSERT_TRUE(sim.state().contact[i]) << "particle " << i << ", " << what;
      if (std::tan(th) < mu) {
        EXPECT_LT(slip.norm(), 1e-4) << what << ": slipped " << slip.transpose();
        EXPECT_LT(rate.norm(), 1e-3) << what;
      } else {
        const double a = g * (std::sin(th) - mu * std::cos(th));
        EXPECT_NEAR(rate.dot(downhill), a * t, 0.05 * a * t) << what;
        EXPECT_NEAR(slip.dot(downhill), a * t * t / 2, 0.05 * a * t * t / 2) << what;
        EXPECT_LT((slip - slip.dot(downhill) * downhill).norm(), 0.01 * a * t * t / 2) << what;
      }
    }
  }
}

// A plate rising at 0.1 m/s lifts the cloth lying on it: contact carries it
// along the normal at the plate's velocity.
TEST(MovingSurfaces, ClothOnAPlateThatRisesMovesUpWithIt) {
  TempDir dir("moving_rise");
  Params p = on_sliding_plate(dir, 0.0, {});
  p.obstacles["plate"].motion.keys = {{0, {0, 0, 0}, {0, 0, 0}}, {1, {0, 0, 0.1}, {0, 0, 0}}};
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(0.3)) << sim.blow_up_reason();
  // The plate's top is at 0.03 + 1 mm; the cloth on it, lifted at 0.1 m/s.
  for (int i = 0; i < sim.model().n; ++i) {
    ASSERT_GE(sim.state().x[i].z(), 0.031 - 1e-9) << "particle " << i;
    ASSERT_NEAR(sim.state().v[i].z(), 0.1, 1e-6) << "particle " << i;
  }
}

// A ball moving into a cloth hanging from its top edge pushes it ahead, and
// no particle is ever inside it.
TEST(MovingSurfaces, MovingBallPushesAHangingCloth) {
  for (const bool xpbd : {false, true}) {
    std::vector<std::string> sets = {
        "cloth.orientation=\"vertical\"", "cloth.center=[0,0,0.3]", "table.enabled=false",
        "contact.surface=\"none\"",       "air.model=\"off\"",      "ball.enabled=true",
        "ball.center=[0,-0.1,0.25]",      "ball.radius=0.06"};
    if (xpbd) sets.insert(sets.end(), kXpbd.begin(), kXpbd.end());
    Params p = test::coarse("hang", sets);
    p.ball.motion.keys = {{0, {0, 0, 0}, {0, 0, 0}}, {0.5, {0, 0.2, 0}, {0, 0, 0}}};
    Simulation sim(p);
    const double dt = p.integrator.dt;
    for (double t = 0.05; t <= 0.5 + 1e-9; t += 0.05) {
      ASSERT_TRUE(sim.advance_to(t)) << sim.blow_up_reason();
      const Vec3 c = ball_pose(p, sim.state().time).to_world(to_vec(p.ball.center));
      for (int i = 0; i < sim.model().n; ++i)
        ASSERT_GE((sim.state().x[i] - c).norm(), p.ball.radius - 1e-9)
            << "particle " << i << " at t = " << t;
    }
    // The ball's front is at y = 0.16 at the end; the cloth hung at y = 0.
    double furthest = -1;
    for (int i = 0; i < sim.model().n; ++i) furthest = std::max(furthest, sim.state().x[i].y());
    EXPECT_GT(furthest, 0.12) << (xpbd ? "xpbd" : "symplectic") << " dt " << dt;
  }
}

// A moving surface is a function of time: the same bits on one thread and on
// two, and a state restored half-way continues with the same bits.
TEST(MovingSurfaces, SameBitsOnAnyThreadCountAndAfterARestore) {
  const auto scene = [](const char* threads) {
    // At the scene's 51 x 51 (a coarser grid runs on one thread), in xpbd's
    // steps; the small steps' friction is per particle, as collide is.
    Params p = load_scene("drape-ball", {threads, "run.duration=0.3", "integrator.type=xpbd",
                                         "integrator.dt=0.004166666666666667"});
    p.ball.motion.interpolation = Interpolation::Smooth;
    p.ball.motion.keys = {{0.05, {0, 0, 0}, {0, 0, 0}}, {0.3, {0.05, 0, 0.02}, {0, 30, 10}}};
    return p;
  };
  std::vector<Simulation> sims;
  for (const char* threads : {"integrator.threads=1", "integrator.threads=2"})
    sims.emplace_back(scene(threads));
  ASSERT_EQ(sims[1].model().threads, 2);
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.1)) << sim.blow_up_reason();
  const State middle = sims[0].state();
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.2)) << sim.blow_up_reason();
  Simulation restored(scene("integrator.threads=1"));
  restored.restore(middle);
  ASSERT_TRUE(restored.advance_to(0.2)) << restored.blow_up_reason();
  EXPECT_TRUE(test::same_bits(sims[0].state().x, sims[1].state().x));
  EXPECT_TRUE(test::same_bits(sims[0].state().v, sims[1].state().v));
  EXPECT_TRUE(test::same_bits(sims[0].state().x, restored.state().x));
  EXPECT_TRUE(test::same_bits(sims[0].state().v, restored.state().v));
  int touching = 0;
  for (int i = 0; i < sims[0].model().n; ++i) touching += sims[0].state().contact[i];
  EXPECT_GT(touching, 0);
}

// Deforming obstacles (obstacle.NAME.cache): the mesh's vertices from a
// cache, linear between its frames; contact, friction and adhesion act on the
// cloth's velocity relative to the surface's, the vertices' velocities
// interpolated at the contact point.
namespace {

// An OBJ sequence meshes/STEM_NN.obj (frames 0 to frames - 1 at `fps`) of
// the n x n grid over [-half, half]² in the xy plane, each vertex at
// where(x, y, t): printed to 17 digits, so that the doubles are the ones given.
void write_grid_sequence(const TempDir& dir, const std::string& stem, int n, double half,
                         int frames, double fps,
                         const std::function<Vec3(double, double, double)>& where) {
  std::string faces;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i + 1, b = a + 1, c = a + n + 1, d = a + n;
      faces += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) +
               "\nf " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) +
               "\n";
    }
  const auto mesh = [&](double t) {
    std::string o;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = -half + 2 * half * i / (n - 1), y = -half + 2 * half * j / (n - 1);
        const Vec3 p = where(x, y, t);
        char line[128];
        std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
        o += line;
      }
    return o + faces;
  };
  dir.write("meshes/" + stem + ".obj", mesh(0));
  for (int k = 0; k < frames; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "meshes/%s_%02d.obj", stem.c_str(), k);
    dir.write(name, mesh(k / fps));
  }
}

// The sliding plate of on_sliding_plate, but moved by an OBJ sequence over
// its own mesh (a 2 x 2 grid: the same four corners and two triangles).
Params on_cached_plate(const TempDir& dir, double speed, const std::vector<std::string>& sets) {
  Params p = on_sliding_plate(dir, speed, sets);
  write_grid_sequence(dir, "slide", 2, 1.0, 13, 24,
                      [&](double x, double y, double t) { return Vec3(x + speed * t, y, 0); });
  ObstacleParams& o = p.obstacles["plate"];
  o.mesh = "meshes/slide.obj";
  o.motion = Motion{};
  o.cache = "meshes/slide_##.obj";
  o.cache_fps = 24;
  return p;
}

}  // namespace

// A cache that slides the plate at constant velocity does what the same
// slide by keyframes does (the one moves the mesh, the other the particle
// into the mesh's frame: the same to rounding), in every integrator.
TEST(MovingSurfaces, CacheOfARigidSlideMatchesTheSameSlideByKeyframes) {
  TempDir dir("moving_cache_rigid");
  const double v = 0.1;
  for (const char* integrator : {"symplectic-euler", "implicit-euler", "xpbd"}) {
    std::vector<std::string> sets = {std::string("integrator.type=\"") + integrator + "\""};
    if (integrator[0] == 'x') sets.push_back(kXpbd[1]);
    Simulation keyed(on_sliding_plate(dir, v, sets));
    Simulation cached(on_cached_plate(dir, v, sets));
    ASSERT_TRUE(keyed.advance_to(0.4)) << keyed.blow_up_reason();
    ASSERT_TRUE(cached.advance_to(0.4)) << cached.blow_up_reason();
    double dx = 0, dv = 0;
    for (int i = 0; i < keyed.model().n; ++i) {
      dx = std::max(dx, (keyed.state().x[i] - cached.state().x[i]).norm());
      dv = std::max(dv, (keyed.state().v[i] - cached.state().v[i]).norm());
      ASSERT_EQ(keyed.state().contact[i], cached.state().contact[i]) << integrator << " " << i;
    }
    // (implicit-euler's conjugate gradients carry the rounding further: 2e-8 m)
    EXPECT_LT(dx, integrator[0] == 'i' ? 1e-7 : 1e-9) << integrator;
    EXPECT_LT(dv, 1e-6) << integrator;
    // And it rode along (dry friction: the slip of ClothRidesAlongOnASlidingPlate).
    EXPECT_GT(mean_of(cached.state().x).x(), 0.03) << integrator;
  }
}

// A cache and a motion compose: the cache's shape in the body's frame, then
// the motion. A cache that slides the plate along x under a motion that lifts
// it along z is the plate keyed to do both.
TEST(MovingSurfaces, CacheUnderAMotionIsTheShapeMovedByIt) {
  TempDir dir("moving_cache_motion");
  const double v = 0.1, w = 0.05;
  for (const char* integrator : {"symplectic-euler", "xpbd"}) {
    std::vector<std::string> sets = {std::string("integrator.type=\"") + integrator + "\""};
    if (integrator[0] == 'x') sets.push_back(kXpbd[1]);
    Params keyed = on_sliding_plate(dir, v, sets);
    keyed.obstacles["plate"].motion.keys = {{0, {0, 0, 0}, {0, 0, 0}},
                                            {10, {10 * v, 0, 10 * w}, {0, 0, 0}}};
    Params both = on_cached_plate(dir, v, sets);
    both.obstacles["plate"].motion.keys = {{0, {0, 0, 0}, {0, 0, 0}},
                                           {10, {0, 0, 10 * w}, {0, 0, 0}}};
    Simulation a(keyed), b(both);
    ASSERT_TRUE(a.advance_to(0.3)) << a.blow_up_reason();
    ASSERT_TRUE(b.advance_to(0.3)) << b.blow_up_reason();
    double dx = 0;
    for (int i = 0; i < a.model().n; ++i)
      dx = std::max(dx, (a.state().x[i] - b.state().x[i]).norm());
    // A lifted particle sits on the surface each step, its distance 0 to
    // rounding: whether it is pushed out flips with the rounding, by the
    // plate's rise in a step (w dt, 5 um at most), never by its 15 mm.
    EXPECT_LT(dx, 1e-5) << integrator;
    EXPECT_GT(mean_of(b.state().x).z(), 0.0012 + 0.9 * w * 0.3) << integrator;  // lifted
    EXPECT_GT(mean_of(b.state().x).x(), 0.02) << integrator;                    // and carried
  }
}

namespace {

// A plate 0.6 m square (a shell 2 mm thick, 17 x 17 vertices) whose middle
// rises as a bump, 3 cm high at 0.4 s and held after, under a cloth lying on
// it: the bump must lift the cloth, never through it.
constexpr double kBumpHeight = 0.03, kBumpTime = 0.4, kBumpWidth = 0.08;
double bump(double x, double y, double t) {
  return kBumpHeight * std::min(t / kBumpTime, 1.0) *
         std::exp(-(x * x + y * y) / (kBumpWidth * kBumpWidth));
}
Params on_growing_bump(const TempDir& dir, const std::vector<std::string>& sets) {
  Params p = on_sliding_plate(dir, 0, sets);
  write_grid_sequence(dir, "bump", 17, 0.3, 14, 24,
                      [](double x, double y, double t) { return Vec3(x, y, bump(x, y, t)); });
  ObstacleParams& o = p.obstacles["plate"];
  o.mesh = "meshes/bump.obj";
  o.motion = Motion{};
  o.cache = "meshes/bump_##.obj";
  return p;
}

}  // namespace

// The bump pushes the cloth up: no particle is ever inside the shell by more
// than rounding, and the cloth ends on the bump's top.
TEST(MovingSurfaces, GrowingBumpInACacheLiftsTheCloth) {
  TempDir dir("moving_cache_bump");
  for (const char* integrator : {"symplectic-euler", "implicit-euler", "xpbd"}) {
    std::vector<std::string> sets = {std::string("integrator.type=\"") + integrator + "\"",
                                     "cloth.humidity=1"};
    if (integrator[0] == 'x') sets.push_back(kXpbd[1]);
    Simulation sim(on_growing_bump(dir, sets));
    const Model& m = sim.model();
    double deepest = 0;
    for (double t = 0.05; t <= 0.5 + 1e-9; t += 0.05) {
      ASSERT_TRUE(sim.advance_to(t)) << integrator << ": " << sim.blow_up_reason();
      const SurfacePoses& at = detail::workspace(sim).surfaces;
      const MeshObstacle& shape = detail::mesh_of(m, at, 0);
      EXPECT_EQ(shape.time, sim.state().time);
      for (int i = 0; i < m.n; ++i)
        deepest = std::min(deepest, shape.query(sim.state().x[i]).distance);
    }
    EXPECT_GT(deepest, -1e-9) << integrator;
    // The particle over the bump's middle is on its top (the shell's 1 mm
    // over it), carried up 3 cm; the cloth's edge stays low.
    double top = -1;
    for (int i = 0; i < m.n; ++i) top = std::max(top, sim.state().x[i].z());
    EXPECT_GT(top, kBumpHeight * 0.95 + 0.001) << integrator;
    EXPECT_LT(top, kBumpHeight + 0.001 + 0.0015) << integrator;
  }
  // New parameters (the viewer's, Python's set) take the new cache: at half
  // its speed the bump is half as high at 0.2 s.
  Simulation sim(on_growing_bump(dir, {"integrator.type=\"xpbd\"", kXpbd[1]}));
  Params slower = sim.model().params;
  slower.obstacles["plate"].cache_fps = 12;
  sim.set_params(slower);
  const MeshObstacle& shape = detail::mesh_of(sim.model(), detail::workspace(sim).surfaces, 0);
  EXPECT_EQ(shape.cache, sim.model().obstacles[0]->cache);
  ASSERT_TRUE(sim.advance_to(0.2)) << sim.blow_up_reason();
  double apex = 0;
  for (const Vec3& x : detail::mesh_of(sim.model(), detail::workspace(sim).surfaces, 0).points)
    apex = std::max(apex, x.z());
  EXPECT_NEAR(apex, bump(0, 0, 0.1), 1e-3 * kBumpHeight);
}

// A deforming obstacle is a function of time too: the same bits on one
// thread and on two, and from a state restored half-way.
TEST(MovingSurfaces, CacheGivesTheSameBitsOnAnyThreadCountAndAfterARestore) {
  TempDir dir("moving_cache_bits");
  const auto scene = [&](const char* threads) {
    return on_growing_bump(dir, {threads, "cloth.resolution=[51,51]", "integrator.type=\"xpbd\"",
                                 kXpbd[1], "cloth.humidity=1"});
  };
  std::vector<Simulation> sims;
  for (const char* threads : {"integrator.threads=1", "integrator.threads=2"})
    sims.emplace_back(scene(threads));
  ASSERT_EQ(sims[1].model().threads, 2);
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.05)) << sim.blow_up_reason();
  const State middle = sims[0].state();
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.1)) << sim.blow_up_reason();
  Simulation restored(scene("integrator.threads=1"));
  restored.restore(middle);
  ASSERT_TRUE(restored.advance_to(0.1)) << restored.blow_up_reason();
  EXPECT_TRUE(test::same_bits(sims[0].state().x, sims[1].state().x));
  EXPECT_TRUE(test::same_bits(sims[0].state().v, sims[1].state().v));
  EXPECT_TRUE(test::same_bits(sims[0].state().x, restored.state().x));
  EXPECT_TRUE(test::same_bits(sims[0].state().v, restored.state().v));
  // A copy steps on a shape of its own (copy on write).
  Simulation copy(sims[0]);
  ASSERT_TRUE(copy.advance_to(0.12));
  ASSERT_TRUE(sims[1].advance_to(0.12));
  EXPECT_TRUE(test::same_bits(copy.state().x, sims[1].state().x));
}
