// Liquid-bridge adhesion (docs/model.md section 4, eqs. 6-13, after Lou et al. 2015).
#include <cmath>

#include "detail.hpp"

namespace wetcloth::detail {

// eq. 13 shared out per particle: every contact particle gets the area part
// ω γ (cos θa + cos θb) / h · A_i, and the border of the contact region shares
// the edge part 2 √S_now ω γ sin θa, so the forces sum to eq. 13 exactly. The
// force points along -n_s, toward the surface.
void add_adhesion(const Model& m, const State& s, Workspace& w) {
  if (m.contact_surface == SurfaceKind::None) return;  // w.adhesion stays zero, as reset left it
  std::fill(w.adhesion.begin(), w.adhesion.end(), 0.0);
  const double pressure = adhesion_pressure(m.params);
  const double tension = adhesion_edge_tension(m.params);
  if (pressure == 0 && tension == 0) return;
  const double s_now = ordered_sum(m, w, [&](int j) {
    double sum = 0;
    for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) sum += s.contact[i] ? m.area[i] : 0.0;
    return sum;
  });
  const double border = ordered_sum(m, w, [&](int j) {
    int count = 0;
    for (int i = j * m.nu; i < (j + 1) * m.nu; ++i) count += s.contact[i] && w.border[i];
    return static_cast<double>(count);
  });
  const double edge_each = border > 0 ? 2.0 * std::sqrt(s_now) * tension / border : 0.0;
  for_each_particle_block(m, [&](int first, int end) {
    const double *__restrict nx = w.surface_normal.column(0),
                             *__restrict ny = w.surface_normal.column(1),
                             *__restrict nz = w.surface_normal.column(2);
    double *__restrict fx = w.force.column(0), *__restrict fy = w.force.column(1),
                       *__restrict fz = w.force.column(2), *__restrict adhesion = w.adhesion.data();
    const auto force = [&](int i) {  // zero off the contact region
      return s.contact[i] ? pressure * m.area[i] + (w.border[i] ? edge_each : 0.0) : 0.0;
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
  });
}

}  // namespace wetcloth::detail
