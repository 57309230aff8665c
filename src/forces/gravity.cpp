// Gravity, m_i g, with the humidity-dependent mass of docs/model.md section 1.
#include "detail.hpp"

namespace wetcloth::detail {

// With `set`, f is set to 0 + m g: the bits of a zeroed force and an add,
// without the pass that zeroed it (xpbd's first force of a substep).
template <bool set>
void gravity(const Model& m, Vec3Array& f, int first, int end) {
  const Vec3 g = to_vec(m.params.forces.gravity);
  // All three components in one loop: the masses are read once.
  double* __restrict fx = f.column(0), * __restrict fy = f.column(1), * __restrict fz = f.column(2);
  const double* __restrict mass = m.mass.data();
  const double gx = g[0], gy = g[1], gz = g[2];
#pragma GCC ivdep
  for (int i = first; i < end; ++i) {
    fx[i] = (set ? 0.0 : fx[i]) + mass[i] * gx;
    fy[i] = (set ? 0.0 : fy[i]) + mass[i] * gy;
    fz[i] = (set ? 0.0 : fz[i]) + mass[i] * gz;
  }
}

void add_gravity(const Model& m, Vec3Array& f, int first, int end) {
  gravity<false>(m, f, first, end);
}
void set_gravity(const Model& m, Vec3Array& f, int first, int end) {
  gravity<true>(m, f, first, end);
}

}  // namespace wetcloth::detail
