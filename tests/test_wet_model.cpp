// The wet-cloth model of MODEL.md sections 3-7, checked against its formulas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "common.hpp"
#include "detail.hpp"
#include "spatial_hash.hpp"

using namespace wetcloth;

namespace {

// The paper's cloth lying flat on the table, every particle in contact.
Simulation flat_on_table(double omega, std::vector<std::string> sets = {}) {
  sets.push_back("cloth.humidity=" + std::to_string(omega));
  return Simulation(load_scene("drop-table", [&] {
    sets.insert(sets.begin(), "cloth.center=[0,0,0]");
    return sets;
  }()));
}

// Lifts the particles within `radius` of the centre into a cone of height h.
void make_tent(Simulation& sim, double h, double radius) {
  for (auto&& x : sim.state().x) {
    const double r = std::hypot(x.x(), x.y());
    if (r < radius) x.z() = h * (1 - r / radius);
  }
}

// The air's time constant τ = V_sum / (P_atm δ A_sum) in the current state.
double air_time_constant(const Simulation& sim) {
  const Model& m = sim.model();
  const State& s = sim.state();
  double a_sum = 0;
  for (int i = 0; i < m.n; ++i)
    if (!s.contact[i]) a_sum += m.area[i];
  return s.air_volume / (m.params.air.p_atm * permeability(m.params) * a_sum);
}

// A 2 cm tent on the flat cloth, its air at atmospheric pressure, then grown
// at a steady rate (about 100 Pa of deficit) for 30 τ in steps of
// τ / steps_per_tau, each followed by update_air.
struct GrowingTent {
  double height, dt, rise, volume_before_last_step;
};
GrowingTent grow_tent_steadily(Simulation& sim, double steps_per_tau) {
  const Model& m = sim.model();
  State& s = sim.state();
  Workspace& w = detail::workspace(sim);
  GrowingTent t{0.02, 0, 0, 0};
  make_tent(sim, t.height, 0.08);
  detail::update_contact(m, s, w);
  detail::update_air(m, s, w, 0.0);
  s.air_atm_volume = s.air_volume;
  const double tau = air_time_constant(sim);
  t.dt = tau / steps_per_tau;
  t.rise = 1e-3 * t.height / tau;
  for (int k = 0; k * t.dt < 30 * tau; ++k) {
    t.volume_before_last_step = s.air_volume;
    t.height += t.rise * t.dt;
    make_tent(sim, t.height, 0.08);
    detail::update_contact(m, s, w);
    detail::update_air(m, s, w, t.dt);
  }
  return t;
}

}  // namespace

TEST(Adhesion, Equation13AtFullHumidity) {
  Params p;
  p.cloth.humidity = 1.0;
  EXPECT_NEAR(adhesion_total(p, 0.09), 4.653, 1e-3);  // laminate table, θb = 58°
  p.adhesion.theta_b_deg = 14;                        // glass
  // γ (S/h (cos 80° + cos 14°) + 2 √S sin 80°) = 7.538 N. (MODEL.md rounds it as 7.549.)
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
    detail::update_contact(sim.model(), sim.state(), w);
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

// The contact border (eq. 13's edge term) is every contact particle on the
// cloth's border or next to a lifted one (4-neighbours), on any grid shape.
TEST(Contact, BorderIsContactOnTheClothsBorderOrNextToLifted) {
  for (const auto& [nu, nv] : {std::pair{2, 7}, {7, 2}, {3, 3}, {9, 6}, {51, 51}}) {
    Simulation sim = flat_on_table(
        1.0, {"cloth.resolution=[" + std::to_string(nu) + "," + std::to_string(nv) + "]"});
    const Model& m = sim.model();
    State& s = sim.state();
    const double h_th = m.params.contact.bridge_height;
    unsigned pattern = 12345;  // a fixed pseudo-random third of the particles lifted
    for (auto&& x : s.x) {
      pattern = pattern * 1103515245u + 12345u;
      x.z() = (pattern >> 16) % 3 == 0 ? 2 * h_th : 0.0;
    }
    Workspace& w = detail::workspace(sim);
    detail::update_contact(m, s, w);
    int borders = 0;
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const int k = m.index(i, j);
        ASSERT_EQ(s.contact[k] != 0, s.x[k].z() < h_th);
        bool expected = false;
        if (s.contact[k]) {
          expected = i == 0 || j == 0 || i == nu - 1 || j == nv - 1;
          for (const auto& [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}})
            if (const int b = detail::grid_neighbour(m, i, j, di, dj); b >= 0 && !s.contact[b])
              expected = true;
        }
        EXPECT_EQ(w.border[k] != 0, expected)
            << nu << " x " << nv << " at (" << i << ", " << j << ")";
        borders += expected;
      }
    EXPECT_GT(borders, 0);
  }
}

TEST(Adhesion, SwitchedOffAboveTheLiquidBridge) {
  Simulation sim = flat_on_table(1.0);
  for (auto&& x : sim.state().x) x.z() = 1.5e-3;  // above h_th = 1 mm
  Workspace& w = detail::workspace(sim);
  detail::update_contact(sim.model(), sim.state(), w);
  detail::add_adhesion(sim.model(), sim.state(), w);
  for (double a : w.adhesion) EXPECT_EQ(a, 0.0);
}

TEST(Air, PermeabilityFallsLinearlyWithHumidity) {
  Params p;
  p.cloth.humidity = 0;
  EXPECT_DOUBLE_EQ(permeability(p), 1.0e-3);  // δ(0) = D_δ
  p.cloth.humidity = 1;
  EXPECT_NEAR(permeability(p), 1.0e-4, 1e-18);  // δ(1) = D_δ - K_δ
  p.air.k_delta = 2e-3;
  EXPECT_EQ(permeability(p), 0.0);  // never negative
}

TEST(Air, SealedPocketKeepsPressureTimesVolume) {
  Params p = test::coarse("pull-straight", {"air.model=sealed", "cloth.humidity=0.7"});
  Simulation sim(p);
  const double pv0 = p.air.p_atm * sim.state().air_atm_volume;
  for (int frame = 1; frame <= 10; ++frame) {
    ASSERT_TRUE(sim.advance_to(0.05 * frame));
    const State& s = sim.state();
    if (s.air_volume > 0) {
      EXPECT_NEAR(s.inner_pressure * s.air_volume, pv0, 1e-12 * p.air.p_atm);
    }
  }
  EXPECT_GT(sim.state().air_volume, 0);
  EXPECT_LT(sim.state().inner_pressure, p.air.p_atm - 1000);  // sealed: no breakthrough
}

TEST(Air, PocketHeldStillRelaxesWithTheModelsTimeConstant) {
  Simulation sim = flat_on_table(0.5);
  make_tent(sim, 0.02, 0.08);
  const Model& m = sim.model();
  State& s = sim.state();
  Workspace& w = detail::workspace(sim);
  detail::update_contact(m, s, w);
  detail::update_air(m, s, w, 0.0);
  const double v_sum = s.air_volume, tau = air_time_constant(sim);
  s.air_atm_volume = v_sum * (1 - 500 / m.params.air.p_atm);  // a 500 Pa deficit, below P_b
  const double dt = tau / 7;
  for (int k = 1; k <= 20; ++k) {
    detail::update_air(m, s, w, dt);
    const double deficit = m.params.air.p_atm - s.inner_pressure;
    EXPECT_NEAR(deficit, 500 * std::exp(-k * dt / tau), 1e-9) << k;
  }
  EXPECT_LT(tau, 1e-2);
}

// A tent growing at a steady rate r holds a lag V_sum - V_atm = r τ (eq. 4
// with V_sum rising linearly over each step), whether the step is far shorter
// than τ (explicit) or far longer (implicit Euler's 1/240 s).
TEST(Air, GrowingTentLagsByRateTimesTimeConstant) {
  for (const double steps_per_tau : {10.0, 0.1}) {
    Simulation sim = flat_on_table(0.5);
    const Model& m = sim.model();
    const State& s = sim.state();
    const GrowingTent t = grow_tent_steadily(sim, steps_per_tau);
    const double lag = (s.air_volume - t.volume_before_last_step) / t.dt * air_time_constant(sim);
    const double deficit = m.params.air.p_atm - s.inner_pressure;
    EXPECT_NEAR(deficit, m.params.air.p_atm * lag / s.air_volume, 0.02 * deficit) << steps_per_tau;
    EXPECT_GT(deficit, 20) << steps_per_tau;
  }
}

// Backward Euler for the air: over a step the cloth feels the deficit at the
// step's end, so the explicit force plus correct_air_implicitly must give each
// lifted particle the impulse -ΔP_end A_i n_s Δt, with ΔP_end what update_air
// then finds. On a tent rising steadily the deficit hardly changes, so a
// correction that adds the growth to the starting deficit without letting that
// deficit seep away over the step (e^(-Δt/τ)) is off by ΔP (1 - e^(-Δt/τ)):
// 10 % at Δt = τ/10, nearly all of it at 10 τ.
TEST(Air, OneStepFeelsTheDeficitAtItsEnd) {
  for (const double steps_per_tau : {10.0, 0.1}) {
    Simulation sim = flat_on_table(0.5);
    const Model& m = sim.model();
    State& s = sim.state();
    Workspace& w = detail::workspace(sim);
    const GrowingTent t = grow_tent_steadily(sim, steps_per_tau);
    const double dt = t.dt;
    // The tent's velocities for one more step of the same growth, then the
    // explicit air force over it and the correction.
    const Vec3Array x0 = s.x;
    make_tent(sim, t.height + t.rise * dt, 0.08);
    for (int i = 0; i < m.n; ++i) {
      s.v[i] = (s.x[i] - x0[i]) / dt;
      s.x[i] = x0[i];
    }
    w.force.assign(w.force.size(), Vec3::Zero());
    detail::add_air_pressure(m, s, w);
    const Vec3Array v0 = s.v;
    for (int i = 0; i < m.n; ++i) s.v[i] += dt * m.inv_mass[i] * w.force[i];
    detail::correct_air_implicitly(m, s, w, dt);
    for (int i = 0; i < m.n; ++i) s.x[i] += dt * s.v[i];
    const double start = m.params.air.p_atm - s.inner_pressure;
    detail::update_contact(m, s, w);
    detail::update_air(m, s, w, dt);
    const double end = m.params.air.p_atm - s.inner_pressure;
    EXPECT_GT(start, 20) << steps_per_tau;
    int lifted = 0;
    for (int i = 0; i < m.n; ++i) {
      if (w.air_direction[i].isZero()) continue;
      ++lifted;
      const double felt = -(m.mass[i] * (s.v[i] - v0[i]) / dt).dot(w.air_direction[i]) /
                          w.air_direction[i].squaredNorm();
      ASSERT_NEAR(felt, end, 0.01 * end)
          << steps_per_tau << " particle " << i << ", start " << start;
    }
    EXPECT_GT(lifted, 100);
  }
}

TEST(Air, BreakthroughCapsTheDeficit) {
  Simulation sim = flat_on_table(1.0);
  make_tent(sim, 0.02, 0.08);
  State& s = sim.state();
  Workspace& w = detail::workspace(sim);
  detail::update_contact(sim.model(), s, w);
  s.air_atm_volume = 0;  // all the air gone: P_in would be 0
  detail::update_air(sim.model(), s, w, 1e-5);
  EXPECT_NEAR(sim.model().params.air.p_atm - s.inner_pressure, 1000, 1e-6);
}

// compute_normals works quad by quad on the grid; the normal of a particle is
// still the area-weighted sum over its triangles in Model::triangles, in their
// order, to the bit, on grids odd and even, square or not.
TEST(Normals, AreTheAreaWeightedSumOverEachParticlesTriangles) {
  for (const auto& [nu, nv] : {std::pair{7, 7}, std::pair{8, 5}, std::pair{6, 9}}) {
    Params p = test::bare();
    p.cloth.resolution = {nu, nv};
    Simulation sim(p);
    const Model& m = sim.model();
    Vec3Array x(m.rest_position);
    Vec3Array normal(m.n);
    std::vector<Vec3> expected(m.n, Vec3::Zero());
    for (int i = 0; i < m.n; ++i)
      x[i] += 0.004 * Vec3(std::sin(3.1 * i), std::cos(1.3 * i), std::sin(0.7 * i * i));
    for (const auto& t : m.triangles) {
      const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
      for (int v : t) expected[v] += n;
    }
    compute_normals(m, x, normal);
    for (int i = 0; i < m.n; ++i)
      ASSERT_EQ(normal[i], Vec3(expected[i] / expected[i].norm()))
          << nu << "x" << nv << " particle " << i;
  }
}

// Suction pushes lifted cloth toward the surface, for the table and the ball.
TEST(Air, ForcePointsTowardTheSurfaceUnderSuction) {
  for (const char* direction : {"surface", "cloth"}) {
    Simulation table = flat_on_table(0.5, {std::string("air.force_direction=") + direction});
    make_tent(table, 0.03, 0.1);
    Simulation ball(test::coarse("drape-ball", {std::string("air.force_direction=") + direction}));
    const Params& bp = ball.model().params;
    for (auto&& x : ball.state().x) {  // wrap the cloth 1 cm above the ball's top
      const Vec3 c = to_vec(bp.ball.center);
      x = c + (x - c).normalized() * (bp.ball.radius + 0.01);
    }
    for (Simulation* sim : {&table, &ball}) {
      State& s = sim->state();
      Workspace& w = detail::workspace(*sim);
      compute_normals(sim->model(), s.x, w.normal);
      detail::update_contact(sim->model(), s, w);
      std::fill(s.pocket_pressure.begin(), s.pocket_pressure.end(),
                sim->model().params.air.p_atm - 200);
      w.force.assign(w.force.size(), Vec3::Zero());
      detail::add_air_pressure(sim->model(), s, w);
      int pushed = 0;
      for (int i = 0; i < sim->model().n; ++i) {
        if (w.force[i].norm() == 0) continue;
        EXPECT_LT(w.force[i].dot(w.surface_normal[i]), 0) << direction << " particle " << i;
        ++pushed;
      }
      EXPECT_GT(pushed, 10) << direction;
    }
  }
}

// A cloth that falls flat onto the table and lies on it, none of it lifted,
// holds no air above the room's pressure. (It had kept the air of the step
// before its last particles landed, 11 atm once squeezed into the film of its
// weave, and a pull after the landing blew up on its first lifted particle.)
TEST(Air, ClothLandingFlatTrapsNoPressure) {
  for (const char* model : {"exchange", "sealed"}) {
    Params p = test::coarse("drop-table", {std::string("air.model=\"") + model + "\""});
    HandleParams pull;
    pull.at = {0.5, 0.5};
    pull.patch = 1;
    pull.force = {0, 0, 0.3};
    pull.start = 0.4;
    p.handles["pull"] = pull;
    Simulation sim(p);
    ASSERT_TRUE(sim.advance_to(0.35)) << model << ": " << sim.blow_up_reason();
    const State& s = sim.state();
    ASSERT_EQ(std::count(s.contact.begin(), s.contact.end(), 1), sim.model().n) << model;
    EXPECT_NEAR(s.inner_pressure, p.air.p_atm, 1.0) << model;
    ASSERT_TRUE(sim.advance_to(0.6)) << model << ": " << sim.blow_up_reason();
    // Air that seeps in lets the pull lift it; sealed air's suction holds it down.
    if (std::string(model) == "exchange") {
      EXPECT_GT(sim.metrics().handle_height_m, 0.002);
    }
  }
}

// A tent ringed by contact is one closed pocket in `vented` as in
// `exchange`, and the two agree on it: a particle peeling from contact
// brings its gap's air at atmospheric pressure. (It brought none: each was a
// vacuum of its 1 mm gap, and the vented tent sat at the breakthrough cap.)
TEST(Air, VentedTentRingedByContactPullsAsExchange) {
  double height[2], deficit[2];
  const char* models[2] = {"air.model=\"exchange\"", "air.model=\"vented\""};
  for (int k = 0; k < 2; ++k) {
    Simulation sim(test::coarse("pull-straight", {models[k]}));
    ASSERT_TRUE(sim.advance_to(0.3)) << models[k] << ": " << sim.blow_up_reason();
    height[k] = sim.metrics().handle_height_m;
    deficit[k] = sim.model().params.air.p_atm - sim.state().inner_pressure;
  }
  EXPECT_GT(height[0], 0.01);
  EXPECT_NEAR(height[1], height[0], 0.1 * height[0]);
  EXPECT_NEAR(deficit[1], deficit[0], 0.2 * deficit[0]);
}

// `vented` around the ball: a cloth falling onto it is one lifted region, open
// at its hem, though only its middle is within the band that holds air. (Its
// middle had been sealed into a cushion from the first step: at 25 x 25 the
// drape then ended with 21-25 particles on the ball under implicit Euler
// against 89-100 under the explicit step.)
TEST(Air, VentedClothFallingOntoTheBallIsOpenToTheRoom) {
  Simulation sim(test::coarse("drape-ball", {"cloth.humidity=0.7"}));
  const Params& p = sim.model().params;
  ASSERT_EQ(p.air.model, AirModel::Vented);
  const Workspace& w = detail::workspace(sim);
  int beyond_band = 0, in_pocket = 0;
  for (int i = 0; i < sim.model().n; ++i) (w.distance[i] < p.air.band ? in_pocket : beyond_band)++;
  ASSERT_GT(beyond_band, 0);  // the test needs both kinds
  ASSERT_GT(in_pocket, 0);
  for (int frame = 1; frame <= 8; ++frame) {
    ASSERT_TRUE(sim.advance_to(0.01 * frame));
    const State& s = sim.state();
    ASSERT_EQ(std::count(s.contact.begin(), s.contact.end(), 1), 0) << "touched at frame " << frame;
    for (int i = 0; i < sim.model().n; ++i)
      ASSERT_EQ(s.pocket_pressure[i], p.air.p_atm) << "frame " << frame << " particle " << i;
  }
}

// ... and a lifted patch that contact rings round is sealed, even where part
// of it is beyond the band: its air answers a change of volume.
TEST(Air, VentedPatchRingedByContactOnTheBallIsSealed) {
  Simulation sim(test::coarse("drape-ball", {"cloth.humidity=0.7"}));
  const Model& m = sim.model();
  const Params& p = m.params;
  State& s = sim.state();
  Workspace& w = detail::workspace(sim);
  const Vec3 c = to_vec(p.ball.center);
  const int mid = m.index(m.nu / 2, m.nv / 2);
  // Wrap the cloth onto the ball, then lift a 5 x 5 patch about its middle by
  // 5 mm, and the middle particle beyond the band.
  const auto wrap = [&](double lift) {
    for (int j = 0; j < m.nv; ++j)
      for (int i = 0; i < m.nu; ++i) {
        const bool patch = std::abs(i - m.nu / 2) <= 2 && std::abs(j - m.nv / 2) <= 2;
        const int k = m.index(i, j);
        const double above = k == mid ? p.air.band + 0.01 : (patch ? lift : 0.0);
        s.x[k] = c + (to_vec(p.cloth.center) + Vec3(0.3 * i / (m.nu - 1) - 0.15,
                                                   0.3 * j / (m.nv - 1) - 0.15, 0) - c)
                             .normalized() *
                         (p.ball.radius + above);
      }
  };
  wrap(0.005);
  detail::update_contact(m, s, w);
  detail::start_air(m, s, w);  // atmospheric in the new pocket
  EXPECT_EQ(s.pocket[mid], -1);  // beyond the band: no air of its own
  const int pocket = s.pocket[mid + 1];
  ASSERT_GE(pocket, 0);
  EXPECT_EQ(s.pocket[mid - 1], pocket);  // one pocket on both sides of it
  EXPECT_EQ(std::count(s.pocket.begin(), s.pocket.end(), pocket), 24);
  wrap(0.006);  // the patch rises by 1 mm in 1 µs: too fast for the air to seep in
  detail::update_contact(m, s, w);
  detail::update_air(m, s, w, 1e-6);
  EXPECT_LT(s.pocket_pressure[mid + 1], p.air.p_atm - 100);
  EXPECT_EQ(s.pocket_pressure[0], p.air.p_atm);  // in contact: no pocket
}

TEST(Friction, NeverReversesOrGrowsAndStopsASlowParticle) {
  Simulation sim = flat_on_table(1.0);
  const Model& m = sim.model();
  State& s = sim.state();
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
  Simulation sim = flat_on_table(0.7, {"cloth.resolution=[70,4]"});
  Model& m = const_cast<Model&>(sim.model());
  ASSERT_GT(m.nu, detail::kChunk);
  State& s = sim.state();
  Workspace& w = detail::workspace(sim);
  detail::update_contact(m, s, w);
  w.force.assign(w.force.size(), Vec3::Zero());
  detail::add_adhesion(m, s, w);
  for (int i = 0; i < m.n; ++i) {
    s.contact[i] = i % 5 != 3;
    m.driven[i] = i % 11 == 4;
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
// MODEL.md's default adds the contact load, so its weight holds it.
TEST(Friction, DryClothStillHasFrictionFromItsWeight) {
  for (const char* normal : {"contact", "adhesion"}) {
    Simulation sim =
        flat_on_table(0.0, {std::string("friction.normal=") + normal, "cloth.resolution=[15,15]"});
    for (auto&& v : sim.state().v) v = Vec3(0.05, 0, 0);
    ASSERT_TRUE(sim.advance_to(0.2));
    const double speed = sim.metrics().kinetic_energy_j;
    if (std::string(normal) == "contact") {
      EXPECT_LT(speed, 1e-12) << normal;
    } else {
      EXPECT_GT(speed, 1e-6) << normal;
    }
  }
}

TEST(SelfCollision, HashFindsExactlyTheAllPairsPairs) {
  std::vector<Vec3> x;
  std::uint64_t seed = 12345;
  auto rnd = [&] {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(seed >> 11) / double(1ULL << 53);
  };
  for (int i = 0; i < 3000; ++i) x.emplace_back(0.1 * rnd() - 0.05, 0.1 * rnd(), 0.03 * rnd());
  const double r = 0.005;
  Workspace w;
  detail::build_hash(x, 2 * r, w);
  auto skip = [](int i, int j) { return (i + j) % 11 == 0; };
  std::set<std::pair<int, int>> found, expected;
  detail::for_each_close_pair(x, r, w, skip, [&](int i, int j, const Vec3&, double) {
    EXPECT_TRUE(found.emplace(i, j).second) << "pair found twice";
  });
  for (int i = 0; i < 3000; ++i)
    for (int j = i + 1; j < 3000; ++j)
      if (!skip(i, j) && (x[i] - x[j]).norm() < r) expected.emplace(i, j);
  EXPECT_GT(expected.size(), 100u);
  EXPECT_EQ(found, expected);
}

// The candidate list is searched again only around particles that moved:
// at every step it must hold exactly the pairs whose anchors are within its
// radius, and every particle must be within margin/2 of its anchor.
TEST(SelfCollision, CandidatesSearchedAroundMoversAreTheWholeSearch) {
  Params p = load_scene("drop-table", {"cloth.center=[0,0,0.02]", "cloth.resolution=[20,20]",
                                       "cloth.size=[0.12,0.12]"});
  p.self_collision.enabled = true;
  Simulation sim(p);
  const Model& m = sim.model();
  // Crumple: a pseudo-random height field, so that layers meet as it falls.
  for (int i = 0; i < m.n; ++i) sim.state().x[i].z() += 0.01 * std::sin(1.7 * i);
  const double d_t = p.self_collision.distance, step = 0.12 / 19;
  const double margin = std::min(0.5 * d_t, 1.5 * step);
  const int reach = std::max(2, static_cast<int>(std::ceil(d_t / step)));
  int partial = 0, with_stale = 0, rebuilt = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3Array x = sim.state().x;  // where the step found the pairs
    sim.step();
    const Workspace& w = detail::workspace(sim);
    const auto& a = w.candidates_anchor;
    const bool moved = !w.candidate_movers.empty() && 4 * w.candidate_movers.size() <= std::size_t(m.n);
    partial += moved;
    // Particles anchored again in earlier steps are still out of the hash.
    with_stale += moved && w.hash_stale.size() > w.candidate_movers.size();
    rebuilt += moved && w.hash_stale.empty();
    std::vector<std::array<int, 2>> expected;
    for (int i = 0; i < m.n; ++i) {
      ASSERT_LE((x[i] - a[i]).norm(), 0.5 * margin) << "particle " << i;
      for (int j = i + 1; j < m.n; ++j) {
        const double len2 = (a[i] - a[j]).squaredNorm();
        const bool grid =
            std::abs(i % m.nu - j % m.nu) <= reach && std::abs(i / m.nu - j / m.nu) <= reach;
        if (len2 < w.candidates_radius * w.candidates_radius && len2 != 0 && !grid)
          expected.push_back({i, j});
      }
    }
    ASSERT_EQ(w.candidates, expected) << "step " << k;
  }
  // The test can fail: the partial search ran, with stale particles found one
  // by one, and with the hash built again once they were many.
  EXPECT_GT(partial, 10);
  EXPECT_GT(with_stale, 50);
  EXPECT_GT(rebuilt, 0);
}

// Movers that meet: two particles far apart on the grid are moved next to
// each other (both searched again, without building the hash), then a third
// next to the first, which the hash still holds where it was.
TEST(SelfCollision, MoversMeetingEachOtherArePaired) {
  Params p = load_scene("drop-table", {"cloth.resolution=[20,20]", "cloth.size=[0.12,0.12]"});
  p.self_collision.enabled = true;
  Simulation sim(p);
  const Model& m = sim.model();
  State& s = sim.state();
  auto& w = detail::workspace(sim);
  detail::add_self_collision(m, s, w, true);  // the whole search
  const auto paired = [&](int i, int j) {
    return std::binary_search(w.candidates.begin(), w.candidates.end(),
                              std::array<int, 2>{std::min(i, j), std::max(i, j)});
  };
  const int a = m.index(3, 3), b = m.index(15, 14), c = m.index(9, 17);
  const Vec3 lift(0, 0, 0.5 * p.self_collision.distance);
  detail::put(s.x[a], Vec3(s.x[b] + lift));
  detail::put(s.x[b], Vec3(s.x[b] - lift));
  detail::add_self_collision(m, s, w, true);
  ASSERT_EQ(w.candidate_movers, (std::vector<int>{a, b}));
  EXPECT_TRUE(paired(a, b));
  detail::put(s.x[c], Vec3(s.x[a] + lift));
  detail::add_self_collision(m, s, w, true);
  ASSERT_EQ(w.candidate_movers, std::vector<int>{c});
  EXPECT_FALSE(w.hash_stale.empty());  // a and b: out of the hash
  EXPECT_TRUE(paired(c, a));
  EXPECT_TRUE(paired(a, b));
}

// A cloth folded onto itself on the table: the top layer rests on the bottom one.
TEST(SelfCollision, KeepsTwoFoldedLayersApart) {
  for (bool enabled : {true, false}) {
    // l = 6 mm: d_t = 5 mm exceeds l/√2, as MODEL.md section 7 requires.
    Params p = load_scene("drop-table", {"cloth.center=[0,0,0]", "cloth.humidity=0.5",
                                         "cloth.resolution=[26,26]", "cloth.size=[0.15,0.15]"});
    p.self_collision.enabled = enabled;
    Simulation sim(p);
    const Model& m = sim.model();
    const double d_t = p.self_collision.distance;
    const int fold = m.nv / 2;  // rows above `fold` are laid back over the rows below
    const double y_fold =
        0.5 * (m.rest_position[m.index(0, fold - 1)].y() + m.rest_position[m.index(0, fold)].y());
    std::vector<int> top;
    for (int j = fold; j < m.nv; ++j)
      for (int i = 0; i < m.nu; ++i) {
        auto x = sim.state().x[m.index(i, j)];
        x = Vec3(x.x(), 2 * y_fold - x.y(), 1.2 * d_t);
        if (j > fold + 1) top.push_back(m.index(i, j));
      }
    ASSERT_TRUE(sim.advance_to(0.5)) << sim.blow_up_reason();
    double lowest = 1;
    for (int k : top) lowest = std::min(lowest, sim.state().x[k].z());
    if (enabled) {
      EXPECT_GT(lowest, 0.5 * d_t);
    } else {
      EXPECT_LT(lowest, 0.5 * d_t);  // the test can fail: without it the layers pass
    }
  }
}

TEST(Contact, ClothRestingOnTheTableDoesNotDrift) {
  Simulation sim = flat_on_table(0.5, {"cloth.resolution=[21,21]"});
  const Metrics m0 = sim.metrics();
  ASSERT_TRUE(sim.advance_to(1.0));
  const Metrics m1 = sim.metrics();
  EXPECT_NEAR(m1.centroid_x_m, m0.centroid_x_m, 1e-9);
  EXPECT_NEAR(m1.centroid_y_m, m0.centroid_y_m, 1e-9);
  EXPECT_LT(m1.kinetic_energy_j, 1e-12);
  EXPECT_NEAR(m1.contact_area_m2, 0.09, 1e-12);
}

// x -> -x, y -> -y and x <-> y map the straight pull onto itself, and the
// discretisation keeps that to rounding. (Later, a particle that crosses the
// liquid-bridge threshold one step earlier on one side than its mirror image
// turns a rounding difference into a visible one: the contact switch is
// discontinuous, so the test looks before the first such crossing.)
TEST(Experiments, StraightPullStaysFourFoldSymmetric) {
  Simulation sim(test::coarse("pull-straight", {"cloth.humidity=0.7"}));
  ASSERT_TRUE(sim.advance_to(0.5));
  const Model& m = sim.model();
  const auto& x = sim.state().x;
  double worst = 0;
  for (int j = 0; j < m.nv; ++j)
    for (int i = 0; i < m.nu; ++i) {
      const Vec3& a = x[m.index(i, j)];
      const Vec3& mx = x[m.index(m.nu - 1 - i, j)];
      const Vec3& my = x[m.index(i, m.nv - 1 - j)];
      const Vec3& t = x[m.index(j, i)];
      worst = std::max({worst, (a - Vec3(-mx.x(), mx.y(), mx.z())).norm(),
                        (a - Vec3(my.x(), -my.y(), my.z())).norm(),
                        (a - Vec3(t.y(), t.x(), t.z())).norm()});
    }
  EXPECT_GT(sim.metrics().handle_height_m, 0.01);
  EXPECT_LT(worst, 1e-9);  // 10 nm against a 2 cm tent
}

// MODEL.md sections 2 and 9: a move handle records everything the rest of the
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
