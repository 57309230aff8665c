// Gravity, m_i g, with the humidity-dependent mass of MODEL.md section 1.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_gravity(const Model& m, Vec3Array& f) {
  const Vec3 g = to_vec(m.params.forces.gravity);
  parallel_for(m, m.nv, [&](int j) {
    for (int k = 0; k < 3; ++k) {
      const double gk = g[k];
      double* __restrict out = f.column(k);
#pragma GCC ivdep
      for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) out[i] += m.mass[i] * gk;
    }
  });
}

}  // namespace wetcloth::detail
