// The large-step integrator, XPBD in substeps (src/integrators/xpbd.cpp): what only
// it has (its sweep, its threads); the laws every integrator keeps are in test_laws.cpp.
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

}  // namespace

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
