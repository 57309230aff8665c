// Friction (eq. 14, docs/model.md section 6): Coulomb's law with the adhesion in the normal load.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "common.hpp"
#include "detail.hpp"
#include "wet_setups.hpp"

using namespace wetcloth;
using namespace wetcloth::test;

TEST(Friction, NeverReversesOrGrowsAndStopsASlowParticle) {
  Simulation sim = flat_on_table(1.0);
  const Model& m = sim.model();
  State& s = detail::state(sim);
  Workspace& w = detail::workspace(sim);
  detail::update_contact(m, s, w);
  w.force.assign(w.force.size(), Vec3::Zero());
  detail::add_adhesion(m, s, w);
  std::vector<std::uint8_t> touched(m.n, 0);
  const double dt = 5e-5;
  for (int i = 0; i < m.n; ++i) s.v[i] = Vec3(0.01 * (i % 7) - 0.03, 0.002 * (i % 5), 0);
  const Vec3Array before = s.v;
  detail::apply_friction(m, s, w, touched, dt);
  int stopped = 0;
  for (int i = 0; i < m.n; ++i) {
    EXPECT_LE(s.v[i].norm(), before[i].norm() + 1e-15);
    EXPECT_GE(s.v[i].dot(before[i]), -1e-15);  // never reversed
    const double dv = m.params.friction.mu * w.adhesion[i] * dt / m.mass[i];
    if (before[i].norm() <= dv) {
      EXPECT_EQ(s.v[i].norm(), 0.0);
      ++stopped;
    } else {
      EXPECT_NEAR(s.v[i].norm(), before[i].norm() - dv, 1e-12);
    }
  }
  EXPECT_GT(stopped, 0);
}

// The friction pass runs over columns in chunks of kChunk particles, with
// the contact and driven flags made doubles first: on rows longer than a
// chunk, with flags, loads and velocities varying particle by particle, each
// particle must get eq. 14 exactly as it would alone.
TEST(Friction, EachParticleAloneOnRowsLongerThanAChunk) {
  Params p = flat_on_table(0.7, {"cloth.resolution=[70,4]"}).model().params;
  std::vector<int> driven;  // every 11th particle, pinned: driven from t = 0
  for (int i = 4; i < 70 * 4; i += 11) driven.push_back(i);
  pin_particles(p, driven);
  Simulation sim(p);
  const Model& m = sim.model();
  ASSERT_GT(m.nu, detail::kChunk);
  for (int i = 0; i < m.n; ++i) ASSERT_EQ(m.driven[i] != 0, i % 11 == 4) << "particle " << i;
  State& s = detail::state(sim);
  Workspace& w = detail::workspace(sim);
  detail::update_contact(m, s, w);
  w.force.assign(w.force.size(), Vec3::Zero());
  detail::add_adhesion(m, s, w);
  for (int i = 0; i < m.n; ++i) {
    s.contact[i] = i % 5 != 3;
    w.force[i] += Vec3(0.01 * std::sin(i), 0.01 * std::cos(i), 0.002 * std::sin(3.0 * i));
    s.v[i] = Vec3(0.02 * std::sin(0.7 * i), 0.02 * std::cos(1.3 * i), 0.001 * std::sin(i));
  }
  const Vec3Array x0 = s.x, v0 = s.v;
  const double dt = 5e-5, mu = m.params.friction.mu;
  detail::apply_friction(m, s, w, std::vector<std::uint8_t>(m.n, 0), dt);
  int slowed = 0, stopped = 0;
  for (int i = 0; i < m.n; ++i) {
    const Vec3 n = w.surface_normal[i], v = v0[i];
    const double load = w.adhesion[i] + std::max(0.0, -(w.force[i].dot(n) + w.adhesion[i]));
    const Vec3 vt = v - v.dot(n) * n;
    Vec3 slowed_by = Vec3::Zero();
    if (s.contact[i] && !m.driven[i] && load > 0 && vt.norm() > 0)
      slowed_by = vt * (std::min(mu * load * dt / m.mass[i], vt.norm()) / vt.norm());
    slowed += slowed_by.norm() > 0;
    stopped += slowed_by.norm() > 0 && slowed_by == vt;
    const double scale = 1e-15 * v.norm();
    EXPECT_LE((s.v[i] - (v - slowed_by)).norm(), scale) << "particle " << i;
    EXPECT_LE((s.x[i] - (x0[i] - dt * slowed_by)).norm(), 1e-15 * x0[i].norm()) << "particle " << i;
  }
  EXPECT_GT(slowed, m.n / 2);
  EXPECT_GT(stopped, 0);
}

// Friction acts on the velocity that moves the particle over the step
// (Bridson et al. 2002), so a load below μ F_n holds a cloth still; applied
// after the move it would let the cloth creep by Δt² a every step. Then above
// the limit the cloth slides with a = g_t - μ g (dry: F_n is the weight; no
// viscous damping).
TEST(Friction, HoldsBelowTheLimitAndSlidesAboveIt) {
  const auto centroid_x = [](const Simulation& sim) { return sim.metrics().centroid_x_m; };
  {
    // Wet: μ F_n / m is about 150 m/s²; a 2 m/s² tilt would creep 20 µm in 0.2 s.
    Simulation sim = flat_on_table(1.0, {"forces.gravity=[2,0,-9.81]", "cloth.resolution=[15,15]"});
    const double x0 = centroid_x(sim);
    ASSERT_TRUE(sim.advance_to(0.2));
    EXPECT_LT(std::abs(centroid_x(sim) - x0), 1e-9);
  }
  {
    const Params p = flat_on_table(0.0, {"forces.gravity=[5,0,-9.81]", "cloth.resolution=[15,15]",
                                         "forces.viscous_damping=0"})
                         .model()
                         .params;
    Simulation sim(p);
    const double x0 = centroid_x(sim), t = 0.1;
    ASSERT_TRUE(sim.advance_to(t));
    const double a = 5 - p.friction.mu * 9.81;
    EXPECT_NEAR(centroid_x(sim) - x0, 0.5 * a * t * t, 0.02 * 0.5 * a * t * t);
  }
}

// The paper's friction uses adhesion alone: a dry cloth would never stop.
// docs/model.md's default adds the contact load, so its weight holds it.
TEST(Friction, DryClothStillHasFrictionFromItsWeight) {
  for (const char* normal : {"contact", "adhesion"}) {
    Simulation sim =
        flat_on_table(0.0, {std::string("friction.normal=") + normal, "cloth.resolution=[15,15]"});
    for (auto&& v : detail::state(sim).v) v = Vec3(0.05, 0, 0);
    ASSERT_TRUE(sim.advance_to(0.2));
    const double speed = sim.metrics().kinetic_energy_j;
    if (std::string(normal) == "contact") {
      EXPECT_LT(speed, 1e-12) << normal;
    } else {
      EXPECT_GT(speed, 1e-6) << normal;
    }
  }
}
