// How a result converges as the time step shrinks (`wetcloth converge`).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

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

// Whether a result prints the same, with `digits` significant digits (%.*g),
// at every time step (two or more): converged as far as it shows. Its
// differences are 0, or below what is printed, so Richardson's order there is
// NaN or noise. Minus zero prints as zero.
inline bool same_to_digits(const std::vector<double>& values, int digits) {
  char first[40], next[40];
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i] == 0 ? 0.0 : values[i];
    if (!std::isfinite(v)) return false;
    std::snprintf(i == 0 ? first : next, sizeof first, "%.*g", digits, v);
    if (i > 0 && std::strcmp(first, next) != 0) return false;
  }
  return values.size() >= 2;
}

}  // namespace wetcloth
