// Backward Euler for large steps (MODEL.md section 8; Baraff & Witkin 1998).
// The springs are linearised about the start of the step and solved for the new
// velocities with preconditioned conjugate gradients, matrix-free on the grid's
// stencil:
//   (M + h D + h² K) v' = M v + h f,
// where f holds every force but the damping (spring, viscous, self-collision),
// which D takes implicitly; K is the springs' stiffness with the compressed-spring
// fix (the transverse term dropped when |d| < l0, so K stays positive
// semi-definite) plus the repulsion of colliding pairs along their line. The air,
// adhesion, friction and surface contacts are taken at the start of the step.
// Pinned, driven and held particles keep their velocity (Baraff & Witkin's filter).
#include <algorithm>
#include <cmath>
#include <utility>

#include "detail.hpp"

namespace wetcloth::detail {

namespace {

Sym outer(const Vec3& u, double a, double b) {  // a u uᵀ + b I
  return {a * u.x() * u.x() + b, a * u.y() * u.y() + b, a * u.z() * u.z() + b,
          a * u.x() * u.y(),     a * u.x() * u.z(),     a * u.y() * u.z()};
}

Vec3 times(const Sym& s, const Vec3& x) {
  return {s[0] * x.x() + s[3] * x.y() + s[4] * x.z(), s[3] * x.x() + s[1] * x.y() + s[5] * x.z(),
          s[4] * x.x() + s[5] * x.y() + s[2] * x.z()};
}

Mat3 full(const Sym& s) {
  Mat3 a;
  a << s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2];
  return a;
}

bool fixed(const Model& m, const State& s, int i) { return m.inv_mass[i] == 0 || s.held[i]; }

double dot(const Model& m, Workspace& w, const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return ordered_sum(m, w, [&](int j) {
    double sum = 0;
    for (int k = j * m.nu; k < (j + 1) * m.nu; ++k) sum += a[k].dot(b[k]);
    return sum;
  });
}

// z = P r, in one pass with r·z (rows summed in order, as dot does) and the
// largest |z|, the convergence test. Returns {r·z, max |z|}.
std::pair<double, double> precondition(const Model& m, Workspace& w) {
  const auto& r = w.cg_r;
  const auto& pre = w.preconditioner;
  auto& z = w.cg_z;
  parallel_for(m, m.nv, [&](int j) {
    double rz = 0, worst = 0;
    for (int k = j * m.nu; k < (j + 1) * m.nu; ++k) {
      z[k] = pre[k] * r[k];
      rz += r[k].dot(z[k]);
      worst = std::max(worst, z[k].norm());
    }
    w.row_sums[j] = rz;
    w.row_max[j] = worst;
  });
  double rz = 0;
  for (int j = 0; j < m.nv; ++j) rz += w.row_sums[j];
  return {rz, *std::max_element(w.row_max.begin(), w.row_max.end())};
}

// The matrix in columns. Edge e's block s sᵀ + β I (s = √α u, α ≥ 0: see
// implicit_euler_velocities), held at its lower end a as four fields: field k
// (s_x, s_y, s_z, β) at edge_blocks[(4 e + k) n + a], four numbers where a
// symmetric block takes six. Then the diagonal blocks' six fields (Sym's
// order) at edge_blocks[(32 + k) n + a].
constexpr int kBlockFields = 4, kDiagonalField = 8 * kBlockFields;
double* edge_field(const Model& m, Workspace& w, int e, int k) {
  return w.edge_blocks.data() + (kBlockFields * std::size_t(e) + k) * m.n;
}
double* diagonal_field(const Model& m, Workspace& w, int k) {
  return w.edge_blocks.data() + (kDiagonalField + std::size_t(k)) * m.n;
}
Sym diagonal_block(const Model& m, Workspace& w, int a) {
  Sym d;
  for (int k = 0; k < 6; ++k) d[k] = diagonal_field(m, w, k)[a];
  return d;
}

// Calls body(e, sign, off, from, to) for each of row j's 16 neighbour
// offsets (edge e forward, sign 1, then back, -1) that stay on the grid, in
// stencil order: the particles i in [from, to) of the row have the neighbour
// a + off.
template <class Body>
void for_each_neighbour_offset(const Model& m, int j, Body&& body) {
  for (int e = 0; e < 8; ++e) {
    const StencilEdge& st = m.stencil[e];
    for (const int sign : {1, -1}) {
      const int di = sign * st.di, dj = sign * st.dj;
      if (j + dj < 0 || j + dj >= m.nv) continue;
      body(e, sign, di + dj * m.nu, std::max(0, -di), std::min(m.nu, m.nu - di));
    }
  }
}

// y = A x over the free particles; fixed ones have identity rows (their x
// never changes, so their columns only enter through the starting residual).
// x is first copied to columns (x, y, z), and y summed in columns, so that the
// loops over a row vectorise.
void multiply(const Model& m, const State& s, Workspace& w, const std::vector<Vec3>& x,
              std::vector<Vec3>& y) {
  const int n = m.n, nu = m.nu;
  w.cg_columns.resize(6 * std::size_t(n));
  double* const X = w.cg_columns.data();
  double* const Y = X + 3 * std::size_t(n);
  to_columns(m, x, X);
  // Row by row, offset by offset over the particles that have that neighbour:
  // no test per particle in the inner loops, the same order of sums per particle.
  parallel_for(m, m.nv, [&](int j) {
    const int row = j * nu;
    double* __restrict y0 = Y + row;
    double* __restrict y1 = Y + n + row;
    double* __restrict y2 = Y + 2 * n + row;
    {
      const double *d0 = diagonal_field(m, w, 0) + row, *d1 = diagonal_field(m, w, 1) + row,
                   *d2 = diagonal_field(m, w, 2) + row, *d3 = diagonal_field(m, w, 3) + row,
                   *d4 = diagonal_field(m, w, 4) + row, *d5 = diagonal_field(m, w, 5) + row;
      const double *x0 = X + row, *x1 = X + n + row, *x2 = X + 2 * n + row;
#pragma GCC ivdep
      for (int i = 0; i < nu; ++i) {
        y0[i] = d0[i] * x0[i] + d3[i] * x1[i] + d4[i] * x2[i];
        y1[i] = d3[i] * x0[i] + d1[i] * x1[i] + d5[i] * x2[i];
        y2[i] = d4[i] * x0[i] + d5[i] * x1[i] + d2[i] * x2[i];
      }
    }
    for_each_neighbour_offset(m, j, [&](int e, int sign, int off, int from, int to) {
      // The block of edge e sits at its lower end: a going forward, a + off going back.
      const int at = row + (sign > 0 ? 0 : off);
      const double *s0 = edge_field(m, w, e, 0) + at, *s1 = edge_field(m, w, e, 1) + at,
                   *s2 = edge_field(m, w, e, 2) + at, *beta = edge_field(m, w, e, 3) + at;
      const double *x0 = X + row + off, *x1 = X + n + row + off, *x2 = X + 2 * n + row + off;
#pragma GCC ivdep
      for (int i = from; i < to; ++i) {
        const double sx = s0[i] * x0[i] + s1[i] * x1[i] + s2[i] * x2[i];
        y0[i] -= s0[i] * sx + beta[i] * x0[i];
        y1[i] -= s1[i] * sx + beta[i] * x1[i];
        y2[i] -= s2[i] * sx + beta[i] * x2[i];
      }
    });
    for (int a = row; a < row + nu; ++a)
      y[a] = fixed(m, s, a) ? x[a] : Vec3(Y[a], Y[n + a], Y[2 * n + a]);
  });
  for (const CollisionPair& c : w.collision_pairs) {  // few: serial, in pair order
    if (!fixed(m, s, c.i)) y[c.i] -= times(c.block, x[c.j]);
    if (!fixed(m, s, c.j)) y[c.j] -= times(c.block, x[c.i]);
  }
}

}  // namespace

void implicit_euler_velocities(const Model& m, State& s, Workspace& w, double h) {
  const double h2 = h * h, c = m.params.forces.viscous_damping;
  const double kf = m.params.self_collision.damping;
  // Each forward stencil edge's block h k_d u uᵀ + h² K_e, row by row, from
  // the positions in columns add_spring_forces left (this substep's).
  // The solver's arrays are sized at the first implicit step: the explicit
  // integrators need none of them. Every one is written before it is read.
  w.edge_blocks.resize((kDiagonalField + 6) * std::size_t(m.n));
  w.preconditioner.resize(m.n);
  for (auto* v : {&w.cg_r, &w.cg_z, &w.cg_p, &w.cg_q}) v->resize(m.n);
  const double* const X = w.soa.data();  // x, y, z by component
  const int n = m.n, nu = m.nu;
  parallel_for(m, m.nv, [&](int j) {
    const int row = j * nu;
    for (int e = 0; e < 8; ++e) {
      const StencilEdge& st = m.stencil[e];
      const int off = st.di + st.dj * nu;
      // Particles of the row whose edge e stays on the grid (every forward edge has dj >= 0).
      const int from = j + st.dj < m.nv ? std::max(0, -st.di) : nu;
      const int to = j + st.dj < m.nv ? std::min(nu, nu - st.di) : nu;
      double *s0 = edge_field(m, w, e, 0) + row, *s1 = edge_field(m, w, e, 1) + row,
             *s2 = edge_field(m, w, e, 2) + row, *beta = edge_field(m, w, e, 3) + row;
      for (double* f : {s0, s1, s2, beta}) {  // edges off the grid: zero blocks
        std::fill(f, f + from, 0.0);
        std::fill(f + to, f + nu, 0.0);
      }
      const double *x0 = X + row, *x1 = X + n + row, *x2 = X + 2 * n + row;
#pragma GCC ivdep
      for (int i = from; i < to; ++i) {
        const double dx = x0[i + off] - x0[i], dy = x1[i + off] - x1[i], dz = x2[i + off] - x2[i];
        const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
        const double inv = len > 0 ? 1.0 / len : 0.0;  // a zero-length spring: a zero block
        // K_e = k (u uᵀ + (1 - l0/|d|)(I - u uᵀ)), the transverse part only when
        // stretched: the block is α u uᵀ + β I, α = h k_d + h² (k - transverse) ≥ 0.
        const double transverse = len > 0 ? std::max(0.0, 1.0 - st.rest * inv) * st.k : 0.0;
        const double q = std::sqrt(h * st.damping + h2 * (st.k - transverse)) * inv;
        s0[i] = q * dx;
        s1[i] = q * dy;
        s2[i] = q * dz;
        beta[i] = h2 * transverse;
      }
    }
  });
  // Diagonal blocks: mass, viscous and collision damping, and every edge at
  // the particle, in the product's order (forward, then back, edge by edge).
  parallel_for(m, m.nv, [&](int j) {
    const int row = j * nu;
    double* d[6];
    for (int k = 0; k < 6; ++k) d[k] = diagonal_field(m, w, k) + row;
    for (int i = 0; i < nu; ++i) {
      const int a = row + i;
      const double own = m.mass[a] + h * c * m.area[a] + (w.colliding[a] ? h * kf : 0.0);
      for (int k = 0; k < 6; ++k) d[k][i] = k < 3 ? own : 0.0;
    }
    for_each_neighbour_offset(m, j, [&](int e, int sign, int off, int from, int to) {
      const int at = row + (sign > 0 ? 0 : off);
      const double *s0 = edge_field(m, w, e, 0) + at, *s1 = edge_field(m, w, e, 1) + at,
                   *s2 = edge_field(m, w, e, 2) + at, *beta = edge_field(m, w, e, 3) + at;
      double* __restrict d0 = d[0], * __restrict d1 = d[1], * __restrict d2 = d[2], * __restrict d3 = d[3], * __restrict d4 = d[4], * __restrict d5 = d[5];
#pragma GCC ivdep
      for (int i = from; i < to; ++i) {
        d0[i] += s0[i] * s0[i] + beta[i];
        d1[i] += s1[i] * s1[i] + beta[i];
        d2[i] += s2[i] * s2[i] + beta[i];
        d3[i] += s0[i] * s1[i];
        d4[i] += s0[i] * s2[i];
        d5[i] += s1[i] * s2[i];
      }
    });
  });
  for (CollisionPair& p : w.collision_pairs) {
    p.block = outer(p.u, h2 * m.params.self_collision.k, 0);
    for (const int a : {p.i, p.j})
      for (int k = 0; k < 6; ++k) diagonal_field(m, w, k)[a] += p.block[k];
  }

  // Right-hand side M v + h f, the block-Jacobi preconditioner, and the start:
  // the velocities the last substep's acceleration would give. A pull or a
  // fall changes little from one substep to the next, so this starts CG
  // nearer the answer than v does (a quarter fewer iterations on the pulls).
  auto& x = s.v;
  auto &r = w.cg_r, &z = w.cg_z, &p = w.cg_p, &q = w.cg_q;
  for_each_particle(m, [&](int a) {
    if (fixed(m, s, a)) {
      w.preconditioner[a] = Mat3::Identity();
      r[a] = x[a];  // b = x: no change
      return;
    }
    w.preconditioner[a] = full(diagonal_block(m, w, a)).inverse();
    r[a] = m.mass[a] * x[a] + h * w.force[a];
    if (!w.acceleration.empty()) x[a] += h * w.acceleration[a];
  });
  multiply(m, s, w, x, q);
  for_each_particle(m, [&](int a) { r[a] -= q[a]; });
  // Converged when no particle's velocity is off by more than the tolerance:
  // z = P r is the preconditioned residual, a velocity. (A norm over the whole
  // cloth would let the adhesion and weight of thousands of particles drown
  // out the few the hand pulls.)
  auto [rz, worst] = precondition(m, w);
  for_each_particle(m, [&](int a) { p[a] = z[a]; });
  int it = 0;
  for (; it < m.params.integrator.cg_max_iterations; ++it) {
    if (worst <= m.params.integrator.cg_tolerance) break;
    multiply(m, s, w, p, q);
    const double pq = dot(m, w, p, q);
    if (pq <= 0) break;
    const double alpha = rz / pq;
    for_each_particle(m, [&](int a) {
      x[a] += alpha * p[a];
      r[a] -= alpha * q[a];
    });
    const auto [rz_next, worst_next] = precondition(m, w);
    const double beta = rz_next / rz;
    rz = rz_next;
    worst = worst_next;
    for_each_particle(m, [&](int a) { p[a] = z[a] + beta * p[a]; });
  }
  w.cg_iterations = it;
}

// Where a spring turns or stretches by a good part of its length within one
// step, its linearisation at the start of the step no longer holds: about a
// flat cloth, springs at rest have no stiffness across it, and a force on a
// few particles would move them at h F / m.
double step_strain(const Model& m, const State& s, double h) {
  return max_over_particles(m, [&](int a) {
    const int i = a % m.nu, j = a / m.nu;
    double worst = 0;
    for (int e = 0; e < 4; ++e) {  // structural and shear
      const StencilEdge& st = m.stencil[e];
      if (const int b = grid_neighbour(m, i, j, st.di, st.dj); b >= 0)
        worst = std::max(worst, h * (s.v[b] - s.v[a]).norm() / st.rest);
    }
    return worst;
  });
}

}  // namespace wetcloth::detail
