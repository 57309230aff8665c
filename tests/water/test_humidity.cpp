// The humidity field (src/water/humidity.cpp, docs/model.md "Humidity
// field"): wicking (water conserved, a Gaussian's variance, a strip's erfc, a
// uniform field kept, stable at any step, the cap), drying, uptake from a film
// (the table's and an obstacle's), the local ω in mass and adhesion, the
// start's maps and regions (and their copies in a run's folder), checkpoints
// and threads.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <regex>

#include "common.hpp"
#include "detail.hpp"
#include "wetcloth/checkpoint.hpp"
#include "wetcloth/run.hpp"

namespace wetcloth {
namespace {

namespace fs = std::filesystem;
using test::bare;

// Σ A_i ω_i: the water held, in units of ρ_A r_w.
double water(const Model& m, const std::vector<double>& c) {
  double sum = 0;
  for (int k = 0; k < m.n; ++k) sum += m.area[k] * c[k];
  return sum;
}

Params grid(int n, double size) {
  Params p = bare(n);
  p.cloth.size = {size, size};
  return p;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

TEST(Wicking, ConservesTheWaterToRounding) {
  const Model m = build_model(grid(31, 0.3));
  std::vector<double> c(m.n);
  for (int k = 0; k < m.n; ++k) c[k] = 0.5 + 0.5 * std::sin(0.37 * k * k + 1.3);  // rough
  HumidityScratch h;
  const double before = water(m, c);
  for (int step = 0; step < 200; ++step) detail::wick(m, c, h, 5e-6 * 0.01);
  EXPECT_NEAR(water(m, c), before, 1e-13 * before);
  for (const double w : c) {
    EXPECT_GE(w, 0.0);
    EXPECT_LE(w, 1.0);
  }
}

// The discrete Laplacian moves the second moment exactly as the continuous
// one, 2 D t along each axis, away from the border.
TEST(Wicking, AGaussianSpotsVarianceGrowsAsTwoDt) {
  const Model m = build_model(grid(121, 0.3));
  const double sigma = 0.01, D = 1e-5, dt = 0.01;
  std::vector<double> c(m.n);
  for (int k = 0; k < m.n; ++k) {
    const Vec3 x = m.rest_position[k];
    c[k] = 0.8 * std::exp(-(x.x() * x.x() + x.y() * x.y()) / (2 * sigma * sigma));
  }
  const auto variance = [&] {
    double w = 0, xx = 0;
    for (int k = 0; k < m.n; ++k) {
      w += m.area[k] * c[k];
      xx += m.area[k] * c[k] * m.rest_position[k].x() * m.rest_position[k].x();
    }
    return xx / w;
  };
  const double v0 = variance();
  EXPECT_NEAR(v0, sigma * sigma, 0.02 * sigma * sigma);
  HumidityScratch h;
  const int steps = 200;  // 2 s
  for (int s = 0; s < steps; ++s) detail::wick(m, c, h, D * dt);
  EXPECT_NEAR(variance() - v0, 2 * D * steps * dt, 0.02 * 2 * D * steps * dt);
}

// A strip wet at one end: its left half soaked (ω1 = 1), its right half damp
// (ω0 = 0.2), the step at x = 0 on the face between two particles (an even
// count). Wicked alone (no forces, no contact) as the step runs it, once per
// kWickingInterval, for t = 10 s at the default D, the field matches the
// line's solution ω0 + (ω1 − ω0)/2 erfc(x / (2√(D t))) away from the ends
// (|x| < a quarter of the strip: the ends' images add erfc(0.1 / 0.014) ≈ 1e−24).
// Returns the largest error there, as a fraction of ω1 − ω0.
double strip_erfc_error(double spacing, double t) {
  const double length = 0.402, D = Params{}.material.wicking_diffusivity;
  const int nu = 2 * static_cast<int>(std::lround((length / spacing + 1) / 2));  // even
  Params p = grid(nu, length);
  p.cloth.resolution = {nu, 3};
  p.cloth.size = {length, 2 * length / (nu - 1)};
  const Model m = build_model(p);
  const double w0 = 0.2, w1 = 1.0;
  std::vector<double> c(m.n);
  for (int k = 0; k < m.n; ++k) c[k] = m.rest_position[k].x() < 0 ? w1 : w0;
  HumidityScratch h;
  const double interval = detail::kWickingInterval;
  const long long steps = std::llround(t / interval);
  for (long long s = 0; s < steps; ++s) detail::wick(m, c, h, D * interval);
  double worst = 0;
  for (int k = 0; k < m.n; ++k) {
    const double x = m.rest_position[k].x();
    if (std::abs(x) > length / 4) continue;
    const double exact = w0 + (w1 - w0) / 2 * std::erfc(x / (2 * std::sqrt(D * t)));
    worst = std::max(worst, std::abs(c[k] - exact) / (w1 - w0));
  }
  return worst;
}

// The erfc check at the default cloth's 6 mm (pull-straight's 51 over 30 cm):
// within 2 %, and second order in the spacing (the error a quarter at half
// the spacing; the 1 ms interval's own error is a few per cent of it).
TEST(Wicking, AStripWetAtOneEndMatchesTheErfcSolution) {
  const double t = 10;  // √(D t) = 7 mm, about one spacing: the hardest the grid sees
  const double e6 = strip_erfc_error(0.006, t), e3 = strip_erfc_error(0.003, t),
               e15 = strip_erfc_error(0.0015, t);
  std::printf(
      "erfc strip, t = %g s: largest error %.3g %% at 6 mm, %.3g %% at 3 mm, %.3g %% at "
      "1.5 mm\n",
      t, 100 * e6, 100 * e3, 100 * e15);
  EXPECT_LT(e6, 0.02);
  EXPECT_LT(e3, e6 / 3);
  EXPECT_LT(e15, e3 / 3);
  // Later, the front wider against the grid, the error smaller.
  EXPECT_LT(strip_erfc_error(0.006, 30), e6 / 2);
}

TEST(Wicking, KeepsAUniformFieldExactly) {
  const Model m = build_model(grid(21, 0.2));
  std::vector<double> c(m.n, 0.3);
  HumidityScratch h;
  detail::wick(m, c, h, 1.0);
  EXPECT_TRUE(same_bits(c, std::vector<double>(m.n, 0.3)));
  EXPECT_EQ(h.cg_iterations, 0);
}

// Wicking every 1 ms (20 steps of 5e-5 s at once, as the step runs it)
// against every step: a wet patch on the default cloth after 1 s.
TEST(Wicking, EveryMillisecondIsWithinTolerance) {
  Params p = grid(51, 0.3);
  p.wet["patch"] = {{0.3, 0.5}, 0.06, 1.0};
  const Model m = build_model(p);
  const double D = 5e-6, dt = 5e-5;
  const long long every = detail::wicking_steps(dt);
  EXPECT_EQ(every, 20);
  std::vector<double> fine = m.initial_humidity, coarse = fine;
  HumidityScratch h;
  for (int s = 0; s < 20000; ++s) detail::wick(m, fine, h, D * dt);
  for (int s = 0; s < 20000 / every; ++s) detail::wick(m, coarse, h, D * dt * every);
  double worst = 0, moved = 0;
  for (int k = 0; k < m.n; ++k) {
    worst = std::max(worst, std::abs(fine[k] - coarse[k]));
    moved = std::max(moved, std::abs(fine[k] - m.initial_humidity[k]));
  }
  std::printf(
      "wicking every 1 ms against every step, 1 s: largest |Δω| %.3g (ω moved up to %.3g)\n", worst,
      moved);
  EXPECT_LT(worst, 1e-4);
  EXPECT_LT(worst, 1e-2 * moved);
}

// Backward Euler: a step far beyond the explicit limit (D Δt / l² = 1e4,
// 40 000 times it) stays within the old field's bounds, keeps the water, and
// evens the field out.
TEST(Wicking, IsStableAtAHugeStep) {
  const Model m = build_model(grid(21, 0.2));
  std::vector<double> c(m.n, 0.0);
  for (int k = 0; k < 40; ++k) c[k] = 1.0;
  const double before = water(m, c),
               mean = before / std::accumulate(m.area.begin(), m.area.end(), 0.0);
  HumidityScratch h;
  detail::wick(m, c, h, 1e-5 * 1e5);  // D = 1e-5 m²/s over Δt = 1e5 s
  EXPECT_NEAR(water(m, c), before, 1e-13 * before);
  double spread = 0;
  for (const double w : c) {
    EXPECT_GE(w, 0.0);
    EXPECT_LE(w, 1.0);
    spread = std::max(spread, std::abs(w - mean));
  }
  EXPECT_LT(spread, 0.02 * mean);  // from 13 times the mean
}

// A saturated region beside a wet one: water flows out of it, never in
// beyond saturation, and none is made or lost.
TEST(Wicking, TheCapKeepsOmegaAtMostOneAndTheWater) {
  const Model m = build_model(grid(25, 0.24));
  std::vector<double> c(m.n, 0.6);
  for (int k = 0; k < m.n; ++k)
    if (k % m.nu < 12) c[k] = 1.0;
  const double before = water(m, c);
  HumidityScratch h;
  for (int s = 0; s < 100; ++s) detail::wick(m, c, h, 1e-5 * 0.1);
  EXPECT_NEAR(water(m, c), before, 1e-13 * before);
  for (const double w : c) EXPECT_LE(w, 1.0);
  EXPECT_LT(c[m.index(11, 12)], 1.0);  // the saturated edge gave some away
  EXPECT_GT(c[m.index(12, 12)], 0.6);
}

// A free cloth (no surface: all of it lifted) dries as exp(-k (1 - RH) t).
TEST(Drying, AFreeUniformClothDecaysExponentially) {
  Params p = grid(11, 0.1);
  p.cloth.humidity = 0.8;
  p.material.drying_rate = 0.5;
  p.air.relative_humidity = 0.4;
  p.integrator.dt = 5e-5;
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(1.0)) << sim.blow_up_reason();
  const double expected = 0.8 * std::exp(-0.5 * 0.6 * 1.0);
  for (const double w : sim.state().humidity) EXPECT_NEAR(w, expected, 0.01 * expected);
  // Its mass follows: ρ_A (1 + r_w ω) A.
  EXPECT_DOUBLE_EQ(sim.model().mass[60],
                   p.cloth.areal_density * (1 + sim.state().humidity[60]) * sim.model().area[60]);
  const Metrics r = sim.metrics();
  EXPECT_NEAR(r.water_kg + r.evaporated_kg, 0.8 * 0.12 * 0.01, 1e-15);
}

// A cloth lying on a wet table takes up its film's water: what the film
// loses, the cloth gains, to rounding.
TEST(Uptake, TheFilmLosesWhatTheClothGains) {
  Params p = grid(11, 0.1);
  p.cloth.center = {0, 0, 0};
  p.table.enabled = true;
  p.contact.surface = SurfaceChoice::Table;
  p.forces.gravity = {0, 0, -9.81};
  p.table.water_film = 2e-5;  // 20 µm: 0.2 g under the 0.1 m cloth, less than it can take
  p.material.uptake_rate = 5;
  p.cloth.humidity = 0.1;
  p.integrator.dt = 1e-4;
  Simulation sim(p);
  const Metrics a = sim.metrics();
  sim.advance_to(0.5);
  const Metrics b = sim.metrics();
  EXPECT_GT(b.water_kg, a.water_kg);
  EXPECT_NEAR(a.film_water_kg - b.film_water_kg, b.water_kg - a.water_kg, 1e-12 * a.film_water_kg);
  EXPECT_NEAR(a.film_water_kg + a.water_kg, b.film_water_kg + b.water_kg, 1e-15);
  for (const double w : sim.state().humidity) EXPECT_LE(w, 1.0);
}

// The same on a mesh obstacle (a plate, obstacle.plate.water_film): the
// film's water and the cloth's together are kept to rounding, in the metrics.
TEST(Uptake, AMeshObstaclesFilmLosesWhatTheClothGains) {
  const test::TempDir dir("obstacle_film");
  dir.write("plate.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  const std::string scene =
      "[cloth]\nresolution = [11, 11]\nsize = [0.1, 0.1]\ncenter = [0, 0, 0.006]\n"
      "humidity = 0.1\n[table]\nenabled = false\n"
      "[obstacle.plate]\nmesh = \"plate.obj\"\nthickness = 0.004\nscale = [0.4, 0.4, 1]\n"
      "translate = [-0.2, -0.2, 0]\ncontact = true\nwater_film = 2e-5\n"
      "[contact]\nsurface = \"obstacle\"\n[material]\nuptake_rate = 5\n";
  Simulation sim(load_scene(dir.write("scene.toml", scene).string()));
  const Metrics a = sim.metrics();
  EXPECT_NEAR(a.film_water_kg, 1000 * 2e-5 * 0.01, 1e-15);  // ρ_w h A over the cloth
  ASSERT_TRUE(sim.advance_to(0.3)) << sim.blow_up_reason();
  const Metrics b = sim.metrics();
  EXPECT_GT(b.contact_area_m2, 0.5 * 0.01);
  EXPECT_GT(b.water_kg - a.water_kg, 0.2 * a.film_water_kg);  // most of it taken up
  EXPECT_NEAR(a.film_water_kg - b.film_water_kg, b.water_kg - a.water_kg, 1e-12 * a.film_water_kg);
  EXPECT_NEAR(a.film_water_kg + a.water_kg, b.film_water_kg + b.water_kg,
              1e-14 * (a.film_water_kg + a.water_kg));
  for (const double w : sim.state().humidity) EXPECT_LE(w, 1.0);

  // A film on an obstacle that is not the contact surface is refused, by key.
  const std::string off = std::regex_replace(scene, std::regex("contact = true\n"), "");
  try {
    load_scene(dir.write("off.toml", off).string());
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("off.toml:13: obstacle.plate.water_film: is set but the "
                                         "obstacle is not the contact surface"),
              std::string::npos)
        << e.what();
  }
}

// Half wet, half dry: each particle's mass follows its own ω, and a dry
// particle in contact feels no adhesion.
TEST(LocalHumidity, MassAndAdhesionFollowEachParticlesOmega) {
  Params p = grid(11, 0.1);
  p.cloth.center = {0, 0, 0};
  p.table.enabled = true;
  p.contact.surface = SurfaceChoice::Table;
  p.material.wicking_diffusivity = 0;
  Simulation sim(p);
  std::vector<double> omega(sim.model().n, 0.0);
  for (int k = 0; k < sim.model().n; ++k)
    if (k % 11 >= 5) omega[k] = 1.0;
  sim.set_humidity_field(omega);
  const Model& m = sim.model();
  for (int k = 0; k < m.n; ++k)
    EXPECT_EQ(m.mass[k],
              p.cloth.areal_density * (1.0 + p.cloth.water_ratio * omega[k]) * m.area[k]);
  sim.step();
  const Params wet = [&] {
    Params q = p;
    q.cloth.humidity = 1;
    return q;
  }();
  const double inner = adhesion_pressure(wet) * m.area[m.index(7, 5)];
  for (int j = 1; j < 10; ++j) {
    EXPECT_EQ(sim.adhesion()[m.index(2, j)], 0.0);
    EXPECT_DOUBLE_EQ(sim.adhesion()[m.index(7, j)], inner);
  }
}

// A mesh cloth (drape-disc's rings of triangles): the cotangent weights,
// none negative, keep the water and the bounds.
TEST(Wicking, OnAMeshClothWithCotangentWeights) {
  const Model m = build_model(load_scene("drape-disc"));
  ASSERT_FALSE(m.grid);
  ASSERT_FALSE(m.topology->wick_w.empty());
  for (const double w : m.topology->wick_w) EXPECT_GT(w, 0.0);
  std::vector<double> c(m.n);
  for (int k = 0; k < m.n; ++k) c[k] = m.rest_position[k].x() > 0 ? 1.0 : 0.2;
  const double before = water(m, c);
  HumidityScratch h;
  for (int s = 0; s < 50; ++s) detail::wick(m, c, h, 1e-5 * 0.1);
  EXPECT_NEAR(water(m, c), before, 1e-13 * before);
  for (const double w : c) {
    EXPECT_GE(w, 0.2 - 1e-12);
    EXPECT_LE(w, 1.0);
  }
  std::vector<double> uniform(m.n, 0.4);
  detail::wick(m, uniform, h, 1.0);
  EXPECT_TRUE(same_bits(uniform, std::vector<double>(m.n, 0.4)));
}

// A uniform field with wicking on gives the bits of one without (nothing to
// spread): today's results are kept.
TEST(LocalHumidity, AUniformFieldRunsAsTheUniformModel) {
  Params p = test::coarse("pull-straight", {"run.duration=0.05"});
  Params off = p;
  off.material.wicking_diffusivity = 0;
  Simulation a(p), b(off);
  a.advance_to(0.05);
  b.advance_to(0.05);
  EXPECT_TRUE(test::same_bits(a.state().x, b.state().x));
  EXPECT_TRUE(same_bits(a.model().mass, b.model().mass));
}

// A wet patch, lifted: the run continues from a checkpoint with the same bits,
// and on two threads as on one (a grid of 51: two threads are used).
TEST(HumidityField, ResumesAndThreadsWithTheSameBits) {
  Params p = load_scene("wet-patch", {"cloth.resolution=[51,51]", "material.drying_rate=0.2"});
  p.integrator.threads = 1;
  Simulation one(p);
  one.advance_to(0.02);
  const fs::path file = fs::temp_directory_path() / "wetcloth_test_humidity.state";
  save_checkpoint(file, one.model().params, one.state());
  one.advance_to(0.04);

  const Checkpoint c = load_checkpoint(file);
  fs::remove(file);
  Simulation resumed(c.params);
  resumed.restore(c.state);
  resumed.advance_to(0.04);
  EXPECT_TRUE(test::same_bits(one.state().x, resumed.state().x));
  EXPECT_TRUE(same_bits(one.state().humidity, resumed.state().humidity));
  EXPECT_TRUE(same_bits(one.model().mass, resumed.model().mass));

  Params p2 = p;
  p2.integrator.threads = 2;
  Simulation two(p2);
  ASSERT_EQ(two.model().threads, 2);
  two.advance_to(0.04);
  EXPECT_TRUE(test::same_bits(one.state().x, two.state().x));
  EXPECT_TRUE(same_bits(one.state().humidity, two.state().humidity));
  // The field varies, and has dried a little.
  const Metrics r = one.metrics();
  EXPECT_LT(r.humidity_max, 1.0);
  EXPECT_GT(r.humidity_max, 0.99);
  EXPECT_LT(r.humidity_min, 1e-6);
  EXPECT_LT(r.humidity_mean, 0.2);
}

// [wet.NAME]: a disc of radius r (m) about the particle nearest `at`.
TEST(WetMaps, ARegionWetsADiscAboutItsCentre) {
  Params p = grid(21, 0.2);  // 1 cm spacing
  p.cloth.humidity = 0.1;
  p.wet["spot"] = {{0.5, 0.5}, 0.03, 0.9};
  const Model m = build_model(p);
  int wet = 0;
  for (int k = 0; k < m.n; ++k) {
    const double r = (m.rest_position[k] - m.rest_position[m.index(10, 10)]).norm();
    EXPECT_EQ(m.initial_humidity[k], r <= 0.03 + 1e-12 ? 0.9 : 0.1) << k;
    wet += m.initial_humidity[k] == 0.9;
  }
  EXPECT_EQ(wet, 29);  // lattice points within 3 steps
}

// cloth.humidity_map: a grayscale image over (u, v), v up.
TEST(WetMaps, AnImageSetsOmegaByUV) {
  const fs::path dir = fs::temp_directory_path() / "wetcloth_test_wetmap";
  fs::create_directories(dir);
  {
    // 2 x 2 PGM: top row black, white; bottom row 51, 102.
    std::ofstream f(dir / "wet.pgm", std::ios::binary);
    f << "P5\n2 2\n255\n";
    const unsigned char px[4] = {0, 255, 51, 102};
    f.write(reinterpret_cast<const char*>(px), 4);
  }
  {
    std::ofstream f(dir / "scene.toml");
    f << "[cloth]\nresolution = [3, 3]\nhumidity_map = \"wet.pgm\"\n";
  }
  const Params p = load_scene((dir / "scene.toml").string());
  const Model m = build_model(p);
  EXPECT_DOUBLE_EQ(m.initial_humidity[m.index(0, 0)], 0.2);  // (u, v) = (0, 0): bottom left
  EXPECT_DOUBLE_EQ(m.initial_humidity[m.index(2, 0)], 0.4);
  EXPECT_DOUBLE_EQ(m.initial_humidity[m.index(0, 2)], 0.0);  // top left
  EXPECT_DOUBLE_EQ(m.initial_humidity[m.index(2, 2)], 1.0);
  EXPECT_DOUBLE_EQ(m.initial_humidity[m.index(1, 1)], (0 + 1 + 0.2 + 0.4) / 4);
  fs::remove_all(dir);
}

// A run's folder holds its own copy of the wet map (maps/) and of a handle's
// vertex list (lists/), listed in its manifest, and its scene.toml names them:
// with the scene's folder gone, the folder resumes, and reruns, to the bytes
// of a run never stopped.
TEST(WetMaps, ARunFolderCopiesTheMapAndResumesWithoutTheScene) {
  const test::TempDir dir("wetmap_run");
  const fs::path src = dir.path / "scene";
  fs::create_directories(src / "img");
  std::string image = "P5\n3 3\n255\n";
  for (const int v : {0, 40, 255, 90, 255, 255, 0, 128, 200}) image += static_cast<char>(v);
  std::ofstream(src / "img" / "wet.pgm", std::ios::binary) << image;
  std::ofstream(src / "pin.txt") << "0 8\n";
  std::ofstream(src / "scene.toml") << "name = \"map\"\n[cloth]\nresolution = [9, 9]\n"
                                       "humidity_map = \"img/wet.pgm\"\n"
                                       "[handle.pin]\ntype = \"pin\"\nvertices = \"pin.txt\"\n"
                                       "[integrator]\ndt = 2e-4\nthreads = 1\n"
                                       "[run]\nduration = 0.06\nfps = 100\n";
  const Params p = load_scene((src / "scene.toml").string());
  ASSERT_EQ(run_scene(p, dir.path / "ref").code, kOk);
  long long polls = 0;
  RunHooks stop_early;
  stop_early.stop = [&] { return ++polls >= 150 ? SIGINT : 0; };  // at 0.03 s
  const fs::path out = dir.path / "stopped";
  ASSERT_EQ(run_scene(p, out, stop_early).code, 128 + SIGINT);
  ASSERT_TRUE(fs::exists(out / "checkpoint.state"));

  const auto text = [](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(text(out / "maps" / "wet.pgm"), image);
  EXPECT_EQ(text(out / "lists" / "pin.txt"), "0 8\n");
  const std::string scene = text(out / "scene.toml"), manifest = text(out / kManifest);
  EXPECT_NE(scene.find("humidity_map = \"maps/wet.pgm\"\n"), std::string::npos) << scene;
  EXPECT_NE(scene.find("vertices = \"lists/pin.txt\"\n"), std::string::npos) << scene;
  for (const char* f : {"maps/\n", "maps/wet.pgm\n", "lists/\n", "lists/pin.txt\n"})
    EXPECT_NE(manifest.find(f), std::string::npos) << f << " not in\n" << manifest;

  fs::rename(src, dir.path / "gone");  // the scene's files are no longer where it named them
  const ResumePoint from = load_resume_point(out);
  ASSERT_EQ(run_scene(from.params, out, {}, &from).code, kOk);
  EXPECT_EQ(text(out / "metrics.csv"), text(dir.path / "ref" / "metrics.csv"));
  const Params again = load_scene((out / "scene.toml").string());
  ASSERT_EQ(run_scene(again, dir.path / "again").code, kOk);
  EXPECT_EQ(text(dir.path / "again" / "metrics.csv"), text(dir.path / "ref" / "metrics.csv"));
}

// Errors name the file, the line and the key.
TEST(WetMaps, SceneErrorsNameFileLineAndKey) {
  const fs::path dir = fs::temp_directory_path() / "wetcloth_test_wetmap_errors";
  fs::create_directories(dir);
  const auto error_of = [&](const std::string& text) {
    std::ofstream(dir / "scene.toml") << text;
    try {
      load_scene((dir / "scene.toml").string());
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string file = (dir / "scene.toml").string();
  std::string e = error_of("name = \"x\"\n[cloth]\nhumidity_map = \"missing.png\"\n");
  EXPECT_NE(e.find(file + ":3: cloth.humidity_map: "), std::string::npos) << e;
  EXPECT_NE(e.find("no such file"), std::string::npos) << e;
  e = error_of("[wet.a]\nat = [0.5, 0.5]\nradius = 0.0\n");
  EXPECT_NE(e.find(file + ":3: wet.a.radius: value 0.0 is out of range"), std::string::npos) << e;
  e = error_of("[wet.a]\n\nhumidity = 1.5\n");
  EXPECT_NE(e.find(file + ":3: wet.a.humidity: value 1.5 is out of range [0, 1]"),
            std::string::npos)
      << e;
  e = error_of("[wet.a]\nradius = 0.1\nhumidty = 1\n");
  EXPECT_NE(e.find("did you mean wet.a.humidity?"), std::string::npos) << e;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace wetcloth
