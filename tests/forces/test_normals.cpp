// Particle normals (src/forces/normals.cpp): area-weighted over each particle's triangles.
#include <gtest/gtest.h>

#include <cmath>

#include "common.hpp"

using namespace wetcloth;

// compute_normals works quad by quad on the grid; the normal of a particle is
// still the area-weighted sum over its triangles in Model::triangles, in their
// order, to the bit, on grids odd and even, square or not.
TEST(Normals, AreTheAreaWeightedSumOverEachParticlesTriangles) {
  for (const auto& [nu, nv] : {std::pair{7, 7}, std::pair{8, 5}, std::pair{6, 9}}) {
    Params p = test::bare();
    p.cloth.resolution = {nu, nv};
    Simulation sim(p);
    const Model& m = sim.model();
    Vec3Array x(m.rest_position);
    Vec3Array normal(m.n);
    std::vector<Vec3> expected(m.n, Vec3::Zero());
    for (int i = 0; i < m.n; ++i)
      x[i] += 0.004 * Vec3(std::sin(3.1 * i), std::cos(1.3 * i), std::sin(0.7 * i * i));
    for (const auto& t : m.triangles) {
      const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
      for (int v : t) expected[v] += n;
    }
    compute_normals(m, x, normal);
    for (int i = 0; i < m.n; ++i)
      ASSERT_EQ(normal[i], Vec3(expected[i] / expected[i].norm()))
          << nu << "x" << nv << " particle " << i;
  }
}
