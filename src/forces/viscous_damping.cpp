// Viscous damping -c v_i (blog seed), with c per unit cloth area so that a finer
// grid damps the same cloth the same way.
#include "detail.hpp"

namespace wetcloth::detail {

void add_viscous_damping(const Model& m, const State& s, Vec3Array& f, int first, int end) {
  const double c = m.params.forces.viscous_damping;
  if (c == 0) return;
  const double *__restrict vx = s.v.column(0), *__restrict vy = s.v.column(1),
                           *__restrict vz = s.v.column(2), *__restrict area = m.area.data();
  double* __restrict fx = f.column(0), * __restrict fy = f.column(1), * __restrict fz = f.column(2);
#pragma GCC ivdep
  for (int i = first; i < end; ++i) {
    fx[i] -= c * area[i] * vx[i];
    fy[i] -= c * area[i] * vy[i];
    fz[i] -= c * area[i] * vz[i];
  }
}

}  // namespace wetcloth::detail
