// Provot's springs, eq. 1: Hooke's law plus damping projected on the spring.
//
// Gathered per particle over the grid's stencil (Model::stencil, both
// directions): each particle sums its own 16 springs in a fixed order, so rows
// are independent, run on any number of threads and give the same bits on each.
// Positions and velocities are first copied to columns (x, y, z, vx, vy, vz)
// so that a row's particles away from the border, which have all 16 springs,
// are summed by one loop the compiler vectorises; particles near the border
// take the same formula one at a time, skipping the springs off the grid.
#include <omp.h>

#include "../detail.hpp"

namespace wetcloth::detail {

namespace {

// Σ over a particle's springs of its force and of its damping on its own
// velocity, Σ k_d u uᵀ (xx yy zz xy xz yz).
struct Sum {
  double fx = 0, fy = 0, fz = 0, cxx = 0, cyy = 0, czz = 0, cxy = 0, cxz = 0, cyz = 0;
};

// Adds the spring with d = x_b - x_a, dv = v_b - v_a:
// F_a = u (k_s (|d| - l0) + k_d dv·u).
inline void add_spring(Sum& s, double dx, double dy, double dz, double dvx, double dvy, double dvz,
                       double k, double rest, double kd) {
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  const double inv = len > 0 ? 1.0 / len : 0.0;  // a zero-length spring pulls nowhere
  const double ux = dx * inv, uy = dy * inv, uz = dz * inv;
  const double t = k * (len - rest) + kd * (dvx * ux + dvy * uy + dvz * uz);
  s.fx += t * ux;
  s.fy += t * uy;
  s.fz += t * uz;
  const double kx = kd * ux, ky = kd * uy;
  s.cxx += kx * ux;
  s.cyy += ky * uy;
  s.czz += kd * uz * uz;
  s.cxy += kx * uy;
  s.cxz += kx * uz;
  s.cyz += ky * uz;
}

// The 16 springs of a particle, in summation order: per stencil offset the
// forward spring, then the backward one.
struct Springs {
  int di[16], dj[16], off[16];
  double k[16], rest[16], kd[16];
};

Springs springs_of(const Model& m, bool with_damping) {
  Springs s{};
  for (int e = 0; e < 8; ++e)
    for (int side = 0; side < 2; ++side) {
      const StencilEdge& st = m.stencil[e];
      const int q = 2 * e + side, sign = side == 0 ? 1 : -1;
      s.di[q] = sign * st.di;
      s.dj[q] = sign * st.dj;
      s.off[q] = s.di[q] + s.dj[q] * m.nu;
      s.k[q] = st.k;
      s.rest[q] = st.rest;
      s.kd[q] = with_damping ? st.damping : 0.0;
    }
  return s;
}

// Columns x, y, z, vx, vy, vz in; the nine sums of Sum out, for one row
// (particle i at out[k][i - row]).
struct Columns {
  const double *px, *py, *pz, *vx, *vy, *vz;
  double* out[9];
  int row = 0;
};

inline void store(const Columns& c, int i, const Sum& s) {
  const int r = i - c.row;
  c.out[0][r] = s.fx;
  c.out[1][r] = s.fy;
  c.out[2][r] = s.fz;
  c.out[3][r] = s.cxx;
  c.out[4][r] = s.cyy;
  c.out[5][r] = s.czz;
  c.out[6][r] = s.cxy;
  c.out[7][r] = s.cxz;
  c.out[8][r] = s.cyz;
}

// Particles [lo, hi) of a row, all of whose springs are on the grid. The
// columns never overlap where the loop reads and writes; `ivdep` tells GCC so,
// which it cannot prove itself.
void sum_interior(const Columns& c, const Springs& sp, int lo, int hi) {
#pragma GCC ivdep
  for (int i = lo; i < hi; ++i) {
    Sum s;
#pragma GCC unroll 16
    for (int q = 0; q < 16; ++q) {
      const int b = i + sp.off[q];
      add_spring(s, c.px[b] - c.px[i], c.py[b] - c.py[i], c.pz[b] - c.pz[i], c.vx[b] - c.vx[i],
                 c.vy[b] - c.vy[i], c.vz[b] - c.vz[i], sp.k[q], sp.rest[q], sp.kd[q]);
    }
    store(c, i, s);
  }
}

// Particle (i, j) near the border: the same sum without the springs off the grid.
void sum_border(const Model& m, const Columns& c, const Springs& sp, int i, int j) {
  const int a = m.index(i, j);
  Sum s;
  for (int q = 0; q < 16; ++q) {
    if (grid_neighbour(m, i, j, sp.di[q], sp.dj[q]) < 0) continue;
    const int b = a + sp.off[q];
    add_spring(s, c.px[b] - c.px[a], c.py[b] - c.py[a], c.pz[b] - c.pz[a], c.vx[b] - c.vx[a],
               c.vy[b] - c.vy[a], c.vz[b] - c.vz[a], sp.k[q], sp.rest[q], sp.kd[q]);
  }
  store(c, a, s);
}

}  // namespace

void add_spring_forces(const Model& m, const State& s, Workspace& w, bool with_damping) {
  const int n = m.n, nu = m.nu;
  // The columns, then per thread one row of sums.
  w.soa.resize(6 * std::size_t(n) + 9 * std::size_t(nu) * m.threads);
  double* const X = w.soa.data();
  const Springs sp = springs_of(m, with_damping);
  constexpr int reach = 2;  // the stencil's longest offset, in grid steps

  parallel_for(m, m.nv, [&](int j) {
    for (int a = j * nu; a < (j + 1) * nu; ++a)
      for (int k = 0; k < 3; ++k) {
        X[k * n + a] = s.x[a][k];
        X[(k + 3) * n + a] = s.v[a][k];
      }
  });
  parallel_for(m, m.nv, [&](int j) {
    Columns c{X, X + n, X + 2 * n, X + 3 * n, X + 4 * n, X + 5 * n, {}, j * nu};
    double* const sums = X + 6 * std::size_t(n) + 9 * std::size_t(nu) * omp_get_thread_num();
    for (int k = 0; k < 9; ++k) c.out[k] = sums + k * nu;
    const bool inner_row = j >= reach && j < m.nv - reach && nu > 2 * reach;
    const int lo = inner_row ? reach : nu, hi = inner_row ? nu - reach : nu;
    for (int i = 0; i < std::min(lo, nu); ++i) sum_border(m, c, sp, i, j);
    if (inner_row) sum_interior(c, sp, j * nu + lo, j * nu + hi);
    for (int i = hi; i < nu; ++i) sum_border(m, c, sp, i, j);
    const auto& o = c.out;
    for (int i = 0; i < nu; ++i) {
      w.force[j * nu + i] += Vec3(o[0][i], o[1][i], o[2][i]);
      if (with_damping)
        w.damping[j * nu + i] = {o[3][i], o[4][i], o[5][i], o[6][i], o[7][i], o[8][i]};
    }
  });
}

}  // namespace wetcloth::detail
