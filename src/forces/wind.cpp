// Wind (blog seed, made physical): F_i = k_w A_i ((u_wind - v_i)·n_i) n_i.
// With no wind it is the cloth's drag against still air, normal to the cloth.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_wind(const Model& m, const State& s, const Workspace& w, std::vector<Vec3>& f) {
  const double k = m.params.wind.k;
  if (k == 0) return;
  const Vec3 u = to_vec(m.params.wind.velocity);
  for_each_particle(m, [&](int i) {
    const Vec3 rel = m.in_wind[i] ? Vec3(u - s.v[i]) : Vec3(-s.v[i]);
    const Vec3& n = w.normal[i];
    add(f[i], (k * m.area[i] * rel.dot(n)) * n);
  });
}

}  // namespace wetcloth::detail
