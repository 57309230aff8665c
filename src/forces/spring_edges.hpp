// Provot's springs, eq. 1, along one offset of the grid's stencil for one row:
// the kernel of forces/springs.cpp. It is a template on the number type only
// so that the micro-benchmarks can time it in float too; the step is in double
// (docs/architecture.md says why).
#pragma once

#include <cmath>
#include <utility>

#include "detail.hpp"

namespace wetcloth::detail {

// Per edge: the force on its lower end (x y z).
constexpr int kSpringFields = 3;

// Positions and velocities by component.
template <class Real>
struct SpringColumns {
  const Real *px, *py, *pz, *vx, *vy, *vz;
};

// The particles i of a row whose spring at offset st is on the grid (given
// that row j + dj is).
inline std::pair<int, int> spring_edge_span(const Model& m, const StencilEdge& st) {
  return {std::max(0, -st.di), std::min(m.nu, m.nu - st.di)};
}

// Offset st's springs starting in row j (j + dj < nv), into out[k][i]; with
// damped, eq. 1's damping too (explicit Euler; the symplectic step takes it
// implicitly, apply_spring_damping).
template <class Real, bool damped>
void spring_edge_row(const Model& m, const SpringColumns<Real>& c, const StencilEdge& st, int j,
                     Real* const out[kSpringFields]) {
  const int nu = m.nu;
  const auto [lo, hi] = spring_edge_span(m, st);
  const int off = st.di + st.dj * nu, base = j * nu;
  const Real k_s = Real(st.k), rest = Real(st.rest), kd = damped ? Real(st.damping) : Real(0);
#pragma GCC ivdep
  for (int i = lo; i < hi; ++i) {
    const int a = base + i, b = a + off;
    const Real dx = c.px[b] - c.px[a], dy = c.py[b] - c.py[a], dz = c.pz[b] - c.pz[a];
    const Real len = std::sqrt(dx * dx + dy * dy + dz * dz);
    const Real inv = len > 0 ? Real(1) / len : Real(0);  // a zero-length spring pulls nowhere
    const Real ux = dx * inv, uy = dy * inv, uz = dz * inv;
    Real t = k_s * (len - rest);
    if constexpr (damped)
      t += kd * ((c.vx[b] - c.vx[a]) * ux + (c.vy[b] - c.vy[a]) * uy + (c.vz[b] - c.vz[a]) * uz);
    out[0][i] = t * ux;
    out[1][i] = t * uy;
    out[2][i] = t * uz;
  }
}

}  // namespace wetcloth::detail
