// Moving obstacles: keyframes sampled as a function of time (docs/guide.md
// "Moving obstacles"); the body frame their meshes are queried in.
#include "wetcloth/motion.hpp"

#include <algorithm>
#include <numbers>

namespace wetcloth {

namespace {

constexpr double kRadians = std::numbers::pi / 180;

// Keyframe k's seven numbers: translate then rotate.
Eigen::Matrix<double, 6, 1> values(const Keyframe& k) {
  Eigen::Matrix<double, 6, 1> v;
  v << k.translate[0], k.translate[1], k.translate[2], k.rotate[0], k.rotate[1], k.rotate[2];
  return v;
}

}  // namespace

MotionSample sample_motion(const Motion& motion, double t) {
  MotionSample s;
  const std::vector<Keyframe>& keys = motion.keys;
  if (keys.empty()) return s;
  using V6 = Eigen::Matrix<double, 6, 1>;
  V6 value = values(keys.front()), rate = V6::Zero();
  if (t >= keys.back().time) {
    value = values(keys.back());
  } else if (t > keys.front().time) {
    // The interval [t_k, t_{k+1}) that holds t: at a key, the one it starts.
    const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                        [](double a, const Keyframe& k) { return a < k.time; });
    const std::size_t k = static_cast<std::size_t>(after - keys.begin()) - 1;
    const double t0 = keys[k].time, t1 = keys[k + 1].time, span = t1 - t0;
    const V6 p0 = values(keys[k]), p1 = values(keys[k + 1]);
    const double f = (t - t0) / span;
    if (motion.interpolation == Interpolation::Linear) {
      value = p0 + f * (p1 - p0);
      rate = (p1 - p0) / span;
    } else {
      // Catmull-Rom tangents on uneven keys; zero at the ends (held there).
      const auto tangent = [&](std::size_t j) -> V6 {
        if (j == 0 || j + 1 >= keys.size()) return V6::Zero();
        return (values(keys[j + 1]) - values(keys[j - 1])) / (keys[j + 1].time - keys[j - 1].time);
      };
      const V6 m0 = tangent(k) * span, m1 = tangent(k + 1) * span;
      const double f2 = f * f, f3 = f2 * f;
      value = (2 * f3 - 3 * f2 + 1) * p0 + (f3 - 2 * f2 + f) * m0 + (-2 * f3 + 3 * f2) * p1 +
              (f3 - f2) * m1;
      rate = ((6 * f2 - 6 * f) * p0 + (3 * f2 - 4 * f + 1) * m0 + (-6 * f2 + 6 * f) * p1 +
              (3 * f2 - 2 * f) * m1) /
             span;
    }
  }
  s.translate = value.head<3>();
  s.rotate = value.tail<3>();
  s.translate_rate = rate.head<3>();
  s.rotate_rate = rate.tail<3>();
  return s;
}

Mat3 rotation_degrees(const Vec3& d) {
  return (Eigen::AngleAxisd(d[2] * kRadians, Vec3::UnitZ()) *
          Eigen::AngleAxisd(d[1] * kRadians, Vec3::UnitY()) *
          Eigen::AngleAxisd(d[0] * kRadians, Vec3::UnitX()))
      .toRotationMatrix();
}

Vec3 angular_velocity(const Vec3& d, const Vec3& rate) {
  // R = Rz(c) Ry(b) Rx(a): ω = ċ z + ḃ Rz(c) y + ȧ Rz(c) Ry(b) x.
  const Eigen::AngleAxisd rz(d[2] * kRadians, Vec3::UnitZ());
  const Eigen::AngleAxisd ry(d[1] * kRadians, Vec3::UnitY());
  return kRadians * (rate[2] * Vec3::UnitZ() + rate[1] * (rz * Vec3::UnitY()) +
                     rate[0] * ((rz * ry) * Vec3::UnitX()));
}

RigidPose motion_pose(const Motion& motion, const Vec3& pivot, double t) {
  RigidPose pose;
  if (!motion.moves()) return pose;
  const MotionSample s = sample_motion(motion, t);
  pose.moving = true;
  pose.rotation = rotation_degrees(s.rotate);
  pose.shift = s.translate;
  pose.pivot = pivot;
  pose.velocity = s.translate_rate;
  pose.spin = angular_velocity(s.rotate, s.rotate_rate);
  return pose;
}

RigidPose ball_pose(const Params& p, double t) {
  return motion_pose(p.ball.motion, to_vec(p.ball.center), t);
}

Vec3 place_obstacle_point(const ObstacleParams& o, const Vec3& p) {
  // y-up: (x, y, z) -> (x, -z, y), the turn of +90° about x.
  const Vec3 up = o.up == UpAxis::Y ? Vec3(p.x(), -p.z(), p.y()) : p;
  return rotation_degrees(to_vec(o.rotate)) * Vec3(up.cwiseProduct(to_vec(o.scale))) +
         to_vec(o.translate);
}

RigidPose obstacle_pose(const Params& p, const std::string& name, double t) {
  const ObstacleParams& o = p.obstacles.at(name);
  return motion_pose(o.motion, place_obstacle_point(o, to_vec(o.pivot)), t);
}

}  // namespace wetcloth
