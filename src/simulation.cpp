// The step of MODEL.md section 8, stage by stage, and the measurements of section 10.
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

// Area-weighted particle normals on the chequerboard triangulation of
// model.cpp. First each quad's two triangle normals, into six columns (x y z
// of each triangle), quad (i, j) at slot j nu + i of its corner (i, j): slot
// nu - 1 of a row, where no quad starts, holds zeros, and so do the slots
// of row nv - 1 and the nu + 1 before the column. Then each particle sums
// the triangles of its four quads, slots a - nu - 1, a - nu, a - 1 and a, in
// the order of Model::triangles: quads (i-1, j-1), (i, j-1), (i-1, j),
// (i, j), each first triangle then second. A particle with i + j even is in
// all eight; an odd one in four, so it adds zero for the others (exact).
// Both passes are loops over each thread's block of rows that vectorise (a
// loop per row of 51 ended in a scalar tail of 3 that cost as much as the
// rest).
void detail::compute_normals(const Model& m, const double* X, Vec3Array& normal,
                             std::vector<double>& quad_normals) {
  if (!m.grid) {
    compute_normals_mesh(m, X, normal);
    return;
  }
  const int nu = m.nu, nv = m.nv, n = m.n;
  const std::size_t before = std::size_t(nu) + 1, stride = before + n;
  quad_normals.resize(6 * stride);
  double* t[6];
  for (int f = 0; f < 6; ++f) {
    t[f] = quad_normals.data() + f * stride + before;
    std::fill(t[f] - before, t[f], 0.0);
    std::fill(t[f] + (nv - 1) * nu, t[f] + n, 0.0);
  }
  const double *x = X, *y = X + n, *z = X + 2 * std::size_t(n);
  const double* even_at = m.chequer.data();
  for_each_row_block(m, [&](int j0, int j1, int) {
    const int q1 = std::min(j1, nv - 1);  // quad rows j0 .. q1 - 1
    if (j0 >= q1) return;
      // Up to the last row's slot nu - 1, whose corners run past the grid.
#pragma GCC ivdep
    for (int a = j0 * nu; a < q1 * nu - 1; ++a) {
      // Corners a, b = a + 1, cc = a + nu + 1, d = a + nu. Even quads split
      // along a-cc: {a, b, cc}, {a, cc, d}; odd ones along b-d: {a, b, d},
      // {b, cc, d}. Eigen's cross, in scalars.
      const bool even = even_at[a] != 0;
      const int b = a + 1, cc = a + nu + 1, d = a + nu;
      const double ux = x[b] - x[a], uy = y[b] - y[a], uz = z[b] - z[a];
      const double vx = (even ? x[cc] : x[d]) - x[a], vy = (even ? y[cc] : y[d]) - y[a],
                   vz = (even ? z[cc] : z[d]) - z[a];
      t[0][a] = uy * vz - uz * vy;
      t[1][a] = uz * vx - ux * vz;
      t[2][a] = ux * vy - uy * vx;
      const int o = even ? a : b;
      const double px = x[cc] - x[o], py = y[cc] - y[o], pz = z[cc] - z[o];
      const double qx = x[d] - x[o], qy = y[d] - y[o], qz = z[d] - z[o];
      t[3][a] = py * qz - pz * qy;
      t[4][a] = pz * qx - px * qz;
      t[5][a] = px * qy - py * qx;
    }
    for (int q = j0; q < q1; ++q)
      for (int f = 0; f < 6; ++f) t[f][q * nu + nu - 1] = 0.0;
  });
  for_each_particle_block(m, [&](int first, int end) {
    double* __restrict out_x = normal.column(0);
    double* __restrict out_y = normal.column(1);
    double* __restrict out_z = normal.column(2);
#pragma GCC ivdep
    for (int a = first; a < end; ++a) {
      const bool even = even_at[a] != 0;
      double sum[3];
      for (int k = 0; k < 3; ++k) {
        const double *t0 = t[k], *t1 = t[3 + k];
        double s = 0;
        s += even ? t0[a - nu - 1] : 0.0;
        s += t1[a - nu - 1];
        s += even ? t0[a - nu] : 0.0;
        s += t1[a - nu];
        s += t0[a - 1];
        s += even ? t1[a - 1] : 0.0;
        s += t0[a];
        s += even ? t1[a] : 0.0;
        sum[k] = s;
      }
      const double len = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
      out_x[a] = len > 0 ? sum[0] / len : 0.0;
      out_y[a] = len > 0 ? sum[1] / len : 0.0;
      out_z[a] = len > 0 ? sum[2] / len : 1.0;
    }
  });
}

void compute_normals(const Model& m, const Vec3Array& x, Vec3Array& normal) {
  if (normal.size() != x.size()) normal.assign(x.size(), Vec3::Zero());
  std::vector<double> quad_normals;
  detail::compute_normals(m, x.column(0), normal, quad_normals);
}

Workspace& detail_workspace(const Simulation& sim) { return *sim.ws_; }

Simulation::Simulation(const Simulation& o)
    : model_(o.model_),
      state_(o.state_),
      ws_(std::make_unique<Workspace>(*o.ws_)),
      grab_particle_(o.grab_particle_),
      grab_target_(o.grab_target_),
      grab_k_(o.grab_k_),
      touched_(o.touched_),
      threads_(o.threads_) {}
Simulation& Simulation::operator=(const Simulation& o) {
  if (this != &o) *this = Simulation(o);
  return *this;
}
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;
Simulation::~Simulation() = default;

StepStats Simulation::stats() const {
  return {ws_->handle_force, ws_->substeps, ws_->solves, ws_->cg_iterations,
          ws_->cg_iterations_total};
}

const std::vector<double>& Simulation::adhesion() const { return ws_->adhesion; }

Simulation::Simulation(const Params& p)
    : model_((validate(p), build_model(p))), ws_(std::make_unique<Workspace>()) {
  start_thread_choice();
  reset();
}

void Simulation::start_thread_choice() {
  threads_ = ThreadChoice{};
  threads_.most = model_.threads;
  threads_.automatic = model_.params.integrator.threads == 0 && model_.threads > 1;
  if (threads_.automatic) model_.threads = 1;  // the first trial
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
  *ws_ = Workspace{};
  ws_->grab_particle = grab_particle_;
  ws_->grab_target = grab_target_;
  ws_->grab_k = grab_k_;
  for (auto* a : {&ws_->force, &ws_->normal, &ws_->surface_normal, &ws_->air_direction})
    a->assign(n, Vec3::Zero());
  ws_->x_before.assign(n, Vec3::Zero());
  ws_->row_sums.assign(model_.nv, 0.0);
  ws_->row_max.assign(model_.nv, 0.0);
  ws_->distance.assign(n, kInf);
  ws_->adhesion.assign(n, 0.0);
  ws_->border.assign(n, 0);
  state_.pocket.assign(n, -1);
  ws_->colliding.assign(n, 0);
  touched_.assign(n, 0);
  release();
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
  state_ = s;
  // What each step's end leaves for the next, made from the state again.
  update_contact(model_, state_, *ws_);
  compute_normals(model_, state_.x, ws_->normal);
}

void Simulation::set_humidity(double omega) {
  Params p = model_.params;  // checked as set_params would check it (a slider's rate: cheap)
  p.cloth.humidity = omega;
  validate(p);
  wetcloth::set_humidity(model_, omega);
}

void Simulation::set_params(const Params& p) {
  validate(p);
  const bool same_grid = p.cloth.resolution == model_.params.cloth.resolution &&
                         p.cloth.mesh == model_.params.cloth.mesh &&
                         p.cloth.mesh_scale == model_.params.cloth.mesh_scale;
  model_ = build_model(p);
  start_thread_choice();
  if (!same_grid) reset();
  ws_->strain_springs.clear();  // their lengths may have changed: ordered again next step
  ws_->mesh_cache.clear();      // an obstacle may have moved: its last answers bound nothing
}

void Simulation::grab(int particle, const Vec3& target, double stiffness) {
  ws_->grab_particle = grab_particle_ = particle;
  ws_->grab_target = grab_target_ = target;
  ws_->grab_k = grab_k_ = stiffness;
}

void Simulation::release() { ws_->grab_particle = grab_particle_ = -1; }

// 1. Forces, in a fixed order (the order of a float sum is part of the result).
// Implicit Euler takes the damping into its matrix, so leaves it out here.
void Simulation::accumulate_forces(bool implicit) {
  const Model& m = model_;
  State& s = state_;
  Workspace& w = *ws_;
  for_each_particle(m, [&](int i) { put(w.force[i], Vec3::Zero()); });
  add_spring_forces(m, s, w, m.params.integrator.type == IntegratorType::ExplicitEuler);
  compute_normals(m, s.x.column(0), w.normal, w.quad_normals);
  add_gravity(m, w.force);
  if (!implicit) add_viscous_damping(m, s, w.force);
  add_wind(m, s, w, w.force);
  add_air_pressure(m, s, w);
  add_adhesion(m, s, w);
  add_self_collision(m, s, w, !implicit);
  add_handle_forces(m, s, w);
}

void Simulation::step() {
  ThreadChoice& c = threads_;
  if (!c.automatic) {
    take_step();
    return;
  }
  (model_.threads == 1 ? c.steps_on_one : c.steps_on_most)++;
  const auto start = std::chrono::steady_clock::now();
  const long long substeps = ws_->substeps;
  take_step();
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

void Simulation::take_step() {
  const Model& m = model_;
  State& s = state_;
  Workspace& w = *ws_;
  const double dt = m.params.integrator.dt;
  const IntegratorType integrator = m.params.integrator.type;

  switch (integrator) {
    case IntegratorType::Xpbd:
      xpbd_step();
      break;
    case IntegratorType::ImplicitEuler: {
      // Baraff & Witkin's step control (their section 5.5): a substep whose
      // springs change too much for their linearisation is taken again at half
      // the size. Where they double the size after every substep that held, the
      // next one here tries twice the size only when this one's springs changed
      // by at most half the limit: a spring's change grows at least in
      // proportion to the substep, so a larger one would fail, and a failed try
      // costs a whole solve (on the pulls, one solve in three was thrown away).
      // Substeps are dt / 2^k and start on a multiple of their size, so they end
      // exactly on the step.
      constexpr long long kWhole = 1LL << kMostHalvings;
      long long done = 0;  // in units of dt / 2^kMostHalvings
      while (done < kWhole) {
        int k = s.halvings;
        while (done % (kWhole >> k) != 0) ++k;
        const int tried = k;
        accumulate_forces(true);
        double strain = 0;
        const double h = implicit_substep(dt, k, strain);
        const bool room = strain <= 0.5 * m.params.integrator.max_step_strain;
        s.halvings = k == tried && room ? std::max(0, k - 1) : k;
        done += kWhole >> k;
        s.time = (static_cast<double>(s.steps) + static_cast<double>(done) / kWhole) * dt;
        finish_step(h);
      }
      break;
    }
    case IntegratorType::ExplicitEuler:
    case IntegratorType::SymplecticEuler:
      accumulate_forces(false);
      if (integrator == IntegratorType::ExplicitEuler) {
        for (int i = 0; i < m.n; ++i) {
          add(s.x[i], dt * s.v[i]);
          add(s.v[i], (dt * m.inv_mass[i]) * w.force[i]);
        }
        correct_air_implicitly(m, s, w, dt);
      } else {  // symplectic Euler
        // The damping is taken at the end of the step: the viscous drag on each
        // particle's own velocity, v += Δt F / (m + Δt c A), then the springs'
        // (apply_spring_damping). Explicit, the 0.01 N·s/m of a particle's
        // springs is unstable at Δt = 5e-5 s from 51 × 51 up: h Σk_d / m ≈ 2.
        const double c = m.params.forces.viscous_damping;
        for_each_particle_block(m, [&](int first, int end) {
          const double *__restrict fx = w.force.column(0), *__restrict fy = w.force.column(1),
                                     *__restrict fz = w.force.column(2);
          double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
#pragma GCC ivdep
          for (int i = first; i < end; ++i) {
            const double h = dt * m.inv_mass[i], own = 1 + h * c * m.area[i], scale = h / own;
            vx[i] += scale * fx[i];
            vy[i] += scale * fy[i];
            vz[i] += scale * fz[i];
          }
        });
        apply_spring_damping(m, s, w, dt);
        move_at_new_velocities(dt);
      }
      s.time = (s.steps + 1) * dt;  // no drift from summing dt
      ++w.substeps;
      finish_step(dt);
      break;
  }
  ++s.steps;
}

int xpbd_substeps(const Params& p) {
  if (p.integrator.substeps > 0) return static_cast<int>(p.integrator.substeps);
  // (A mesh cloth: as the default grid's.)
  const long long longer =
      p.cloth.mesh.empty() ? std::max(p.cloth.resolution[0], p.cloth.resolution[1]) : 51;
  return static_cast<int>(10 + std::max(0LL, (longer - 101 + 9) / 10));
}

int xpbd_substeps(const Model& m) {
  if (m.grid || m.params.integrator.substeps > 0) return xpbd_substeps(m.params);
  return static_cast<int>(10 + std::max(0, (m.along - 101 + 9) / 10));
}

// XPBD in substeps (xpbd.cpp): per substep the external forces move the
// particles, the constraints are projected once, then contact and friction;
// the air and the contact state follow every substep (the air is stiff: a
// tent's pressure answers its volume within a millisecond). The rig's force is
// the mean over the substeps.
void Simulation::xpbd_step() {
  const Model& m = model_;
  State& s = state_;
  Workspace& w = *ws_;
  const double dt = m.params.integrator.dt, c = m.params.forces.viscous_damping;
  const int substeps = xpbd_substeps(m);
  const double h = dt / substeps, inv_h2 = 1.0 / (h * h);
  Vec3 rig = Vec3::Zero();
  for (int k = 0; k < substeps; ++k) {
    for_each_particle(m, [&](int i) { put(w.force[i], Vec3::Zero()); });
    compute_normals(m, s.x.column(0), w.normal, w.quad_normals);
    add_gravity(m, w.force);
    add_wind(m, s, w, w.force);
    add_air_pressure(m, s, w);
    add_adhesion(m, s, w);
    add_handle_forces(m, s, w);
    // v += h F / m, the viscous drag on each particle's own velocity implicit.
    for_each_particle_block(m, [&](int first, int end) {
      for (int q = 0; q < 3; ++q) {
        const double* __restrict f = w.force.column(q);
        double* __restrict v = s.v.column(q);
#pragma GCC ivdep
        for (int i = first; i < end; ++i) {
          const double hm = h * m.inv_mass[i];
          v[i] += hm / (1 + hm * c * m.area[i]) * f[i];
        }
      }
    });
    w.x_prev = s.x;
    move_at_new_velocities(h);  // the air term implicit, then x += h v
    s.time = (static_cast<double>(s.steps) + static_cast<double>(k + 1) / substeps) * dt;
    apply_handle_constraints(m, s, w);
    xpbd_begin_substep(m, s, w);
    project_springs(m, s, w, h);
    // The strain limit's further passes (MODEL.md section 2's 1-3): one sweep
    // carries a stretch only a grid step or two from a pulled patch.
    if (m.params.strain_limit.enabled)
      for (long long pass = 1; pass < m.params.strain_limit.passes; ++pass)
        project_springs(m, s, w, h, true);
    project_self_collision(m, s, w, h);
    collide_with_friction(m, s, w, touched_, h);
    // The paper's damping -k_f v of colliding particles, implicit.
    const double k_f = m.params.self_collision.damping;
    for (const int q : w.colliding_particles) s.v[q] *= 1.0 / (1.0 + h * k_f * m.inv_mass[q]);
    hold_stopped_handles(m, s);
    // The rig holds its patch against the external forces (apply_handle_constraints)
    // and the constraints' pull: J / h² on each particle it holds.
    w.handle_force -= inv_h2 * w.reaction_impulse;
    rig += w.handle_force;
    update_contact(m, s, w);
    update_air(m, s, w, h);
    ++w.substeps;
  }
  w.handle_force = rig / substeps;
  s.time = static_cast<double>(s.steps + 1) * dt;
}

// 2. Integrate by backward Euler over dt / 2^k, halving while the springs
// change more than integrator.max_step_strain; returns the substep taken, and
// its springs' largest change in `strain`.
double Simulation::implicit_substep(double dt, int& k, double& strain) {
  const Model& m = model_;
  State& s = state_;
  Workspace& w = *ws_;
  w.v_start = s.v;
  for (;;) {
    const double h = std::ldexp(dt, -k);
    implicit_euler_velocities(m, s, w, h);
    ++w.solves;
    strain = step_strain(m, s, h);
    if (k == kMostHalvings || strain <= m.params.integrator.max_step_strain) {
      ++w.substeps;
      if (s.acceleration.size() != std::size_t(m.n)) s.acceleration.assign(m.n, Vec3::Zero());
      for_each_particle_block(m, [&](int first, int end) {
        for (int k = 0; k < 3; ++k) {
          const double* __restrict v = s.v.column(k), * __restrict v0 = w.v_start.column(k);
          double* __restrict a = s.acceleration.column(k);
          for (int i = first; i < end; ++i) a[i] = (v[i] - v0[i]) / h;
        }
      });
      move_at_new_velocities(h);
      return h;
    }
    s.v = w.v_start;
    ++k;
  }
}

// The air term taken implicitly on the new velocities, then x += h v.
void Simulation::move_at_new_velocities(double h) {
  correct_air_implicitly(model_, state_, *ws_, h);
  for_each_particle_block(model_, [&](int first, int end) {
    const double *__restrict vx = state_.v.column(0), *__restrict vy = state_.v.column(1),
                             *__restrict vz = state_.v.column(2);
    double *__restrict x = state_.x.column(0), *__restrict y = state_.x.column(1),
                       *__restrict z = state_.x.column(2);
#pragma GCC ivdep
    for (int i = first; i < end; ++i) {
      x[i] += h * vx[i];
      y[i] += h * vy[i];
      z[i] += h * vz[i];
    }
  });
}

// After integrating over h: handles; 3. collide; 4. friction; 5. strain
// limiting (then no particle may be left inside a surface); 6. contact state
// and air.
void Simulation::finish_step(double h) {
  const Model& m = model_;
  State& s = state_;
  Workspace& w = *ws_;
  apply_handle_constraints(m, s, w);
  collide(m, s, &touched_, nullptr, &w);
  apply_friction(m, s, w, touched_, h);
  if (m.params.strain_limit.enabled) {
    limit_strain(m, s, w, h);
    add_strain_limit_reaction(m, s, w);
    // On the table alone only the particles strain limiting moved can be
    // inside: collide put the others on it (z - (z - H) is exactly H when H is
    // 0 or z within a factor 2 of it, as a step's motion keeps it). A ball's
    // projection can leave one an ulp inside, and two obstacles can push a
    // particle out of one into the other: then all are looked at again.
    const bool table_alone =
        m.params.table.enabled && !m.params.ball.enabled && m.obstacles.empty();
    collide(m, s, nullptr, table_alone ? &w.strain_changed : nullptr, &w);
  } else if (!m.obstacles.empty()) {
    collide_with_meshes(m, s, w);  // friction's move along a curved mesh dips inside
  }
  hold_stopped_handles(m, s);
  update_contact(m, s, w);
  update_air(m, s, w, h);
}

bool Simulation::advance_to(double t) {
  const double dt = model_.params.integrator.dt;
  const auto target = static_cast<long long>(std::llround(t / dt));
  while (state_.steps < target) {
    step();
    if (!blow_up_reason().empty()) return false;  // O(n): cheap next to a step
  }
  return blow_up_reason().empty();
}

std::string Simulation::blow_up_reason() const {
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

namespace {

// Largest extent over 8 directions in the table plane: the diagonal of a square
// footprint, the diameter of a round one.
double footprint_diameter(const Model& m, const State& s) {
  double best = 0;
  for (int d = 0; d < 8; ++d) {
    const double a = d * std::numbers::pi / 8;
    const double cx = std::cos(a), cy = std::sin(a);
    double lo = kInf, hi = -kInf;
    for (int i = 0; i < m.n; ++i) {
      if (!s.contact[i]) continue;
      const double t = s.x[i].x() * cx + s.x[i].y() * cy;
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    if (hi > lo) best = std::max(best, hi - lo);
  }
  return best;
}

}  // namespace

Metrics Simulation::metrics() const {
  const Model& m = model_;
  const State& s = state_;
  const Params& p = m.params;
  Metrics r;
  r.time_s = s.time;
  const double base = p.table.enabled ? p.table.height : 0.0;
  if (m.measured_handle >= 0) {
    const Handle& h = m.handles[m.measured_handle];
    double z = 0;
    for (int k : h.particles) z += s.x[k].z();
    r.handle_height_m = z / h.particles.size() - base;
    const Vec3 dir = h.type == HandleType::Move  ? h.velocity
                     : h.type == HandleType::Pin ? Vec3::UnitZ()
                                                 : h.force;
    r.handle_force_n = dir.norm() > 0 ? ws_->handle_force.dot(dir.normalized()) : 0.0;
  }
  double zmax = -kInf, cx = 0, cy = 0, mass = 0;
  for (int i = 0; i < m.n; ++i) {
    zmax = std::max(zmax, s.x[i].z());
    (s.contact[i] ? r.contact_area_m2 : r.lifted_area_m2) += m.area[i];
    r.kinetic_energy_j += 0.5 * m.mass[i] * s.v[i].squaredNorm();
    cx += m.mass[i] * s.x[i].x();
    cy += m.mass[i] * s.x[i].y();
    mass += m.mass[i];
  }
  r.max_height_m = zmax - base;
  r.centroid_x_m = cx / mass;
  r.centroid_y_m = cy / mass;
  if (m.contact_surface == SurfaceKind::None) {
    r.contact_area_m2 = 0;
    r.lifted_area_m2 = 0;
  } else {
    // The tent's base as the paper treats the contact region (eq. 11): a square,
    // here of the lifted area, whose diagonal is √(2 A).
    r.base_diagonal_m = std::sqrt(2 * r.lifted_area_m2);
    r.outer_diagonal_m = footprint_diameter(m, s);
  }
  r.inner_pressure_pa = s.inner_pressure;
  r.trapped_air_m3 = s.air_atm_volume;
  r.air_volume_m3 = s.air_volume;
  for (std::size_t e = 0; e < m.structural.size(); ++e) {
    const double len = (s.x[m.structural.b[e]] - s.x[m.structural.a[e]]).norm();
    r.max_strain = std::max(r.max_strain, len / m.structural.rest[e] - 1.0);
  }
  // Wrinkles: mean |dihedral angle| over edges between two lifted triangles.
  std::vector<Vec3> tn(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tr = m.triangles[t];
    tn[t] = (s.x[tr[1]] - s.x[tr[0]]).cross(s.x[tr[2]] - s.x[tr[0]]).normalized();
  }
  auto lifted = [&](int t) {
    const auto& tr = m.triangles[t];
    return !s.contact[tr[0]] && !s.contact[tr[1]] && !s.contact[tr[2]];
  };
  double sum = 0;
  long count = 0;
  for (const auto& [a, b] : m.triangle_pairs) {
    if (!lifted(a) || !lifted(b)) continue;
    sum += std::acos(std::clamp(tn[a].dot(tn[b]), -1.0, 1.0));
    ++count;
  }
  r.wrinkle_rad = count ? sum / count : 0.0;
  if (m.contact_surface == SurfaceKind::None) r.wrinkle_rad = 0;
  // The pull across the contact region's edge: the springs from lifted
  // particles to particles in contact, their elastic force on the latter along
  // the surface normal (the springs between two contact particles cancel). A
  // peel rig's force is the lifted part's weight and suction plus this.
  if (m.contact_surface != SurfaceKind::None && !m.grid) {
    for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
      for (std::size_t e = 0; e < set->size(); ++e)
        for (const auto& [k, o] :
             {std::pair{set->a[e], set->b[e]}, std::pair{set->b[e], set->a[e]}}) {
          if (!s.contact[k] || s.contact[o]) continue;
          const Vec3 d = s.x[o] - s.x[k];
          const double len = d.norm();
          if (len > 0)
            r.front_pull_n +=
                set->k[e] * (len - set->rest[e]) / len * d.dot(ws_->surface_normal[k]);
        }
  } else if (m.contact_surface != SurfaceKind::None)
    for (int k = 0; k < m.n; ++k) {
      if (!s.contact[k]) continue;
      const int i = k % m.nu, j = k / m.nu;
      for (const StencilEdge& e : m.stencil)
        for (const int sign : {1, -1}) {
          const int o = grid_neighbour(m, i, j, sign * e.di, sign * e.dj);
          if (o < 0 || s.contact[o]) continue;
          const Vec3 d = s.x[o] - s.x[k];
          const double len = d.norm();
          if (len > 0) r.front_pull_n += e.k * (len - e.rest) / len * d.dot(ws_->surface_normal[k]);
        }
    }
  return r;
}

std::vector<std::string> metrics_columns() {
  return {"time_s",          "handle_height_m",  "handle_force_n",
          "max_height_m",    "contact_area_m2",  "lifted_area_m2",
          "base_diagonal_m", "outer_diagonal_m", "inner_pressure_pa",
          "trapped_air_m3",  "air_volume_m3",    "kinetic_energy_j",
          "max_strain",      "wrinkle_rad",      "centroid_x_m",
          "centroid_y_m",    "front_pull_n"};
}

std::vector<double> metrics_values(const Metrics& r) {
  return {r.time_s,          r.handle_height_m,  r.handle_force_n,
          r.max_height_m,    r.contact_area_m2,  r.lifted_area_m2,
          r.base_diagonal_m, r.outer_diagonal_m, r.inner_pressure_pa,
          r.trapped_air_m3,  r.air_volume_m3,    r.kinetic_energy_j,
          r.max_strain,      r.wrinkle_rad,      r.centroid_x_m,
          r.centroid_y_m,    r.front_pull_n};
}

}  // namespace wetcloth
