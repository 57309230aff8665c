// Liquid-bridge adhesion (eq. 13, docs/model.md sections 3-4) on the contact region
// (whose border tests/contact/test_surfaces.cpp checks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "common.hpp"
#include "detail.hpp"
#include "wet_setups.hpp"

using namespace wetcloth;
using namespace wetcloth::test;

TEST(Adhesion, Equation13AtFullHumidity) {
  Params p;
  p.cloth.humidity = 1.0;
  EXPECT_NEAR(adhesion_total(p, 0.09), 4.653, 1e-3);  // laminate table, θb = 58°
  p.adhesion.theta_b_deg = 14;                        // glass
  // γ (S/h (cos 80° + cos 14°) + 2 √S sin 80°) = 7.538 N. (docs/model.md rounds it as 7.549.)
  EXPECT_NEAR(adhesion_total(p, 0.09), 7.538, 1e-3);
  p.adhesion.theta_b_deg = 58;
  p.cloth.humidity = 0.5;
  EXPECT_NEAR(adhesion_total(p, 0.09), 0.5 * 4.653, 1e-3);  // linear in ω (eq. 13)
}

TEST(Adhesion, ParticleForcesSumToEquation13) {
  for (double lift : {0.0, 0.02}) {
    Simulation sim = flat_on_table(1.0);
    make_tent(sim, lift, 0.08);  // a contact region with an inner border too
    Workspace& w = detail::workspace(sim);
    detail::update_contact(sim.model(), detail::state(sim), w);
    w.force.assign(w.force.size(), Vec3::Zero());
    detail::add_adhesion(sim.model(), sim.state(), w);
    double s_now = 0;
    Vec3 total = Vec3::Zero();
    for (int i = 0; i < sim.model().n; ++i) {
      if (sim.state().contact[i]) s_now += sim.model().area[i];
      total += w.force[i];
    }
    EXPECT_NEAR(-total.z(), adhesion_total(sim.model().params, s_now), 1e-12);
    EXPECT_NEAR(total.head<2>().norm(), 0, 1e-12);  // toward the surface, not along the cloth
    if (lift == 0) {
      EXPECT_NEAR(s_now, 0.09, 1e-12);
    } else {
      EXPECT_LT(s_now, 0.09);
    }
  }
}

TEST(Adhesion, SwitchedOffAboveTheLiquidBridge) {
  Simulation sim = flat_on_table(1.0);
  for (auto&& x : detail::state(sim).x) x.z() = 1.5e-3;  // above h_th = 1 mm
  Workspace& w = detail::workspace(sim);
  detail::update_contact(sim.model(), detail::state(sim), w);
  detail::add_adhesion(sim.model(), sim.state(), w);
  for (double a : w.adhesion) EXPECT_EQ(a, 0.0);
}
