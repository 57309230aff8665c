// Eq. 14's Coulomb clamp on one particle, in scalars for the vectorised loops
// of friction.cpp and XPBD's contact (integrators/xpbd.cpp).
#pragma once

#include <cmath>

namespace wetcloth::detail {

// The velocity's part along the surface of normal (nx, ny, nz) shrinks by dv
// and never reverses; the move over h is taken back by as much. `acts` (and a
// zero tangential speed) leaves both as they are, without a branch.
inline void coulomb_clamp(double& vx, double& vy, double& vz, double& x, double& y, double& z,
                          double nx, double ny, double nz, double dv, bool acts, double h) {
  const double vn = vx * nx + vy * ny + vz * nz;
  const double tx = vx - vn * nx, ty = vy - vn * ny, tz = vz - vn * nz;
  const double speed = std::sqrt(tx * tx + ty * ty + tz * tz);
  const bool on = acts & (speed > 0);
  const double factor = on ? (dv < speed ? dv : speed) / speed : 0.0;
  const double sx = tx * factor, sy = ty * factor, sz = tz * factor;
  vx -= sx;
  vy -= sy;
  vz -= sz;
  x -= h * sx;
  y -= h * sy;
  z -= h * sz;
}

}  // namespace wetcloth::detail
