// Handles (src/constraints/handles.cpp): the force a move handle records.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;

// docs/model.md sections 2 and 9: a move handle records everything the rest of the
// cloth does to its patch, the strain limiter's corrections included, so that
// on a slow peel it balances the load of what it lifts: the lifted cloth's
// weight, the suction on it (deficit × lifted area, along the table's normal
// as eq. 3 takes it), and the pull of the cloth still in contact across the
// peel front (front_pull_n: the springs' pull on it, which its adhesion holds
// less what the table carries; negative once the lifted cloth presses the
// front down). At 21 × 21 over the 4 s peel it holds to 0.8 % at the median
// frame and 1.2 % at the 90th percentile (6 % in the frame where the tent
// collapses, 2.77 s). From about 1.4 s the limiter holds the springs at the
// patch: the force it takes reaches 30 % of the rig's by 4 s, and without it
// the recorded force fell short by 7 % at the median frame and 30 % at the
// 90th percentile. (So 3 %, not 10 %: the balance is that good, and 10 %
// would not see the limiter's part at the median.)
// The symplectic step's alone (tests/integrators/test_laws.cpp holds the laws
// every integrator keeps): measured on 2026-11-27, implicit Euler at 1/240 s
// is 32 % off at the median frame (its rig force agrees with this step's
// within 6 % to 1.3 s, but its front pull is twice as large), XPBD 69 % (its
// rig records 0.35 N where this step's records 0.55 N at 0.67 s).
TEST(Handles, PeelRigForceBalancesTheLiftedLoad) {
  const Params p = load_scene("peel-rig", {"cloth.resolution=[21,21]"});
  Simulation sim(p);
  const Model& m = sim.model();
  const Handle& rig = m.handles[m.measured_handle];
  ASSERT_EQ(rig.type, HandleType::Move);
  const double areal_weight =
      p.cloth.areal_density * (1 + p.cloth.water_ratio * p.cloth.humidity) * -p.forces.gravity[2];
  double patch = 0;
  for (const int k : rig.particles) patch += m.area[k];
  std::vector<double> off;   // |recorded / load - 1|, frame by frame
  double limiter_share = 0;  // the largest part of the recorded force the limiter's is
  const long frames = std::lround(p.run.duration * p.run.fps);
  for (long frame = 1; frame <= frames; ++frame) {
    ASSERT_TRUE(sim.advance_to(frame / p.run.fps)) << sim.blow_up_reason();
    const Metrics r = sim.metrics();
    if (r.lifted_area_m2 <= patch * (1 + 1e-9)) continue;  // the peel is not under way yet
    const double suction = p.air.p_atm - r.inner_pressure_pa;
    const double load = (areal_weight + suction) * r.lifted_area_m2 + r.front_pull_n;
    off.push_back(std::abs(r.handle_force_n / load - 1));
    double limiter = 0;
    for (const int k : rig.particles) limiter -= detail::workspace(sim).strain_reaction[k].z();
    limiter_share = std::max(limiter_share, limiter / r.handle_force_n);
  }
  ASSERT_GT(off.size(), std::size_t(frames / 2));
  EXPECT_GT(limiter_share, 0.2);  // the test can fail: the limiter's part matters
  std::sort(off.begin(), off.end());
  EXPECT_LT(off[off.size() / 2], 0.03);
  EXPECT_LT(off[off.size() * 9 / 10], 0.05);
}
