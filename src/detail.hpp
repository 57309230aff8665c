// Internal: the stages of one step (MODEL.md section 8), one file each.
#pragma once

#include <limits>

#include "wetcloth/simulation.hpp"

namespace wetcloth::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

// surfaces.cpp: signed distance and outward normal of the table and the ball.
struct SurfaceHit {
  double distance = kInf;
  Vec3 normal = Vec3::UnitZ();
};
SurfaceHit query_surface(const Params& p, SurfaceKind kind, const Vec3& x);
// Projects particles out of every obstacle and removes inward normal velocity.
// touched[i] is the obstacle it was pushed out of (SurfaceKind), or None.
void collide(const Model& m, State& s, std::vector<std::uint8_t>* touched);
// Distances to the contact surface, contact flags and the contact border.
void update_contact(const Model& m, State& s, Workspace& w);

// forces/*.cpp: each adds its force into w.force.
// With `damping`, also adds each spring's damping on its own ends' velocities
// (k_d u uᵀ), which the step takes implicitly.
void add_spring_forces(const SpringSet& springs, const std::vector<Vec3>& x,
                       const std::vector<Vec3>& v, std::vector<Vec3>& f,
                       std::vector<Mat3>* damping = nullptr);
void add_gravity(const Model& m, std::vector<Vec3>& f);
void add_viscous_damping(const Model& m, const State& s, std::vector<Vec3>& f);
void add_wind(const Model& m, const State& s, const Workspace& w, std::vector<Vec3>& f);
void add_air_pressure(const Model& m, const State& s, Workspace& w);
void add_adhesion(const Model& m, const State& s, Workspace& w);
void add_self_collision(const Model& m, const State& s, Workspace& w);
void add_handle_forces(const Model& m, const State& s, Workspace& w);

// air.cpp: advances the trapped air over dt (eqs. 2, 4, 5).
void update_air(const Model& m, State& s, Workspace& w, double dt);
// The air term taken implicitly, after the explicit velocity update.
void correct_air_implicitly(const Model& m, State& s, Workspace& w, double dt);
// handles.cpp: pins, driven particles, height caps; records the rig's force.
void apply_handle_constraints(const Model& m, State& s, Workspace& w);
// Keeps the particles of a force handle that reached its height cap where it stopped.
void hold_stopped_handles(const Model& m, State& s);
// friction.cpp: eq. 14 on particles in contact.
void apply_friction(const Model& m, State& s, const Workspace& w,
                    const std::vector<std::uint8_t>& touched, double dt);
// strain_limit.cpp: Provot's correction in adaptive order.
void update_strain_order(const Model& m, State& s, Workspace& w);
void limit_strain(const Model& m, State& s, Workspace& w, double dt);

}  // namespace wetcloth::detail
