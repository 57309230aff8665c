// Backward Euler for large steps (docs/model.md section 8; Baraff & Witkin 1998).
// The springs are linearised about the start of the step and solved for the new
// velocities with preconditioned conjugate gradients, matrix-free on the grid's
// stencil:
//   (M + h D + h² K) v' = M v + h f,
// where f holds every force but the damping (spring, viscous, self-collision),
// which D takes implicitly; K is the springs' stiffness with the compressed-spring
// fix (the transverse term dropped when |d| < l0, so K stays positive
// semi-definite), the quadratic bending's constant Q (forces/bending.cpp),
// plus the repulsion of colliding pairs along their line. The air,
// adhesion and friction are taken at the start of the step; collisions with
// the surfaces after it. Pinned, driven and held particles keep their velocity,
// and particles the forces press into the contact surface keep no normal
// velocity (Baraff & Witkin's filter).
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

bool fixed(const Model& m, const State& s, int i) { return m.inv_mass[i] == 0 || s.held[i]; }

// The matrix and the solver's vectors are held in columns, each with zeros
// for two rows and two particles before and after it. Column k of a store:
std::size_t padding(const Model& m) { return 2 * std::size_t(m.nu) + 2; }
std::size_t padded_size(const Model& m, int columns) {
  return columns * (std::size_t(m.n) + 2 * padding(m));
}
template <class T>
T* column(const Model& m, std::vector<T>& store, int k) {
  return store.data() + k * (std::size_t(m.n) + 2 * padding(m)) + padding(m);
}

// The matrix. Edge e's block s sᵀ + β I (s = √α u, α ≥ 0: see
// implicit_euler_velocities), held at its lower end as four fields, column
// 4 e + k for s_x, s_y, s_z, β: four numbers where a symmetric block takes
// six. An edge that leaves the grid has a zero block. The edge blocks are
// float: the product streams them, and half the bytes is what it is bound by.
// The diagonal blocks are summed in double from the same float fields, so the
// matrix stays symmetric and each row's blocks add up as they should; only
// the vectors' precision decides how the solve converges.
// An edge with neither stiffness nor damping (the Provot bending offsets
// under the quadratic bending) has no fields (64 B a particle): its block
// would be zero everywhere, and every loop leaves it out (a zero block adds
// ±0, which changes no sum but an exact −0's sign).
// The block-Jacobi preconditioner follows them in the same store, six float
// columns (Sym's order): it only steers the solve, which converges on the
// double residual. Then one column of flags: 1 for a particle held on the
// contact surface (set_up_solve), whose normal is then w.surface_normal's.
constexpr int kBlockFields = 4;
bool has_block(const Model& m, int e) {
  return m.topology->stencil[e].k != 0 || m.topology->stencil[e].damping != 0;
}
int edges_with_blocks(const Model& m) {
  int count = 0;
  for (int e = 0; e < 8; ++e) count += has_block(m, e);
  return count;
}
int float_columns(const Model& m) { return kBlockFields * edges_with_blocks(m) + 7; }
float* edge_field(const Model& m, Workspace& w, int e, int k) {
  int slot = 0;  // edge e's place among those with blocks
  for (int f = 0; f < e; ++f) slot += has_block(m, f);
  return column(m, w.float_columns, kBlockFields * slot + k);
}
float* preconditioner_field(const Model& m, Workspace& w, int k) {
  return column(m, w.float_columns, kBlockFields * edges_with_blocks(m) + k);
}
float* held_flags(const Model& m, Workspace& w) { return preconditioner_field(m, w, 6); }

// The solver's vectors in columns, three each (x, y, z), then the matrix's
// diagonal blocks (Sym's order): every loop over a row vectorises. z = P r
// and q = A p share their columns: each is dead when the other is written
// (q once r is updated from it, z once p is).
enum Vector { kX, kR, kZ, kP, kQ = kZ };
constexpr int kDiagonalColumn = 12, kSolverColumns = 18;
struct Columns {
  double* c[3];
  Vec3 at(int a) const { return {c[0][a], c[1][a], c[2][a]}; }
};
double* solver_column(const Model& m, Workspace& w, int k) { return column(m, w.cg_columns, k); }
double* diagonal_field(const Model& m, Workspace& w, int k) {
  return solver_column(m, w, kDiagonalColumn + k);
}
Columns columns(const Model& m, Workspace& w, Vector v) {
  return {
      {solver_column(m, w, 3 * v), solver_column(m, w, 3 * v + 1), solver_column(m, w, 3 * v + 2)}};
}

// The normal of each particle held on the contact surface, zero for the others.
struct HeldNormals {
  const float* held;
  const double *x, *y, *z;
  HeldNormals(const Model& m, Workspace& w)
      : held(held_flags(m, w)),
        x(w.surface_normal.column(0)),
        y(w.surface_normal.column(1)),
        z(w.surface_normal.column(2)) {}
};

// v -= (v·n) n for the particles held on the surface (Baraff & Witkin's
// filter S = I - n nᵀ; n is zero for the others).
void filter(const Model& m, Workspace& w, Vector v) {
  const Columns c = columns(m, w, v);
  const HeldNormals normals(m, w);
  for_each_row_block(m, [&](int j0, int j1, int) {
    const HeldNormals h = normals;
#pragma GCC ivdep
    for (int a = j0 * m.nu; a < j1 * m.nu; ++a) {
      const bool held = h.held[a] != 0;
      const double n0 = held ? h.x[a] : 0.0, n1 = held ? h.y[a] : 0.0, n2 = held ? h.z[a] : 0.0;
      const double d = c.c[0][a] * n0 + c.c[1][a] * n1 + c.c[2][a] * n2;
      c.c[0][a] -= d * n0;
      c.c[1][a] -= d * n1;
      c.c[2][a] -= d * n2;
    }
  });
}

// y += h² Q x over [a0, a1) (Q's off-diagonal entries: its diagonal is in the
// diagonal blocks): the quadratic bending, a constant part of the matrix.
void add_bending_product(const Model& m, Workspace& w, const Columns& x, const Columns& y, int a0,
                         int a1) {
  if (m.topology->bending.start.empty()) return;
  for (int k = 0; k < 3; ++k)
    detail::add_bending_off_diagonal(m, x.c[k], y.c[k], w.bending_h2, a0, a1);
}

// y = A x over the free particles; fixed ones have identity rows (their x
// never changes, so their columns only enter through the starting residual).
// Each thread takes its block of rows, offset by offset in stencil order,
// forward then back, over all its particles at once: a neighbour off the grid
// meets a zero block (an offset that wraps round a row reaches the block of
// an edge that leaves the grid; one past the first or last row, the padding),
// so the loops need no test, and each particle sums in the same order.
void multiply(const Model& m, const State& s, Workspace& w, Vector in, Vector out) {
  const Columns xc = columns(m, w, in), yc = columns(m, w, out);
  const double *const x0 = xc.c[0], *const x1 = xc.c[1], *const x2 = xc.c[2];
  double *const y0 = yc.c[0], *const y1 = yc.c[1], *const y2 = yc.c[2];
  if (!m.grid) {  // a mesh cloth: the diagonal blocks, then each spring's at both ends
    const double *d0 = diagonal_field(m, w, 0), *d1 = diagonal_field(m, w, 1),
                 *d2 = diagonal_field(m, w, 2), *d3 = diagonal_field(m, w, 3),
                 *d4 = diagonal_field(m, w, 4), *d5 = diagonal_field(m, w, 5);
    for (int a = 0; a < m.n; ++a) {
      y0[a] = d0[a] * x0[a] + d3[a] * x1[a] + d4[a] * x2[a];
      y1[a] = d3[a] * x0[a] + d1[a] * x1[a] + d5[a] * x2[a];
      y2[a] = d4[a] * x0[a] + d5[a] * x1[a] + d2[a] * x2[a];
    }
    const float* block = w.mesh_blocks.data();
    for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
      for (std::size_t e = 0; e < set->size(); ++e, block += 4) {
        const double sx = block[0], sy = block[1], sz = block[2], beta = block[3];
        for (const auto& [a, b] :
             {std::pair{set->a[e], set->b[e]}, std::pair{set->b[e], set->a[e]}}) {
          const double t = sx * x0[b] + sy * x1[b] + sz * x2[b];
          y0[a] -= sx * t + beta * x0[b];
          y1[a] -= sy * t + beta * x1[b];
          y2[a] -= sz * t + beta * x2[b];
        }
      }
    add_bending_product(m, w, xc, yc, 0, m.n);
    for (const int a : w.fixed_particles) {
      y0[a] = x0[a];
      y1[a] = x1[a];
      y2[a] = x2[a];
    }
  } else
    for_each_row_block(m, [&](int j0, int j1, int) {
      const int a0 = j0 * m.nu, a1 = j1 * m.nu;
      {
        const double *d0 = diagonal_field(m, w, 0), *d1 = diagonal_field(m, w, 1),
                     *d2 = diagonal_field(m, w, 2), *d3 = diagonal_field(m, w, 3),
                     *d4 = diagonal_field(m, w, 4), *d5 = diagonal_field(m, w, 5);
#pragma GCC ivdep
        for (int a = a0; a < a1; ++a) {
          y0[a] = d0[a] * x0[a] + d3[a] * x1[a] + d4[a] * x2[a];
          y1[a] = d3[a] * x0[a] + d1[a] * x1[a] + d5[a] * x2[a];
          y2[a] = d4[a] * x0[a] + d5[a] * x1[a] + d2[a] * x2[a];
        }
      }
      for (int e = 0; e < 8; ++e) {
        if (!has_block(m, e)) continue;
        // Edge e's block sits at its lower end: particle a's forward edge (to
        // a + off) at a, its backward edge (from a - off) at a - off.
        const int off = m.topology->stencil[e].di + m.topology->stencil[e].dj * m.nu;
        const float *s0 = edge_field(m, w, e, 0), *s1 = edge_field(m, w, e, 1),
                    *s2 = edge_field(m, w, e, 2), *beta = edge_field(m, w, e, 3);
        const float *t0 = s0 - off, *t1 = s1 - off, *t2 = s2 - off, *tb = beta - off;
        const double *n0 = x0 + off, *n1 = x1 + off, *n2 = x2 + off;
        const double *m0 = x0 - off, *m1 = x1 - off, *m2 = x2 - off;
#pragma GCC ivdep
        for (int a = a0; a < a1; ++a) {
          const double sx = s0[a] * n0[a] + s1[a] * n1[a] + s2[a] * n2[a];
          const double tx = t0[a] * m0[a] + t1[a] * m1[a] + t2[a] * m2[a];
          const double f0 = y0[a] - (s0[a] * sx + beta[a] * n0[a]);
          const double f1 = y1[a] - (s1[a] * sx + beta[a] * n1[a]);
          const double f2 = y2[a] - (s2[a] * sx + beta[a] * n2[a]);
          y0[a] = f0 - (t0[a] * tx + tb[a] * m0[a]);
          y1[a] = f1 - (t1[a] * tx + tb[a] * m1[a]);
          y2[a] = f2 - (t2[a] * tx + tb[a] * m2[a]);
        }
      }
      add_bending_product(m, w, xc, yc, a0, a1);
      for (const int a : w.fixed_particles)
        if (a >= a0 && a < a1) {
          y0[a] = x0[a];
          y1[a] = x1[a];
          y2[a] = x2[a];
        }
    });
  for (const CollisionPair& c : w.collision_pairs)  // few: serial, in pair order
    for (const auto& [a, b] : {std::pair{c.i, c.j}, std::pair{c.j, c.i}}) {
      if (fixed(m, s, a)) continue;
      const Vec3 d = times(c.block, xc.at(b));
      for (int k = 0; k < 3; ++k) yc.c[k][a] -= d[k];
    }
}

// A row's term(i) over [begin, end) folded with op (from 0) in kLanes
// partial results, particle i into lane (i - begin) mod kLanes, then the
// lanes in order: a fixed order (the same bits every run and for any number
// of threads) whose lanes a vector holds. One running sum would make each
// add wait for the last.
constexpr int kLanes = 8;
template <class Term, class Op>
double fold_lanes(int begin, int end, Term term, Op op) {
  double lane[kLanes] = {};
  int i = begin;
  for (; i + kLanes <= end; i += kLanes)
    for (int l = 0; l < kLanes; ++l) lane[l] = op(lane[l], term(i + l));
  for (int l = 0; i < end; ++i, ++l) lane[l] = op(lane[l], term(i));
  double result = 0;
  for (const double x : lane) result = op(result, x);
  return result;
}
template <class Term>
double lane_sum(int begin, int end, Term term) {
  return fold_lanes(begin, end, term, [](double a, double b) { return a + b; });
}

// a · b, rows summed in order (the same bits for any number of threads).
double dot(const Model& m, Workspace& w, Vector av, Vector bv) {
  const Columns a = columns(m, w, av), b = columns(m, w, bv);
  return ordered_sum(m, w, [&](int j) {
    return lane_sum(j * m.nu, (j + 1) * m.nu, [&](int k) {
      return a.c[0][k] * b.c[0][k] + a.c[1][k] * b.c[1][k] + a.c[2][k] * b.c[2][k];
    });
  });
}

// z = P r, with r·z (rows summed in order, as dot does) and the largest
// |r_i| / m_i, the convergence test. Returns {r·z, max |r_i| / m_i}.
std::pair<double, double> precondition(const Model& m, Workspace& w) {
  const Columns r = columns(m, w, kR), z = columns(m, w, kZ);
  const float* P[6];
  for (int k = 0; k < 6; ++k) P[k] = preconditioner_field(m, w, k);
  const HeldNormals normals(m, w);
  const double *r0 = r.c[0], *r1 = r.c[1], *r2 = r.c[2], *inv_mass = m.inv_mass.data();
  double* __restrict z0 = z.c[0];
  double* __restrict z1 = z.c[1];
  double* __restrict z2 = z.c[2];
  // By chunks of kChunkRows rows: z over the chunk in one loop (a loop per
  // row of 51 ended in a scalar tail of 3), then each row's sums while the
  // chunk is still in cache.
  constexpr int kChunkRows = 4;
  parallel_for(m, (m.nv + kChunkRows - 1) / kChunkRows, [&](int chunk) {
    const int j0 = chunk * kChunkRows, j1 = std::min(m.nv, j0 + kChunkRows);
#pragma GCC ivdep
    for (int a = j0 * m.nu; a < j1 * m.nu; ++a) {
      // In registers, then stored once: a store read straight back stalls.
      const double a0 = P[0][a] * r0[a] + P[3][a] * r1[a] + P[4][a] * r2[a];
      const double a1 = P[3][a] * r0[a] + P[1][a] * r1[a] + P[5][a] * r2[a];
      const double a2 = P[4][a] * r0[a] + P[5][a] * r1[a] + P[2][a] * r2[a];
      const bool held = normals.held[a] != 0;
      const double n0 = held ? normals.x[a] : 0.0, n1 = held ? normals.y[a] : 0.0,
                   n2 = held ? normals.z[a] : 0.0;
      const double d = a0 * n0 + a1 * n1 + a2 * n2;
      z0[a] = a0 - d * n0;
      z1[a] = a1 - d * n1;
      z2[a] = a2 - d * n2;
    }
    for (int j = j0; j < j1; ++j) {
      const int b = j * m.nu, e = b + m.nu;
      w.row_sums[j] =
          lane_sum(b, e, [&](int a) { return r0[a] * z0[a] + r1[a] * z1[a] + r2[a] * z2[a]; });
      w.row_max[j] = fold_lanes(
          b, e,
          [&](int a) {
            return (r0[a] * r0[a] + r1[a] * r1[a] + r2[a] * r2[a]) * (inv_mass[a] * inv_mass[a]);
          },
          [](double x, double y) { return std::max(x, y); });
    }
  });
  double rz = 0;
  for (int j = 0; j < m.nv; ++j) rz += w.row_sums[j];
  return {rz, std::sqrt(*std::max_element(w.row_max.begin(), w.row_max.end()))};
}

// On each pinned, driven or held particle, the force the springs and
// colliding pairs exert at the end of the substep, as the solve took them:
// f - (1/h) Σ B (v'_a - v'_b), their stiffness over the step and their damping
// (left out of f). The rig's force (docs/model.md section 9) is minus these: from f
// alone, it lagged by h K v' and fell as the substep grew.
void add_forces_at_new_velocities(const Model& m, const State& s, Workspace& w, double h) {
  if (w.fixed_particles.empty()) return;
  const Columns v = columns(m, w, kX);
  const auto pull = [&](int a, int b, const Vec3& sv, double beta) {
    const Vec3 d = v.at(a) - v.at(b);
    w.force[a] -= (sv * sv.dot(d) + beta * d) / h;
  };
  if (m.grid)
    for (const int a : w.fixed_particles)
      for (int e = 0; e < 8; ++e) {
        if (!has_block(m, e)) continue;
        // An edge off the grid has a zero block (its far end in the padding).
        const int off = m.topology->stencil[e].di + m.topology->stencil[e].dj * m.nu;
        for (const int at : {a, a - off}) {
          const float* f[4];
          for (int k = 0; k < 4; ++k) f[k] = edge_field(m, w, e, k);
          pull(a, at == a ? a + off : at, Vec3(f[0][at], f[1][at], f[2][at]), f[3][at]);
        }
      }
  else {
    const float* block = w.mesh_blocks.data();
    for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
      for (std::size_t e = 0; e < set->size(); ++e, block += 4)
        for (const auto& [a, b] :
             {std::pair{set->a[e], set->b[e]}, std::pair{set->b[e], set->a[e]}})
          if (fixed(m, s, a)) pull(a, b, Vec3(block[0], block[1], block[2]), block[3]);
  }
  for (const CollisionPair& c : w.collision_pairs)
    for (const auto& [a, b] : {std::pair{c.i, c.j}, std::pair{c.j, c.i}})
      if (fixed(m, s, a)) w.force[a] -= times(c.block, v.at(a) - v.at(b)) / h;
  // The quadratic bending's -Q (x + h v'): its -h Q v'.
  const BendingMatrix& b = m.topology->bending;
  if (!b.start.empty())
    for (const int a : w.fixed_particles) {
      Vec3 qv = Vec3::Zero();
      b.for_each_in_row(a, [&](int j, double q) { qv += q * (v.at(j) - v.at(a)); });
      w.force[a] -= h * qv;
    }
}

// body(first, end) over each thread's block of particles.
template <class Body>
void for_each_block(const Model& m, Body&& body) {
  for_each_row_block(m, [&](int j0, int j1, int) { body(j0 * m.nu, j1 * m.nu); });
}

// Each spring's block h k_d u uᵀ + h² K_e from the substep's positions: a mesh
// cloth's in the springs' order, a grid's per forward stencil edge, row by row.
void assemble_spring_blocks(const Model& m, const State& s, Workspace& w, double h) {
  const double h2 = h * h;
  const double* const X = s.x.column(0);  // x, y, z by component
  const int n = m.n, nu = m.nu;
  if (!m.grid) {  // a mesh cloth: each spring's block, in the springs' order
    w.mesh_blocks.clear();
    for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
      for (std::size_t e = 0; e < set->size(); ++e) {
        const Vec3 d = s.x[set->b[e]] - s.x[set->a[e]];
        const double len = d.norm(), inv = len > 0 ? 1.0 / len : 0.0, k = set->k[e];
        const double transverse = len > 0 ? std::max(0.0, 1.0 - set->rest[e] * inv) * k : 0.0;
        const double q = std::sqrt(h * set->damping[e] + h2 * (k - transverse)) * inv;
        for (const double f : {q * d.x(), q * d.y(), q * d.z(), h2 * transverse})
          w.mesh_blocks.push_back(float(f));
      }
  }
  if (m.grid)
    parallel_for(m, m.nv, [&](int j) {
      const int row = j * nu;
      for (int e = 0; e < 8; ++e) {
        if (!has_block(m, e)) continue;
        const StencilEdge& st = m.topology->stencil[e];
        const int off = st.di + st.dj * nu;
        // Particles of the row whose edge e stays on the grid (every forward edge has dj >= 0).
        const int from = j + st.dj < m.nv ? std::max(0, -st.di) : nu;
        const int to = j + st.dj < m.nv ? std::min(nu, nu - st.di) : nu;
        float *s0 = edge_field(m, w, e, 0) + row, *s1 = edge_field(m, w, e, 1) + row,
              *s2 = edge_field(m, w, e, 2) + row, *beta = edge_field(m, w, e, 3) + row;
        for (float* f : {s0, s1, s2, beta}) {  // edges off the grid: zero blocks
          std::fill(f, f + from, 0.0f);
          std::fill(f + to, f + nu, 0.0f);
        }
        const double *x0 = X + row, *x1 = X + n + row, *x2 = X + 2 * n + row;
        const double rest = st.rest, k = st.k, damping = st.damping;
#pragma GCC ivdep
        for (int i = from; i < to; ++i) {
          const double dx = x0[i + off] - x0[i], dy = x1[i + off] - x1[i], dz = x2[i + off] - x2[i];
          const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
          const double inv = len > 0 ? 1.0 / len : 0.0;  // a zero-length spring: a zero block
          // K_e = k (u uᵀ + (1 - l0/|d|)(I - u uᵀ)), the transverse part only when
          // stretched: the block is α u uᵀ + β I, α = h k_d + h² (k - transverse) ≥ 0.
          const double transverse = len > 0 ? std::max(0.0, 1.0 - rest * inv) * k : 0.0;
          const double q = std::sqrt(h * damping + h2 * (k - transverse)) * inv;
          s0[i] = float(q * dx);
          s1[i] = float(q * dy);
          s2[i] = float(q * dz);
          beta[i] = float(h2 * transverse);
        }
      }
    });
}

// Diagonal blocks: mass, viscous and collision damping, and every edge at
// the particle, in the product's order and over the same blocks of rows (an
// edge off the grid adds its zero block).
void assemble_diagonal_blocks(const Model& m, Workspace& w, double h) {
  const double h2 = h * h, c = m.params.forces.viscous_damping;
  const CollisionConstants collision = collision_constants(m);
  const double kt = collision.k, kf = collision.damping;
  const std::vector<double>& bending = m.topology->bending.diagonal;
  w.bending_h2 = h2;
  const int nu = m.nu;
  for_each_row_block(m, [&](int j0, int j1, int) {
    const int a0 = j0 * nu, a1 = j1 * nu;
    double* __restrict d0 = diagonal_field(m, w, 0);
    double* __restrict d1 = diagonal_field(m, w, 1);
    double* __restrict d2 = diagonal_field(m, w, 2);
    double* __restrict d3 = diagonal_field(m, w, 3);
    double* __restrict d4 = diagonal_field(m, w, 4);
    double* __restrict d5 = diagonal_field(m, w, 5);
    for (int a = a0; a < a1; ++a) {
      d0[a] = d1[a] = d2[a] = m.mass[a] + h * c * m.area[a] + (w.colliding[a] ? h * kf : 0.0) +
                              (bending.empty() ? 0.0 : h2 * bending[a]);
      d3[a] = d4[a] = d5[a] = 0.0;
    }
    // An edge's block s sᵀ + β I, added at particle a.
    const auto add = [&](int a, double x, double y, double z, double b) {
      d0[a] += x * x + b;
      d1[a] += y * y + b;
      d2[a] += z * z + b;
      d3[a] += x * y;
      d4[a] += x * z;
      d5[a] += y * z;
    };
    if (!m.grid) {
      const float* block = w.mesh_blocks.data();
      for (const SpringSet* set : {&m.structural, &m.shear, &m.bending})
        for (std::size_t e = 0; e < set->size(); ++e, block += 4)
          for (const int a : {set->a[e], set->b[e]}) add(a, block[0], block[1], block[2], block[3]);
      return;
    }
    for (int e = 0; e < 8; ++e)
      for (const int sign : {1, -1}) {
        if (!has_block(m, e)) continue;
        const StencilEdge& st = m.topology->stencil[e];
        const int at = sign > 0 ? 0 : -(st.di + st.dj * nu);
        const float *s0 = edge_field(m, w, e, 0) + at, *s1 = edge_field(m, w, e, 1) + at,
                    *s2 = edge_field(m, w, e, 2) + at, *beta = edge_field(m, w, e, 3) + at;
#pragma GCC ivdep
        for (int a = a0; a < a1; ++a) add(a, s0[a], s1[a], s2[a], beta[a]);
      }
  });
  for (CollisionPair& p : w.collision_pairs) {
    p.block = outer(p.u, h2 * kt, 0);
    for (const int a : {p.i, p.j})
      for (int k = 0; k < 6; ++k) diagonal_field(m, w, k)[a] += p.block[k];
  }
}

// The preconditioner: each diagonal block's inverse by its cofactors (the
// formula of Eigen's 3 × 3 inverse), in a loop over columns that
// vectorises; the identity for the fixed particles, listed here.
void invert_diagonal_blocks(const Model& m, const State& s, Workspace& w) {
  const int n = m.n, nu = m.nu;
  float* P[6];
  for (int k = 0; k < 6; ++k) P[k] = preconditioner_field(m, w, k);
  w.fixed_particles.clear();
  for (int a = 0; a < n; ++a)
    if (fixed(m, s, a)) w.fixed_particles.push_back(a);
  parallel_for(m, m.nv, [&](int j) {
    const int row = j * nu;
    const double *d0 = diagonal_field(m, w, 0) + row, *d1 = diagonal_field(m, w, 1) + row,
                 *d2 = diagonal_field(m, w, 2) + row, *d3 = diagonal_field(m, w, 3) + row,
                 *d4 = diagonal_field(m, w, 4) + row, *d5 = diagonal_field(m, w, 5) + row;
    float *p0 = P[0] + row, *p1 = P[1] + row, *p2 = P[2] + row, *p3 = P[3] + row, *p4 = P[4] + row,
          *p5 = P[5] + row;
#pragma GCC ivdep
    for (int i = 0; i < nu; ++i) {
      const double xx = d0[i], yy = d1[i], zz = d2[i], xy = d3[i], xz = d4[i], yz = d5[i];
      const double c00 = yy * zz - yz * yz, c10 = yz * xz - zz * xy, c20 = xy * yz - xz * yy;
      const double inverse_det = 1.0 / (c00 * xx + c10 * xy + c20 * xz);
      p0[i] = float(c00 * inverse_det);
      p1[i] = float((zz * xx - xz * xz) * inverse_det);
      p2[i] = float((xx * yy - xy * xy) * inverse_det);
      p3[i] = float(c10 * inverse_det);
      p4[i] = float(c20 * inverse_det);
      p5[i] = float((xz * xy - xx * yz) * inverse_det);
    }
  });
  for (const int a : w.fixed_particles)
    for (int k = 0; k < 6; ++k) P[k][a] = k < 3 ? 1.0f : 0.0f;
}

// The right-hand side b = M v + h f, the start x, and its residual b - A x.
// The start: the velocities the last substep's acceleration would give. A pull or a
// fall changes little from one substep to the next, so this starts CG
// nearer the answer than v does (a quarter fewer iterations on the pulls).
// A particle on the contact surface that the step's forces press into it
// is held on it: its new velocity keeps no normal part (Baraff & Witkin's
// constraint, their section 5.3: the start, r, z and A p are filtered).
// Free, the solve would carry it into the surface for the whole substep,
// and drag its lifted neighbours down with it through the springs, before
// collide stopped it: the peel front lagged, and the step control halved
// substeps for a motion the surface takes away. On the surface means where
// collide put it (within kOnSurface), not anywhere within the liquid
// bridge's h_th: held there, a cloth falling onto the ball stopped wherever
// it entered that band, up to 1 mm off, and covered half the area.
void set_up_solve(const Model& m, const State& s, Workspace& w, double h) {
  const Columns x = columns(m, w, kX), r = columns(m, w, kR), q = columns(m, w, kQ);
  const bool guess = !s.acceleration.empty();
  // Held with no normal velocity: not where a moving surface has one (collide
  // then carries the particle, docs/model.md section 3).
  const RigidPose* moving = pose_of(w.surfaces, m.contact_code());
  for_each_particle(m, [&](int a) {
    const Vec3& v = s.v[a];
    Vec3 b = v, start = v;  // fixed: b = x, no change
    if (!fixed(m, s, a)) {
      b = m.mass[a] * v + h * w.force[a];
      if (guess) start += h * s.acceleration[a];
    }
    const bool held =
        !fixed(m, s, a) && w.distance[a] <= kOnSurface && w.force[a].dot(w.surface_normal[a]) < 0 &&
        (!moving ||
         surface_velocity(w.surfaces, m.contact_code(), s.x[a]).dot(w.surface_normal[a]) == 0);
    held_flags(m, w)[a] = held ? 1.0f : 0.0f;
    for (int k = 0; k < 3; ++k) {
      r.c[k][a] = b[k];
      x.c[k][a] = start[k];
    }
  });
  filter(m, w, kX);
  multiply(m, s, w, kX, kQ);
  for_each_block(m, [&](int a0, int a1) {
    for (int k = 0; k < 3; ++k)
#pragma GCC ivdep
      for (int a = a0; a < a1; ++a) r.c[k][a] -= q.c[k][a];
  });
  filter(m, w, kR);
}

// Converged when no particle's velocity is off by more than the tolerance,
// taken as M⁻¹ r: the velocity error of a motion the springs do not resist
// (the cloth sliding or falling as a whole), and more than that of one they
// do. The preconditioned residual z = P r (P: the inverse diagonal blocks)
// is smaller by up to 1 + h² k / m (about 13 at 1/240 s): a hanging cloth
// or one on an incline stopped at the first iteration, and did not move.
// (A norm over the whole cloth would let the adhesion and weight of
// thousands of particles drown out the few the hand pulls.)
// Returns the iterations taken.
int conjugate_gradients(const Model& m, const State& s, Workspace& w) {
  const Columns x = columns(m, w, kX), r = columns(m, w, kR), z = columns(m, w, kZ),
                p = columns(m, w, kP), q = columns(m, w, kQ);
  auto [rz, worst] = precondition(m, w);
  for_each_block(m, [&](int a0, int a1) {
    for (int k = 0; k < 3; ++k) std::copy(z.c[k] + a0, z.c[k] + a1, p.c[k] + a0);
  });
  int it = 0;
  for (; it < m.params.integrator.cg_max_iterations; ++it) {
    if (worst <= m.params.integrator.cg_tolerance) break;
    multiply(m, s, w, kP, kQ);
    filter(m, w, kQ);
    const double pq = dot(m, w, kP, kQ);
    if (pq <= 0) break;
    const double alpha = rz / pq;
    for_each_block(m, [&](int a0, int a1) {
      for (int k = 0; k < 3; ++k)
#pragma GCC ivdep
        for (int a = a0; a < a1; ++a) {
          x.c[k][a] += alpha * p.c[k][a];
          r.c[k][a] -= alpha * q.c[k][a];
        }
    });
    const auto [rz_next, worst_next] = precondition(m, w);
    const double beta = rz_next / rz;
    rz = rz_next;
    worst = worst_next;
    for_each_block(m, [&](int a0, int a1) {
      for (int k = 0; k < 3; ++k)
#pragma GCC ivdep
        for (int a = a0; a < a1; ++a) p.c[k][a] = z.c[k][a] + beta * p.c[k][a];
    });
  }
  return it;
}

}  // namespace

void implicit_euler_velocities(const Model& m, State& s, Workspace& w, double h) {
  // The solver's arrays are sized at the first implicit step: the explicit
  // integrators need none of them. Every one is written before it is read.
  w.float_columns.resize(padded_size(m, float_columns(m)));  // the padding stays zero
  w.cg_columns.resize(padded_size(m, kSolverColumns));
  assemble_spring_blocks(m, s, w, h);
  assemble_diagonal_blocks(m, w, h);
  invert_diagonal_blocks(m, s, w);
  set_up_solve(m, s, w, h);
  const int it = conjugate_gradients(m, s, w);
  w.cg_iterations = it;
  w.cg_iterations_total += it;
  add_forces_at_new_velocities(m, s, w, h);
  const Columns x = columns(m, w, kX);
  const int nu = m.nu;
  parallel_for(m, m.nv, [&](int j) {
    for (int k = 0; k < 3; ++k) std::copy_n(x.c[k] + j * nu, nu, s.v.column(k) + j * nu);
  });
}

// Where a spring turns or stretches by a good part of its length within one
// step, its linearisation at the start of the step no longer holds: about a
// flat cloth, springs at rest have no stiffness across it, and a force on a
// few particles would move them at h F / m.
double step_strain(const Model& m, const State& s, double h) {
  if (!m.grid) {
    double worst = 0;
    for (const SpringSet* set : {&m.structural, &m.shear})
      for (std::size_t e = 0; e < set->size(); ++e)
        worst = std::max(worst, h * (s.v[set->b[e]] - s.v[set->a[e]]).norm() / set->rest[e]);
    return worst;
  }
  const double *const VX = s.v.column(0), *const VY = s.v.column(1), *const VZ = s.v.column(2);
  const int nu = m.nu;
  double worst = 0;
#pragma omp parallel for reduction(max : worst) num_threads(m.threads) if (m.threads > 1)
  for (int j = 0; j < m.nv; ++j)
    for (int e = 0; e < 4; ++e) {  // structural and shear
      const StencilEdge& st = m.topology->stencil[e];
      if (j + st.dj >= m.nv) continue;
      const int off = st.di + st.dj * nu, end = j * nu + std::min(nu, nu - st.di);
      // h |Δv| / rest grows with |Δv|², so its largest value is the one of the
      // largest |Δv|²: a maximum, which vectorises (in any order, the same).
      double most = 0;
#pragma omp simd reduction(max : most)
      for (int a = j * nu + std::max(0, -st.di); a < end; ++a) {
        const double dx = VX[a + off] - VX[a], dy = VY[a + off] - VY[a], dz = VZ[a + off] - VZ[a];
        most = std::max(most, dx * dx + dy * dy + dz * dz);
      }
      worst = std::max(worst, h * std::sqrt(most) / st.rest);
    }
  return worst;
}

}  // namespace wetcloth::detail
