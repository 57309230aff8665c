// The paper's experiments (section 4) at a coarser grid (25 x 25), physics
// unchanged: the trends of MODEL.md section 11 as humidity rises.
#include <gtest/gtest.h>

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
    EXPECT_TRUE(sim.advance_to(p.run.duration)) << scene << " ω=" << w << ": " << sim.blow_up_reason();
    out.push_back(sim.metrics());
  }
  return out;
}

template <class F>
void expect_falling(const std::vector<Metrics>& ms, F value, const char* what) {
  for (std::size_t k = 1; k < ms.size(); ++k)
    EXPECT_LT(value(ms[k]), value(ms[k - 1]))
        << what << " should fall from ω=" << kHumidities[k - 1] << " to ω=" << kHumidities[k];
}

}  // namespace

TEST(Experiments, StraightPullHeightAndBaseFallWithHumidity) {
  const auto ms = final_metrics("pull-straight");
  expect_falling(ms, [](const Metrics& m) { return m.handle_height_m; }, "handle height");
  expect_falling(ms, [](const Metrics& m) { return m.base_diagonal_m; }, "base diagonal");
}

TEST(Experiments, CornerPullLiftsLessWithHumidity) {
  const auto ms = final_metrics("pull-corner");
  expect_falling(ms, [](const Metrics& m) { return m.lifted_area_m2; }, "lifted area");
}

TEST(Experiments, DraggedCornerSlidesLessWithHumidity) {
  const auto ms = final_metrics("drag-corner");
  // The cloth starts centred on the origin: the centroid's offset is the slid distance.
  expect_falling(ms, [](const Metrics& m) { return std::hypot(m.centroid_x_m, m.centroid_y_m); },
                 "slid distance");
}

TEST(Experiments, SealedAirHoldsALargerDeficitThanExchange) {
  double deficit[2];
  int k = 0;
  for (const char* model : {"exchange", "sealed"}) {
    Params p = test::coarse("pull-straight", {std::string("air.model=") + model, "run.duration=1.0"});
    Simulation sim(p);
    ASSERT_TRUE(sim.advance_to(p.run.duration)) << sim.blow_up_reason();
    deficit[k++] = p.air.p_atm - sim.state().inner_pressure;
  }
  EXPECT_GT(deficit[1], 10 * deficit[0]);
}
