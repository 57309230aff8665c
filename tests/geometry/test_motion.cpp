// Moving obstacles' keyframes (src/geometry/motion.cpp): exact at the keys,
// the linear and the smooth spline's values and rates between them, the
// angular velocity of the Euler angles; a rigid mesh queried in its body
// frame gives what a mesh rebuilt where it is gives.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "common.hpp"
#include "detail.hpp"
#include "geometry/mesh_obstacle.hpp"
#include "wetcloth/motion.hpp"

using namespace wetcloth;

namespace {

Motion three_keys(Interpolation how) {
  Motion m;
  m.interpolation = how;
  m.keys = {{0.5, {0, 0, 0}, {0, 0, 0}},
            {1.5, {0.2, -0.1, 0.3}, {10, 20, 30}},
            {2.0, {0.4, 0.1, 0.3}, {0, 90, 45}}};
  return m;
}

Vec3 translate_of(const Keyframe& k) { return to_vec(k.translate); }
Vec3 rotate_of(const Keyframe& k) { return to_vec(k.rotate); }

}  // namespace

TEST(Motion, ExactAtTheKeysAndHeldBeyondThem) {
  for (const Interpolation how : {Interpolation::Linear, Interpolation::Smooth}) {
    const Motion m = three_keys(how);
    for (const Keyframe& k : m.keys) {
      const MotionSample s = sample_motion(m, k.time);
      EXPECT_EQ(s.translate, translate_of(k)) << k.time;
      EXPECT_EQ(s.rotate, rotate_of(k)) << k.time;
    }
    for (const double t : {-1.0, 0.0, 0.4999}) {
      EXPECT_EQ(sample_motion(m, t).translate, translate_of(m.keys.front()));
      EXPECT_EQ(sample_motion(m, t).translate_rate, Vec3::Zero());
    }
    for (const double t : {2.0, 2.5, 100.0}) {
      EXPECT_EQ(sample_motion(m, t).translate, translate_of(m.keys.back()));
      EXPECT_EQ(sample_motion(m, t).rotate_rate, Vec3::Zero());
    }
    EXPECT_EQ(sample_motion(Motion{}, 1.0).translate, Vec3::Zero());  // no keys: still
  }
}

TEST(Motion, LinearIsTheMeanAtMidpointsWithConstantRates) {
  const Motion m = three_keys(Interpolation::Linear);
  for (std::size_t k = 0; k + 1 < m.keys.size(); ++k) {
    const Keyframe &a = m.keys[k], &b = m.keys[k + 1];
    const double span = b.time - a.time;
    for (const double f : {0.25, 0.5, 0.75}) {
      const MotionSample s = sample_motion(m, a.time + f * span);
      EXPECT_LT((s.translate - (translate_of(a) + f * (translate_of(b) - translate_of(a)))).norm(),
                1e-15);
      EXPECT_LT((s.rotate - (rotate_of(a) + f * (rotate_of(b) - rotate_of(a)))).norm(), 1e-13);
      EXPECT_LT((s.translate_rate - (translate_of(b) - translate_of(a)) / span).norm(), 1e-14);
    }
  }
  // At a key the rate is the next interval's.
  const MotionSample at = sample_motion(m, 1.5);
  EXPECT_LT((at.translate_rate - (translate_of(m.keys[2]) - translate_of(m.keys[1])) / 0.5).norm(),
            1e-14);
}

// The cubic Hermite spline: at a midpoint (p0 + p1)/2 + (m0 - m1) Δt / 8, with
// Catmull-Rom tangents (p_{k+1} - p_{k-1}) / (t_{k+1} - t_{k-1}), zero at the
// ends; its rate is zero at the first and last keys, the tangent at the inner
// one, and the difference quotient of its values.
TEST(Motion, SmoothMidpointsAndRatesAreTheHermiteSplines) {
  const Motion m = three_keys(Interpolation::Smooth);
  const Vec3 p0 = translate_of(m.keys[0]), p1 = translate_of(m.keys[1]),
             p2 = translate_of(m.keys[2]);
  const Vec3 m1 = (p2 - p0) / (2.0 - 0.5);  // the inner key's tangent
  EXPECT_LT(
      (sample_motion(m, 1.0).translate - ((p0 + p1) / 2 + (Vec3::Zero() - m1) * 1.0 / 8)).norm(),
      1e-15);
  EXPECT_LT(
      (sample_motion(m, 1.75).translate - ((p1 + p2) / 2 + (m1 - Vec3::Zero()) * 0.5 / 8)).norm(),
      1e-15);
  EXPECT_LT(sample_motion(m, 0.5).translate_rate.norm(), 1e-15);
  EXPECT_LT((sample_motion(m, 1.5).translate_rate - m1).norm(), 1e-14);
  EXPECT_LT((sample_motion(m, 1.5 - 1e-12).translate_rate - m1).norm(), 1e-9);  // C1 across it
  for (const double t : {0.7, 1.2, 1.6, 1.9}) {
    const double e = 1e-6;
    const MotionSample s = sample_motion(m, t);
    const Vec3 quotient =
        (sample_motion(m, t + e).translate - sample_motion(m, t - e).translate) / (2 * e);
    EXPECT_LT((s.translate_rate - quotient).norm(), 1e-7) << t;
    const Vec3 turn = (sample_motion(m, t + e).rotate - sample_motion(m, t - e).rotate) / (2 * e);
    EXPECT_LT((s.rotate_rate - turn).norm(), 1e-5) << t;
  }
}

// ω from the Euler angles' rates: Ṙ Rᵀ is [ω]×, checked by differences.
TEST(Motion, AngularVelocityIsTheRotationsRate) {
  const Motion m = three_keys(Interpolation::Smooth);
  for (const double t : {0.8, 1.3, 1.8}) {
    const double e = 1e-6;
    const Mat3 dR = (rotation_degrees(sample_motion(m, t + e).rotate) -
                     rotation_degrees(sample_motion(m, t - e).rotate)) /
                    (2 * e);
    const Mat3 W = dR * rotation_degrees(sample_motion(m, t).rotate).transpose();
    const Vec3 omega(W(2, 1), W(0, 2), W(1, 0));
    const MotionSample s = sample_motion(m, t);
    EXPECT_LT((angular_velocity(s.rotate, s.rotate_rate) - omega).norm(), 1e-6) << t;
  }
}

// A rigid pose: the body's point moves with velocity_at (a difference of
// to_world over time), and to_body undoes to_world.
TEST(Motion, PoseMovesPointsAtItsVelocity) {
  const Motion m = three_keys(Interpolation::Smooth);
  const Vec3 pivot(0.1, 0.2, -0.3), x0(0.4, -0.2, 0.5);
  for (const double t : {0.9, 1.7}) {
    const RigidPose pose = motion_pose(m, pivot, t);
    const double e = 1e-6;
    const Vec3 moved =
        (motion_pose(m, pivot, t + e).to_world(x0) - motion_pose(m, pivot, t - e).to_world(x0)) /
        (2 * e);
    EXPECT_LT((pose.velocity_at(pose.to_world(x0)) - moved).norm(), 1e-7) << t;
    EXPECT_LT((pose.to_body(pose.to_world(x0)) - x0).norm(), 1e-15) << t;
  }
  EXPECT_FALSE(motion_pose(Motion{}, pivot, 1.0).moving);
}

// A mesh obstacle moved rigidly is queried in its body frame: the same
// distances and normals as the mesh rebuilt where the motion puts it.
TEST(Motion, BodyFrameQueryEqualsTheRebuiltMesh) {
  Params p = load_scene("arm-swing");
  ObstacleParams& arm = p.obstacles.at("arm");
  for (const double t : {0.3, 0.75, 1.2}) {
    const RigidPose pose = obstacle_pose(p, "arm", t);
    ASSERT_TRUE(pose.moving);
    // The rebuilt mesh: its keys and the motion composed into one placement
    // (rotation about the pivot, then the shift).
    const MotionSample s = sample_motion(arm.motion, t);
    Params rebuilt = p;
    ObstacleParams& there = rebuilt.obstacles.at("arm");
    const Mat3 R = rotation_degrees(s.rotate) * rotation_degrees(to_vec(arm.rotate));
    const Eigen::Vector3d euler = R.eulerAngles(2, 1, 0) * 180 / std::numbers::pi;  // z, y, x
    there.rotate = {euler[2], euler[1], euler[0]};
    const Vec3 T = pose.to_world(to_vec(arm.translate));  // where the file's origin goes
    there.translate = {T.x(), T.y(), T.z()};
    there.motion = Motion{};
    const auto moving = build_mesh_obstacle(p, "arm");
    const auto placed = build_mesh_obstacle(rebuilt, "arm");
    int n = 0;
    for (double x = -0.3; x <= 0.3; x += 0.05)
      for (double z = 0.2; z <= 0.4; z += 0.025) {
        const Vec3 q(x, 0.01 * (n++ % 11) - 0.047, z);  // off the axis: no ties
        const MeshObstacle::Hit a =
            detail::query_mesh(*moving, &pose, q, MeshObstacle::kWhole, nullptr, 0);
        const MeshObstacle::Hit b = placed->query(q);
        EXPECT_NEAR(a.distance, b.distance, 1e-12) << q.transpose() << " t = " << t;
        EXPECT_LT((a.normal - b.normal).norm(), 1e-9) << q.transpose();
        // And its surface's velocity is the rebuilt mesh's closest point's.
        const Vec3 on = q - b.distance * b.normal;
        EXPECT_LT(
            (pose.velocity_at(on) - (obstacle_pose(p, "arm", t + 1e-6).to_world(pose.to_body(on)) -
                                     obstacle_pose(p, "arm", t - 1e-6).to_world(pose.to_body(on))) /
                                        2e-6)
                .norm(),
            1e-6);
      }
  }
}
