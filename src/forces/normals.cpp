// Particle normals, area-weighted over the adjacent triangles: the direction
// the wind (eq. 3's neighbour) and the trapped air push along.
#include <algorithm>
#include <cmath>

#include "detail.hpp"

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
// rest). They run kChunkRows particle rows at a time, each thread holding
// the quads of those rows and of the row before (found again by the next
// chunk, the same numbers): the quads of the whole cloth would be 48 B a
// particle.
namespace {
constexpr int kChunkRows = 32;
// A thread's column: the slot before its chunk's first quad row, then the rows.
std::size_t quad_column(const Model& m) { return std::size_t(kChunkRows + 1) * m.nu + 1; }
}  // namespace

void detail::prepare_normals(const Model& m, NormalsScratch& scratch) {
  const int nu = m.nu, nv = m.nv, n = m.n;
  scratch.quad_normals.resize(6 * quad_column(m) * std::size_t(std::max(1, m.threads)));
  if (scratch.chequer_nu != nu || scratch.chequer.size() != std::size_t(n)) {
    scratch.chequer.resize(n);
    scratch.chequer_nu = nu;
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) scratch.chequer[m.index(i, j)] = (i + j) % 2 == 0 ? 1.0 : 0.0;
  }
}

void detail::compute_normal_rows(const Model& m, const double* X, Vec3Array& normal,
                                 NormalsScratch& scratch, int j0, int j1, int thread) {
  const int nu = m.nu, nv = m.nv, n = m.n;
  const std::size_t column = quad_column(m);
  const double *x = X, *y = X + n, *z = X + 2 * std::size_t(n);
  const double* even_at = scratch.chequer.data();
  double* const own = scratch.quad_normals.data() + 6 * column * thread;
  for (int r0 = j0; r0 < j1; r0 += kChunkRows) {
    const int r1 = std::min(j1, r0 + kChunkRows);
    // Quad rows r0 - 1 .. r1 - 1, the cloth's slot a at t[f][a].
    const long long first = (r0 - 1) * static_cast<long long>(nu) - 1;
    double* t[6];
    for (int f = 0; f < 6; ++f) t[f] = own + f * column - first;
    const int q0 = std::max(r0 - 1, 0), q1 = std::min(r1, nv - 1);  // rows with quads
    for (int f = 0; f < 6; ++f) {
      std::fill(t[f] + first, t[f] + std::max<long long>(first, q0 * static_cast<long long>(nu)),
                0.0);
      std::fill(t[f] + std::max(q0, q1) * static_cast<long long>(nu),
                t[f] + r1 * static_cast<long long>(nu), 0.0);
    }
    if (q0 < q1) {
      double *const t0 = t[0], *const t1 = t[1], *const t2 = t[2], *const t3 = t[3],
                    *const t4 = t[4], *const t5 = t[5];
      // Up to the last row's slot nu - 1, whose corners run past the grid.
#pragma GCC ivdep
      for (int a = q0 * nu; a < q1 * nu - 1; ++a) {
        // Corners a, b = a + 1, cc = a + nu + 1, d = a + nu. Even quads split
        // along a-cc: {a, b, cc}, {a, cc, d}; odd ones along b-d: {a, b, d},
        // {b, cc, d}. Eigen's cross, in scalars.
        // Every corner loaded and the split's chosen among the values: an
        // index chosen per quad made the loop gather.
        const bool even = even_at[a] != 0;
        const int b = a + 1, cc = a + nu + 1, d = a + nu;
        const double ax = x[a], ay = y[a], az = z[a], bx = x[b], by = y[b], bz = z[b];
        const double cx = x[cc], cy = y[cc], cz = z[cc], dx = x[d], dy = y[d], dz = z[d];
        const double ux = bx - ax, uy = by - ay, uz = bz - az;
        const double vx = (even ? cx : dx) - ax, vy = (even ? cy : dy) - ay,
                     vz = (even ? cz : dz) - az;
        t0[a] = uy * vz - uz * vy;
        t1[a] = uz * vx - ux * vz;
        t2[a] = ux * vy - uy * vx;
        const double ox = even ? ax : bx, oy = even ? ay : by, oz = even ? az : bz;
        const double px = cx - ox, py = cy - oy, pz = cz - oz;
        const double qx = dx - ox, qy = dy - oy, qz = dz - oz;
        t3[a] = py * qz - pz * qy;
        t4[a] = pz * qx - px * qz;
        t5[a] = px * qy - py * qx;
      }
      for (int q = q0; q < q1; ++q)
        for (int f = 0; f < 6; ++f) t[f][q * nu + nu - 1] = 0.0;
    }
    double* __restrict out_x = normal.column(0);
    double* __restrict out_y = normal.column(1);
    double* __restrict out_z = normal.column(2);
#pragma GCC ivdep
    for (int a = r0 * nu; a < r1 * nu; ++a) {
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
  }
}

void detail::compute_normals(const Model& m, const double* X, Vec3Array& normal,
                             NormalsScratch& scratch) {
  if (!m.grid) {
    compute_normals_mesh(m, X, normal);
    return;
  }
  prepare_normals(m, scratch);
  for_each_row_block(m, [&](int j0, int j1, int thread) {
    compute_normal_rows(m, X, normal, scratch, j0, j1, thread);
  });
}

void compute_normals(const Model& m, const Vec3Array& x, Vec3Array& normal) {
  if (normal.size() != x.size()) normal.assign(x.size(), Vec3::Zero());
  NormalsScratch scratch;
  detail::compute_normals(m, x.column(0), normal, scratch);
}

}  // namespace wetcloth
