// Viscous damping -c v_i (blog seed), with c per unit cloth area so that a finer
// grid damps the same cloth the same way.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_viscous_damping(const Model& m, const State& s, Vec3Array& f) {
  const double c = m.params.forces.viscous_damping;
  if (c == 0) return;
  parallel_for(m, m.nv, [&](int j) {
    for (int k = 0; k < 3; ++k) {
      const double* __restrict v = s.v.column(k);
      double* __restrict out = f.column(k);
#pragma GCC ivdep
      for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) out[i] -= c * m.area[i] * v[i];
    }
  });
}

}  // namespace wetcloth::detail
