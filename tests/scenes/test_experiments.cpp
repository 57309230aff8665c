// The paper's experiments (section 4) at a coarser grid (25 x 25), the same
// material: the trends of docs/model.md section 11 as humidity rises.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common.hpp"

using namespace wetcloth;

namespace {

const std::vector<double> kHumidities = {0.3, 0.5, 0.7, 1.0};

std::vector<Metrics> final_metrics(const std::string& scene, std::vector<std::string> sets = {}) {
  std::vector<Metrics> out;
  for (double w : kHumidities) {
    auto s = sets;
    s.push_back("cloth.humidity=" + std::to_string(w));
    Params p = test::coarse(scene, s);
    Simulation sim(p);
    EXPECT_TRUE(sim.advance_to(p.run.duration))
        << scene << " ω=" << w << ": " << sim.blow_up_reason();
    out.push_back(sim.metrics());
  }
  return out;
}

template <class T, class F>
void expect_falling(const std::vector<T>& ms, F value, const char* what) {
  for (std::size_t k = 1; k < ms.size(); ++k)
    EXPECT_LT(value(ms[k]), value(ms[k - 1]))
        << what << " should fall from ω=" << kHumidities[k - 1] << " to ω=" << kHumidities[k];
}

// A scene a hand drives (a move handle with a travel): the hand's mean force
// over its travel (the work per metre, from its force every frame, as
// metrics.csv has it) and the metrics when it stops.
struct Hand {
  double travel_force = 0;
  Metrics at_stop;
};

std::vector<Hand> driven(const std::string& scene) {
  std::vector<Hand> out;
  for (double w : kHumidities) {
    Params p = test::coarse(scene, {"cloth.humidity=" + std::to_string(w)});
    const HandleParams& h = p.handles.begin()->second;
    const double speed = std::hypot(h.velocity[0], h.velocity[1], h.velocity[2]);
    const int frames = static_cast<int>(std::lround(h.max_travel / speed * p.run.fps));
    Simulation sim(p);
    Hand hand;
    for (int f = 1; f <= frames; ++f) {
      EXPECT_TRUE(sim.advance_to(f / p.run.fps))
          << scene << " ω=" << w << ": " << sim.blow_up_reason();
      hand.travel_force += sim.metrics().handle_force_n / frames;
    }
    hand.at_stop = sim.metrics();
    out.push_back(hand);
  }
  return out;
}

}  // namespace

// The base diagonal is the lifted footprint's, so it moves in steps of the
// grid's diagonal, l √2 = 17.7 mm at 25 x 25. From ω = 0.3 to 0.5 it fell
// 25 mm with Provot's bending; with the quadratic bending it changes by less
// than a step at this grid (+3.6 mm at 25, -24 mm at 31, -0.3 mm at 35), and
// falls 22 mm at 51 x 51 (validation/report.md checks the claim at 51 and
// 101). Here: within a step from 0.3 to 0.5, falling from there on.
TEST(Experiments, StraightPullHeightAndBaseFallWithHumidity) {
  const auto ms = final_metrics("pull-straight");
  expect_falling(
      ms, [](const Metrics& m) { return m.handle_height_m; }, "handle height");
  const std::vector<Metrics> wetter(ms.begin() + 1, ms.end());
  for (std::size_t k = 1; k < wetter.size(); ++k)
    EXPECT_LT(wetter[k].base_diagonal_m, wetter[k - 1].base_diagonal_m)
        << "base diagonal should fall from ω=" << kHumidities[k] << " to ω=" << kHumidities[k + 1];
  const double step = 0.3 / 24 * std::sqrt(2.0);
  EXPECT_LT(ms[1].base_diagonal_m, ms[0].base_diagonal_m + step);
}

TEST(Experiments, CornerPullLiftsLessWithHumidity) {
  const auto ms = final_metrics("pull-corner");
  expect_falling(
      ms, [](const Metrics& m) { return m.lifted_area_m2; }, "lifted area");
}

// Section 1: a wetter cloth takes more force to drag, and slides less as a whole.
TEST(Experiments, DraggedCornerTakesMoreForceAndSlidesLessWithHumidity) {
  const auto hands = driven("drag-corner");
  expect_falling(
      hands, [](const Hand& h) { return -h.travel_force; }, "minus the hand's force");
  // The cloth starts centred on the origin: the centroid's offset is the slid distance.
  expect_falling(
      hands,
      [](const Hand& h) { return std::hypot(h.at_stop.centroid_x_m, h.at_stop.centroid_y_m); },
      "slid distance");
}

// Fig. 2: a wetter cloth is harder to pull up obliquely: more force for the
// same travel, and less of it lifted.
TEST(Experiments, ObliquePullTakesMoreForceAndLiftsLessWithHumidity) {
  const auto hands = driven("pull-oblique");
  expect_falling(
      hands, [](const Hand& h) { return -h.travel_force; }, "minus the hand's force");
  expect_falling(
      hands, [](const Hand& h) { return h.at_stop.lifted_area_m2; }, "lifted area");
}

TEST(Experiments, SealedAirHoldsALargerDeficitThanExchange) {
  double deficit[2];
  int k = 0;
  for (const char* model : {"exchange", "sealed"}) {
    Params p =
        test::coarse("pull-straight", {std::string("air.model=") + model, "run.duration=1.0"});
    Simulation sim(p);
    ASSERT_TRUE(sim.advance_to(p.run.duration)) << sim.blow_up_reason();
    deficit[k++] = p.air.p_atm - sim.state().inner_pressure;
  }
  EXPECT_GT(deficit[1], 10 * deficit[0]);
}

// x -> -x, y -> -y and x <-> y map the straight pull onto itself, and the
// discretisation keeps that to rounding. (Later, a particle that crosses the
// liquid-bridge threshold one step earlier on one side than its mirror image
// turns a rounding difference into a visible one: the contact switch is
// discontinuous, so the test looks before the first such crossing.)
TEST(Experiments, StraightPullStaysFourFoldSymmetric) {
  Simulation sim(test::coarse("pull-straight", {"cloth.humidity=0.7"}));
  ASSERT_TRUE(sim.advance_to(0.5));
  const Model& m = sim.model();
  const auto& x = sim.state().x;
  double worst = 0;
  for (int j = 0; j < m.nv; ++j)
    for (int i = 0; i < m.nu; ++i) {
      const Vec3& a = x[m.index(i, j)];
      const Vec3& mx = x[m.index(m.nu - 1 - i, j)];
      const Vec3& my = x[m.index(i, m.nv - 1 - j)];
      const Vec3& t = x[m.index(j, i)];
      worst = std::max({worst, (a - Vec3(-mx.x(), mx.y(), mx.z())).norm(),
                        (a - Vec3(my.x(), -my.y(), my.z())).norm(),
                        (a - Vec3(t.y(), t.x(), t.z())).norm()});
    }
  EXPECT_GT(sim.metrics().handle_height_m, 0.01);
  EXPECT_LT(worst, 1e-9);  // 10 nm against a 2 cm tent
}
