// The time step the viewer's panel gives an integrator picked in it.
#pragma once

#include "wetcloth/params.hpp"

namespace wetcloth::viewer {

// The scene's own step when it ran an integrator of the same kind, else the
// kind's for this cloth (default_step): 1/240 s for xpbd and implicit Euler,
// which take it in substeps, and a fraction of the explicit limit for the
// small-step integrators. xpbd kept at 1e-4 s would take ten substeps where
// one is too many, and run slower than the explicit step instead of in real
// time.
inline double step_for_integrator(const Params& picked, IntegratorType scene_type,
                                  double scene_dt) {
  if (takes_large_steps(picked.integrator.type) == takes_large_steps(scene_type)) return scene_dt;
  return default_step(picked);
}

}  // namespace wetcloth::viewer
