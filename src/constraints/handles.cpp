// Handles (docs/model.md section 9): how scenes pull, drive and pin the cloth.
#include <algorithm>
#include <cmath>

#include "detail.hpp"

namespace wetcloth::detail {

namespace {
bool active(const Handle& h, const State& s) { return s.time >= h.start; }
// Where a handle's particle e starts its path: its rest position, or for a
// handle that starts late (held from then on), where it was at `start`.
const Vec3& origin(const Handle& h, const State& s, std::size_t e) {
  return h.start > 0 ? s.held_at[h.particles[e]] : h.anchor[e];
}
// A pin's or move handle's particle e where its path has it now.
void put_on_path(const Handle& h, State& s, std::size_t e) {
  const int k = h.particles[e];
  if (h.type == HandleType::Pin) {
    s.x[k] = origin(h, s, e);
    s.v[k].setZero();
    return;
  }
  // Its time on the path, which ends after max_travel.
  const double t = std::max(0.0, s.time - h.start), speed = h.velocity.norm();
  const bool moving = active(h, s) && !(h.max_travel > 0 && speed * t >= h.max_travel);
  const double on_path = h.max_travel > 0 && speed > 0 ? std::min(t, h.max_travel / speed) : t;
  s.x[k] = origin(h, s, e) + h.velocity * on_path;
  s.v[k] = moving ? h.velocity : Vec3::Zero();
}

double height(const Model& m, const Vec3& x) {
  return m.params.table.enabled ? x.z() - m.params.table.height : x.z();
}
}  // namespace

void add_handle_forces(const Model& m, const State& s, Workspace& w) {
  for (const Handle& h : m.handles) {
    if (h.type != HandleType::Force || !active(h, s) || s.held[h.particles[0]]) continue;
    for (std::size_t e = 0; e < h.particles.size(); ++e)
      w.force[h.particles[e]] += h.share[e] * h.force;
  }
  if (w.grab_particle >= 0) {
    const int k = w.grab_particle;
    w.force[k] +=
        w.grab_k * (w.grab_target - s.x[k]) - 2.0 * std::sqrt(w.grab_k * m.mass[k]) * s.v[k];
  }
}

// After integration: pinned particles stay at their anchors, moved ones follow
// their path; the force the rig exerts is minus the sum of the other forces on
// the particles it drives (they do not accelerate).
void apply_handle_constraints(const Model& m, State& s, Workspace& w) {
  // The force recorded is the measured handle's, the one whose height the
  // metrics give (zero before it starts).
  w.handle_force = Vec3::Zero();
  const Handle* measured = m.measured_handle >= 0 ? &m.handles[m.measured_handle] : nullptr;
  for (const Handle& h : m.handles) {
    if (h.type == HandleType::Force) {
      if ((h.max_height > 0 || h.max_travel > 0) && !s.held[h.particles[0]]) {
        // A height cap or a travel limit: the hand stops there, and holds.
        double z = 0;
        Vec3 moved = Vec3::Zero();
        for (std::size_t e = 0; e < h.particles.size(); ++e) {
          z += height(m, s.x[h.particles[e]]);
          moved += s.x[h.particles[e]] - h.anchor[e];
        }
        const double n = static_cast<double>(h.particles.size());
        if ((h.max_height > 0 && z / n >= h.max_height) ||
            (h.max_travel > 0 && moved.norm() / n >= h.max_travel))
          for (int k : h.particles) {
            s.held[k] = 1;
            s.held_at[k] = s.x[k];
          }
      }
      if (&h == measured && active(h, s)) {
        Vec3 rig = h.force;
        if (s.held[h.particles[0]]) {  // holding: minus the other forces on the patch
          rig.setZero();
          for (int k : h.particles) rig -= w.force[k];
        }
        w.handle_force = rig;
      }
      continue;
    }
    // Pins and move handles. A late one leaves its particles free until it
    // starts, then takes them where they are and holds them on its path
    // (hold_stopped_handles puts them there again at the end of the step).
    if (h.start > 0) {
      if (!active(h, s)) continue;
      for (int k : h.particles)
        if (!s.held[k]) {
          s.held[k] = 1;
          s.held_at[k] = s.x[k];
        }
    }
    Vec3 rig = Vec3::Zero();
    for (std::size_t e = 0; e < h.particles.size(); ++e) {
      const int k = h.particles[e];
      rig -= w.force[k];
      put_on_path(h, s, e);
    }
    if (&h == measured) w.handle_force = rig;
  }
}

// The measured handle's force also holds its particles against the strain
// limiter's corrections (docs/model.md section 2): limit_strain recorded, for each
// pinned, driven or held particle, minus the momentum its corrections gave the
// free particles, over dt².
void add_strain_limit_reaction(const Model& m, const State& s, Workspace& w) {
  if (m.measured_handle < 0 || w.strain_reacting.empty()) return;
  const Handle& h = m.handles[m.measured_handle];
  const bool holds = h.type == HandleType::Force ? s.held[h.particles[0]] != 0 : active(h, s);
  if (!holds) return;  // a force handle that pulls records its own force
  for (const int k : h.particles) w.handle_force -= w.strain_reaction[k];
}

void hold_stopped_handles(const Model& m, State& s) {
  // Force handles first: a particle a late pin or move handle shares with one
  // follows the path, whatever the handles' names.
  for (const bool forces : {true, false})
    for (const Handle& h : m.handles) {
      if ((h.type == HandleType::Force) != forces) continue;
      for (std::size_t e = 0; e < h.particles.size(); ++e) {
        const int k = h.particles[e];
        if (!s.held[k]) continue;
        if (forces) {
          s.x[k] = s.held_at[k];
          s.v[k].setZero();
        } else {
          put_on_path(h, s, e);
        }
      }
    }
}

}  // namespace wetcloth::detail
