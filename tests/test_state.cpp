// State is the whole state of a run: a copy taken at t and restored into a
// fresh Simulation of the same scene continues with the same bits, on every
// integrator and with every wet effect the scenes switch on.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "common.hpp"

namespace wetcloth {
namespace {

struct Case {
  const char* scene;
  std::vector<std::string> sets;
  double t_copy, t_end;
};

void PrintTo(const Case& c, std::ostream* o) {
  *o << c.scene;
  for (const auto& s : c.sets) *o << " " << s;
}

class Restore : public ::testing::TestWithParam<Case> {};

TEST_P(Restore, ContinuesWithTheSameBits) {
  const Case& c = GetParam();
  std::vector<std::string> sets = c.sets;
  sets.insert(sets.begin(), "cloth.resolution=[15,15]");
  const Params p = load_scene(c.scene, sets);
  Simulation first(p);
  ASSERT_TRUE(first.advance_to(c.t_copy)) << first.blow_up_reason();
  const State copy = first.state();
  ASSERT_TRUE(first.advance_to(c.t_end)) << first.blow_up_reason();

  Simulation second(p);
  second.advance_to(0.25 * c.t_copy);  // a different history, overwritten
  second.restore(copy);
  ASSERT_TRUE(second.advance_to(c.t_end)) << second.blow_up_reason();
  EXPECT_EQ(second.state().steps, first.state().steps);
  EXPECT_TRUE(test::same_bits(second.state().x, first.state().x));
  EXPECT_TRUE(test::same_bits(second.state().v, first.state().v));
  EXPECT_EQ(second.state().inner_pressure, first.state().inner_pressure);
  EXPECT_EQ(second.metrics().handle_force_n, first.metrics().handle_force_n);
}

const std::string kImplicit = "integrator.type=\"implicit-euler\"";
const std::string kXpbd = "integrator.type=\"xpbd\"";
const std::string kLarge = "integrator.dt=0.004166666666666667";

INSTANTIATE_TEST_SUITE_P(Scenes, Restore,
                         ::testing::Values(Case{"pull-straight", {}, 0.1, 0.2},  // exchange air
                                           Case{"drape-ball", {}, 0.2, 0.3},     // vented air, ball
                                           Case{"pull-oblique", {}, 0.1, 0.2},   // a move handle
                                           Case{"hang",
                                                {"self_collision.enabled=true"},
                                                0.2,
                                                0.3},  // pins, self-collision
                                           Case{"pull-straight", {kImplicit, kLarge}, 0.1, 0.2},
                                           Case{"drape-ball", {kImplicit, kLarge}, 0.2, 0.3},
                                           Case{"pull-straight", {kXpbd, kLarge}, 0.1, 0.2},
                                           Case{"drape-ball", {kXpbd, kLarge}, 0.2, 0.3}));

TEST(Restore, RefusesAStateOfAnotherGrid) {
  Simulation small(test::bare(3)), large(test::bare(4));
  EXPECT_THROW(large.restore(small.state()), std::invalid_argument);
}

}  // namespace
}  // namespace wetcloth
