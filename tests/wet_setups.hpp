// Wet-cloth test set-ups shared by the air, adhesion, contact and friction tests.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "common.hpp"
#include "detail.hpp"

namespace wetcloth::test {

// The paper's cloth lying flat on the table, every particle in contact.
inline Simulation flat_on_table(double omega, std::vector<std::string> sets = {}) {
  sets.push_back("cloth.humidity=" + std::to_string(omega));
  return Simulation(load_scene("drop-table", [&] {
    sets.insert(sets.begin(), "cloth.center=[0,0,0]");
    return sets;
  }()));
}

// Lifts the particles within `radius` of the centre into a cone of height h.
inline void make_tent(Simulation& sim, double h, double radius) {
  for (auto&& x : detail::state(sim).x) {
    const double r = std::hypot(x.x(), x.y());
    if (r < radius) x.z() = h * (1 - r / radius);
  }
}

// The air's time constant τ = V_sum / (P_atm δ A_sum) in the current state.
inline double air_time_constant(const Simulation& sim) {
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
inline GrowingTent grow_tent_steadily(Simulation& sim, double steps_per_tau) {
  const Model& m = sim.model();
  State& s = detail::state(sim);
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

}  // namespace wetcloth::test
