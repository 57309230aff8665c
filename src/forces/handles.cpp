// Handles (MODEL.md section 9): how scenes pull, drive and pin the cloth.
#include <cmath>

#include "../detail.hpp"

namespace wetcloth::detail {

namespace {
bool active(const Handle& h, const State& s) { return s.time >= h.start; }
double height(const Model& m, const Vec3& x) {
  return m.params.table.enabled ? x.z() - m.params.table.height : x.z();
}
}  // namespace

void add_handle_forces(const Model& m, const State& s, Workspace& w) {
  for (const Handle& h : m.handles) {
    if (h.type != HandleType::Force || !active(h, s)) continue;
    for (int k : h.particles) {
      // A height cap stops the pull where the hand stops.
      if (h.max_height > 0 && height(m, s.x[k]) >= h.max_height && h.force_per_particle.z() > 0)
        continue;
      w.force[k] += h.force_per_particle;
    }
  }
  if (w.grab_particle >= 0) {
    const int k = w.grab_particle;
    w.force[k] += w.grab_k * (w.grab_target - s.x[k]) - 2.0 * std::sqrt(w.grab_k * m.mass[k]) * s.v[k];
  }
}

// After integration: pinned particles stay at their anchors, moved ones follow
// their path; the force the rig exerts is minus the sum of the other forces on
// the particles it drives (they do not accelerate).
void apply_handle_constraints(const Model& m, State& s, Workspace& w) {
  w.handle_force = Vec3::Zero();
  bool recorded = false;
  for (const Handle& h : m.handles) {
    if (h.type == HandleType::Force) {
      if (!recorded && active(h, s)) {
        w.handle_force = h.force_per_particle * static_cast<double>(h.particles.size());
        recorded = true;
      }
      continue;
    }
    const double t = std::max(0.0, s.time - h.start);
    Vec3 rig = Vec3::Zero();
    for (std::size_t e = 0; e < h.particles.size(); ++e) {
      const int k = h.particles[e];
      rig -= w.force[k];
      if (h.type == HandleType::Pin) {
        s.x[k] = h.anchor[e];
        s.v[k].setZero();
      } else {
        // Driven particles: where they were at t = 0 plus the path so far.
        s.x[k] = h.anchor[e] + h.velocity * (s.time >= h.start ? t : 0.0);
        s.v[k] = s.time >= h.start ? h.velocity : Vec3::Zero();
      }
    }
    if (!recorded && h.type == HandleType::Move) {
      w.handle_force = rig;
      recorded = true;
    }
  }
}

}  // namespace wetcloth::detail
