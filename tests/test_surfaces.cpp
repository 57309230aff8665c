#include <gtest/gtest.h>

#include "common.hpp"
#include "detail.hpp"

using namespace wetcloth;

TEST(Surfaces, TableAndBallDistances) {
  Params p;
  p.ball.enabled = true;
  p.ball.center = {0, 0, 0.1};
  p.ball.radius = 0.05;
  const auto t = detail::query_surface(p, SurfaceKind::Table, Vec3(1, 2, 0.3));
  EXPECT_DOUBLE_EQ(t.distance, 0.3);
  const auto b = detail::query_surface(p, SurfaceKind::Ball, Vec3(0, 0.08, 0.1));
  EXPECT_NEAR(b.distance, 0.03, 1e-15);
  EXPECT_NEAR((b.normal - Vec3(0, 1, 0)).norm(), 0, 1e-15);
}

TEST(Surfaces, CollisionProjectsOutAndRemovesInwardVelocity) {
  Params p = test::bare(2);
  p.table.enabled = true;
  Simulation sim(p);
  State& s = sim.state();
  s.x[0].z() = -0.01;
  s.v[0] = Vec3(0.5, 0, -2);
  detail::collide(sim.model(), s, nullptr);
  EXPECT_EQ(s.x[0].z(), 0.0);
  EXPECT_EQ(s.v[0], Vec3(0.5, 0, 0));
}
