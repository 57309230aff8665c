// The large-step integrator, the live tier (docs/model.md section 8): small-step XPBD
// (Macklin et al. 2019, "Small Steps in Physics Simulation"). A step of Δt is
// taken in substeps of h; each substep moves every particle by its external
// forces (gravity, wind, air, adhesion, handles), then projects the springs
// once, as compliant distance constraints with their damping (XPBD, Macklin
// et al. 2016, eq. 26), the strain limit as an inequality constraint folded
// into the same projection, and self-collision as compliant one-sided
// constraints; contact and friction follow, and the velocities are the
// positions' change over h.
//
// One Gauss-Seidel sweep: the springs of one stencil offset split into two
// classes (by the parity of i, or of j for the offsets across rows), and no
// two springs of a class share a particle, so each spring of a class is
// projected and applied in one vectorised loop, in any order, on any thread.
// The order of the offsets and classes is fixed, so the result is the same on
// any number of threads.
#include <algorithm>
#include <array>
#include <cmath>

#include "constraints/coulomb.hpp"
#include "detail.hpp"

namespace wetcloth::detail {

// Inverse masses the constraints see: pinned, driven and held particles are
// infinitely heavy.
void xpbd_begin_substep(const Model& m, const State& s, Workspace& w) {
  w.free_inv_mass.resize(m.n);
  for_each_particle_block(m, [&](int first, int end) {
    const std::uint8_t* __restrict driven = m.driven.data(), * __restrict held = s.held.data();
    const double* __restrict inv = m.inv_mass.data();
    double* __restrict free = w.free_inv_mass.data();
#pragma omp simd
    for (int i = first; i < end; ++i) free[i] = (driven[i] | held[i]) != 0 ? 0.0 : inv[i];
  });
  // The measured handle's particles while it holds them (a move or pin
  // handle, a force handle stopped at its cap): the constraints' impulses on
  // them are part of the rig's force.
  w.reaction_particles.clear();
  w.reaction_impulse.setZero();
  if (m.measured_handle >= 0) {
    const Handle& h = m.handles[m.measured_handle];
    if (h.type != HandleType::Force || s.held[h.particles[0]]) w.reaction_particles = h.particles;
  }
}

namespace {

// The sweep's arrays: positions (x, y, z columns, moved in place), the
// positions at the substep's start, the inverse masses the constraints see.
struct Sweep {
  double *x, *y, *z;
  const double *px, *py, *pz, *inv;
};

// One stencil offset's springs a = (i, j) -> b = a + off, for i in [lo, hi)
// and j < rows, and their constants. Two springs of an offset share a
// particle only when one starts where the other ends, a whole offset apart;
// so the springs split into two classes that share none: an offset across
// rows by the row's parity (by pairs of rows for a reach of 2), one along a
// row by i's (by pairs of columns for a reach of 2).
struct OffsetSprings {
  int off, lo, hi, rows, shift;
  bool by_row;
  double rest, max_len, alpha, gamma;
  bool starts_in_class(int a, int nu, int c) const {
    if (a < 0) return false;
    const int i = a % nu, j = a / nu;
    return i >= lo && i < hi && j < rows && (((by_row ? j : i) >> shift) & 1) == c;
  }
};

// Spring a -> b's correction Δλ n = f (x_b - x_a), into d and f: XPBD's Δλ
// with damping (Macklin et al. 2016, eq. 26), one iteration (λ = 0), the
// strain limit folded in; 0 for a spring of zero length or between two
// immovable particles. One square root and one division a spring: with
// D = (1 + γ) w + α̃ and q = 1 / (D w |d|), 1/|d| = D w q, Δλ/|d| = -(C + γ ċ) w q
// and the strain limit's (l_max - |d|) / (w |d|) = (l_max - |d|) D q.
enum class Projection { Spring, SpringLimited, LimitOnly };

template <Projection kind>
[[gnu::always_inline]] inline double spring_factor(const Sweep& s, const OffsetSprings& o, int a,
                                                   int b, double& dx, double& dy, double& dz) {
  dx = s.x[b] - s.x[a], dy = s.y[b] - s.y[a], dz = s.z[b] - s.z[a];
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  const double ws = s.inv[a] + s.inv[b];
  const bool on = (len > 0) & (ws > 0);
  const double d = (1 + o.gamma) * ws + o.alpha;
  const double q = 1.0 / (on ? d * ws * len : 1.0);
  double f = 0.0;
  if constexpr (kind != Projection::LimitOnly) {
    // The spring's change of length over the substep so far (h dC/dt).
    const double rate = ((dx - (s.px[b] - s.px[a])) * dx + (dy - (s.py[b] - s.py[a])) * dy +
                         (dz - (s.pz[b] - s.pz[a])) * dz) *
                        (d * ws * q);
    f = -((len - o.rest) + o.gamma * rate) * ws * q;
  }
  if constexpr (kind != Projection::Spring) {
    // No longer than (1 + τ_c) l0 after the projection (docs/model.md section 2): a
    // hard constraint, split by inverse mass as the spring's own.
    const double limit = (o.max_len - len) * d * q;
    f = f < limit ? f : limit;
  }
  return on ? f : 0.0;
}

// The spring projected and applied at once: a moves by -w_a Δλ n, b by +w_b Δλ n.
template <Projection kind>
[[gnu::always_inline]] inline void project_spring(const Sweep& s, const OffsetSprings& o, int a,
                                                  int b) {
  double dx, dy, dz;
  const double f = spring_factor<kind>(s, o, a, b, dx, dy, dz);
  const double cx = f * dx, cy = f * dy, cz = f * dz;
  s.x[a] -= s.inv[a] * cx;
  s.y[a] -= s.inv[a] * cy;
  s.z[a] -= s.inv[a] * cz;
  s.x[b] += s.inv[b] * cx;
  s.y[b] += s.inv[b] * cy;
  s.z[b] += s.inv[b] * cz;
}

// A class's springs in one row, from its first spring's start a0 (the arrays
// are taken by value: through a reference GCC reloaded them after each
// store). No two share a particle, so each loop vectorises as it is.
// Across rows: springs a0 + k -> a0 + k + off, k < count.
template <Projection kind>
void project_run(Sweep s, const OffsetSprings o, int a0, int count) {
#pragma omp simd
  for (int k = a0; k < a0 + count; ++k) project_spring<kind>(s, o, k, k + o.off);
}

// Along a row, offset (1, 0): springs a0 + 2m -> a0 + 2m + 1, m < count.
template <Projection kind>
void project_pairs(Sweep s, const OffsetSprings o, int a0, int count) {
#pragma omp simd
  for (int m = 0; m < count; ++m) project_spring<kind>(s, o, a0 + 2 * m, a0 + 2 * m + 1);
}

// Along a row, offset (2, 0): springs a0 + 4m + t -> a0 + 4m + t + 2, t = 0, 1,
// m < count, then the spring a0 + 4 count -> + 2 when `tail`.
template <Projection kind>
void project_quads(Sweep s, const OffsetSprings o, int a0, int count, bool tail) {
#pragma omp simd
  for (int m = 0; m < count; ++m) {
    const int a = a0 + 4 * m;
    project_spring<kind>(s, o, a, a + 2);
    project_spring<kind>(s, o, a + 1, a + 3);
  }
  if (tail) project_spring<kind>(s, o, a0 + 4 * count, a0 + 4 * count + 2);
}

// Whether any spring a -> a + off, a in [first, first + count), is longer than
// its limit (slightly shorter, so that rounding never skips one that is). A
// row with none is left to the limit-only pass as it is: it would move no
// particle, and the check reads what the projection reads but writes nothing.
bool any_over_limit(const Sweep& s, const OffsetSprings& o, int first, int count) {
  const double* __restrict xa = s.x + first, * __restrict ya = s.y + first, * __restrict za = s.z + first;
  const double* __restrict xb = xa + o.off, * __restrict yb = ya + o.off, * __restrict zb = za + o.off;
  double most = 0;
#pragma omp simd reduction(max : most)
  for (int k = 0; k < count; ++k) {
    const double dx = xb[k] - xa[k], dy = yb[k] - ya[k], dz = zb[k] - za[k];
    const double len2 = dx * dx + dy * dy + dz * dz;
    most = most > len2 ? most : len2;
  }
  return most > o.max_len * o.max_len * (1 - 1e-9);
}

// Class c of one row j.
template <Projection kind>
void project_class_row(const Sweep& s, const OffsetSprings& o, int nu, int j, int c) {
  const int row = j * nu;
  // (Along a row the check takes both classes' springs: a superset.)
  if constexpr (kind == Projection::LimitOnly)
    if (!any_over_limit(s, o, row + o.lo, o.hi - o.lo)) return;
  if (o.by_row) return project_run<kind>(s, o, row + o.lo, o.hi - o.lo);
  if (o.off == 1) return project_pairs<kind>(s, o, row + c, (o.hi - c + 1) / 2);
  const int first = 2 * c, full = std::max(0, (o.hi - first + 2) / 4);
  project_quads<kind>(s, o, row + first, full, first + 4 * full < o.hi);
}

// Both classes of an offset, one after the other; each class's rows on the
// step's threads (a row writes only its own springs' ends). The impulses of a
// class on the particles the measured handle holds (immovable: the class
// does not move them) are found first, from the positions the class sees,
// by the same arithmetic: the rig's reaction, exact.
template <Projection kind>
void project_offset(const Model& m, Workspace& w, const Sweep& s, const OffsetSprings& o) {
  const int nu = m.nu;
  for (int c = 0; c < 2; ++c) {
    for (const int k : w.reaction_particles) {
      double dx, dy, dz;
      if (o.starts_in_class(k, nu, c)) {
        const double f = spring_factor<kind>(s, o, k, k + o.off, dx, dy, dz);
        w.reaction_impulse -= Vec3(f * dx, f * dy, f * dz);
      }
      if (o.starts_in_class(k - o.off, nu, c)) {
        const double f = spring_factor<kind>(s, o, k - o.off, k, dx, dy, dz);
        w.reaction_impulse += Vec3(f * dx, f * dy, f * dz);
      }
    }
    parallel_for(m, o.rows, [&](int j) {
      if (!o.by_row || ((j >> o.shift) & 1) == c) project_class_row<kind>(s, o, nu, j, c);
    });
  }
}

// A mesh cloth: the same projection, one spring at a time (Gauss-Seidel in
// the springs' order: structural, shear, bending), on one thread.
void project_springs_mesh(const Model& m, State& s, Workspace& w, double h, bool limit_only) {
  const double tau = m.params.strain_limit.enabled ? m.params.strain_limit.tau : -1.0;
  const double* const inv = w.free_inv_mass.data();
  // The particles the measured handle holds, flagged (their reaction force).
  w.reaction_flag.assign(m.n, 0.0);
  for (const int k : w.reaction_particles) w.reaction_flag[k] = 1.0;
  const SpringSet* const sets[3] = {&m.structural, &m.shear, &m.bending};
  for (int kind = 0; kind < 3; ++kind) {
    const SpringSet& set = *sets[kind];
    const bool limited = kind < 2 && tau >= 0;
    if (limit_only && !limited) continue;
    for (std::size_t e = 0; e < set.size(); ++e) {
      const double k = set.k[e];
      if (k <= 0) continue;
      const int a = set.a[e], b = set.b[e];
      const Vec3 d = s.x[b] - s.x[a];
      const double len = d.norm(), ws = inv[a] + inv[b];
      if (!(len > 0) || !(ws > 0)) continue;
      const double alpha = 1.0 / (k * h * h), gamma = set.damping[e] / (k * h);
      const double dd = (1 + gamma) * ws + alpha;
      const Vec3 before = w.x_prev[b] - w.x_prev[a];
      const double rate = (d - before).dot(d) / len;
      double f = limit_only ? 0.0 : -((len - set.rest[e]) + gamma * rate) / (dd * len);
      if (limited) f = std::min(f, ((1.0 + tau) * set.rest[e] - len) / (ws * len));
      const Vec3 c = f * d;
      if (w.reaction_flag[a] != 0) w.reaction_impulse -= c;
      if (w.reaction_flag[b] != 0) w.reaction_impulse += c;
      sub(s.x[a], inv[a] * c);
      add(s.x[b], inv[b] * c);
    }
  }
}

}  // namespace

void project_springs(const Model& m, State& s, Workspace& w, double h, bool limit_only) {
  if (!m.grid) {
    project_springs_mesh(m, s, w, h, limit_only);
    return;
  }
  const int nu = m.nu, nv = m.nv;
  const double tau = m.params.strain_limit.enabled ? m.params.strain_limit.tau : -1.0;
  const Sweep sweep{s.x.column(0),         s.x.column(1),      s.x.column(2),
                    w.x_prev.column(0),    w.x_prev.column(1), w.x_prev.column(2),
                    w.free_inv_mass.data()};
  for (int e = 0; e < 8; ++e) {
    const StencilEdge& st = m.topology->stencil[e];
    if (st.k <= 0 || (limit_only && (e >= 4 || tau < 0))) continue;
    const int di = st.di, dj = st.dj;
    const int lo = std::max(0, -di), hi = std::min(nu, nu - di), rows = nv - dj;
    if (rows <= 0 || hi <= lo) continue;
    // XPBD's compliance α̃ = 1/(k h²) and damping γ = α̃ β̃ / h with β̃ = h² k_d;
    // the strain limit on structural and shear springs (the first four offsets).
    const double max_len = e < 4 && tau >= 0 ? (1.0 + tau) * st.rest : 1e30;
    const bool by_row = dj != 0;
    const OffsetSprings o{di + dj * nu,
                          lo,
                          hi,
                          rows,
                          (by_row ? dj : std::abs(di)) == 2 ? 1 : 0,
                          by_row,
                          st.rest,
                          max_len,
                          1.0 / (st.k * h * h),
                          st.damping / (st.k * h)};
    if (limit_only)
      project_offset<Projection::LimitOnly>(m, w, sweep, o);
    else if (max_len < 1e30)
      project_offset<Projection::SpringLimited>(m, w, sweep, o);
    else
      project_offset<Projection::Spring>(m, w, sweep, o);
  }
}

// Self-collision (eq. 15) as a one-sided compliant constraint |x_i - x_j| >= d_t
// with the stiffness k_t, in the candidates' sorted order.
void project_self_collision(const Model& m, State& s, Workspace& w, double h) {
  const auto& p = m.params.self_collision;
  if (!p.enabled || p.k <= 0) return;
  refresh_collision_candidates(m, s, w);
  const double alpha = 1.0 / (collision_constants(m).k * h * h), d_t = p.distance;
  for (const int q : w.colliding_particles) w.colliding[q] = 0;
  w.colliding_particles.clear();
  for (const auto& [i, j] : w.candidates) {
    const Vec3 d = s.x[i] - s.x[j];
    const double len2 = d.squaredNorm();
    if (len2 >= d_t * d_t || len2 == 0) continue;
    const double len = std::sqrt(len2);
    const double wi = w.free_inv_mass[i], wj = w.free_inv_mass[j];
    const double lambda = (d_t - len) / (wi + wj + alpha);
    const Vec3 corr = (lambda / len) * d;
    add(s.x[i], wi * corr);
    sub(s.x[j], wj * corr);
    for (const int k : w.reaction_particles) {
      if (k == i) w.reaction_impulse += corr;
      if (k == j) w.reaction_impulse -= corr;
    }
    for (const int q : {i, j})
      if (!w.colliding[q]) {
        w.colliding[q] = 1;
        w.colliding_particles.push_back(q);
      }
  }
}

namespace {

// Whether collide may move a particle: not when there is nothing to collide
// with, nor when the table alone is there and every particle is above it.
bool may_collide(const Model& m, const State& s) {
  const Params& p = m.params;
  // On a contact surface the cloth lies on it: not worth a pass to ask.
  if (p.ball.enabled || !m.obstacles.empty() || m.contact_surface != SurfaceKind::None) return true;
  if (!p.table.enabled) return false;
  const double* z = s.x.column(2);
  return -max_over_particles(m, [&](int i) { return -z[i]; }) < p.table.height;
}

// The positions at the substep's start taken by a swap, not a copy; then
// x = x_prev + h v (the same sums as x += h v), the air term implicit first.
void move_from_substep_start(const Model& m, State& s, Workspace& w, double h) {
  correct_air_implicitly(m, s, w, h);
  if (w.x_prev.size() != s.x.size()) w.x_prev.assign(s.x.size(), Vec3::Zero());
  std::swap(w.x_prev, s.x);
  for_each_particle_block(m, [&](int first, int end) {
    for (int k = 0; k < 3; ++k) {
      const double* __restrict p = w.x_prev.column(k), * __restrict v = s.v.column(k);
      double* __restrict x = s.x.column(k);
#pragma omp simd
      for (int i = first; i < end; ++i) x[i] = p[i] + h * v[i];
    }
  });
}

}  // namespace

// Contact with the surfaces, then Coulomb friction (eq. 14) on the velocity the
// substep ends with. The normal load is what the surface had to push back: the
// projection's depth, m d / h² (it holds the adhesion that pulled the particle
// in, its weight and the springs pressing it), and at least the adhesion of a
// contact particle resting just above the surface (`contact`); the adhesion
// alone (`adhesion`, the paper's).
void collide_with_friction(const Model& m, State& s, Workspace& w,
                           std::vector<std::uint8_t>& touched, double h) {
  // Nothing to push out of, or a table that every particle is above (a
  // hanging cloth): collide would leave every particle as it is. Friction
  // then acts only on the contact surface, when there is one.
  const bool reaches = may_collide(m, s);
  const bool friction = m.params.friction.mu != 0 && (reaches || m.contact_code() != 0);
  if (friction) w.x_before_collide = s.x;
  if (reaches)
    collide(m, s, &touched, nullptr, &w);
  else
    std::fill(touched.begin(), touched.end(), std::uint8_t{0});
  const double inv_h = 1.0 / h;
  for_each_particle_block(m, [&](int first, int end) {
    for (int k = 0; k < 3; ++k) {
      const double* __restrict x = s.x.column(k), * __restrict p = w.x_prev.column(k);
      double* __restrict v = s.v.column(k);
#pragma omp simd
      for (int i = first; i < end; ++i) v[i] = (x[i] - p[i]) * inv_h;
    }
  });
  if (!friction) return;
  const double mu = m.params.friction.mu;

  const bool with_load = m.params.friction.normal == FrictionNormal::Contact;
  const std::uint8_t surface = m.contact_code();
  // Per particle, from its flags: 0 no friction, 1 friction from its load,
  // 2 friction from its load and its adhesion (on the contact surface).
  const auto kind = [&](int i) {
    if (m.driven[i] || s.held[i]) return 0.0;
    const bool on_surface = s.contact[i] && surface != 0;
    if (touched[i] == 0 && !on_surface) return 0.0;
    return on_surface && (touched[i] == 0 || touched[i] == surface) ? 2.0 : 1.0;
  };
  const double load_scale = with_load ? inv_h * inv_h : 0.0, dv_scale = mu * h;
  // On a moving surface eq. 14 acts on the velocity relative to it
  // (docs/model.md section 3): the surface's velocity where each particle
  // is, of the surface that pushed it or else the contact surface.
  const bool moving = w.surfaces.any;
  if (moving) {
    w.surface_velocity.assign(s.x.size(), Vec3::Zero());
    for_each_particle(m, [&](int i) {
      const int code = touched[i] != 0 ? touched[i] : surface;
      if (pose_of(w.surfaces, code))
        put(w.surface_velocity[i], surface_velocity(w.surfaces, code, s.x[i]));
    });
  }
  const auto clamp_all = [&]<bool relative>() {
    for_each_particle_block(m, [&](int first, int end) {
      double* __restrict xx = s.x.column(0), * __restrict xy = s.x.column(1), * __restrict xz = s.x.column(2);
      double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
      const double *__restrict bx = w.x_before_collide.column(0),
                             *__restrict by = w.x_before_collide.column(1),
                             *__restrict bz = w.x_before_collide.column(2);
      const double *__restrict nx = w.surface_normal.column(0),
                             *__restrict ny = w.surface_normal.column(1),
                             *__restrict nz = w.surface_normal.column(2);
      const double *__restrict adhesion = w.adhesion.data(), *__restrict mass = m.mass.data(),
                             *__restrict inv_mass = m.inv_mass.data();
      const double *svx = relative ? w.surface_velocity.column(0) : nullptr,
                   *svy = relative ? w.surface_velocity.column(1) : nullptr,
                   *svz = relative ? w.surface_velocity.column(2) : nullptr;
      for_each_chunk(first, end, kind, [&](int i0, int count, const double* how) {
#pragma omp simd
        for (int k = 0; k < count; ++k) {
          const int i = i0 + k;
          // The surface's push: its depth and direction (the contact surface's
          // normal where it did not push).
          const double px = xx[i] - bx[i], py = xy[i] - by[i], pz = xz[i] - bz[i];
          const double pushed = std::sqrt(px * px + py * py + pz * pz);
          const double inv_p = pushed > 0 ? 1.0 / pushed : 0.0;
          const double ux = pushed > 0 ? px * inv_p : nx[i], uy = pushed > 0 ? py * inv_p : ny[i],
                       uz = pushed > 0 ? pz * inv_p : nz[i];
          const double ad = how[k] > 1.5 ? adhesion[i] : 0.0;
          const double pressing = mass[i] * pushed * load_scale;
          const double load = ad > pressing ? ad : pressing;
          const double dv = dv_scale * load * inv_mass[i];
          if constexpr (relative) {
            const double sx = svx[i], sy = svy[i], sz = svz[i];
            double rx = vx[i] - sx, ry = vy[i] - sy, rz = vz[i] - sz;
            coulomb_clamp(rx, ry, rz, xx[i], xy[i], xz[i], ux, uy, uz, dv,
                          (how[k] > 0.5) & (load > 0), h);
            vx[i] = rx + sx, vy[i] = ry + sy, vz[i] = rz + sz;
          } else {
            coulomb_clamp(vx[i], vy[i], vz[i], xx[i], xy[i], xz[i], ux, uy, uz, dv,
                          (how[k] > 0.5) & (load > 0), h);
          }
        }
      });
    });
  };
  if (moving)
    clamp_all.template operator()<true>();
  else
    clamp_all.template operator()<false>();
  // Friction moved particles along the surface: on a curved mesh that chord
  // dips inside (on the ball it is left as it was, its results unchanged).
  if (!m.obstacles.empty()) collide_with_meshes(m, s, w);
}

namespace {

// v += h F / m, the viscous drag on each particle's own velocity implicit;
// and the quadratic bending's force (w.bending_force), taken with the mass a
// substep needs to take it stably. Alone, a symplectic step of h holds while
// h² λ_max(M⁻¹ Q) < 4, and Gershgorin bounds λ_max by max_i Σ_j |Q_ij| / m_i;
// a particle whose row would pass h² Σ_j |Q_ij| / m_i = 1 is taken as that
// much heavier (with the constraints' projections after it, 3.5 let `hang`
// at 201 x 201 stretch 66 % in 0.05 s where 1 keeps it at 12 %). That slows
// the fast bends of fine grids only (by 1.4 at most at 51 x 51 in 10
// substeps); where the cloth comes to rest the forces balance as they would.
void add_external_velocity(const Model& m, State& s, const Workspace& w, double h) {
  const double c = m.params.forces.viscous_damping;
  const BendingMatrix& b = m.topology->bending;
  const double stable = 1.0 / (h * h);
  const bool bending = !b.start.empty();
  // One pass: each particle's two factors found once, for its three
  // components (the same sums, in the same order, as a pass for each).
  for_each_particle_block(m, [&, h, c, stable](int first, int end) {
    const double *__restrict fx = w.force.column(0), *__restrict fy = w.force.column(1),
                             *__restrict fz = w.force.column(2);
    double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
    const double* __restrict inv_mass = m.inv_mass.data(), * __restrict area = m.area.data();
    if (!bending) {
#pragma omp simd
      for (int i = first; i < end; ++i) {
        const double hm = h * inv_mass[i], a = hm / (1 + hm * c * area[i]);
        vx[i] += a * fx[i];
        vy[i] += a * fy[i];
        vz[i] += a * fz[i];
      }
      return;
    }
    const double *__restrict bx = w.bending_force.column(0), *__restrict by = w.bending_force.column(1),
                             *__restrict bz = w.bending_force.column(2),
                             *__restrict bound = b.bound.data();
#pragma omp simd
    for (int i = first; i < end; ++i) {
      const double hm = h * inv_mass[i], a = hm / (1 + hm * c * area[i]);
      const double heavier = stable / bound[i];  // (not std::min: a reference, a gather)
      const double e = h * (inv_mass[i] < heavier ? inv_mass[i] : heavier);
      vx[i] = (vx[i] + a * fx[i]) + e * bx[i];
      vy[i] = (vy[i] + a * fy[i]) + e * by[i];
      vz[i] = (vz[i] + a * fz[i]) + e * bz[i];
    }
  });
}

}  // namespace

// XPBD in substeps: per substep the external forces move the particles, the
// constraints are projected once, then contact and friction; the air and the
// contact state follow every substep (the air is stiff: a tent's pressure
// answers its volume within a millisecond). The rig's force is the mean over
// the substeps.
void xpbd_step(const Model& m, State& s, Workspace& w) {
  const double dt = m.params.integrator.dt;
  const int substeps = xpbd_substeps(m);
  const double h = dt / substeps, inv_h2 = 1.0 / (h * h);
  Vec3 rig = Vec3::Zero();
  for (int k = 0; k < substeps; ++k) {
    // The external forces (docs/model.md section 8's first stage without the
    // springs and self-collision, which are constraints here).
    // The normals once a step: the wind and the air push along them.
    if (k == 0) compute_normals(m, s.x.column(0), w.normal, w.normals_scratch);
    add_own_forces(m, s, w, false, true);
    add_air_pressure(m, s, w);
    add_adhesion(m, s, w);
    add_handle_forces(m, s, w);
    if (!m.topology->bending.start.empty()) {
      // xpbd's alone: made at its first step (an integrator set later included).
      if (w.bending_force.size() != static_cast<std::size_t>(m.n))
        w.bending_force.assign(m.n, Vec3::Zero());
      bending_forces(m, s, w.bending_force);
    }
    add_external_velocity(m, s, w, h);
    move_from_substep_start(m, s, w, h);  // the air term implicit, then x += h v
    s.time = (static_cast<double>(s.steps) + static_cast<double>(k + 1) / substeps) * dt;
    if (w.surfaces.any) place_surfaces(m, w, s.time);  // moving surfaces at the substep's end
    apply_handle_constraints(m, s, w);
    xpbd_begin_substep(m, s, w);
    project_springs(m, s, w, h);
    // The strain limit's further passes (docs/model.md section 2's 1-3): one sweep
    // carries a stretch only a grid step or two from a pulled patch.
    if (m.params.strain_limit.enabled)
      for (long long pass = 1; pass < m.params.strain_limit.passes; ++pass)
        project_springs(m, s, w, h, true);
    project_self_collision(m, s, w, h);
    collide_with_friction(m, s, w, w.touched, h);
    // The paper's damping -k_f v of colliding particles, implicit.
    const double k_f = collision_constants(m).damping;
    for (const int q : w.colliding_particles) s.v[q] *= 1.0 / (1.0 + h * k_f * m.inv_mass[q]);
    hold_stopped_handles(m, s);
    // The rig holds its patch against the external forces (apply_handle_constraints)
    // and the constraints' pull: J / h² on each particle it holds.
    w.handle_force -= inv_h2 * w.reaction_impulse;
    rig += w.handle_force;
    update_contact_and_air(m, s, w, h);
    ++w.substeps;
  }
  w.handle_force = rig / substeps;
  s.time = static_cast<double>(s.steps + 1) * dt;
}

}  // namespace wetcloth::detail

namespace wetcloth {

int xpbd_substeps(const Params& p) {
  if (p.integrator.substeps > 0) return static_cast<int>(p.integrator.substeps);
  // (A mesh cloth: as the default grid's.)
  const long long longer =
      p.cloth.mesh.empty() ? std::max(p.cloth.resolution[0], p.cloth.resolution[1]) : 51;
  return static_cast<int>(10 + std::max(0LL, (longer - 101 + 9) / 10));
}

int xpbd_substeps(const Model& m) {
  if (m.grid || m.params.integrator.substeps > 0) return xpbd_substeps(m.params);
  return static_cast<int>(10 + std::max(0, (m.topology->along - 101 + 9) / 10));
}

}  // namespace wetcloth
