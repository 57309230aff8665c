// Friction (docs/model.md section 5; paper eq. 14, after Bridson et al. 2002).
#include <algorithm>
#include <cmath>

#include "constraints/coulomb.hpp"
#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// Eq. 14 on particle i, given its surface normal n and load (the loop over
// the contact surface below does the same arithmetic in columns), on its
// velocity relative to a moving surface's `surface` (null: one standing still).
void slow_down(const Model& m, State& s, int i, const Vec3& n, double load, double mu, double dt,
               const Vec3* surface = nullptr) {
  if (load <= 0) return;
  const Vec3 v = surface ? Vec3(s.v[i] - *surface) : Vec3(s.v[i]);
  const Vec3 vt = v - v.dot(n) * n;
  const double speed = vt.norm();
  if (speed == 0) return;
  const double dv = mu * load * dt * m.inv_mass[i];
  const Vec3 slowed = vt * (std::min(dv, speed) / speed);
  sub(s.v[i], slowed);
  sub(s.x[i], dt * slowed);
}

}  // namespace

// Velocity-level Coulomb friction: the tangential velocity shrinks by
// Δv_f = μ F_n Δt / m and never reverses. As in Bridson et al. 2002, it acts on
// the velocity that moves the particle over the step, so the step's move is
// taken back by Δt Δv_f too: applied after the move, a load under μ F_n would
// still creep Δt² a a step, and a cloth that should hold would slide. On the
// contact surface F_n is the adhesion plus, by default, the part of the other
// forces that presses the particle in; on other obstacles it is that load
// alone.
void apply_friction(const Model& m, State& s, const Workspace& w,
                    const std::vector<std::uint8_t>& touched, double dt, int first, int end) {
  const double mu = m.params.friction.mu;
  if (mu == 0) return;
  const bool with_load = m.params.friction.normal == FrictionNormal::Contact;
  // A moving contact surface (docs/model.md section 3): eq. 14 on each
  // particle's velocity relative to the surface where it is. A particle
  // held by friction then rides along with it.
  if (pose_of(w.surfaces, m.contact_code())) {
    for (int i = first; i < end; ++i) {
      if (!s.contact[i] || m.driven[i]) continue;
      const Vec3 n = w.surface_normal[i];
      const double pressing = -(w.force[i].dot(n) + w.adhesion[i]);
      const double load = w.adhesion[i] + (with_load && pressing > 0 ? pressing : 0.0);
      const Vec3 surface = surface_velocity(w.surfaces, m.contact_code(), s.x[i]);
      slow_down(m, s, i, n, load, mu, dt, &surface);
    }
  } else {
    // On the contact surface, slow_down's arithmetic without a branch (a factor
    // of zero where it does not apply), over columns: a loop that vectorises.
    // w.force holds the step's forces, adhesion included (it is -adhesion·n_s).
    const double *__restrict nx = w.surface_normal.column(0),
                             *__restrict ny = w.surface_normal.column(1),
                             *__restrict nz = w.surface_normal.column(2);
    const double *__restrict fx = w.force.column(0), *__restrict fy = w.force.column(1),
                             *__restrict fz = w.force.column(2);
    double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
    double* __restrict xx = s.x.column(0), * __restrict xy = s.x.column(1), * __restrict xz = s.x.column(2);
    const double* __restrict adhesion = w.adhesion.data(), * __restrict inv_mass =
                                                               m.inv_mass.data();
    const auto acts = [&](int i) { return s.contact[i] && !m.driven[i] ? 1.0 : 0.0; };
    for_each_chunk(first, end, acts, [&](int i0, int count, const double* gate) {
#pragma omp simd
      for (int k = 0; k < count; ++k) {
        const int i = i0 + k;
        const double pressing = -((fx[i] * nx[i] + fy[i] * ny[i] + fz[i] * nz[i]) + adhesion[i]);
        const double load = adhesion[i] + (with_load && pressing > 0 ? pressing : 0.0);
        const double dv = mu * load * dt * inv_mass[i];
        coulomb_clamp(vx[i], vy[i], vz[i], xx[i], xy[i], xz[i], nx[i], ny[i], nz[i], dv,
                      (gate[k] != 0) & (load > 0), dt);
      }
    });
  }
  // Off the contact surface, a particle pushed out of another obstacle this
  // step: its load is the part of the forces that presses it in.
  // They are few: 64 particles' flags are looked at in one vector first (a
  // branch per particle had been 2 % of the step at 201 x 201).
  if (!with_load) return;
  const std::uint8_t *__restrict driven = m.driven.data(), *__restrict contact = s.contact.data(),
                                 *__restrict by = touched.data();
  for (int i0 = first; i0 < end; i0 += 64) {
    const int i1 = std::min(end, i0 + 64);
    int any = 0;
#pragma omp simd reduction(| : any)
    for (int i = i0; i < i1; ++i) any |= (by[i] != 0) & !contact[i] & !driven[i];
    if (!any) continue;
    for (int i = i0; i < i1; ++i) {
      if (driven[i] || contact[i] || by[i] == 0) continue;
      const Vec3 n = query_code(m, w.surfaces, by[i], s.x[i]).normal;
      const Vec3 surface = surface_velocity(w.surfaces, by[i], s.x[i]);
      slow_down(m, s, i, n, std::max(0.0, -w.force[i].dot(n)), mu, dt,
                pose_of(w.surfaces, by[i]) ? &surface : nullptr);
    }
  }
}

void apply_friction(const Model& m, State& s, const Workspace& w,
                    const std::vector<std::uint8_t>& touched, double dt) {
  for_each_particle_block(
      m, [&](int first, int end) { apply_friction(m, s, w, touched, dt, first, end); });
}

}  // namespace wetcloth::detail
