// The time step the viewer's panel gives an integrator picked in it.
#pragma once

#include "wetcloth/params.hpp"

namespace wetcloth::viewer {

inline bool takes_large_steps(IntegratorType t) {
  return t == IntegratorType::Xpbd || t == IntegratorType::ImplicitEuler;
}

// The scene's own step when it ran an integrator of the same kind, else the
// kind's: 5e-5 s for the small-step integrators (docs/model.md section 8), 1/240 s
// for xpbd and implicit Euler, which take it in substeps. xpbd kept at 5e-5 s
// would take ten substeps where one is too many, and run slower than the
// explicit step instead of in real time.
inline double step_for_integrator(IntegratorType picked, IntegratorType scene_type,
                                  double scene_dt) {
  if (takes_large_steps(picked) == takes_large_steps(scene_type)) return scene_dt;
  return takes_large_steps(picked) ? 1.0 / 240 : Params{}.integrator.dt;
}

}  // namespace wetcloth::viewer
