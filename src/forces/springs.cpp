// Provot's springs, eq. 1: Hooke's law plus damping projected on the spring.
// Gathered per particle over the grid's stencil (Model::stencil, both
// directions): each particle sums its own springs in a fixed order, so rows are
// independent, run on any number of threads, and give the same bits on each.
#include "../detail.hpp"

namespace wetcloth::detail {

void add_spring_forces(const Model& m, const State& s, Workspace& w, bool with_damping) {
  parallel_for(m, m.nv, [&](int j) {
    for (int i = 0; i < m.nu; ++i) {
      const int a = m.index(i, j);
      Vec3 f = Vec3::Zero();
      Mat3 c = Mat3::Zero();
      for (const StencilEdge& e : m.stencil)
        for (const int sign : {1, -1}) {
          const int b = grid_neighbour(m, i, j, sign * e.di, sign * e.dj);
          if (b < 0) continue;
          const Vec3 d = s.x[b] - s.x[a];
          const double len = d.norm();
          if (len <= 0) continue;
          const Vec3 u = d / len;
          // F_a = u (k_s (|d| - l0) + k_d (v_b - v_a)·u)
          double t = e.k * (len - e.rest);
          if (with_damping) {
            t += e.damping * (s.v[b] - s.v[a]).dot(u);
            c.noalias() += e.damping * u * u.transpose();  // -∂F_a/∂v_a
          }
          f += t * u;
        }
      w.force[a] += f;
      if (with_damping) w.damping[a] = c;
    }
  });
}

}  // namespace wetcloth::detail
