// Wind (blog seed, made physical): F_i = k_w A_i ((u_wind - v_i)·n_i) n_i.
// With no wind it is the cloth's drag against still air, normal to the cloth.
#include "detail.hpp"

namespace wetcloth::detail {

void add_wind(const Model& m, const State& s, const Workspace& w, Vec3Array& f, int first,
              int end) {
  const double k = m.params.wind.k;
  if (k == 0) return;
  const Vec3 u = to_vec(m.params.wind.velocity);
  const double* __restrict vx = s.v.column(0), * __restrict vy = s.v.column(1), * __restrict vz = s.v.column(2);
  const double *__restrict nx = w.normal.column(0), *__restrict ny = w.normal.column(1),
                               *__restrict nz = w.normal.column(2);
  double* __restrict fx = f.column(0), * __restrict fy = f.column(1), * __restrict fz = f.column(2);
  const double* __restrict area = m.area.data();
  const double ux = u[0], uy = u[1], uz = u[2];
  if (ux == 0 && uy == 0 && uz == 0) {
    // Still air (every scene's drag without wind): in the wind or not, the
    // relative velocity is -v (0 - v and -v differ only in a zero's sign,
    // which no sum below can keep: f holds +0 or more before it), so no
    // per-particle flags are gathered.
#pragma omp simd
    for (int i = first; i < end; ++i) {
      const double t = k * area[i] * (-vx[i] * nx[i] + -vy[i] * ny[i] + -vz[i] * nz[i]);
      fx[i] += t * nx[i];
      fy[i] += t * ny[i];
      fz[i] += t * nz[i];
    }
    return;
  }
  const auto in_wind = [&](int i) { return m.in_wind[i] ? 1.0 : 0.0; };
  for_each_chunk(first, end, in_wind, [&](int i0, int count, const double* in) {
#pragma omp simd
    for (int c = 0; c < count; ++c) {
      const int i = i0 + c;
      const bool blown = in[c] != 0;
      const double rx = blown ? ux - vx[i] : -vx[i], ry = blown ? uy - vy[i] : -vy[i],
                   rz = blown ? uz - vz[i] : -vz[i];
      const double t = k * area[i] * (rx * nx[i] + ry * ny[i] + rz * nz[i]);
      fx[i] += t * nx[i];
      fy[i] += t * ny[i];
      fz[i] += t * nz[i];
    }
  });
}

}  // namespace wetcloth::detail
