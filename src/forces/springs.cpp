// Provot's springs, eq. 1: Hooke's law plus damping projected on the spring.
//
// The force. Each spring is evaluated once, as a forward edge of the grid's
// stencil (Topology::stencil): particle (i, j) to (i + di, j + dj). A row's edges
// go into rows of numbers (the force on the lower end), zero where the spring
// is off the grid, and each particle then gathers its springs from them in
// a fixed order: forward edge of an offset, then the backward one (minus the
// force stored at its other end). Rows are independent, so any number of
// threads gives the same bits, and both passes are loops over a row the
// compiler vectorises, reading the state's position and velocity columns
// (Vec3Array). Edge rows live in a ring of three per thread: a
// particle's backward springs start at most two rows back.
//
// The damping, in the symplectic step, is taken implicitly on its own
// (apply_spring_damping, below).
#include <span>

#include "forces/spring_edges.hpp"

namespace wetcloth::detail {

namespace {

constexpr int kReach = 2;          // the stencil's longest offset, in grid steps
constexpr int kRing = kReach + 1;  // edge rows a thread keeps
constexpr int kEdges = 8;          // forward offsets of the stencil

// Each particle of a row sums its springs: per live offset the forward edge
// (+F) and the backward one (-F), and sets its force, out[k][i], to the sum
// (the step's first force: +0 + the sum, the bits of a zeroed force and an add).
// kLive > 0: that many offsets, the loop over them unrolled; 0: `live`.
template <int kLive>
void gather_row(const double* const fwd[kEdges][kSpringFields],
                const double* const bwd[kEdges][kSpringFields], const int live, const int nu,
                double* const force[kSpringFields]) {
  const int count = kLive > 0 ? kLive : live;
  for (int k = 0; k < kSpringFields; ++k) {
    double* __restrict out = force[k];
#pragma GCC ivdep
    for (int i = 0; i < nu; ++i) {
      double total = 0;
#pragma GCC unroll 8
      for (int e = 0; e < count; ++e) total = total + fwd[e][k][i] - bwd[e][k][i];
      out[i] = 0.0 + total;
    }
  }
}

void gather_row(const double* const fwd[kEdges][kSpringFields],
                const double* const bwd[kEdges][kSpringFields], const int live, const int nu,
                double* const force[kSpringFields]) {
  switch (live) {  // a grid's springs without Provot's bending, and with them
    case 4:
      return gather_row<4>(fwd, bwd, live, nu, force);
    case 8:
      return gather_row<8>(fwd, bwd, live, nu, force);
    default:
      return gather_row<0>(fwd, bwd, live, nu, force);
  }
}

// Where the edge rows live in w.spring_rows: the zero row, which stands for
// edges above the first row, then each thread's ring of kRing edge rows.
struct EdgeRows {
  int stride;              // a field's row: nu and kReach either side
  std::size_t per_row;     // an edge row: every offset's fields
  std::size_t per_thread;  // a thread's ring
  explicit EdgeRows(const Model& m)
      : stride(m.nu + 2 * kReach),
        per_row(std::size_t(kEdges) * kSpringFields * stride),
        per_thread(kRing * per_row) {}
};

template <bool damped>
void set_spring_force_rows(const Model& m, const State& s, Workspace& w, int j0, int j1,
                           int thread) {
  const int nu = m.nu;
  const EdgeRows rows(m);
  const int stride = rows.stride;
  const std::size_t per_row = rows.per_row;
  double* const zero_row = w.spring_rows.data();
  const SpringColumns<double> c{s.x.column(0), s.x.column(1), s.x.column(2),
                                s.v.column(0), s.v.column(1), s.v.column(2)};
  // The offsets that hold springs, in order: with the quadratic bending,
  // Provot's bending offsets have none (k = 0, no damping), and their zero
  // forces, half the stencil, are neither computed nor summed (a sum's +0
  // changes no bit of a force).
  int live[kEdges], lives = 0;
  for (int e = 0; e < kEdges; ++e) {
    const StencilEdge& st = m.topology->stencil[e];
    if (st.k != 0 || (damped && st.damping != 0)) live[lives++] = e;
  }
  double* const ring = zero_row + kSpringFields * stride + rows.per_thread * thread;
  // Field k of offset e's edge row j, at its particle i = 0.
  const auto edges = [&](int j, int e, int k) {
    return ring + (j % kRing) * per_row + (std::size_t(e) * kSpringFields + k) * stride + kReach;
  };
  for (int slot = 0; slot < kRing; ++slot)
    for (int e = 0; e < kEdges; ++e) {
      const auto [lo, hi] = spring_edge_span(m, m.topology->stencil[e]);
      for (int k = 0; k < kSpringFields; ++k) {
        double* const row = edges(slot, e, k);
        std::fill(row - kReach, row + lo, 0.0);
        std::fill(row + hi, row + nu + kReach, 0.0);
      }
    }
  for (int j = std::max(0, j0 - kReach); j < j1; ++j) {
    for (const int e : std::span(live, lives)) {
      if (j + m.topology->stencil[e].dj >= m.nv) continue;  // gathered from the zero row instead
      double* out[kSpringFields];
      for (int k = 0; k < kSpringFields; ++k) out[k] = edges(j, e, k);
      spring_edge_row<double, damped>(m, c, m.topology->stencil[e], j, out);
    }
    if (j < j0) continue;
    // Row j's particles gather: per offset, the edge starting here (force
    // +F) and the one ending here, which starts at (i - di, j - dj) (-F).
    const double* fwd[kEdges][kSpringFields];
    const double* bwd[kEdges][kSpringFields];
    for (int q = 0; q < lives; ++q) {
      const int e = live[q];
      const StencilEdge& st = m.topology->stencil[e];
      for (int k = 0; k < kSpringFields; ++k) {
        fwd[q][k] = j + st.dj < m.nv ? edges(j, e, k) : zero_row + kReach;
        bwd[q][k] = (j >= st.dj ? edges(j - st.dj, e, k) : zero_row + kReach) - st.di;
      }
    }
    double* force[kSpringFields];
    for (int k = 0; k < kSpringFields; ++k) force[k] = w.force.column(k) + j * nu;
    gather_row(fwd, bwd, lives, nu, force);
  }
}

}  // namespace

void prepare_spring_rows(const Model& m, Workspace& w) {
  const EdgeRows rows(m);
  w.spring_rows.resize(kSpringFields * rows.stride + rows.per_thread * m.threads);
  std::fill(w.spring_rows.begin(), w.spring_rows.begin() + kSpringFields * rows.stride, 0.0);
}

void set_spring_force_rows(const Model& m, const State& s, Workspace& w, bool with_damping, int j0,
                           int j1, int thread) {
  if (with_damping)
    set_spring_force_rows<true>(m, s, w, j0, j1, thread);
  else
    set_spring_force_rows<false>(m, s, w, j0, j1, thread);
}

void set_spring_forces(const Model& m, const State& s, Workspace& w, bool with_damping) {
  if (!m.grid) {
    for_each_particle(m, [&](int i) { put(w.force[i], Vec3::Zero()); });
    add_spring_forces_mesh(m, s, w, with_damping);
    return;
  }
  prepare_spring_rows(m, w);
  for_each_row_block(m, [&](int j0, int j1, int thread) {
    set_spring_force_rows(m, s, w, with_damping, j0, j1, thread);
  });
}

// Eq. 1's damping over a step h, by backward Euler with additive operator
// splitting (AOS; Weickert, ter Haar Romeny & Viergever 1998). With K damped
// offsets, each offset solves its own springs' damping implicitly at K times
// its strength, all from the same velocities, and each particle takes the mean
// of the K changes. Why:
// - Its impulses act equal and opposite on a spring's two ends, so momentum is
//   conserved exactly: a cloth that accelerates as a whole feels no drag. (A
//   particle's own damping taken implicitly against its neighbours' explicit
//   velocities slows every acceleration by 1 / (1 + h Σk_d / m), about a half
//   at 51 × 51: a tilted dry cloth that should slide stayed put.)
// - Each solve is a backward Euler step, so the mean is stable at any h, even
//   where h k_d / m is large (light corner particles, fine grids).
// - A mirror or transposition of the grid only permutes the offsets, so a
//   symmetric cloth stays symmetric.
// An offset's springs form chains across the grid, (i, j), (i + di, j + dj),
// ..., so its solve is tridiagonal in the springs' impulses λ (on the lower
// end +λ u, on the upper −λ u), with u·u' coupling consecutive springs:
//   λ_k (1 + c (w_a + w_b)) − c w_a (u_{k-1}·u_k) λ_{k-1} − c w_b (u_k·u_{k+1}) λ_{k+1}
//     = c u_k·(v_b − v_a),    c = K h k_d, w = 1/m,
// solved by elimination along the chains, a row of the grid at a time (a
// vectorised loop). Horizontal offsets run on the transposed grid, where
// their chains are vertical too.
namespace {

// The solve runs in float, at twice the vector width and half the memory
// traffic of double; its impulses are summed in double. A spring's impulse λ u
// is the same float at both ends, so each pair still cancels exactly and
// momentum is conserved to double rounding.
using Real = float;
constexpr int kWhole = 16;  // slots of a vector (AVX-512: 16 floats); padding after each column

// A grid's particles by component (row-major over nu columns and nv rows).
struct DampingGrid {
  int nu = 0, nv = 0;
  const Real *px = nullptr, *py = nullptr, *pz = nullptr, *vx = nullptr, *vy = nullptr,
             *vz = nullptr, *inv_mass = nullptr;
  double *jx = nullptr, *jy = nullptr,
         *jz = nullptr;  // impulses: the first offset sets them, the others add
};

// Per spring slot of one offset (one per particle: the spring it starts).
// Where no spring starts, u, λ and the coupling are zero.
struct ChainScratch {
  Real *ux, *uy, *uz;
  Real *inv_diag, *rhs;  // after elimination
  Real* coupling;        // with the spring before in the chain
  Real* lambda;
};

// Forward elimination of offset (di, dj)'s chains on grid g, into t.
void eliminate_chains(const DampingGrid& g, int di, int dj, Real c, const ChainScratch& t) {
  const int nu = g.nu, nv = g.nv, n = nu * nv, off = di + dj * nu, springs_end = (nv - dj) * nu;
  const int lo = std::max(0, -di), hi = std::min(nu, nu - di);
  // Forward elimination, row by row: a spring's predecessor starts dj rows up
  // (at a - off; zero u where there is none). Each row runs in whole vectors
  // (kWhole slots): its last one runs on into the next rows, whose
  // predecessors are final or which that row computes again, and after the
  // last row into slots the fill below zeroes or the padding. A row of 51
  // had a scalar tail of 3 slots that cost as much as a vector.
  const int width = (nu + kWhole - 1) / kWhole * kWhole;
  for (int j = 0; j + dj < nv; ++j) {
    const int row = j * nu;
    const bool first = j < dj;
#pragma GCC ivdep
    for (int i = 0; i < width; ++i) {
      const int a = row + i, b = a + off;  // b: off the grid where no spring starts
      const bool on = i >= lo && i < hi;
      const Real dx = g.px[b] - g.px[a], dy = g.py[b] - g.py[a], dz = g.pz[b] - g.pz[a];
      const Real len = std::sqrt(dx * dx + dy * dy + dz * dz);
      const Real inv =
          on && len > 0 ? Real(1) / len : Real(0);  // a zero-length spring damps nothing
      const Real ux = dx * inv, uy = dy * inv, uz = dz * inv;
      Real diag = 1 + c * (g.inv_mass[a] + (on ? g.inv_mass[b] : Real(0)));
      Real rhs =
          c * (ux * (g.vx[b] - g.vx[a]) + uy * (g.vy[b] - g.vy[a]) + uz * (g.vz[b] - g.vz[a]));
      Real coupling = 0;
      if (!first) {
        const int p = a - off;
        coupling = -c * g.inv_mass[a] * (t.ux[p] * ux + t.uy[p] * uy + t.uz[p] * uz);
        const Real f = coupling * t.inv_diag[p];
        diag -= f * coupling;
        rhs -= f * t.rhs[p];
      }
      t.ux[a] = ux;
      t.uy[a] = uy;
      t.uz[a] = uz;
      t.coupling[a] = coupling;
      t.inv_diag[a] = Real(1) / diag;
      t.rhs[a] = on ? rhs : Real(0);
    }
  }
  // Rows where no spring starts, and the padding after them.
  for (Real* z : {t.ux, t.uy, t.uz, t.coupling, t.lambda})
    std::fill(z + springs_end, z + n + kWhole, Real(0));
}

// Back substitution of offset (di, dj)'s chains, from eliminate_chains' t,
// with take_impulses adding each particle's impulse (first_offset: setting).
void substitute_chains(const DampingGrid& g, int di, int dj, const ChainScratch& t,
                       bool take_impulses, bool first_offset) {
  const int nu = g.nu, nv = g.nv, off = di + dj * nu;
  // Back substitution, λ = (rhs - coupling to the next spring · its λ) / diag,
  // from the last row up; once row j's λ is known, row j + dj's particles
  // take +λ u of the spring each starts and −λ u of the one each ends.
  const auto take = [&](int r, auto ends, auto set) {
    const Real* __restrict lambda = t.lambda;
    const Real* __restrict ux = t.ux;
    const Real* __restrict uy = t.uy;
    const Real* __restrict uz = t.uz;
    double* __restrict jx = g.jx;
    double* __restrict jy = g.jy;
    double* __restrict jz = g.jz;
#pragma GCC ivdep
    for (int a = r * nu; a < (r + 1) * nu; ++a) {
      double x = lambda[a] * ux[a], y = lambda[a] * uy[a], z = lambda[a] * uz[a];
      if constexpr (ends) {
        const int p = a - off;
        x -= lambda[p] * ux[p];
        y -= lambda[p] * uy[p];
        z -= lambda[p] * uz[p];
      }
      if constexpr (set) {
        jx[a] = x;
        jy[a] = y;
        jz[a] = z;
      } else {
        jx[a] += x;
        jy[a] += y;
        jz[a] += z;
      }
    }
  };
  const auto take_row = [&](int r, auto ends) {
    if (first_offset)
      take(r, ends, std::true_type{});
    else
      take(r, ends, std::false_type{});
  };
  for (int j = nv - 1 - dj; j >= 0; --j) {
    const int row = j * nu;
#pragma GCC ivdep
    for (int i = 0; i < nu; ++i) {
      const int a = row + i;
      t.lambda[a] = (t.rhs[a] - t.coupling[a + off] * t.lambda[a + off]) * t.inv_diag[a];
    }
    if (take_impulses) take_row(j + dj, std::true_type{});
  }
  if (take_impulses)
    for (int r = 0; r < std::min(dj, nv); ++r) take_row(r, std::false_type{});
}

// One offset (di, dj), dj > 0, of grid g: solves its chains for λ (in
// t.lambda) and, with take_impulses, adds each particle's impulse (the first
// offset into a j sets it). Every loop runs over whole rows (a spring slot
// off the grid computes zeros), so that it vectorises.
void damp_offset(const DampingGrid& g, int di, int dj, Real c, const ChainScratch& t,
                 bool take_impulses, bool first_offset) {
  eliminate_chains(g, di, dj, c, t);
  substitute_chains(g, di, dj, t, take_impulses, first_offset);
}

// A horizontal offset (di, 0)'s coefficients, before elimination, on grid g
// in its own layout: each spring's direction into u, its diagonal 1 + c (w_a
// + w_b), right-hand side c u·(v_b − v_a) and coupling −c w_a (u'·u) with the
// spring before it in its row. The same floats eliminate_chains computes on
// the transposed grid (its chains vertical there), for a row's springs
// [0, nu − di); its last di slots hold no spring (zero u, right-hand side and
// coupling).
void horizontal_coefficients(const DampingGrid& g, int di, Real c, Real* const u[3], Real* diag0,
                             Real* rhs0, Real* coupling0) {
  const int nu = g.nu;
  for (int j = 0; j < g.nv; ++j) {
    const int row = j * nu;
#pragma GCC ivdep
    for (int i = 0; i < nu - di; ++i) {
      const int a = row + i, b = a + di;
      const Real dx = g.px[b] - g.px[a], dy = g.py[b] - g.py[a], dz = g.pz[b] - g.pz[a];
      const Real len = std::sqrt(dx * dx + dy * dy + dz * dz);
      const Real inv = len > 0 ? Real(1) / len : Real(0);  // a zero-length spring damps nothing
      const Real ux = dx * inv, uy = dy * inv, uz = dz * inv;
      u[0][a] = ux;
      u[1][a] = uy;
      u[2][a] = uz;
      diag0[a] = 1 + c * (g.inv_mass[a] + g.inv_mass[b]);
      rhs0[a] =
          c * (ux * (g.vx[b] - g.vx[a]) + uy * (g.vy[b] - g.vy[a]) + uz * (g.vz[b] - g.vz[a]));
    }
    for (int i = nu - di; i < nu; ++i) {
      for (int k = 0; k < 3; ++k) u[k][row + i] = 0;
      diag0[row + i] = 1;
      rhs0[row + i] = 0;
    }
    // The first di springs of a row start a chain: no spring before them.
    for (int i = 0; i < std::min(di, nu); ++i) coupling0[row + i] = 0;
#pragma GCC ivdep
    for (int i = di; i < nu; ++i) {
      const int a = row + i, p = a - di;
      coupling0[a] =
          -c * g.inv_mass[a] * (u[0][p] * u[0][a] + u[1][p] * u[1][a] + u[2][p] * u[2][a]);
    }
  }
}

// Forward elimination of vertical chains (offset (0, dj)) on a grid of nu
// columns and nv rows from their coefficients (horizontal_coefficients,
// transposed), into t; as eliminate_chains, whose arithmetic it repeats.
void eliminate_coefficients(int nu, int nv, int dj, const Real* diag0, const Real* rhs0,
                            const Real* coupling0, const ChainScratch& t) {
  const int n = nu * nv, off = dj * nu, springs_end = (nv - dj) * nu;
  const int width = (nu + kWhole - 1) / kWhole * kWhole;
  for (int j = 0; j + dj < nv; ++j) {
    const int row = j * nu;
    const bool first = j < dj;
#pragma GCC ivdep
    for (int i = 0; i < width; ++i) {
      const int a = row + i;
      Real diag = diag0[a], rhs = rhs0[a];
      const Real coupling = first ? Real(0) : coupling0[a];
      if (!first) {
        const int p = a - off;
        const Real f = coupling * t.inv_diag[p];
        diag -= f * coupling;
        rhs -= f * t.rhs[p];
      }
      t.coupling[a] = coupling;
      t.inv_diag[a] = Real(1) / diag;
      t.rhs[a] = rhs;
    }
  }
  for (Real* z : {t.coupling, t.lambda}) std::fill(z + springs_end, z + n + kWhole, Real(0));
}

// Eigen's packet types carry alignment attributes that a template argument
// drops; Eigen silences the same warning inside itself.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
// out[i rows + j] = in[j cols + i] for each of `count` arrays, the k-th at
// in + k stride and out + k stride: by blocks of a vector's width square,
// each transposed in registers (Eigen's packet transpose); the rows and
// columns left over one by one. All the arrays in one region (one a column
// had cost a region each, 7 a step, and left the threads' shares uneven).
// `alone`: on this thread (called inside a parallel region, a region of its
// own would be a nested one of one thread, at the cost of a region).
void transpose(const Model& m, const Real* __restrict first_in, Real* __restrict first_out,
               int rows, int cols, int count = 1, std::size_t stride = 0, bool alone = false) {
  namespace ei = Eigen::internal;
  // Half a vector: 8 floats with AVX-512, where 16 left a 51-wide grid a
  // fifth in the scalar edges.
  using Packet = ei::unpacket_traits<ei::packet_traits<Real>::type>::half;
  constexpr int kWidth = ei::unpacket_traits<Packet>::size;
  const int strips = rows / kWidth;
  const auto block = [&](int item) {
    const int strip = item % (strips + 1);
    const Real* __restrict const in = first_in + (item / (strips + 1)) * stride;
    Real* __restrict const out = first_out + (item / (strips + 1)) * stride;
    const int j0 = strip * kWidth;
    if (strip == strips) {  // the rows left over
      for (int i = 0; i < cols; ++i)
        for (int j = j0; j < rows; ++j) out[i * rows + j] = in[j * cols + i];
      return;
    }
    int i0 = 0;
    for (; i0 + kWidth <= cols; i0 += kWidth) {
      ei::PacketBlock<Packet, kWidth> block;
      for (int r = 0; r < kWidth; ++r)
        block.packet[r] = ei::ploadu<Packet>(in + (j0 + r) * cols + i0);
      ei::ptranspose(block);
      for (int r = 0; r < kWidth; ++r) ei::pstoreu(out + (i0 + r) * rows + j0, block.packet[r]);
    }
    for (int i = i0; i < cols; ++i)
      for (int j = j0; j < j0 + kWidth; ++j) out[i * rows + j] = in[j * cols + i];
  };
  if (alone)
    for (int item = 0; item < count * (strips + 1); ++item) block(item);
  else
    parallel_for(m, count * (strips + 1), block);
}
#pragma GCC diagnostic pop

}  // namespace

namespace {

// The offsets in two fixed groups, each adding its offsets in stencil order
// into its own impulses: the groups may run on two threads, and the sums are
// the same for any number of threads. With damped bending springs
// (Provot's), structural and shear, then bending; without them (the
// quadratic bending), structural, then shear, so that two threads still
// share the solve (one group had run on one thread: 11 % of the dry pull's
// step, serial). A group's horizontal offset, if it has one, is solved on the
// transposed grid; its λ u come back to the grid and its impulses are taken
// there, at the end.
constexpr int kGroups = 2;
using GroupBounds = std::array<int, kGroups + 1>;  // group g: offsets [bound[g], bound[g + 1])
GroupBounds group_bounds(const Model& m) {
  for (int e = kEdges / 2; e < kEdges; ++e)
    if (m.topology->stencil[e].damping > 0) return {0, kEdges / 2, kEdges};
  return {0, kEdges / 4, kEdges / 2};
}

// apply_spring_damping's columns in w.damping_columns, in float: the grid
// (x y z, v, 1/m); each thread's chain scratch and a horizontal offset's
// coefficients; per group the horizontal offset's λ u (x y z) on the grid.
// Each has kPad zeros before and after it, for the slots two springs beyond
// the grid's ends and those the last row's last vector runs into
// (damp_offset). In double, in w.damping_impulses: each group's impulses from
// its offsets along the columns of the grid. A group with no damped offset
// (the bending's, with the quadratic bending) has none of its own: its
// impulses would all be zero, and adding them changes no sum
// (apply_spring_damping).
struct DampingColumns {
  static constexpr int kPad = kWhole, kGrid = 7, kScratch = 7, kCoefficients = 3, kBack = 3;
  static constexpr int kPerThread = kScratch + kCoefficients;
  int n, threads;
  std::size_t stride;
  Workspace& w;
  std::array<int, kGroups> slot{};  // each damped group's place among them (-1: none)
  DampingColumns(const Model& m, Workspace& ws, const std::array<bool, kGroups>& live)
      : n(m.n), stride(std::size_t(m.n) + 2 * kPad), w(ws) {
    int groups = 0;
    for (int g = 0; g < kGroups; ++g) slot[g] = live[g] ? groups++ : -1;
    threads = std::min(m.threads, groups);
    w.damping_columns.resize((kGrid + kPerThread * threads + kBack * groups) * stride);
    w.damping_impulses.resize(3 * groups * std::size_t(n));
  }
  Real* col(int k) const { return w.damping_columns.data() + k * stride + kPad; }
  Real* scratch(int thread) const { return col(kGrid + kPerThread * thread); }
  Real* coefficients(int thread) const { return scratch(thread) + kScratch * stride; }
  Real* back(int group, int k) const {  // λ u_k
    return col(kGrid + kPerThread * threads + kBack * slot[group] + k);
  }
  double* impulse(int group, int k) const {
    return w.damping_impulses.data() + (3 * slot[group] + k) * std::size_t(n);
  }
};

// The grid's positions, velocities and inverse masses in float; each chunk of
// particles first through `before`.
void load_damping_columns(const Model& m, const State& s, const DampingColumns& d,
                          const ParticleChunks& before) {
  for_each_particle_chunk(m, [&](int first, int end) {
    if (before) before(first, end);
    for (int k = 0; k < 3; ++k) {
      const double* __restrict x = s.x.column(k);
      const double* __restrict v = s.v.column(k);
      Real* __restrict to_x = d.col(k);
      Real* __restrict to_v = d.col(3 + k);
      for (int a = first; a < end; ++a) {
        to_x[a] = Real(x[a]);
        to_v[a] = Real(v[a]);
      }
    }
    const double* __restrict inv_mass = m.inv_mass.data();
    Real* __restrict to_w = d.col(6);
    for (int a = first; a < end; ++a) to_w[a] = Real(inv_mass[a]);
  });
}

// Each group's offsets solved (damp_offset), on up to two threads: per group,
// first whether nothing is in its impulses yet, solved whether its horizontal
// λ u are.
void solve_damping_groups(const Model& m, double h, int damped, const DampingColumns& d,
                          const GroupBounds& bound, bool (&first)[kGroups],
                          bool (&solved)[kGroups]) {
  const int n = m.n, nu = m.nu, nv = m.nv;
  const std::size_t stride = d.stride;
  const auto solve_group = [&](int group, int thread) {
    Real* const t = d.scratch(thread);
    const ChainScratch scratch{t,
                               t + stride,
                               t + 2 * stride,
                               t + 3 * stride,
                               t + 4 * stride,
                               t + 5 * stride,
                               t + 6 * stride};
    const Real* const g = d.col(0);
    double* const j = d.impulse(group, 0);
    const DampingGrid grid{nu,
                           nv,
                           g,
                           g + stride,
                           g + 2 * stride,
                           g + 3 * stride,
                           g + 4 * stride,
                           g + 5 * stride,
                           g + 6 * stride,
                           j,
                           j + n,
                           j + 2 * n};
    for (int e = bound[group]; e < bound[group + 1]; ++e) {
      const StencilEdge& st = m.topology->stencil[e];
      if (st.damping == 0) continue;
      const Real c = Real(damped * h * st.damping);
      if (st.dj != 0) {
        damp_offset(grid, st.di, st.dj, c, scratch, true, first[group]);
        first[group] = false;
        continue;
      }
      // A horizontal offset's chains run along the rows: its coefficients
      // are found on the grid, and its chains solved on their transpose,
      // where they are vertical. Its λ come back, and its λ u are taken
      // on the grid, at the end.
      Real* const u[3] = {d.back(group, 0), d.back(group, 1), d.back(group, 2)};
      Real* const coefficients = d.coefficients(thread);
      horizontal_coefficients(grid, st.di, c, u, coefficients, coefficients + stride,
                              coefficients + 2 * stride);
      // Into the scratch's first three columns (its u, not needed here).
      transpose(m, coefficients, scratch.ux, nv, nu, 3, stride, d.threads > 1);
      eliminate_coefficients(nv, nu, st.di, scratch.ux, scratch.uy, scratch.uz, scratch);
      const DampingGrid transposed{nv, nu};
      substitute_chains(transposed, 0, st.di, scratch, false, false);
      Real* const lambda = coefficients;
      transpose(m, scratch.lambda, lambda, nu, nv, 1, stride, d.threads > 1);
      for (int k = 0; k < 3; ++k) {
        Real* __restrict lu = u[k];
        const Real* __restrict l = lambda;
        for (int a = 0; a < n; ++a) lu[a] = l[a] * lu[a];
      }
      solved[group] = true;
    }
  };
  // On one thread no region: even one its `if` turns off costs a futex call.
  if (d.threads <= 1) {
    for (int group = 0; group < kGroups; ++group)
      if (d.slot[group] >= 0) solve_group(group, 0);
  } else {
#pragma omp parallel for schedule(static) num_threads(d.threads)
    for (int group = 0; group < kGroups; ++group) solve_group(group, omp_get_thread_num());
  }
  for (int group = 0; group < kGroups; ++group) {
    if (d.slot[group] < 0) continue;
    if (first[group])
      for (int k = 0; k < 3; ++k) std::fill_n(d.impulse(group, k), n, 0.0);
    // The zeros before the first row (see below); a group with no horizontal
    // offset has no λ u to add (apply_spring_damping skips them).
    if (solved[group])
      for (int k = 0; k < 3; ++k)
        std::fill(d.back(group, k) - DampingColumns::kPad, d.back(group, k), Real(0));
  }
}

}  // namespace

void apply_spring_damping(const Model& m, State& s, Workspace& w, double h,
                          const ParticleChunks& before, const ParticleChunks& after) {
  int damped = 0;
  if (m.grid)
    for (const StencilEdge& st : m.topology->stencil) damped += st.damping > 0;
  if (damped == 0) {  // a mesh cloth, or no damped springs: the hooks in passes of their own
    if (before) for_each_particle_chunk(m, before);
    if (!m.grid) apply_spring_damping_mesh(m, s, h);
    if (after) for_each_particle_chunk(m, after);
    return;
  }
  std::array<int, kGroups> horizontal{};  // each group's horizontal offset, di
  std::array<bool, kGroups> live{};       // each group: some offset of it damped
  const GroupBounds bound = group_bounds(m);
  for (int group = 0; group < kGroups; ++group)
    for (int e = bound[group]; e < bound[group + 1]; ++e) {
      if (m.topology->stencil[e].dj == 0) horizontal[group] = m.topology->stencil[e].di;
      live[group] = live[group] || m.topology->stencil[e].damping > 0;
    }
  const DampingColumns d(m, w, live);
  load_damping_columns(m, s, d, before);
  bool first[kGroups] = {true, true};     // per group: nothing in its impulses yet
  bool solved[kGroups] = {false, false};  // per group: its horizontal λ solved
  solve_damping_groups(m, h, damped, d, bound, first, solved);
  // v += the mean change, by component in the groups' order: per group its
  // offsets along the columns, then its horizontal one, whose spring starting
  // at a particle gives it +λ u and the one ending there −λ u. (Before the
  // di first particles of a row, where no spring ends, are the zeros of the
  // row before it, where none starts: x − 0 is x.) A group without damped
  // offsets would add +0 to a sum that is not −0 (0 + x never is): left out.
  static_assert(kGroups == 2);
  const double share = 1.0 / damped;
  const int di0 = horizontal[0], di1 = horizontal[1];
  // A group with no horizontal offset (the shear's) has no λ u: its term
  // would be J + (0 - 0), which adds to the sum what J does (the sum is
  // never −0), so its zeroed columns are neither written nor read.
  // Each group's part, a template argument: 0 none, 1 its impulses, 2 its
  // impulses and its horizontal λ u. (Chosen in the loop, the λ u's loads
  // were masked gathers: 7 % of the step at 201 x 201.)
  const auto add_groups = [&]<int kPart0, int kPart1>() {
    for_each_particle_chunk(m, [&](int first, int end) {
      for (int k = 0; k < 3; ++k) {
        const double* __restrict jv0 = kPart0 > 0 ? d.impulse(0, k) : nullptr;
        const double* __restrict jv1 = kPart1 > 0 ? d.impulse(1, k) : nullptr;
        const Real* __restrict lu0 = kPart0 == 2 ? d.back(0, k) : nullptr;
        const Real* __restrict lu1 = kPart1 == 2 ? d.back(1, k) : nullptr;
        const double* __restrict inv_mass = m.inv_mass.data();
        double* __restrict out = s.v.column(k);
#pragma GCC ivdep
        for (int a = first; a < end; ++a) {
          double sum = 0;
          if constexpr (kPart0 == 2)
            sum += jv0[a] + (double(lu0[a]) - double(lu0[a - di0]));
          else if constexpr (kPart0 == 1)
            sum += jv0[a];
          if constexpr (kPart1 == 2)
            sum += jv1[a] + (double(lu1[a]) - double(lu1[a - di1]));
          else if constexpr (kPart1 == 1)
            sum += jv1[a];
          out[a] += share * inv_mass[a] * sum;
        }
      }
      if (after) after(first, end);
    });
  };
  const auto second = [&]<int kPart0>(int part1) {
    if (part1 == 2)
      add_groups.template operator()<kPart0, 2>();
    else if (part1 == 1)
      add_groups.template operator()<kPart0, 1>();
    else
      add_groups.template operator()<kPart0, 0>();
  };
  const int part0 = live[0] ? 1 + solved[0] : 0, part1 = live[1] ? 1 + solved[1] : 0;
  if (part0 == 2)
    second.template operator()<2>(part1);
  else if (part0 == 1)
    second.template operator()<1>(part1);
  else
    second.template operator()<0>(part1);  // part1 > 0: some group is damped
}

}  // namespace wetcloth::detail
