#include <gtest/gtest.h>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;

namespace {
double max_stretch(const Simulation& sim) {
  const Model& m = sim.model();
  double worst = 0;
  for (const SpringKind kind : {SpringKind::Structural, SpringKind::Shear})
    for_each_spring(m, kind, [&](int a, int b, double rest, double, double) {
      const double len = (sim.state().x[b] - sim.state().x[a]).norm();
      worst = std::max(worst, len / rest - 1);
    });
  return worst;
}
}  // namespace

// A cloth of soft springs hanging from two corners: without the limit gravity
// stretches it far past τ_c; with it no spring ends a step longer than the limit.
// At 5e-5 s: at the default 1e-4 s a step's fall under gravity is four times
// longer, and the limiter's two passes leave these springs, 200 times softer
// than the default's, 2.7e-3 over τ_c (the default's stay at 0.023).
TEST(StrainLimit, NoStructuralSpringEndsLongerThanTheLimit) {
  Params p =
      test::coarse("hang", {"springs.structural_k=1", "springs.shear_k=0.1", "integrator.dt=5e-5"});
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
  const State& s = detail::state(sim);
  const Model& m = sim.model();
  const int centre = m.index(m.nu / 2, m.nv / 2);
  EXPECT_EQ(s.source_distance[centre], 0);
  EXPECT_EQ(s.source_distance[0], m.nu / 2 - 1);  // 3 x 3 patch: corner is 11 steps out
}

namespace {
// The plain form of docs/model.md section 2: every pass looks at every spring, level
// by level. A level's corrections are all found from the same positions, each
// split between its ends by inverse mass (a pinned, driven or held end takes
// none) and scaled by 1 / (the most corrections that move either of its ends),
// then applied.
void limit_strain_plainly(const Model& m, State& s, const Workspace& w, double dt) {
  const Vec3Array before = s.x;
  struct Correction {
    int a, b;
    double wa, wb;
    Vec3 corr;
  };
  for (int pass = 0; pass < m.params.strain_limit.passes; ++pass) {
    bool corrected = false;
    for (std::size_t l = 0; l + 1 < w.strain_levels.size(); ++l) {
      std::vector<Correction> level;
      std::vector<int> count(m.n, 0);
      for (int e = w.strain_levels[l]; e < w.strain_levels[l + 1]; ++e) {
        const Workspace::StrainSpring sp = detail::strain_spring(m, w, e);
        const Vec3 d = s.x[sp.b] - s.x[sp.a];
        const double len2 = d.squaredNorm();
        if (len2 <= sp.max_len * sp.max_len) continue;
        const bool fa = m.driven[sp.a] || s.held[sp.a], fb = m.driven[sp.b] || s.held[sp.b];
        const double ia = fa ? 0.0 : m.inv_mass[sp.a], ib = fb ? 0.0 : m.inv_mass[sp.b];
        if (ia + ib == 0) continue;
        corrected = true;
        const double len = std::sqrt(len2);
        level.push_back(
            {sp.a, sp.b, ia / (ia + ib), ib / (ia + ib), d * ((len - sp.max_len) / len)});
        if (ia > 0) ++count[sp.a];
        if (ib > 0) ++count[sp.b];
      }
      std::vector<Vec3> delta(m.n, Vec3::Zero());
      for (const Correction& c : level) {
        const Vec3 step =
            c.corr / double(std::max(c.wa > 0 ? count[c.a] : 0, c.wb > 0 ? count[c.b] : 0));
        if (c.wa > 0) delta[c.a] += c.wa * step;
        if (c.wb > 0) delta[c.b] -= c.wb * step;
      }
      for (int k = 0; k < m.n; ++k)
        if (count[k] > 0) s.x[k] += delta[k];
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
  Workspace w = detail::workspace(sim);
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

namespace {
// A 21 x 21 free cloth (no table, no forces), pulled by a force handle at a
// corner (a source of the adaptive order, its particles free) and, with
// `pinned`, pinned at the opposite corner; then jolted: every particle moved
// by up to 3 mm (spacing 1 cm) and given a velocity, so that many structural
// and shear springs are stretched past τ_c in several levels.
struct Jolted {
  Model m;
  State s;
  Workspace w;
};
Jolted jolted_cloth(bool pinned) {
  Params p = test::bare(21);
  p.strain_limit.enabled = true;
  p.cloth.humidity = 0.6;
  HandleParams pull;
  pull.at = {0, 0};
  pull.patch = 1;
  pull.force = {0.1, 0, 0};
  p.handles["pull"] = pull;
  if (pinned) {
    HandleParams pin;
    pin.type = HandleType::Pin;
    pin.at = {1, 1};
    pin.patch = 1;
    p.handles["pin"] = pin;
  }
  Simulation sim(p);
  Jolted j{sim.model(), sim.state(), detail::workspace(sim)};
  unsigned seed = 12345;
  auto random = [&] {  // in [-1, 1)
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) / double(1u << 23) - 1.0;
  };
  for (int i = 0; i < j.m.n; ++i) {
    if (j.m.driven[i]) continue;
    j.s.x[i] += 3e-3 * Vec3(random(), random(), random());
    j.s.v[i] = Vec3(0.3 + random(), random(), random());
  }
  return j;
}

Vec3 momentum(const Model& m, const State& s) {
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < m.n; ++i) sum += m.mass[i] * Vec3(s.v[i]);
  return sum;
}
Vec3 first_moment(const Model& m, const State& s) {  // Σ m x
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < m.n; ++i) sum += m.mass[i] * Vec3(s.x[i]);
  return sum;
}
}  // namespace

// docs/model.md section 2: a correction is an internal force. One call on a free,
// over-stretched cloth moves no centre of mass and changes no momentum (to
// rounding); the farther end alone moving (Provot's rule, before) changed both.
TEST(StrainLimit, ConservesMomentum) {
  Jolted j = jolted_cloth(false);
  const Vec3 p0 = momentum(j.m, j.s), x0 = first_moment(j.m, j.s);
  const Vec3Array before = j.s.x;
  const double dt = 5e-5;
  detail::limit_strain(j.m, j.s, j.w, dt);
  // How much it did: Σ m |Δx| and Σ m |Δv|, the scales of the sums' rounding.
  double moved = 0;
  int particles = 0;
  for (int i = 0; i < j.m.n; ++i) {
    moved += j.m.mass[i] * (j.s.x[i] - before[i]).norm();
    particles += j.s.x[i] != before[i];
  }
  ASSERT_GT(particles, j.m.n / 4);  // the test can fail: the limiter moved much of the cloth
  EXPECT_GT(j.w.strain_levels.size(), 10u);  // in many levels
  EXPECT_LT((first_moment(j.m, j.s) - x0).norm(), 1e-12 * x0.norm() + 1e-12 * moved);
  EXPECT_LT((momentum(j.m, j.s) - p0).norm(), 1e-12 * p0.norm() + 1e-12 * moved / dt);
  EXPECT_TRUE(j.w.strain_reacting.empty());  // nothing held: nothing to record
}

// With a pin, the pin takes the corrections' other half: the momentum the
// free particles gain is minus the impulse recorded on the pinned ones, and
// pinned particles never move.
TEST(StrainLimit, PinnedParticlesTakeTheReaction) {
  Jolted j = jolted_cloth(true);
  const Vec3 p0 = momentum(j.m, j.s);
  const Vec3Array before = j.s.x;
  const double dt = 5e-5;
  detail::limit_strain(j.m, j.s, j.w, dt);
  Vec3 reaction = Vec3::Zero();
  double moved = 0;
  for (int i = 0; i < j.m.n; ++i) {
    moved += j.m.mass[i] * (j.s.x[i] - before[i]).norm();
    if (j.m.driven[i]) {
      EXPECT_EQ(j.s.x[i], before[i]);
      reaction += j.w.strain_reaction[i];
    } else {
      EXPECT_EQ(j.w.strain_reaction[i], Vec3::Zero());
    }
  }
  ASSERT_GT(reaction.norm(), 0.0);  // the test can fail: a spring to the pin was corrected
  EXPECT_LT((momentum(j.m, j.s) - p0 + dt * reaction).norm(), 1e-12 * moved / dt);
}

// A free cloth (no table, gravity or damping) pulled by a force on its
// midpoint accelerates its centre of mass at F/M, strain limiting or not
// (docs/model.md section 2). Soft springs (20 N/m) let the 1 N pull stretch the
// 51 x 51 cloth past τ_c every step; with the farther end alone moving, the
// limiter pushed the cloth towards the pull, and it accelerated 54 % faster
// (24 % with the springs' default damping). The quadratic bending is on.
TEST(StrainLimit, FreeClothUnderAForceAcceleratesAtFOverM) {
  const Params p =
      load_scene("pull-straight",
                 {"table.enabled=false", "contact.surface=\"none\"", "air.model=\"off\"",
                  "adhesion.enabled=false", "forces.gravity=[0,0,0]", "forces.viscous_damping=0",
                  "wind.k=0", "self_collision.enabled=false", "springs.structural_k=20",
                  "springs.shear_k=20", "springs.structural_damping=0", "springs.shear_damping=0",
                  "handle.pull.force=[1,0,0]", "handle.pull.max_height=0"});
  Simulation sim(p);
  double mass = 0;
  for (const double mi : sim.model().mass) mass += mi;
  const double x0 = sim.metrics().centroid_x_m, t = 0.05, dt = p.integrator.dt;
  double limited = 0;  // steps in which the limiter moved a particle
  while (sim.state().time < t - dt / 2) {
    sim.step();
    limited += !detail::workspace(sim).strain_changed.empty();
  }
  ASSERT_TRUE(sim.blow_up_reason().empty()) << sim.blow_up_reason();
  ASSERT_GT(limited, 0.5 * t / dt);  // the test can fail: the limiter acts most steps
  // Symplectic Euler from rest under a constant force: x_n - x_0 = a dt² n (n + 1) / 2.
  const double a = 2 * (sim.metrics().centroid_x_m - x0) / (t * (t + dt)), force = 1.0;
  EXPECT_NEAR(a / (force / mass), 1.0, 0.01);
}
