// Contact surfaces and obstacles (MODEL.md section 3): the table plane and the ball.
#include "detail.hpp"

namespace wetcloth::detail {

namespace {

// The table alone, as the general loop below treats it (n = z: x.z -= d, an
// inward v.z becomes v.z - v.z = 0), in scalars without branches: in contact
// the adhesion pulls particles in every step, and a branch per particle was
// mispredicted (3 x faster at 51 x 51, BM_collide).
template <bool record>
void collide_with_table(const Model& m, State& s, std::uint8_t* touched) {
  const double height = m.params.table.height;
  const auto table = static_cast<std::uint8_t>(SurfaceKind::Table);
  const int nu = m.nu;  // locals: a store through X could alias m's fields
  parallel_for(m, m.nv, [&, nu, height](int j) {
    const std::size_t first = std::size_t(j) * nu;
    double* X = s.x[first].data();
    double* V = s.v[first].data();
    const std::uint8_t* driven = m.driven.data() + first;
    std::uint8_t* hit = record ? touched + first : nullptr;
    for (int i = 0; i < nu; ++i) {
      const double z = X[3 * i + 2], d = z - height, vz = V[3 * i + 2];
      const bool in = (d < 0) & (driven[i] == 0);  // &, not &&: no branch
      X[3 * i + 2] = in ? z - d : z;
      V[3 * i + 2] = in & (vz < 0) ? vz - vz : vz;
      if constexpr (record) hit[i] = in ? table : 0;
    }
  });
}

}  // namespace

void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched,
             const std::vector<int>* only) {
  const Params& p = m.params;
  if (!only && p.table.enabled && !p.ball.enabled)
    return touched ? collide_with_table<true>(m, s, touched->data())
                   : collide_with_table<false>(m, s, nullptr);
  const SurfaceKind kinds[] = {SurfaceKind::Table, SurfaceKind::Ball};
  const bool enabled[] = {p.table.enabled, p.ball.enabled};
  auto one = [&](int i) {
    if (touched) (*touched)[i] = 0;
    if (m.driven[i]) return;
    for (int o = 0; o < 2; ++o) {
      if (!enabled[o]) continue;
      const SurfaceHit h = query_surface(p, kinds[o], s.x[i]);
      if (h.distance >= 0) continue;
      sub(s.x[i], h.distance * h.normal);
      const double vn = s.v[i].dot(h.normal);
      if (vn < 0) sub(s.v[i], vn * h.normal);
      if (touched) (*touched)[i] = static_cast<std::uint8_t>(kinds[o]);
    }
  };
  if (only)
    for (const int i : *only) one(i);
  else
    for_each_particle(m, one);
}

void update_contact(const Model& m, State& s, Workspace& w) {
  const Params& p = m.params;
  const double h_th = p.contact.bridge_height;
  for_each_particle(m, [&](int i) {
    const SurfaceHit h = query_surface(p, m.contact_surface, s.x[i]);
    w.distance[i] = h.distance;
    put(w.surface_normal[i], h.normal);
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
