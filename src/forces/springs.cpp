// Provot's springs, eq. 1: Hooke's law plus damping projected on the spring.
//
// Each spring is evaluated once, as a forward edge of the grid's stencil
// (Model::stencil): particle (i, j) to (i + di, j + dj). A row's edges go into
// rows of numbers (force on the lower end; k_d u uᵀ), zero where the spring is
// off the grid, and each particle then gathers its 16 springs from them in a
// fixed order: forward edge of an offset, then the backward one (minus the
// force stored at its other end). Rows are independent, so any number of
// threads gives the same bits, and both passes are loops over a row the
// compiler vectorises. Positions and velocities are first copied to columns
// (x, y, z, vx, vy, vz). Edge rows live in a ring of three per thread: a
// particle's backward springs start at most two rows back.
#include <functional>

#include "spring_edges.hpp"

namespace wetcloth::detail {

namespace {

constexpr int kReach = 2;          // the stencil's longest offset, in grid steps
constexpr int kRing = kReach + 1;  // edge rows a thread keeps
constexpr int kEdges = 8;          // forward offsets of the stencil

// Each particle of a row sums its springs: per offset the forward edge (+F)
// and the backward one (-F, the same k_d u uᵀ), into sums[k][i].
template <bool damped>
void gather_row(const double* const fwd[kEdges][kSpringFields],
                const double* const bwd[kEdges][kSpringFields], const int nu,
                double* const sums[kSpringFields]) {
  const auto sum = [&](int k, auto sign) {
    double* __restrict out = sums[k];
#pragma GCC ivdep
    for (int i = 0; i < nu; ++i) {
      double total = 0;
#pragma GCC unroll 8
      for (int e = 0; e < kEdges; ++e) total = sign(total + fwd[e][k][i], bwd[e][k][i]);
      out[i] = total;
    }
  };
  for (int k = 0; k < 3; ++k) sum(k, std::minus<>());
  if constexpr (damped)
    for (int k = 3; k < kSpringFields; ++k) sum(k, std::plus<>());
}

template <bool damped>
void add_spring_forces(const Model& m, const State& s, Workspace& w) {
  const int n = m.n, nu = m.nu, stride = nu + 2 * kReach;
  const std::size_t per_row = std::size_t(kEdges) * kSpringFields * stride;
  const std::size_t per_thread = kRing * per_row + kSpringFields * stride;  // edge rows, then sums
  w.soa.resize(6 * std::size_t(n) + kSpringFields * stride + per_thread * m.threads);
  double* const X = w.soa.data();
  double* const zero_row = X + 6 * std::size_t(n);  // stands for edges above the first row
  std::fill(zero_row, zero_row + kSpringFields * stride, 0.0);
  const SpringColumns<double> c{X, X + n, X + 2 * n, X + 3 * n, X + 4 * n, X + 5 * n};
  constexpr int fields = damped ? kSpringFields : 3;

  to_columns(m, s.x, X);
  to_columns(m, s.v, X + 3 * std::size_t(n));
  for_each_row_block(m, [&](int j0, int j1, int thread) {
    double* const ring = X + 6 * std::size_t(n) + kSpringFields * stride + per_thread * thread;
    double* sums[kSpringFields];
    for (int k = 0; k < kSpringFields; ++k) sums[k] = ring + kRing * per_row + k * stride;
    // Field k of offset e's edge row j, at its particle i = 0.
    const auto edges = [&](int j, int e, int k) {
      return ring + (j % kRing) * per_row + (std::size_t(e) * kSpringFields + k) * stride + kReach;
    };
    for (int slot = 0; slot < kRing; ++slot)
      for (int e = 0; e < kEdges; ++e) {
        const auto [lo, hi] = spring_edge_span(m, m.stencil[e]);
        for (int k = 0; k < fields; ++k) {
          double* const row = edges(slot, e, k);
          std::fill(row - kReach, row + lo, 0.0);
          std::fill(row + hi, row + nu + kReach, 0.0);
        }
      }
    for (int j = std::max(0, j0 - kReach); j < j1; ++j) {
      for (int e = 0; e < kEdges; ++e) {
        if (j + m.stencil[e].dj >= m.nv) continue;  // gathered from the zero row instead
        double* out[kSpringFields];
        for (int k = 0; k < kSpringFields; ++k) out[k] = edges(j, e, k);
        spring_edge_row<double, damped>(m, c, m.stencil[e], j, out);
      }
      if (j < j0) continue;
      // Row j's particles gather: per offset, the edge starting here (force
      // +F) and the one ending here, which starts at (i - di, j - dj) (-F).
      const double* fwd[kEdges][kSpringFields];
      const double* bwd[kEdges][kSpringFields];
      for (int e = 0; e < kEdges; ++e) {
        const StencilEdge& st = m.stencil[e];
        for (int k = 0; k < fields; ++k) {
          fwd[e][k] = j + st.dj < m.nv ? edges(j, e, k) : zero_row + kReach;
          bwd[e][k] = (j >= st.dj ? edges(j - st.dj, e, k) : zero_row + kReach) - st.di;
        }
      }
      gather_row<damped>(fwd, bwd, nu, sums);
      for (int i = 0; i < nu; ++i) {
        const int a = j * nu + i;
        w.force[a] += Vec3(sums[0][i], sums[1][i], sums[2][i]);
        if constexpr (damped)
          w.damping[a] = {sums[3][i], sums[4][i], sums[5][i], sums[6][i], sums[7][i], sums[8][i]};
      }
    }
  });
}

}  // namespace

void add_spring_forces(const Model& m, const State& s, Workspace& w, bool with_damping) {
  if (with_damping)
    add_spring_forces<true>(m, s, w);
  else
    add_spring_forces<false>(m, s, w);
}

}  // namespace wetcloth::detail
