#include <gtest/gtest.h>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;

namespace {
double max_stretch(const Simulation& sim) {
  const Model& m = sim.model();
  double worst = 0;
  for (const SpringSet* set : {&m.structural, &m.shear})
    for (std::size_t e = 0; e < set->size(); ++e) {
      const double len = (sim.state().x[set->b[e]] - sim.state().x[set->a[e]]).norm();
      worst = std::max(worst, len / set->rest[e] - 1);
    }
  return worst;
}
}  // namespace

// A cloth of soft springs hanging from two corners: without the limit gravity
// stretches it far past τ_c; with it no spring ends a step longer than the limit.
TEST(StrainLimit, NoStructuralSpringEndsLongerThanTheLimit) {
  Params p = test::coarse("hang", {"springs.structural_k=1", "springs.shear_k=0.1"});
  Params free = p;
  free.strain_limit.enabled = false;
  Simulation limited(p), unlimited(free);
  double worst = 0;
  for (int frame = 1; frame <= 50; ++frame) {
    ASSERT_TRUE(limited.advance_to(frame * 0.02)) << limited.blow_up_reason();
    unlimited.advance_to(frame * 0.02);
    worst = std::max(worst, max_stretch(limited));
  }
  EXPECT_GT(unlimited.metrics().max_strain, 2 * p.strain_limit.tau);  // the test can fail
  EXPECT_LE(worst, p.strain_limit.tau + 1e-3);
}

TEST(StrainLimit, PinnedParticlesNeverMove) {
  Params p = test::coarse("hang", {"springs.structural_k=2", "run.duration=0.2"});
  Simulation sim(p);
  const Vec3 a = sim.state().x[0], b = sim.state().x[sim.model().nu - 1];
  sim.advance_to(0.2);
  EXPECT_EQ(sim.state().x[0], a);
  EXPECT_EQ(sim.state().x[sim.model().nu - 1], b);
  EXPECT_LE(max_stretch(sim), p.strain_limit.tau + 2e-3);
}

TEST(StrainLimit, AdaptiveOrderStartsAtTheHandle) {
  Params p = test::coarse("pull-straight");
  Simulation sim(p);
  const State& s = sim.state();
  const Model& m = sim.model();
  const int centre = m.index(m.nu / 2, m.nv / 2);
  EXPECT_EQ(s.source_distance[centre], 0);
  EXPECT_EQ(s.source_distance[0], m.nu / 2 - 1);  // 3 x 3 patch: corner is 11 steps out
}
