// Contact surfaces and obstacles (MODEL.md section 3): the table plane and the ball.
#include "detail.hpp"

namespace wetcloth::detail {

void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched) {
  const Params& p = m.params;
  const SurfaceKind kinds[] = {SurfaceKind::Table, SurfaceKind::Ball};
  const bool enabled[] = {p.table.enabled, p.ball.enabled};
  for_each_particle(m, [&](int i) {
    if (touched) (*touched)[i] = 0;
    if (m.driven[i]) return;
    for (int o = 0; o < 2; ++o) {
      if (!enabled[o]) continue;
      const SurfaceHit h = query_surface(p, kinds[o], s.x[i]);
      if (h.distance >= 0) continue;
      s.x[i] -= h.distance * h.normal;
      const double vn = s.v[i].dot(h.normal);
      if (vn < 0) s.v[i] -= vn * h.normal;
      if (touched) (*touched)[i] = static_cast<std::uint8_t>(kinds[o]);
    }
  });
}

void update_contact(const Model& m, State& s, Workspace& w) {
  const Params& p = m.params;
  const double h_th = p.contact.bridge_height;
  for_each_particle(m, [&](int i) {
    const SurfaceHit h = query_surface(p, m.contact_surface, s.x[i]);
    w.distance[i] = h.distance;
    w.surface_normal[i] = h.normal;
    s.contact[i] = h.distance < h_th;
  });
  // The border of the contact region: contact particles on the cloth's border or
  // next to a lifted particle. They carry eq. 13's edge term.
  for_each_particle(m, [&](int k) {
    bool b = s.contact[k] && m.on_border[k];
    if (s.contact[k] && !b)
      b = !s.contact[k - 1] || !s.contact[k + 1] || !s.contact[k - m.nu] || !s.contact[k + m.nu];
    w.border[k] = b;
  });
}

}  // namespace wetcloth::detail
