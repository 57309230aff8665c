// The Simulation: its state made and restored, and the step of docs/model.md
// section 8 as named stages.
#include "wetcloth/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>

#include "detail.hpp"
#include "wetcloth/scene.hpp"

namespace wetcloth {

using namespace detail;

Workspace& detail_workspace(const Simulation& sim) { return *sim.ws_; }
State& detail_state(Simulation& sim) { return sim.state_; }

Simulation::Simulation(const Simulation& o)
    : model_(o.model_),
      state_(o.state_),
      ws_(std::make_unique<Workspace>(*o.ws_)),
      grab_particle_(o.grab_particle_),
      grab_target_(o.grab_target_),
      grab_k_(o.grab_k_) {}
Simulation& Simulation::operator=(const Simulation& o) {
  if (this != &o) *this = Simulation(o);
  return *this;
}
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;
Simulation::~Simulation() = default;

StepStats Simulation::stats() const {
  const ThreadChoice& c = ws_->threads;
  StepStats r;
  r.handle_force = ws_->handle_force;
  r.substeps = ws_->substeps;
  r.solves = ws_->solves;
  r.cg_iterations = ws_->cg_iterations;
  r.cg_iterations_total = ws_->cg_iterations_total;
  r.threads_chosen = c.automatic;
  r.most_threads = c.most;
  r.steps_on_one = c.steps_on_one;
  r.steps_on_most = c.steps_on_most;
  return r;
}

const std::vector<double>& Simulation::adhesion() const { return ws_->adhesion; }

Simulation::Simulation(const Params& p)
    : model_((validate(p), build_model(p))), ws_(std::make_unique<Workspace>()) {
  start_thread_choice();
  reset();
}

void Simulation::start_thread_choice() {
  ThreadChoice& c = ws_->threads;
  c = ThreadChoice{};
  c.most = model_.threads;
  c.automatic = model_.params.integrator.threads == 0 && model_.threads > 1;
  if (c.automatic) model_.threads = 1;  // the first trial
}

void Simulation::reset() {
  const int n = model_.n;
  state_ = State{};
  state_.x = Vec3Array(model_.rest_position);
  state_.v.assign(n, Vec3::Zero());
  state_.contact.assign(n, 0);
  state_.held.assign(n, 0);
  state_.held_at.assign(n, Vec3::Zero());
  state_.air_share.assign(n, 0.0);
  state_.air_gap.assign(n, 0.0);
  state_.pocket_pressure.assign(n, model_.params.air.p_atm);
  state_.source_distance.assign(n, 0);
  const ThreadChoice threads = ws_->threads;
  *ws_ = Workspace{};
  ws_->threads = threads;
  ws_->grab_particle = grab_particle_;
  ws_->grab_target = grab_target_;
  ws_->grab_k = grab_k_;
  for (auto* a : {&ws_->force, &ws_->normal, &ws_->surface_normal, &ws_->air_direction})
    a->assign(n, Vec3::Zero());
  ws_->row_sums.assign(model_.nv, 0.0);
  ws_->row_max.assign(model_.nv, 0.0);
  ws_->distance.assign(n, kInf);
  ws_->adhesion.assign(n, 0.0);
  ws_->border.assign(n, 0);
  state_.pocket.assign(n, -1);
  ws_->colliding.assign(n, 0);
  ws_->touched.assign(n, 0);
  // The humidity field at its start, and the masses it gives (a run may have
  // changed them).
  start_humidity(model_, state_, *ws_);
  set_masses(model_, state_.humidity);
  release();
  place_surfaces(model_, *ws_, 0.0);
  update_contact(model_, state_, *ws_);
  start_air(model_, state_, *ws_);
  update_strain_order(model_, state_, *ws_);
  compute_normals(model_, state_.x, ws_->normal);
}

void Simulation::restore(const State& s) {
  const auto n = static_cast<std::size_t>(model_.n);
  if (s.x.size() != n || s.v.size() != n || s.contact.size() != n || s.pocket.size() != n)
    throw std::invalid_argument("restore: a state of " + std::to_string(s.x.size()) +
                                " particles, the scene has " + std::to_string(n));
  reset();
  const std::vector<double> film = state_.film;
  state_ = s;
  // A state of before the humidity field (a format-3 checkpoint): the field
  // the scene starts with, and its film.
  if (state_.humidity.size() != n) state_.humidity = model_.initial_humidity;
  if (state_.film.size() != film.size()) state_.film = film;
  note_humidity_changed(state_, *ws_);
  set_masses(model_, state_.humidity);
  // What each step's end leaves for the next, made from the state again (the
  // surfaces' poses are a function of its time).
  place_surfaces(model_, *ws_, state_.time);
  update_contact(model_, state_, *ws_);
  compute_normals(model_, state_.x, ws_->normal);
}

namespace {

void check_count(const Vec3Array& a, int n, const char* what) {
  if (a.size() != static_cast<std::size_t>(n))
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(a.size()) +
                                " particles, the scene has " + std::to_string(n));
}

}  // namespace

void Simulation::set_positions(const Vec3Array& x) {
  check_count(x, model_.n, "set_positions");
  state_.x = x;
}

void Simulation::set_velocities(const Vec3Array& v) {
  check_count(v, model_.n, "set_velocities");
  state_.v = v;
}

void Simulation::set_humidity(double omega) {
  Params p = model_.params;  // checked as set_params would check it (a slider's rate: cheap)
  p.cloth.humidity = omega;
  validate(p);
  wetcloth::set_humidity(model_, omega);
  state_.humidity.assign(model_.n, omega);
  note_humidity_changed(state_, *ws_);
}

void Simulation::set_humidity_field(const std::vector<double>& omega) {
  if (omega.size() != static_cast<std::size_t>(model_.n))
    throw std::invalid_argument("set_humidity_field: " + std::to_string(omega.size()) +
                                " values, the scene has " + std::to_string(model_.n) +
                                " particles");
  for (std::size_t k = 0; k < omega.size(); ++k)
    if (!(omega[k] >= 0 && omega[k] <= 1))
      throw std::invalid_argument("set_humidity_field: particle " + std::to_string(k) + "'s ω is " +
                                  std::to_string(omega[k]) + ", out of range [0, 1]");
  state_.humidity = omega;
  note_humidity_changed(state_, *ws_);
  set_masses(model_, state_.humidity);
}

int Simulation::wet_near(const Vec3& x, double radius, double omega) {
  omega = std::clamp(omega, 0.0, 1.0);
  int changed = 0;
  for (int k = 0; k < model_.n; ++k) {
    if ((state_.x[k] - x).squaredNorm() > radius * radius) continue;
    const double before = state_.humidity[k];
    // Wetting raises ω to the brush's, drying (ω = 0) lowers it.
    state_.humidity[k] = omega > 0 ? std::max(before, omega) : 0.0;
    changed += state_.humidity[k] != before;
  }
  if (changed) {
    note_humidity_changed(state_, *ws_);
    set_masses(model_, state_.humidity);
  }
  return changed;
}

void Simulation::set_params(const Params& p) {
  validate(p);
  const bool same_grid = p.cloth.resolution == model_.params.cloth.resolution &&
                         p.cloth.mesh == model_.params.cloth.mesh &&
                         p.cloth.mesh_scale == model_.params.cloth.mesh_scale;
  const Params before = model_.params;
  model_ = build_model(p);
  start_thread_choice();
  if (!same_grid) {
    reset();
  } else {
    // The field runs on unless its start changed; the film restarts with a new depth.
    const auto region = [](const WetRegionParams& a, const WetRegionParams& b) {
      return a.at == b.at && a.radius == b.radius && a.humidity == b.humidity;
    };
    const bool same_start = p.cloth.humidity == before.cloth.humidity &&
                            p.cloth.humidity_map == before.cloth.humidity_map &&
                            p.wet.size() == before.wet.size() &&
                            std::equal(p.wet.begin(), p.wet.end(), before.wet.begin(),
                                       [&](const auto& a, const auto& b) {
                                         return a.first == b.first && region(a.second, b.second);
                                       });
    if (!same_start || state_.humidity.size() != static_cast<std::size_t>(model_.n))
      state_.humidity = model_.initial_humidity;
    const auto obstacle_films = [](const Params& q) {
      std::vector<std::pair<bool, double>> films;
      for (const auto& [name, o] : q.obstacles) films.emplace_back(o.contact, o.water_film);
      return films;
    };
    if (p.table.water_film != before.table.water_film ||
        p.ball.water_film != before.ball.water_film ||
        p.contact.surface != before.contact.surface || obstacle_films(p) != obstacle_films(before))
      start_film(model_, state_);
    note_humidity_changed(state_, *ws_);
    set_masses(model_, state_.humidity);
    // A new step keeps the clock: every integrator reads the time as steps
    // times Δt, so the count is the time over the new step (the time snapped
    // to it, within half a step). Kept as it was, a viewer switched from the
    // accurate tier's 1e-4 s to 1/240 s at 2 s would have jumped to 83 s,
    // its handles and moving surfaces with it.
    if (p.integrator.dt != before.integrator.dt) {
      state_.steps = std::llround(state_.time / p.integrator.dt);
      state_.time = static_cast<double>(state_.steps) * p.integrator.dt;
    }
  }
  ws_->strain_springs.clear();  // their lengths may have changed: ordered again next step
  ws_->strain_slots.clear();
  ws_->mesh_cache.clear();  // an obstacle may have moved: its last answers bound nothing
  place_surfaces(model_, *ws_, state_.time);
}

void Simulation::grab(int particle, const Vec3& target, double stiffness) {
  ws_->grab_particle = grab_particle_ = particle;
  ws_->grab_target = grab_target_ = target;
  ws_->grab_k = grab_k_ = stiffness;
}

void Simulation::release() { ws_->grab_particle = grab_particle_ = -1; }

namespace {

// The stages of one step, in docs/model.md section 8's order: accumulate forces,
// integrate, collide with surfaces, friction on contact particles, strain
// limiting, update contact state and air. Each integrator's step below runs
// them around its own integration; XPBD's substeps run their own order
// (integrators/xpbd.cpp).

// 1. Accumulate forces, in a fixed order (the order of a float sum is part of
// the result). Implicit Euler takes the damping into its matrix, so leaves it
// out here.
// On a grid, the forces up to adhesion run in one parallel region, each
// thread through its own rows: each of them writes only its rows, and reads
// others' only of the state, which none of them changes. A region of its own
// each cost about 1.25 µs a stage beyond its work (docs/performance.md,
// eighteenth stop). A mesh cloth's springs and normals go by its lists, not
// by rows: each stage over the whole cloth.
void accumulate_forces(const Model& m, const State& s, Workspace& w, bool implicit) {
  const bool damped_springs = m.params.integrator.type == IntegratorType::ExplicitEuler;
  if (m.grid) {
    prepare_spring_rows(m, w);
    prepare_normals(m, w.normals_scratch);
    w.row_sums.resize(2 * std::size_t(m.nv));  // adhesion's sums
    for_each_row_block(m, [&](int j0, int j1, int thread) {
      const int first = j0 * m.nu, end = j1 * m.nu;
      set_spring_force_rows(m, s, w, damped_springs, j0, j1, thread);
      add_bending_forces(m, s, w.force, first, end);
      compute_normal_rows(m, s.x.column(0), w.normal, w.normals_scratch, j0, j1, thread);
      add_own_forces(m, s, w, !implicit, false, first, end);
      add_air_pressure(m, s, w, first, end);
      add_adhesion_rows(m, s, w, j0, j1);
    });
  } else {
    set_spring_forces(m, s, w, damped_springs);
    add_bending_forces(m, s, w.force);
    compute_normals(m, s.x.column(0), w.normal, w.normals_scratch);
    add_own_forces(m, s, w, !implicit, false);
    add_air_pressure(m, s, w);
    add_adhesion(m, s, w);
  }
  add_self_collision(m, s, w, !implicit);
  add_handle_forces(m, s, w);
}

// 2. Integrate: integrators/*.cpp.

// 3. Collide with surfaces: out of the table, the ball and the mesh
// obstacles, recording in w.touched which one pushed each particle; then
// 4. friction on contact particles (eq. 14, constraints/friction.cpp). Each
// particle stands alone in both: one parallel region, each thread through
// its own particles.
void collide_with_surfaces_then_friction(const Model& m, State& s, Workspace& w, double h) {
  prepare_contact(m, w);
  for_each_particle_block(m, [&](int first, int end) {
    collide(m, s, &w.touched, &w, first, end);
    apply_friction(m, s, w, w.touched, h, first, end);
  });
}

// 5. Strain limiting; then no particle may be left inside a surface. On the
// table alone only the particles strain limiting moved can be inside: collide
// put the others on it (z - (z - H) is exactly H when H is 0 or z within a
// factor 2 of it, as a step's motion keeps it). A ball's projection can leave
// one an ulp inside, and two obstacles can push a particle out of one into the
// other: then all are looked at again. Without strain limiting, friction's
// move along a curved mesh dips inside.
void limit_strain_outside_surfaces(const Model& m, State& s, Workspace& w, double h) {
  if (!m.params.strain_limit.enabled) {
    if (!m.obstacles.empty()) collide_with_meshes(m, s, w);
    return;
  }
  limit_strain(m, s, w, h);
  add_strain_limit_reaction(m, s, w);
  const bool table_alone = m.params.table.enabled && !m.params.ball.enabled && m.obstacles.empty();
  collide(m, s, nullptr, table_alone ? &w.strain_changed : nullptr, &w);
}

// 5b. The symplectic step takes the air term's implicit part here, after the
// constraints: the velocities the strain limiter gave the lifting cloth are
// then in the air's answer to the cloth's motion. Taken before them, it saw
// the cloth the limiter pulled up as sinking under the suction, and its
// answer (a gas spring and a seepage time of about 1e−4 s, as short as a
// step) took the suction off by Δt/τ: the oblique pull's hand force fell by
// 4 % at 5e−5 s and by 9 % at 1e−4 s (docs/performance.md, eleventh stop).
// A particle it moves into a surface is put back out.
void take_air_after_constraints(const Model& m, State& s, Workspace& w, double h) {
  prepare_contact(m, w);
  correct_air_implicitly(m, s, w, h, true,
                         [&](int first, int end) { collide(m, s, nullptr, &w, first, end); });
}

// 6. Update the contact state and the trapped air: air/air.cpp.

// Stages 3-6, after an integration over h. Handles hold their particles
// first, and hold those that stopped after the constraints moved them.
void finish_substep(const Model& m, State& s, Workspace& w, double h) {
  if (w.surfaces.any) place_surfaces(m, w, s.time);  // where they are at the substep's end
  apply_handle_constraints(m, s, w);
  collide_with_surfaces_then_friction(m, s, w, h);
  limit_strain_outside_surfaces(m, s, w, h);
  if (m.params.integrator.type == IntegratorType::SymplecticEuler)
    take_air_after_constraints(m, s, w, h);
  hold_stopped_handles(m, s);
  update_contact_and_air(m, s, w, h);
}

// A cloth landing on its contact surface traps a cushion of air that rings
// as a gas spring, P_atm A² / V_sum against the lifted cloth's mass (a period
// of 3.3 ms under `drop-ball`'s wet cloth). Where the cloth settles is decided in
// the cushion's first ringing: in the step in which the pocket closes,
// exchange() takes it as closed from the step's start, and at 1e-4 s that
// deficit, a step early, bounced the wet cloth off the ball into another
// resting place (67 cm² of contact against the reference's 25;
// docs/performance.md, thirteenth stop). The symplectic step is therefore
// taken in substeps of at most integrator.landing_dt from two steps before a
// cloth with no contact reaches h_th of its surface, at the speed it
// approaches, until two of the cushion's periods after the first contact.
bool about_to_land(const Model& m, const State& s, const Workspace& w, double dt) {
  const double h_th = m.params.contact.bridge_height;
  for (int i = 0; i < m.n; ++i) {
    const double approach = -s.v[i].dot(w.surface_normal[i]);
    if (w.distance[i] - h_th < 2 * dt * std::max(approach, 0.0)) return true;
  }
  return false;
}

bool touching(const State& s) {
  return std::find(s.contact.begin(), s.contact.end(), std::uint8_t{1}) != s.contact.end();
}

// The period of the stiffest cushion the air now holds: ω² = c Σ A_i² / m_i
// over the pocket's lifted particles, c = P_atm / V_sum (pocket_air's
// spring); zero where no air is trapped.
double cushion_period(const Model& m, const State& s) {
  std::vector<double> sums(s.pocket_air.size(), 0.0);
  for (int i = 0; i < m.n; ++i)
    if (const int k = s.pocket[i]; k >= 0 && !s.contact[i] && std::size_t(k) < sums.size())
      sums[k] += m.area[i] * m.area[i] * m.inv_mass[i];
  double omega2 = 0;
  for (std::size_t k = 0; k < sums.size(); ++k)
    omega2 = std::max(omega2, s.pocket_air[k].spring * sums[k]);
  return omega2 > 0 ? 2 * std::numbers::pi / std::sqrt(omega2) : 0.0;
}

// Whether the step watches for a landing: the symplectic step, on a contact
// surface, with air, and a landing_dt shorter than its step.
bool can_land(const Model& m) {
  const double most = m.params.integrator.landing_dt;
  return m.params.integrator.type == IntegratorType::SymplecticEuler && most > 0 &&
         most < m.params.integrator.dt && m.contact_surface != SurfaceKind::None &&
         m.params.air.model != AirModel::Off;
}

// Explicit or symplectic Euler: one substep a step, or a landing's substeps.
void explicit_step(const Model& m, State& s, Workspace& w) {
  const double dt = m.params.integrator.dt;
  const bool watch = can_land(m) && !touching(s);  // a first contact starts the cushion's clock
  const bool landing =
      can_land(m) && (s.time < s.landing_until || (watch && about_to_land(m, s, w, dt)));
  const int n =
      landing ? static_cast<int>(std::ceil(dt / m.params.integrator.landing_dt * (1 - 1e-12))) : 1;
  const double h = dt / n;
  bool touched = !watch;
  for (int k = 1; k <= n; ++k) {
    accumulate_forces(m, s, w, false);
    if (m.params.integrator.type == IntegratorType::ExplicitEuler)
      integrate_explicit_euler(m, s, w, h);
    else
      integrate_symplectic_euler(m, s, w, h);
    // No drift from summing dt: the step's end is (steps + 1) dt exactly.
    s.time = (static_cast<double>(s.steps) + static_cast<double>(k) / n) * dt;
    ++w.substeps;
    finish_substep(m, s, w, h);
    if (!touched && touching(s)) {
      touched = true;
      s.landing_until = s.time + 2 * cushion_period(m, s);
    }
  }
}

// Implicit Euler with Baraff & Witkin's step control (their section 5.5): a
// substep whose springs change too much for their linearisation is taken
// again at half the size (implicit_euler_substep). Where they double the size
// after every substep that held, the next one here tries twice the size only
// when this one's springs changed by at most half the limit: a spring's change
// grows at least in proportion to the substep, so a larger one would fail, and
// a failed try costs a whole solve (on the pulls, one solve in three was
// thrown away). Substeps are dt / 2^k and start on a multiple of their size,
// so they end exactly on the step.
void implicit_euler_step(const Model& m, State& s, Workspace& w) {
  const double dt = m.params.integrator.dt;
  constexpr long long kWhole = 1LL << kMostHalvings;
  long long done = 0;  // in units of dt / 2^kMostHalvings
  while (done < kWhole) {
    int k = s.halvings;
    while (done % (kWhole >> k) != 0) ++k;
    const int tried = k;
    accumulate_forces(m, s, w, true);
    double strain = 0;
    const double h = implicit_euler_substep(m, s, w, dt, k, strain);
    const bool room = strain <= 0.5 * m.params.integrator.max_step_strain;
    s.halvings = k == tried && room ? std::max(0, k - 1) : k;
    done += kWhole >> k;
    s.time = (static_cast<double>(s.steps) + static_cast<double>(done) / kWhole) * dt;
    finish_substep(m, s, w, h);
  }
}

// One step of the chosen integrator.
void take_step(const Model& m, State& s, Workspace& w) {
  switch (m.params.integrator.type) {
    case IntegratorType::Xpbd:
      xpbd_step(m, s, w);
      break;
    case IntegratorType::ImplicitEuler:
      implicit_euler_step(m, s, w);
      break;
    case IntegratorType::ExplicitEuler:
    case IntegratorType::SymplecticEuler:
      explicit_step(m, s, w);
      break;
  }
  ++s.steps;
}

}  // namespace

void Simulation::step() {
  ThreadChoice& c = ws_->threads;
  if (!c.automatic) {
    take_step(model_, state_, *ws_);
    update_humidity(model_, state_, *ws_, model_.params.integrator.dt);
    return;
  }
  (model_.threads == 1 ? c.steps_on_one : c.steps_on_most)++;
  const auto start = std::chrono::steady_clock::now();
  const long long substeps = ws_->substeps;
  take_step(model_, state_, *ws_);
  // The humidity field, once a step (docs/model.md "Humidity field"): the
  // masses follow it into the next step.
  update_humidity(model_, state_, *ws_, model_.params.integrator.dt);
  c.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  c.substeps += ws_->substeps - substeps;
  // A trial times each count for 2 ms (two substeps at least); the faster is
  // kept for 0.25 s of stepping, a trial's cost under 2 %.
  constexpr double kTrialSeconds = 2e-3, kKeepSeconds = 0.25;
  if (c.phase < 2 ? c.seconds < kTrialSeconds || c.substeps < 2 : c.seconds < kKeepSeconds) return;
  if (c.phase < 2) c.per_substep[c.phase] = c.seconds / static_cast<double>(c.substeps);
  c.phase = (c.phase + 1) % 3;
  c.seconds = 0;
  c.substeps = 0;
  const bool one = c.phase == 0 || (c.phase == 2 && c.per_substep[0] <= c.per_substep[1]);
  model_.threads = one ? 1 : c.most;
}

bool Simulation::advance_to(double t) {
  const double dt = model_.params.integrator.dt;
  const auto target = static_cast<long long>(std::llround(t / dt));
  while (state_.steps < target) {
    step();
    if (!blow_up_reason().empty()) return false;  // one vectorised pass: cheap next to a step
  }
  return blow_up_reason().empty();
}

namespace {

// Whether every particle is finite and under max_speed, in one pass that
// vectorises: the common case, checked after every step. It flags a superset
// of what blow_up_reason reports (its bound a hair lower, NaN and infinity
// flagged), so that the message is built, exactly, only when it may be due.
bool calm(const Model& m, const State& s) {
  const double speed = m.params.integrator.max_speed, bound = speed * speed * (1 - 1e-12);
  const double *const VX = s.v.column(0), *const VY = s.v.column(1), *const VZ = s.v.column(2);
  const double *const X = s.x.column(0), *const Y = s.x.column(1), *const Z = s.x.column(2);
  // 0 * x is NaN for an infinite or NaN x, and NaN fails every comparison.
  const auto flag = [&](int i) {
    const double q = VX[i] * VX[i] + VY[i] * VY[i] + VZ[i] * VZ[i] + 0 * (X[i] + Y[i] + Z[i]);
    return !(q <= bound);
  };
  bool flagged = false;
  if (m.threads <= 1) {  // no region: even one its `if` turns off costs a futex call
#pragma omp simd reduction(| : flagged)
    for (int i = 0; i < m.n; ++i) flagged |= flag(i);
    return !flagged;
  }
  // On the step's threads: on one, 2 % of a two-thread step that the other
  // thread waited out (docs/performance.md).
#pragma omp parallel for simd reduction(| : flagged) num_threads(m.threads)
  for (int i = 0; i < m.n; ++i) flagged |= flag(i);
  return !flagged;
}

}  // namespace

std::string Simulation::blow_up_reason() const {
  if (calm(model_, state_)) return {};
  const Params& p = model_.params;
  const double vmax =
      std::sqrt(std::max(0.0, max_over_particles(model_, [&](int i) {
                           const double v2 = state_.v[i].squaredNorm();
                           const bool finite = std::isfinite(v2) && state_.x[i].allFinite();
                           return finite ? v2 : std::numeric_limits<double>::infinity();
                         })));
  if (vmax <= p.integrator.max_speed) return {};
  const double m_min = *std::min_element(model_.mass.begin(), model_.mass.end());
  const double limit = explicit_step_limit(model_);
  std::ostringstream o;
  o << "the simulation blew up at t = " << state_.time << " s (";
  if (std::isfinite(vmax))
    o << "a particle reached " << vmax
      << " m/s, over integrator.max_speed = " << p.integrator.max_speed;
  else
    o << "NaN in the particle state";
  o << ").";
  // Within the explicit limit, a force handle that alone would have driven
  // its patch past max_speed by now is the likelier cause than the step: a
  // single particle of a few mg takes 1 N as 1e5 m/s².
  const bool explicit_step = p.integrator.type != IntegratorType::ImplicitEuler &&
                             p.integrator.type != IntegratorType::Xpbd;
  const char* lead = " Likely cause: ";
  if (p.integrator.type == IntegratorType::ExplicitEuler && p.integrator.dt <= limit) {
    // Forward Euler grows every oscillation a little each step, whatever the
    // step: the limit below is the symplectic step's.
    o << lead << "integrator.type = \"explicit-euler\" (the blog's forward Euler) amplifies "
      << "every spring's oscillation a little each step, and integrator.dt = " << p.integrator.dt
      << " s lets it grow (the symplectic step's limit, " << limit
      << " s, does not hold for it). Use integrator.type = \"symplectic-euler\", or a much "
         "smaller integrator.dt.";
    lead = " Or: ";
  }
  for (const Handle& h : model_.handles) {
    if (h.type != HandleType::Force || (explicit_step && p.integrator.dt > limit)) continue;
    double a = 0;
    for (std::size_t e = 0; e < h.particles.size(); ++e)
      a = std::max(a, h.share[e] * h.force.norm() / model_.mass[h.particles[e]]);
    if (a * (state_.time - h.start) < p.integrator.max_speed) continue;
    o << lead << "handle." << h.name << ".force = " << h.force.norm() << " N on its "
      << h.particles.size() << (h.particles.size() == 1 ? " particle" : " particles") << " (" << a
      << " m/s²). Lower it, or spread it over a larger handle." << h.name << ".patch.";
    lead = " Or: ";
  }
  if (p.integrator.type == IntegratorType::Xpbd) {
    o << lead << "integrator.dt = " << p.integrator.dt << " s in " << xpbd_substeps(model_)
      << " substeps (integrator.substeps = " << p.integrator.substeps
      << ") is too coarse for a force this large: raise integrator.substeps, or look at the "
         "handles' forces (handle.*.force), the trapped air (air.model) and self_collision.k.";
    return o.str();
  }
  if (!explicit_step) {
    o << lead << "integrator.max_step_strain = " << p.integrator.max_step_strain
      << " lets a substep's springs change too much for their linearisation, or "
         "integrator.cg_max_iterations = "
      << p.integrator.cg_max_iterations
      << " stops the solve short. Lower integrator.max_step_strain, or raise "
         "integrator.cg_max_iterations.";
    return o.str();
  }
  if (p.integrator.dt > limit) {
    o << lead << "integrator.dt = " << p.integrator.dt << " s is too large for the springs ("
      << (model_.grid ? detail::step_limit_springs_text(p) + " at this spacing"
                      : std::string("the mesh's stiffest of each kind"))
      << ") and the lightest particle (" << m_min << " kg): the explicit limit is about " << limit
      << " s. Lower integrator.dt, or the stiffness (material.*, springs.*_k, self_collision.k).";
    return o.str();
  }
  // Within the springs' limit: a force far beyond what they carry.
  o << lead << "a force the springs cannot carry: integrator.dt = " << p.integrator.dt
    << " s is within their explicit limit of about " << limit
    << " s. Look at the trapped air (air.model; its pressure is now " << state_.inner_pressure
    << " Pa against air.p_atm = " << p.air.p_atm
    << "), the handles' forces (handle.*.force, handle.*.patch) and self_collision.k; a smaller "
       "integrator.dt may still help.";
  return o.str();
}

}  // namespace wetcloth
