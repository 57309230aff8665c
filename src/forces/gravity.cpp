// Gravity, m_i g, with the humidity-dependent mass of MODEL.md section 1.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_gravity(const Model& m, std::vector<Vec3>& f) {
  const Vec3 g = to_vec(m.params.forces.gravity);
  for_each_particle(m, [&](int i) { add(f[i], m.mass[i] * g); });
}

}  // namespace wetcloth::detail
