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

namespace {
// The plain form of MODEL.md section 2: every pass looks at every spring, level
// by level, each level's corrections averaged per particle.
void limit_strain_plainly(const Model& m, State& s, const Workspace& w, double dt) {
  const Vec3Array before = s.x;
  for (int pass = 0; pass < m.params.strain_limit.passes; ++pass) {
    bool corrected = false;
    for (std::size_t l = 0; l + 1 < w.strain_levels.size(); ++l) {
      std::vector<Vec3> delta(m.n, Vec3::Zero());
      std::vector<int> count(m.n, 0);
      for (int e = w.strain_levels[l]; e < w.strain_levels[l + 1]; ++e) {
        const auto& sp = w.strain_springs[e];
        const Vec3 d = s.x[sp.b] - s.x[sp.a];
        const double len2 = d.squaredNorm();
        if (len2 <= sp.max_len * sp.max_len) continue;
        corrected = true;
        double wa = sp.nearer == 0 ? 0.5 : (sp.nearer < 0 ? 0.0 : 1.0), wb = 1.0 - wa;
        const bool fa = m.driven[sp.a] || s.held[sp.a], fb = m.driven[sp.b] || s.held[sp.b];
        if (fa) wa = 0, wb = fb ? 0 : 1;
        if (fb) wb = 0, wa = fa ? 0 : 1;
        const double len = std::sqrt(len2);
        const Vec3 corr = d * ((len - sp.max_len) / len);
        if (wa > 0) delta[sp.a] += wa * corr, ++count[sp.a];
        if (wb > 0) delta[sp.b] -= wb * corr, ++count[sp.b];
      }
      for (int k = 0; k < m.n; ++k)
        if (count[k] > 0) s.x[k] += delta[k] / count[k];
    }
    if (!corrected) break;
  }
  for (int i = 0; i < m.n; ++i) s.v[i] += (s.x[i] - before[i]) * (1.0 / dt);
}
}  // namespace

// limit_strain looks only at the springs that can be stretched (those that were
// at the start of a pass, and those of particles moved since): it must give
// exactly the bits of looking at every spring.
TEST(StrainLimit, LooksOnlyWhereNeededWithTheSameBits) {
  // Soft springs and no limit: the pull stretches the cloth far past τ_c.
  Params p = test::coarse("pull-straight", {"springs.structural_k=5", "springs.shear_k=0.5"});
  p.strain_limit.enabled = false;
  Simulation sim(p);
  ASSERT_TRUE(sim.advance_to(0.3)) << sim.blow_up_reason();
  ASSERT_GT(sim.metrics().max_strain, 2 * p.strain_limit.tau);
  const Model& m = sim.model();
  State fast = sim.state(), plain = sim.state();
  Workspace w = sim.workspace();
  p.strain_limit.enabled = true;
  Model limited = m;
  limited.params = p;
  detail::update_strain_order(limited, fast, w);
  plain.source_distance = fast.source_distance;
  const double dt = p.integrator.dt;
  limit_strain_plainly(limited, plain, w, dt);
  detail::limit_strain(limited, fast, w, dt);
  int moved = 0;
  for (int i = 0; i < m.n; ++i) {
    moved += fast.x[i] != sim.state().x[i];
    ASSERT_EQ(fast.x[i], plain.x[i]) << "particle " << i;
    ASSERT_EQ(fast.v[i], plain.v[i]) << "particle " << i;
  }
  EXPECT_GT(moved, 10);  // the test can fail: the cloth was over-stretched
}
