// How a result converges as the time step shrinks (`wetcloth converge`).
#pragma once

#include <cmath>
#include <limits>

namespace wetcloth {

// Richardson extrapolation from a result at three time steps, each `ratio`
// times the next: with f(Δt) = f* + C Δt^p, the differences of successive
// results shrink by ratio^p, which gives the observed order p and the limit f*.
// Both are NaN when the differences do not shrink monotonically (no order to
// observe: the results are converged to their noise, or not yet in the
// asymptotic range).
struct Extrapolation {
  double order = std::numeric_limits<double>::quiet_NaN();
  double limit = std::numeric_limits<double>::quiet_NaN();
};

inline Extrapolation richardson(double coarse, double mid, double fine, double ratio) {
  const double a = coarse - mid, b = mid - fine;
  if (!(ratio > 1) || b == 0 || !(a / b > 1)) return {};
  const double p = std::log(a / b) / std::log(ratio);
  return {p, fine - b / (std::pow(ratio, p) - 1)};
}

}  // namespace wetcloth
