// Moving obstacles (docs/guide.md "Moving obstacles", docs/model.md section 3):
// a rigid motion by keyframes, as a function of time, and how a body's points
// and velocities follow it. A function of time alone: a run resumed from a
// checkpoint, or stepped on any number of threads, sees the same motion.
#pragma once

#include "wetcloth/params.hpp"
#include "wetcloth/simulation.hpp"

namespace wetcloth {

// A motion's translation (m) and rotation angles (degrees about x, y, z) at
// time t, and their rates (m/s, degrees/s). Linear: straight between keys,
// the rates constant on each interval (the next one's at a key). Smooth: a
// cubic Hermite spline through the keys with Catmull-Rom tangents, (p_{k+1} -
// p_{k-1}) / (t_{k+1} - t_{k-1}), and zero at the first and last keys, so
// that the body starts and stops without a jolt. Held at the first key before
// it and at the last after it, with zero rates.
struct MotionSample {
  Vec3 translate = Vec3::Zero(), rotate = Vec3::Zero();
  Vec3 translate_rate = Vec3::Zero(), rotate_rate = Vec3::Zero();
};
MotionSample sample_motion(const Motion& motion, double t);

// The rotation R = Rz Ry Rx of angles in degrees about x, then y, then z
// (fixed axes), as obstacle.NAME.rotate turns a mesh.
Mat3 rotation_degrees(const Vec3& degrees);
// The angular velocity (rad/s) of R(angles(t)) for angles and their rates in degrees.
Vec3 angular_velocity(const Vec3& degrees, const Vec3& degrees_rate);

// A body's rigid placement at one time. A point x0 of the body where it
// stands still (its keys' placement) is at R (x0 - pivot) + pivot + shift;
// the body's velocity at a point x is velocity + spin × (x - pivot - shift).
struct RigidPose {
  bool moving = false;  // false: the identity, standing still
  Mat3 rotation = Mat3::Identity();
  Vec3 shift = Vec3::Zero(), pivot = Vec3::Zero();
  Vec3 velocity = Vec3::Zero(), spin = Vec3::Zero();  // m/s of the pivot; rad/s
  Vec3 to_world(const Vec3& x0) const {
    return moving ? Vec3(rotation * (x0 - pivot) + pivot + shift) : x0;
  }
  Vec3 to_body(const Vec3& x) const {
    return moving ? Vec3(rotation.transpose() * (x - pivot - shift) + pivot) : x;
  }
  Vec3 velocity_at(const Vec3& x) const {
    return moving ? Vec3(velocity + spin.cross(x - pivot - shift)) : Vec3::Zero();
  }
};
RigidPose motion_pose(const Motion& motion, const Vec3& pivot, double t);

// The ball at time t (its motion turns it about its centre), and obstacle
// NAME (about its pivot, placed with the mesh).
RigidPose ball_pose(const Params& p, double t);
RigidPose obstacle_pose(const Params& p, const std::string& name, double t);

// Where obstacle NAME's keys place a point p of its file (up, scale, rotate,
// translate), before any motion.
Vec3 place_obstacle_point(const ObstacleParams& o, const Vec3& p);

}  // namespace wetcloth
