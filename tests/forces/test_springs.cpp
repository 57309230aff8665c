#include <gtest/gtest.h>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;

namespace {

// A 2 x 2 cloth of 1 cm cells with structural springs only (k, k_d); particles
// 2 and 3 sit 1 cm above 0 and 1 and move with them, so that their springs
// are at rest and only the spring 0-1 acts on particles 0 and 1.
Vec3Array forces_on_pair(double k, double kd, const Vec3& x1, const Vec3& v1) {
  Params p = test::bare(2);
  p.springs.structural_k = k;
  p.springs.structural_damping = kd;
  p.springs.shear_k = p.springs.bending_k = 0;
  Simulation sim(p);
  State& s = detail::state(sim);
  const Vec3 up(0, 0, 0.01);
  s.x = {Vec3::Zero(), x1, up, x1 + up};
  s.v = {Vec3::Zero(), v1, Vec3::Zero(), v1};
  Workspace& w = detail::workspace(sim);
  w.force.assign(w.force.size(),
                 Vec3::Constant(7.0));  // the springs set the force: none of it stays
  detail::set_spring_forces(sim.model(), s, w, true);
  return w.force;
}

}  // namespace

TEST(Springs, ForceMatchesEquation1) {
  // |d| = 0.02 against a rest length of 0.01; (v_b - v_a)·u = 0.5
  const auto f = forces_on_pair(200, 0.01, Vec3(0.012, 0.016, 0), Vec3(0.3, 0.4, 1.0));
  const Vec3 u(0.6, 0.8, 0);
  const Vec3 expected = u * (200 * (0.02 - 0.01) + 0.01 * 0.5);
  EXPECT_NEAR((f[0] - expected).norm(), 0, 1e-12);
  EXPECT_NEAR((f[1] + expected).norm(), 0, 1e-12);
}

TEST(Springs, CompressedSpringPushesApart) {
  const auto f = forces_on_pair(100, 0, Vec3(0.005, 0, 0), Vec3::Zero());
  EXPECT_NEAR(f[0].x(), -0.5, 1e-12);
  EXPECT_NEAR(f[1].x(), 0.5, 1e-12);
}

TEST(Springs, UndampedSpringKeepsEnergyUnderSymplecticEuler) {
  // 2 x 2 particles of 7.5 g on a 1 m square: ω Δt ≈ 0.006, where symplectic
  // Euler's energy error (of order ω Δt) is well under 1 %.
  Params p = test::bare(2);
  p.cloth.size = {1.0, 1.0};
  p.springs.structural_k = 200;
  p.springs.shear_k = 0;
  p.springs.bending_k = 0;
  Simulation sim(p);
  detail::state(sim).x[3] += Vec3(0.05, -0.02, 0.03);  // stretch, then let go
  auto energy = [&] {
    const Model& m = sim.model();
    const State& s = detail::state(sim);
    double e = 0;
    for (int i = 0; i < m.n; ++i) e += 0.5 * m.mass[i] * s.v[i].squaredNorm();
    for_each_spring(m, SpringKind::Structural, [&](int a, int b, double rest, double k, double) {
      const double ext = (s.x[b] - s.x[a]).norm() - rest;
      e += 0.5 * k * ext * ext;
    });
    return e;
  };
  const double e0 = energy();
  ASSERT_GT(e0, 0);
  double worst = 0;
  for (int step = 0; step < 100000; ++step) {
    sim.step();
    if (step % 100 == 0) worst = std::max(worst, std::abs(energy() / e0 - 1));
  }
  worst = std::max(worst, std::abs(energy() / e0 - 1));
  EXPECT_LT(worst, 0.01);
}

// The symplectic step's spring damping (apply_spring_damping) on a crumpled
// cloth with random velocities: at a small step it is eq. 1's damping
// force, Δv = h F_d / m; at any step its impulses conserve momentum, its
// velocities stay bounded, and the relative motion only loses energy; and a
// velocity shared by the whole cloth is left alone. On 25 x 25, and on grids
// narrower than a vector (16 floats), whose rows' last vector runs on over
// several rows and past the grid's end; and with the structural or the
// bending springs undamped, where a group of offsets (its horizontal one
// among them) has nothing to solve.
class DampingSolve : public testing::TestWithParam<std::vector<std::string>> {};
INSTANTIATE_TEST_SUITE_P(Grids, DampingSolve,
                         testing::Values(std::vector<std::string>{"cloth.resolution=[25,25]"},
                                         std::vector<std::string>{"cloth.resolution=[7,12]"},
                                         std::vector<std::string>{"cloth.resolution=[12,7]"},
                                         std::vector<std::string>{"cloth.resolution=[25,25]",
                                                                  "springs.structural_damping=0"},
                                         std::vector<std::string>{"cloth.resolution=[12,7]",
                                                                  "springs.bending_damping=0"},
                                         std::vector<std::string>{"cloth.resolution=[25,25]",
                                                                  "springs.structural_damping=0",
                                                                  "springs.shear_damping=0"}));
TEST_P(DampingSolve, ConservesMomentumAndMatchesEquation1) {
  // Provot's bending springs: the solve's second group of offsets.
  std::vector<std::string> sets = GetParam();
  sets.push_back("material.bending=\"provot\"");
  Simulation sim(test::coarse("pull-straight", sets));
  const Model& m = sim.model();
  State& s = detail::state(sim);
  Workspace& w = detail::workspace(sim);
  std::uint64_t seed = 7;
  auto rnd = [&] {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(seed >> 11) / double(1ULL << 53) - 0.5;
  };
  for (int i = 0; i < m.n; ++i) {
    s.x[i] += 2e-3 * Vec3(rnd(), rnd(), rnd());
    s.v[i] = Vec3(rnd(), rnd(), rnd());
  }
  // Eq. 1's damping force: the springs' force with damping minus without.
  std::vector<Vec3> damping(m.n, Vec3::Zero());
  for (const bool with : {true, false}) {
    detail::set_spring_forces(m, s, w, with);
    for (int i = 0; i < m.n; ++i) damping[i] += (with ? 1.0 : -1.0) * w.force[i];
  }
  const Vec3Array v0 = s.v;
  const auto momentum = [&] {
    Vec3 p = Vec3::Zero();
    for (int i = 0; i < m.n; ++i) p += m.mass[i] * s.v[i];
    return p;
  };
  const auto energy = [&] {
    double e = 0;
    for (int i = 0; i < m.n; ++i) e += 0.5 * m.mass[i] * s.v[i].squaredNorm();
    return e;
  };
  const Vec3 p0 = momentum();
  const double e0 = energy();
  const double small = 1e-8;  // h Σk_d / m under 1e-4
  detail::apply_spring_damping(m, s, w, small);
  double worst = 0, scale = 0;
  for (int i = 0; i < m.n; ++i) {
    worst = std::max(worst, (s.v[i] - v0[i] - small * m.inv_mass[i] * damping[i]).norm());
    scale = std::max(scale, (small * m.inv_mass[i] * damping[i]).norm());
  }
  EXPECT_GT(scale, 0);
  EXPECT_LT(worst, 1e-3 * scale);
  for (const double h : {5e-5, 1e-2, 10.0}) {  // h Σk_d / m up to about 1e5
    s.v = v0;
    detail::apply_spring_damping(m, s, w, h);
    EXPECT_LT((momentum() - p0).norm(), 1e-12 * p0.norm() + 1e-15) << h;
    EXPECT_LT(energy(), e0) << h;
  }
  s.v.assign(m.n, Vec3(0.3, -0.2, 0.1));
  detail::apply_spring_damping(m, s, w, 5e-5);
  for (int i = 0; i < m.n; ++i) EXPECT_LT((s.v[i] - Vec3(0.3, -0.2, 0.1)).norm(), 1e-14);
}
