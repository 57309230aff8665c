// The large-step integrator, XPBD in substeps (src/integrators/xpbd.cpp): laws with exact
// answers, and agreement with the small-step reference.
#include <gtest/gtest.h>

#include <cmath>

#include "common.hpp"
#include "detail.hpp"
#include "wetcloth/simulation.hpp"

using namespace wetcloth;

namespace {

const std::vector<std::string> kXpbd = {"integrator.type=xpbd",
                                        "integrator.dt=0.004166666666666667"};

std::vector<std::string> with(std::vector<std::string> sets, const std::vector<std::string>& more) {
  sets.insert(sets.end(), more.begin(), more.end());
  return sets;
}

Params xpbd(Params p) {
  p.integrator.type = IntegratorType::Xpbd;
  p.integrator.dt = 1.0 / 240;
  return p;
}

Vec3 centroid(const Simulation& sim) {
  Vec3 c = Vec3::Zero();
  double mass = 0;
  for (int i = 0; i < sim.model().n; ++i) {
    c += sim.model().mass[i] * sim.state().x[i];
    mass += sim.model().mass[i];
  }
  return c / mass;
}

double total_mass(const Model& m) {
  double mass = 0;
  for (double mi : m.mass) mass += mi;
  return mass;
}

}  // namespace

// Newton's second law for the whole cloth: the springs, the strain limit and
// the damping are internal, so a free cloth's centroid accelerates at F/M
// whatever they do, here with the corner pulled hard enough that the strain
// limit acts every substep.
TEST(Xpbd, FreeClothPulledByACornerAcceleratesAtForceOverMass) {
  Params p = xpbd(test::bare(11));
  p.springs.structural_k = 0.5;  // soft: the corner's pull stretches them past τ_c
  p.springs.shear_k = 0.05;
  p.strain_limit.enabled = true;
  HandleParams corner;
  corner.at = {0, 0};
  corner.force = {0.005, 0.002, 0};
  p.handles["corner"] = corner;
  Simulation sim(p);
  const double t = 0.25;
  ASSERT_TRUE(sim.advance_to(t)) << sim.blow_up_reason();
  EXPECT_GT(sim.metrics().max_strain, 0.05);  // the limit is in play
  const double M = total_mass(sim.model());
  const Vec3 expected = 0.5 * (Vec3(0.005, 0.002, 0) / M) * t * t;
  const Vec3 moved = centroid(sim) - Vec3(to_vec(p.cloth.center));
  EXPECT_NEAR(moved.x(), expected.x(), 0.01 * expected.x());
  EXPECT_NEAR(moved.y(), expected.y(), 0.01 * expected.y());
  EXPECT_NEAR(moved.z(), 0.0, 1e-9);
}

// One sweep over the springs moves no particle's share of the momentum: Σ m Δx = 0.
TEST(Xpbd, SpringSweepConservesMomentum) {
  Params p = xpbd(test::bare(9));
  p.springs = Params{}.springs;
  p.strain_limit.enabled = true;
  Simulation sim(p);
  State& s = detail::state(sim);
  for (int i = 0; i < sim.model().n; ++i)  // stretched unevenly, beyond the limit
    s.x[i] = 1.3 * s.x[i] + Vec3(0.001 * std::sin(i), 0.002 * std::cos(3.0 * i), 0.0);
  const Vec3 before = centroid(sim);
  Workspace w = detail::workspace(sim);
  w.x_prev = s.x;
  detail::xpbd_begin_substep(sim.model(), s, w);
  detail::project_springs(sim.model(), s, w, 1.0 / 2400);
  const Vec3 after = centroid(sim);
  EXPECT_GT((s.x[0] - 1.3 * sim.model().rest_position[0]).norm(), 1e-4);  // it did move them
  EXPECT_NEAR((after - before).norm(), 0.0, 1e-15);
}

// Force balance at rest: a cloth hung from a pin along its top edge weighs on
// the pin exactly its weight, carried by the constraints' impulses.
TEST(Xpbd, PinCarriesTheWeightOfTheHangingCloth) {
  Params p = xpbd(test::bare(9));
  p.springs = Params{}.springs;
  p.cloth.orientation = Orientation::Vertical;
  p.forces.gravity = {0, 0, -9.81};
  p.forces.viscous_damping = 2.0;  // settle quickly
  HandleParams top;
  top.type = HandleType::Pin;
  top.at = {0, 1};
  top.span = {1, 0};
  p.handles["top"] = top;
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(3.0)) << sim.blow_up_reason();
  double hanging = 0;  // the weight of the particles the pin does not hold
  for (int i = 0; i < sim.model().n; ++i)
    if (!sim.model().driven[i]) hanging += sim.model().mass[i];
  const double weight = hanging * 9.81;
  // The rig's force: it holds the pinned particles against everything else,
  // their own weight included.
  EXPECT_NEAR(sim.metrics().handle_force_n, total_mass(sim.model()) * 9.81, 0.01 * weight);
  EXPECT_LT(sim.metrics().kinetic_energy_j, 1e-8);
}

// Coulomb's threshold: on a dry table tilted by θ (gravity turned), a cloth
// holds when tan θ < μ and slides when tan θ > μ, as the reference step does.
TEST(Xpbd, DryClothHoldsBelowTheFrictionAngleAndSlidesAbove) {
  const double mu = Params{}.friction.mu;  // 0.3: 16.7°
  for (const double degrees : {12.0, 30.0}) {
    const double th = degrees * M_PI / 180;
    const std::string g = "forces.gravity=[" + std::to_string(9.81 * std::sin(th)) + ",0," +
                          std::to_string(-9.81 * std::cos(th)) + "]";
    Params p = test::coarse("pull-straight", with({"cloth.humidity=0", g}, kXpbd));
    p.handles.clear();
    Simulation sim(p);
    ASSERT_TRUE(sim.advance_to(0.5)) << sim.blow_up_reason();
    const double slid = sim.metrics().centroid_x_m;
    if (std::tan(th) < mu) {
      EXPECT_LT(std::abs(slid), 1e-3) << degrees << "°";
    } else {
      // Sliding at g (sin θ - μ cos θ): 0.5 a t² with the load its weight.
      const double a = 9.81 * (std::sin(th) - mu * std::cos(th));
      EXPECT_NEAR(slid, 0.5 * a * 0.25, 0.05 * 0.5 * a * 0.25) << degrees << "°";
    }
  }
}

// The same bits on one thread and on two, on a grid that takes two.
TEST(Xpbd, TwoThreadsGiveTheSameBitsAsOne) {
  std::vector<Simulation> sims;
  for (const char* threads : {"integrator.threads=1", "integrator.threads=2"})
    sims.emplace_back(load_scene("pull-straight", with({threads, "cloth.humidity=0.5"}, kXpbd)));
  ASSERT_EQ(sims[1].model().threads, 2);
  for (auto& sim : sims) ASSERT_TRUE(sim.advance_to(0.05)) << sim.blow_up_reason();
  for (int i = 0; i < sims[0].model().n; ++i) {
    ASSERT_EQ(sims[0].state().x[i], sims[1].state().x[i]) << "particle " << i;
    ASSERT_EQ(sims[0].state().v[i], sims[1].state().v[i]) << "particle " << i;
  }
}

// Every wet effect on, at a step of 1/240 s: the straight pull runs, lifts and
// keeps within the strain limit's reach.
TEST(Xpbd, RunsTheWetPullAtAFrameRateStep) {
  Simulation sim(test::coarse("pull-straight", with({"cloth.humidity=0.7"}, kXpbd)));
  ASSERT_TRUE(sim.advance_to(1.0)) << sim.blow_up_reason();
  const Metrics r = sim.metrics();
  EXPECT_GT(r.handle_height_m, 0.01);
  EXPECT_GT(r.contact_area_m2, 0.01);
  EXPECT_LT(r.inner_pressure_pa, Params{}.air.p_atm);  // the tent holds suction
  EXPECT_LT(r.max_strain, 0.3);
}
