// The explicit integrators (docs/model.md section 8): forward Euler, as the blog
// steps, and the symplectic Euler step; and the move x += h v every
// integrator ends its velocity update with.
#include "detail.hpp"

namespace wetcloth::detail {

namespace {
// x += h v, over particles [first, end).
void move_at_velocities(State& s, double h, int first, int end) {
  const double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
  double* __restrict x = s.x.column(0), * __restrict y = s.x.column(1), * __restrict z = s.x.column(2);
#pragma GCC ivdep
  for (int i = first; i < end; ++i) {
    x[i] += h * vx[i];
    y[i] += h * vy[i];
    z[i] += h * vz[i];
  }
}
}  // namespace

// Forward Euler: x by the old velocities, then v by the forces; the air term
// implicit after.
void integrate_explicit_euler(const Model& m, State& s, Workspace& w, double dt) {
  for (int i = 0; i < m.n; ++i) {
    add(s.x[i], dt * s.v[i]);
    add(s.v[i], (dt * m.inv_mass[i]) * w.force[i]);
  }
  correct_air_implicitly(m, s, w, dt);
}

// Symplectic Euler: v by the forces, then x by the new velocities. The
// damping is taken at the end of the step: the viscous drag on each
// particle's own velocity, v += Δt F / (m + Δt c A), then the springs'
// (apply_spring_damping). Explicit, the 0.01 N·s/m of a particle's springs
// is unstable at Δt = 5e-5 s from 51 × 51 up: h Σk_d / m ≈ 2. The air term's
// implicit part comes after the constraints (take_air_after_constraints).
void integrate_symplectic_euler(const Model& m, State& s, Workspace& w, double dt) {
  const double c = m.params.forces.viscous_damping;
  const auto kick = [&](int first, int end) {
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
  };
  // The kick and the move within the damping's passes over the particles.
  apply_spring_damping(m, s, w, dt, kick,
                       [&](int first, int end) { move_at_velocities(s, dt, first, end); });
}

// The air term taken implicitly on the new velocities, then x += h v.
void move_at_new_velocities(const Model& m, State& s, Workspace& w, double h) {
  correct_air_implicitly(m, s, w, h);
  for_each_particle_block(m, [&](int first, int end) { move_at_velocities(s, h, first, end); });
}

}  // namespace wetcloth::detail
