// Implicit Euler's step control (Baraff & Witkin 1998, section 5.5): a
// substep whose springs change too much for their linearisation is taken
// again at half the size.
#include <cmath>

#include "detail.hpp"

namespace wetcloth::detail {

// Backward Euler over dt / 2^k, halving while the springs change more than
// integrator.max_step_strain; returns the substep taken, and its springs'
// largest change in `strain`.
double implicit_euler_substep(const Model& m, State& s, Workspace& w, double dt, int& k,
                              double& strain) {
  w.v_start = s.v;
  for (;;) {
    const double h = std::ldexp(dt, -k);
    implicit_euler_velocities(m, s, w, h);
    ++w.solves;
    strain = step_strain(m, s, h);
    if (k == kMostHalvings || strain <= m.params.integrator.max_step_strain) {
      ++w.substeps;
      if (s.acceleration.size() != std::size_t(m.n)) s.acceleration.assign(m.n, Vec3::Zero());
      for_each_particle_block(m, [&](int first, int end) {
        for (int k = 0; k < 3; ++k) {
          const double* __restrict v = s.v.column(k), * __restrict v0 = w.v_start.column(k);
          double* __restrict a = s.acceleration.column(k);
          for (int i = first; i < end; ++i) a[i] = (v[i] - v0[i]) / h;
        }
      });
      move_at_new_velocities(m, s, w, h);
      return h;
    }
    s.v = w.v_start;
    ++k;
  }
}

}  // namespace wetcloth::detail
