// The surfaces and the contact region (src/contact/surfaces.cpp): distances to
// the table and the ball, collision, which particles are in contact and which
// of them are its border.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "common.hpp"
#include "detail.hpp"
#include "wet_setups.hpp"

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
  State& s = detail::state(sim);
  s.x[0].z() = -0.01;
  s.v[0] = Vec3(0.5, 0, -2);
  detail::collide(sim.model(), s, nullptr);
  EXPECT_EQ(s.x[0].z(), 0.0);
  EXPECT_EQ(s.v[0], Vec3(0.5, 0, 0));
}

// The table alone takes a loop of its own, without branches; it must do what
// the general loop does (here with a ball too far away to touch), to the bit,
// touched flags and driven particles included.
TEST(Surfaces, TableAloneCollidesAsTheGeneralLoopDoes) {
  Params p = test::bare(6);
  p.table.enabled = true;
  p.handles["pin"].type = HandleType::Pin;
  p.handles["pin"].at = {0, 0};
  Simulation table_only(p);
  p.ball.enabled = true;
  p.ball.center = {5, 5, 5};
  Simulation with_ball(p);
  ASSERT_TRUE(table_only.model().driven[0]);
  State& a = detail::state(table_only);
  for (int i = 0; i < table_only.model().n; ++i) {
    a.x[i].z() = 0.01 * std::sin(2.3 * i + 4);  // particle 0 below the table
    a.v[i] = Vec3(std::cos(i), std::sin(1.7 * i), std::cos(0.9 * i));
  }
  State b = a;
  std::vector<std::uint8_t> touched_a(a.x.size(), 7), touched_b(a.x.size(), 7);
  detail::collide(table_only.model(), a, &touched_a);
  detail::collide(with_ball.model(), b, &touched_b);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(touched_a, touched_b);
  EXPECT_LT(a.x[0].z(), 0);  // driven: never moved
  int pushed = 0;
  for (std::uint8_t t : touched_a) pushed += t == static_cast<std::uint8_t>(SurfaceKind::Table);
  EXPECT_GT(pushed, 5);
}

// The contact border (eq. 13's edge term) is every contact particle on the
// cloth's border or next to a lifted one (4-neighbours), on any grid shape.
TEST(Contact, BorderIsContactOnTheClothsBorderOrNextToLifted) {
  for (const auto& [nu, nv] : {std::pair{2, 7}, {7, 2}, {3, 3}, {9, 6}, {51, 51}}) {
    Simulation sim = test::flat_on_table(
        1.0, {"cloth.resolution=[" + std::to_string(nu) + "," + std::to_string(nv) + "]"});
    const Model& m = sim.model();
    State& s = detail::state(sim);
    const double h_th = m.params.contact.bridge_height;
    unsigned pattern = 12345;  // a fixed pseudo-random third of the particles lifted
    for (auto&& x : s.x) {
      pattern = pattern * 1103515245u + 12345u;
      x.z() = (pattern >> 16) % 3 == 0 ? 2 * h_th : 0.0;
    }
    Workspace& w = detail::workspace(sim);
    detail::update_contact(m, s, w);
    int borders = 0;
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const int k = m.index(i, j);
        ASSERT_EQ(s.contact[k] != 0, s.x[k].z() < h_th);
        bool expected = false;
        if (s.contact[k]) {
          expected = i == 0 || j == 0 || i == nu - 1 || j == nv - 1;
          for (const auto& [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}})
            if (const int b = detail::grid_neighbour(m, i, j, di, dj); b >= 0 && !s.contact[b])
              expected = true;
        }
        EXPECT_EQ(w.border[k] != 0, expected)
            << nu << " x " << nv << " at (" << i << ", " << j << ")";
        borders += expected;
      }
    EXPECT_GT(borders, 0);
  }
}

TEST(Contact, ClothRestingOnTheTableDoesNotDrift) {
  Simulation sim = test::flat_on_table(0.5, {"cloth.resolution=[21,21]"});
  const Metrics m0 = sim.metrics();
  ASSERT_TRUE(sim.advance_to(1.0));
  const Metrics m1 = sim.metrics();
  EXPECT_NEAR(m1.centroid_x_m, m0.centroid_x_m, 1e-9);
  EXPECT_NEAR(m1.centroid_y_m, m0.centroid_y_m, 1e-9);
  EXPECT_LT(m1.kinetic_energy_j, 1e-12);
  EXPECT_NEAR(m1.contact_area_m2, 0.09, 1e-12);
}
