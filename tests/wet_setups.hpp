// Wet-cloth test set-ups shared by the air, adhesion, contact and friction tests.
#pragma once

#include <algorithm>
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

// The peel rig's force balance (docs/model.md sections 2 and 9): a move
// handle records everything the rest of the cloth does to its patch, so on a
// slow peel it balances the load of what it lifts: the lifted cloth's weight,
// the suction on it (deficit × lifted area, along the table's normal as eq. 3
// takes it), and the pull of the cloth still in contact across the peel front
// (front_pull_n). Frame by frame once the peel is under way: |recorded / load
// - 1| sorted, and the largest share of the recorded force that the strain
// limiter's reaction is.
struct PeelBalance {
  std::vector<double> off;
  double limiter_share = 0;
  double median() const { return off[off.size() / 2]; }
  double p90() const { return off[off.size() * 9 / 10]; }
};
inline PeelBalance peel_balance(const Params& p) {
  Simulation sim(p);
  const Model& m = sim.model();
  const Handle& rig = m.handles[m.measured_handle];
  const double areal_weight =
      p.cloth.areal_density * (1 + p.cloth.water_ratio * p.cloth.humidity) * -p.forces.gravity[2];
  double patch = 0;
  for (const int k : rig.particles) patch += m.area[k];
  PeelBalance b;
  const long frames = std::lround(p.run.duration * p.run.fps);
  for (long frame = 1; frame <= frames; ++frame) {
    if (!sim.advance_to(frame / p.run.fps)) return {};
    const Metrics r = sim.metrics();
    if (r.lifted_area_m2 <= patch * (1 + 1e-9)) continue;  // the peel is not under way yet
    const double suction = p.air.p_atm - r.inner_pressure_pa;
    const double load = (areal_weight + suction) * r.lifted_area_m2 + r.front_pull_n;
    b.off.push_back(std::abs(r.handle_force_n / load - 1));
    const std::vector<Vec3>& reaction = detail::workspace(sim).strain_reaction;
    double limiter = 0;
    if (!reaction.empty())  // the symplectic step's limiter alone records one
      for (const int k : rig.particles) limiter -= reaction[k].z();
    b.limiter_share = std::max(b.limiter_share, limiter / r.handle_force_n);
  }
  std::sort(b.off.begin(), b.off.end());
  return b;
}

}  // namespace wetcloth::test
