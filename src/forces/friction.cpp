// Friction (MODEL.md section 5; paper eq. 14, after Bridson et al. 2002).
#include <cmath>

#include "../detail.hpp"

namespace wetcloth::detail {

// Velocity-level Coulomb friction: the tangential velocity shrinks by
// Δv_f = μ F_n Δt / m and never reverses. As in Bridson et al. 2002, it acts on
// the velocity that moves the particle over the step, so the step's move is
// taken back by Δt Δv_f too: applied after the move, a load under μ F_n would
// still creep Δt² a a step, and a cloth that should hold would slide. On the contact surface F_n is
// the adhesion plus, by default, the part of the other forces that presses the particle in; on
// other obstacles it is that load alone.
void apply_friction(const Model& m, State& s, const Workspace& w,
                    const std::vector<std::uint8_t>& touched, double dt) {
  const double mu = m.params.friction.mu;
  if (mu == 0) return;
  const bool with_load = m.params.friction.normal == "contact";
  for_each_particle(m, [&](int i) {
    if (m.driven[i]) return;
    double load = 0;
    Vec3 n;
    if (s.contact[i]) {
      n = w.surface_normal[i];
      // w.force holds the step's forces, adhesion included (it is -adhesion·n_s).
      const double pressing = -(w.force[i].dot(n) + w.adhesion[i]);
      load = w.adhesion[i] + (with_load && pressing > 0 ? pressing : 0.0);
    } else if (touched[i] != 0 && with_load) {
      n = query_surface(m.params, static_cast<SurfaceKind>(touched[i]), s.x[i]).normal;
      load = std::max(0.0, -w.force[i].dot(n));
    } else {
      return;
    }
    if (load <= 0) return;
    const Vec3 vt = s.v[i] - s.v[i].dot(n) * n;
    const double speed = vt.norm();
    if (speed == 0) return;
    const double dv = mu * load * dt * m.inv_mass[i];
    const Vec3 slowed = vt * (std::min(dv, speed) / speed);  // eq. 14
    sub(s.v[i], slowed);
    sub(s.x[i], dt * slowed);
  });
}

}  // namespace wetcloth::detail
