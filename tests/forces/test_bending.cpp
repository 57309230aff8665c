// The quadratic bending (docs/model.md section 1, forces/bending.cpp) against the
// laws it must meet exactly: a cylinder bend stores B κ²/2 per unit area on a
// grid and on an irregular mesh, a flat or rigidly moved cloth feels nothing,
// the forces sum to zero.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;

namespace {

constexpr double kB = 2e-5;  // N·m

// ½ xᵀ Q x of a matrix built by hand (detail::bending_energy's sum).
double energy(const BendingMatrix& b, const std::vector<Vec3>& x) {
  double e = 0;
  for (std::size_t i = 0; i + 1 < b.start.size(); ++i)
    for (int c = b.start[i]; c < b.start[i + 1]; ++c)
      e -= 0.25 * b.value[c] * (x[b.column[c]] - x[i]).squaredNorm();
  return e;
}

// The flat point (u, v) on a cylinder of curvature κ whose axis runs at
// `degrees` to u: arc length across the axis kept (an isometric bend).
Vec3 on_cylinder(double u, double v, double kappa, double degrees) {
  const double a = degrees * std::numbers::pi / 180;
  const double s = u * std::cos(a) + v * std::sin(a), t = -u * std::sin(a) + v * std::cos(a);
  const double r = 1 / kappa, across = r * std::sin(s / r);
  return {across * std::cos(a) - t * std::sin(a), across * std::sin(a) + t * std::cos(a),
          r * (1 - std::cos(s / r))};
}

Params quadratic(int n) {
  Params p = test::bare(n);
  p.material.bending = BendingModel::Quadratic;
  p.springs.bending_k.reset();
  p.springs.bending_damping.reset();
  p.material.bending_rigidity = kB;
  return p;
}

// A 23 x 17 grid cloth under the quadratic bending (its border rows and
// stencil both present), each particle moved at random by up to 1 cm.
Params small_grid() {
  Params p = quadratic(23);
  p.cloth.resolution = {23, 17};
  return p;
}
void jitter(Simulation& sim, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> by(-0.01, 0.01);
  State& s = detail::state(sim);
  for (int i = 0; i < sim.model().n; ++i) s.x[i] += Vec3(by(rng), by(rng), by(rng));
}

// Q_ij == Q_ji to the bit, every row's entries as for_each_in_row gives them.
void expect_symmetric(const BendingMatrix& b, int n) {
  std::map<std::pair<int, int>, double> q;
  for (int i = 0; i < n; ++i) b.for_each_in_row(i, [&](int j, double v) { q[{i, j}] = v; });
  for (const auto& [ij, v] : q) {
    const auto ji = q.find({ij.second, ij.first});
    ASSERT_TRUE(ji != q.end()) << ij.first << " " << ij.second;
    EXPECT_EQ(v, ji->second) << ij.first << " " << ij.second;
  }
}

}  // namespace

// A grid cloth (split both ways) bent into a cylinder at any direction to its
// rows stores B κ²/2 per unit area, the border included (its area is carried
// by the rows inside).
TEST(QuadraticBending, CylinderBendStoresHalfBKappaSquaredOnAGrid) {
  const Model m = build_model(quadratic(31));
  const double side = 0.3, kappa = 5.0;  // a 30 cm cloth, 20 cm radius
  for (const double degrees : {0.0, 30.0, 45.0, 90.0}) {
    Vec3Array x(m.n);
    for (int k = 0; k < m.n; ++k) {
      const Vec3 flat = m.rest_position[k] - m.rest_position[0];
      x[k] = on_cylinder(flat.x(), flat.y(), kappa, degrees);
    }
    const double e = detail::bending_energy(m, x);
    EXPECT_NEAR(e / (0.5 * kB * kappa * kappa * side * side), 1.0, 0.01) << degrees << "°";
  }
}

// An irregular mesh: a grid's inner vertices moved by up to a quarter of a
// step at random, each quad split along its Delaunay diagonal (the cotangent
// Laplacian's error grows on long thin triangles): B κ²/2 within 1 %.
TEST(QuadraticBending, CylinderBendStoresHalfBKappaSquaredOnAnIrregularMesh) {
  const int n = 41;
  const double side = 0.3, l = side / (n - 1), kappa = 5.0;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.25 * l, 0.25 * l);
  std::vector<Vec3> rest(n * n);
  std::vector<std::uint8_t> border(n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool edge = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      border[j * n + i] = edge;
      rest[j * n + i] = Vec3(i * l, j * l, 0);
      if (!edge) rest[j * n + i] += Vec3(jitter(random), jitter(random), 0);
    }
  const auto angle = [&](int at, int a, int b) {
    const Vec3 u = rest[a] - rest[at], v = rest[b] - rest[at];
    return std::acos(u.dot(v) / (u.norm() * v.norm()));
  };
  std::vector<std::array<int, 3>> triangles;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n + 1, d = a + n;
      if (angle(b, a, c) + angle(d, a, c) < std::numbers::pi) {  // a-c is Delaunay
        triangles.push_back({a, b, c});
        triangles.push_back({a, c, d});
      } else {
        triangles.push_back({a, b, d});
        triangles.push_back({b, c, d});
      }
    }
  const BendingMatrix q = detail::build_bending_matrix(rest, {triangles}, border, kB);
  for (const double degrees : {0.0, 30.0, 45.0, 90.0}) {
    std::vector<Vec3> x(rest.size());
    for (std::size_t k = 0; k < x.size(); ++k)
      x[k] = on_cylinder(rest[k].x(), rest[k].y(), kappa, degrees);
    EXPECT_NEAR(energy(q, x) / (0.5 * kB * kappa * kappa * side * side), 1.0, 0.01) << degrees;
  }
}

// A flat cloth, moved and turned as a rigid body, feels no bending force;
// any shape's forces sum to zero (momentum), and the matrix is symmetric.
TEST(QuadraticBending, RigidMotionFeelsNoForceAndForcesSumToZero) {
  Params p = quadratic(21);
  p.cloth.tilt = 35;
  Simulation sim(p);
  const Model& m = sim.model();
  State& s = detail::state(sim);
  const Eigen::AngleAxisd turn(0.7, Vec3(0.3, -0.5, 0.8).normalized());
  for (int k = 0; k < m.n; ++k) s.x[k] = turn * m.rest_position[k] + Vec3(12.0, -3.0, 40.0);
  Vec3Array f(m.n);
  detail::add_bending_forces(m, s, f);
  double largest = 0;
  for (int k = 0; k < m.n; ++k) largest = std::max(largest, f[k].norm());
  EXPECT_LT(largest, 1e-12);
  // Crumpled at random: the forces are far from zero, their sum is not.
  std::mt19937 random(3);
  std::normal_distribution<double> bump(0, 0.003);
  for (int k = 0; k < m.n; ++k) s.x[k] += Vec3(bump(random), bump(random), bump(random));
  f.assign(m.n, Vec3::Zero());
  detail::add_bending_forces(m, s, f);
  Vec3 sum = Vec3::Zero();
  largest = 0;
  for (int k = 0; k < m.n; ++k) {
    sum += f[k];
    largest = std::max(largest, f[k].norm());
  }
  EXPECT_GT(largest, 1e-4);
  EXPECT_LT(sum.norm(), 1e-13 * largest * m.n);
  expect_symmetric(m.topology->bending, m.n);
}

// Provot's chord springs stay as an option; the quadratic model has no
// bending springs, and a [springs] bending constant with it is an error.
TEST(QuadraticBending, ProvotKeepsItsSpringsAndQuadraticHasNone) {
  Params p = quadratic(11);
  EXPECT_EQ(spring_count(build_model(p), SpringKind::Bending), 0u);
  EXPECT_FALSE(build_model(p).topology->bending.start.empty());
  p.material.bending = BendingModel::Provot;
  EXPECT_GT(spring_count(build_model(p), SpringKind::Bending), 0u);
  EXPECT_TRUE(build_model(p).topology->bending.start.empty());
  EXPECT_THROW(load_scene("hang", {"springs.bending_k=20"}), SceneError);
  EXPECT_NO_THROW(load_scene("hang", {"springs.bending_k=20", "material.bending=\"provot\""}));
}

// A grid's rows away from its border run as one stencil, in loops that
// vectorise: every particle but those within three of the border uses it,
// and the force and implicit Euler's product are the matrix's rows (each
// summing to zero with its diagonal).
TEST(QuadraticBending, TheGridsStencilIsItsMatrixRows) {
  Simulation sim(small_grid());
  const Model& m = sim.model();
  const BendingMatrix& b = m.topology->bending;
  ASSERT_EQ(b.stencil.offset.size(), 24u);  // 5 x 5 about the particle
  ASSERT_EQ(b.stencil.mirror.size(), 8u);   // the same under di → -di, dj → -dj: by groups
  for (int j = 3; j + 3 < m.nv; ++j) {
    EXPECT_LE(b.stencil.first[j], 3) << j;
    EXPECT_GE(b.stencil.last[j], m.nu - 3) << j;
  }
  jitter(sim, 7);
  const State& s = detail::state(sim);
  Vec3Array f(m.n);
  detail::add_bending_forces(m, s, f);
  std::vector<double> x(m.n), product(m.n, 0.0);
  for (int i = 0; i < m.n; ++i) x[i] = s.x[i][2];
  detail::add_bending_off_diagonal(m, x.data(), product.data(), 2.0, 0, m.n);
  for (int i = 0; i < m.n; ++i) {
    Vec3 row = Vec3::Zero();
    double off_diagonal = 0, sum = b.diagonal[i];
    b.for_each_in_row(i, [&](int j, double q) {
      row += q * (s.x[j] - s.x[i]);
      off_diagonal += q * x[j];
      sum += q;
    });
    EXPECT_NEAR(sum, 0, 1e-12 * std::abs(b.diagonal[i])) << i;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(f[i][k], -row[k], 1e-12 * (1 + row.norm())) << i;
    EXPECT_NEAR(product[i], 2 * off_diagonal, 1e-12 * std::abs(off_diagonal) + 1e-15) << i;
  }
  // Symmetric to the bit; the stencil's rows are not stored twice.
  expect_symmetric(b, m.n);
  for (int i = 0; i < m.n; ++i)
    if (b.in_stencil(i)) EXPECT_EQ(b.start[i + 1], b.start[i]) << i;
}

// The rows stored beside the stencil are summed kLanes at a time in groups
// (BendingMatrix::Groups): each still sums its own entries in their order,
// so a row gives the bits of a row summed alone, and any cut of the
// particles (as threads make) the bits of none.
TEST(QuadraticBending, GroupedRowsGiveTheBitsOfARowAtATime) {
  Simulation sim(small_grid());
  const Model& m = sim.model();
  const BendingMatrix& b = m.topology->bending;
  const BendingMatrix::Groups& g = b.groups;
  ASSERT_FALSE(g.length.empty());
  EXPECT_GT(std::count(g.side_by_side.begin(), g.side_by_side.end(), 1), 0);
  EXPECT_GT(std::count(g.side_by_side.begin(), g.side_by_side.end(), 0), 0);
  jitter(sim, 11);
  const State& s = detail::state(sim);
  Vec3Array f(m.n);
  detail::add_bending_forces(m, s, f);
  int grouped = 0;
  for (std::size_t place = 0; place < g.stored.size(); ++place) {
    const int i = g.stored[place];
    grouped += g.group_of[place] >= 0;
    double sum[3] = {};
    for (int e = b.start[i]; e < b.start[i + 1]; ++e)
      for (int k = 0; k < 3; ++k) sum[k] += b.value[e] * (s.x[b.column[e]][k] - s.x[i][k]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(f[i][k], -1.0 * sum[k]) << i << " " << k;
  }
  EXPECT_GT(grouped, static_cast<int>(g.stored.size()) / 2);
  std::vector<double> x(m.n), whole(m.n, 0.0);
  for (int i = 0; i < m.n; ++i) x[i] = s.x[i][0];
  detail::add_bending_off_diagonal(m, x.data(), whole.data(), 1.0, 0, m.n);
  for (const int cut : {1, 2, 25, 47, m.n / 2, m.n - 3}) {
    std::vector<double> parts(m.n, 0.0);
    detail::add_bending_off_diagonal(m, x.data(), parts.data(), 1.0, 0, cut);
    detail::add_bending_off_diagonal(m, x.data(), parts.data(), 1.0, cut, m.n);
    for (int i = 0; i < m.n; ++i) ASSERT_EQ(parts[i], whole[i]) << "cut " << cut << ", row " << i;
  }
}
