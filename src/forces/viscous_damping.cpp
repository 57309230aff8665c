// Viscous damping -c v_i (blog seed), with c per unit cloth area so that a finer
// grid damps the same cloth the same way.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_viscous_damping(const Model& m, const State& s, std::vector<Vec3>& f) {
  const double c = m.params.forces.viscous_damping;
  if (c == 0) return;
  for_each_particle(m, [&](int i) { sub(f[i], c * m.area[i] * s.v[i]); });
}

}  // namespace wetcloth::detail
