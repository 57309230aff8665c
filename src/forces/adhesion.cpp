// Liquid-bridge adhesion (docs/model.md section 4, eqs. 6-13, after Lou et al. 2015).
#include <cmath>

#include "detail.hpp"

namespace wetcloth::detail {

// eq. 13 shared out per particle: every contact particle gets the area part
// ω_i γ (cos θa + cos θb) / h · A_i, and each of the B particles on the border
// of the contact region 2 √S_now ω_i γ sin θa / B, each with its own ω_i (the
// humidity field), so that with a uniform ω the forces sum to eq. 13 exactly
// (with a field, eq. 13 with the border's mean ω in its edge part). The
// force points along -n_s, toward the surface.
void add_adhesion_rows(const Model& m, const State& s, Workspace& w, int j0, int j1) {
  if (m.contact_surface == SurfaceKind::None) return;  // w.adhesion stays zero, as reset left it
  const int first = j0 * m.nu, end = j1 * m.nu;
  // Each particle's own ω (the humidity field); a state without a field (made
  // by hand) has cloth.humidity's everywhere.
  const bool field = s.humidity.size() == static_cast<std::size_t>(m.n);
  const double omega0 = field ? s.humidity[0] : m.params.cloth.humidity;
  const AdhesionConstants c = adhesion_constants(m.params);
  if (!c.enabled || ((!field || w.humidity.uniform) && c.pressure_per_omega(omega0) == 0 &&
                     c.tension_per_omega(omega0) == 0)) {
    std::fill(w.adhesion.begin() + first, w.adhesion.begin() + end, 0.0);
    return;
  }
  // A uniform field: eq. 13's two parts once, as before the field.
  const bool per_particle = field && !w.humidity.uniform;
  const double* omega = field ? s.humidity.data() : nullptr;
  // The contact area and its border's particles, in one pass.
  const auto [s_now, border] = ordered_sums_in_rows<2>(m, w, j0, j1, [&](int j) {
    double area = 0;
    int count = 0;
    for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) {
      area += s.contact[i] ? m.area[i] : 0.0;
      count += s.contact[i] && w.border[i];
    }
    return std::array<double, 2>{area, static_cast<double>(count)};
  });
  const double two_root_s = 2.0 * std::sqrt(s_now);
  const double pressure0 = c.pressure_per_omega(omega0),
               edge0 = border > 0 ? two_root_s * c.tension_per_omega(omega0) / border : 0.0;
  const double *__restrict nx = w.surface_normal.column(0),
                           *__restrict ny = w.surface_normal.column(1),
                           *__restrict nz = w.surface_normal.column(2);
  double *__restrict fx = w.force.column(0), *__restrict fy = w.force.column(1),
                     *__restrict fz = w.force.column(2), *__restrict adhesion = w.adhesion.data();
  const auto force = [&](int i) {  // zero off the contact region
    if (!s.contact[i]) return 0.0;
    if (!per_particle) return pressure0 * m.area[i] + (w.border[i] ? edge0 : 0.0);
    const double o = omega[i];
    return c.pressure_per_omega(o) * m.area[i] +
           (w.border[i] && border > 0 ? two_root_s * c.tension_per_omega(o) / border : 0.0);
  };
  for_each_chunk(first, end, force, [&](int i0, int count, const double* f) {
#pragma omp simd
    for (int k = 0; k < count; ++k) {
      const int i = i0 + k;
      adhesion[i] = f[k];
      fx[i] -= f[k] * nx[i];
      fy[i] -= f[k] * ny[i];
      fz[i] -= f[k] * nz[i];
    }
  });
}

void add_adhesion(const Model& m, const State& s, Workspace& w) {
  w.row_sums.resize(2 * std::size_t(m.nv));
  for_each_row_block(m, [&](int j0, int j1, int) { add_adhesion_rows(m, s, w, j0, j1); });
}

}  // namespace wetcloth::detail
