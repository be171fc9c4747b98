// The paper's Algorithm 2 (rotation between two vectors), which builds every
// joint's constraint frame: general, parallel and anti-parallel cases.
#include "frames.hpp"

#include <gtest/gtest.h>

namespace afhub::physics {
namespace {

void expect_maps(const btVector3& from, const btVector3& to) {
  const btVector3 turned = quatRotate(rotation_between(from, to), from.normalized());
  EXPECT_NEAR((turned - to.normalized()).length(), 0.0, 1e-12)
      << "from " << from.x() << "," << from.y() << "," << from.z() << " to " << to.x() << ","
      << to.y() << "," << to.z();
}

TEST(RotationBetween, TakesOneVectorOntoAnother) {
  expect_maps({0, 0, 1}, {0, 1, 0});
  expect_maps({1, 2, 3}, {-3, 0.5, 2});
  expect_maps({0, 0, 2}, {1, 1, 1});
}

TEST(RotationBetween, ParallelVectorsGiveTheIdentity) {
  const btQuaternion q = rotation_between({0, 0, 1}, {0, 0, 3});
  EXPECT_NEAR(q.getAngle(), 0.0, 1e-12);
}

TEST(RotationBetween, AntiParallelVectorsTurnHalfWayRoundAPerpendicularAxis) {
  for (const btVector3& from : {btVector3(0, 0, 1), btVector3(1, 0, 0), btVector3(0, -2, 0)}) {
    const btQuaternion q = rotation_between(from, -from);
    EXPECT_NEAR(q.getAngle(), SIMD_PI, 1e-12);
    EXPECT_NEAR(q.getAxis().dot(from.normalized()), 0.0, 1e-12);
    expect_maps(from, -from);
  }
}

TEST(Frames, RollPitchYawIsFixedAxisXyz) {
  // Roll a quarter turn about x takes y onto z; a yaw about the fixed z leaves it there.
  const btQuaternion q = rpy_rotation({SIMD_HALF_PI, 0, SIMD_HALF_PI});
  EXPECT_NEAR((quatRotate(q, btVector3(0, 1, 0)) - btVector3(0, 0, 1)).length(), 0.0, 1e-12);
  // And x: roll leaves it, yaw takes it to y.
  EXPECT_NEAR((quatRotate(q, btVector3(1, 0, 0)) - btVector3(0, 1, 0)).length(), 0.0, 1e-12);
}

TEST(Frames, RollPitchYawAsAQuaternionIsTheSameRotation) {
  const Vec3 rpy{0.3, -0.7, 1.9};
  const Quaternion q = rpy_to_quaternion(rpy);
  const btQuaternion expected = rpy_rotation(rpy);
  EXPECT_NEAR(q.x, expected.x(), 1e-15);
  EXPECT_NEAR(q.y, expected.y(), 1e-15);
  EXPECT_NEAR(q.z, expected.z(), 1e-15);
  EXPECT_NEAR(q.w, expected.w(), 1e-15);
}

}  // namespace
}  // namespace afhub::physics
