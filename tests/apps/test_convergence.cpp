// How a result converges as the time step shrinks (apps/common/convergence.hpp,
// which `wetcloth converge` reports with).
#include <gtest/gtest.h>

#include <cmath>

#include "common/convergence.hpp"

using namespace wetcloth;

TEST(Convergence, RichardsonRecoversTheOrderAndTheLimit) {
  // f(Δt) = f* + C Δt^p at Δt = 4e-5, 2e-5, 1e-5.
  for (const double p : {1.0, 2.0}) {
    auto f = [p](double dt) { return 0.07 - 3.0 * std::pow(dt * 1e4, p); };
    const Extrapolation e = richardson(f(4e-5), f(2e-5), f(1e-5), 2.0);
    EXPECT_NEAR(e.order, p, 1e-9);
    EXPECT_NEAR(e.limit, 0.07, 1e-12);
  }
  // Differences that grow, or change sign, show no order.
  EXPECT_TRUE(std::isnan(richardson(1.0, 1.1, 1.3, 2.0).order));
  EXPECT_TRUE(std::isnan(richardson(1.0, 1.1, 1.05, 2.0).limit));
  EXPECT_TRUE(std::isnan(richardson(1.0, 1.0, 1.0, 2.0).order));
}

TEST(Convergence, SameToItsDigitsAtEveryStep) {
  // The same, exactly or to the digits printed: converged, no order to observe.
  EXPECT_TRUE(same_to_digits({0.0, 0.0, -0.0}, 5));
  EXPECT_TRUE(same_to_digits({0.08999999999999991, 0.09, 0.09000000000000002}, 5));
  EXPECT_TRUE(same_to_digits({0.12345, 0.123451, 0.1234549}, 5));
  // A difference that shows, a NaN, or fewer than two steps is not.
  EXPECT_FALSE(same_to_digits({0.12345, 0.12346, 0.12346}, 5));
  EXPECT_FALSE(same_to_digits({0.0, 1e-20}, 5));
  EXPECT_FALSE(same_to_digits({std::nan(""), std::nan("")}, 5));
  EXPECT_FALSE(same_to_digits({0.07}, 5));
  EXPECT_FALSE(same_to_digits({}, 5));
}
