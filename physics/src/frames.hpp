// Frames in Bullet's types: ADF placements as transforms, and the paper's
// Algorithm 2 (the rotation that takes one vector onto another).
#pragma once

#include <btBulletDynamicsCommon.h>

#include <cmath>

#include "afhub/physics/model.hpp"

namespace afhub::physics {

inline btVector3 to_bt(const Vec3& v) {
  return {v.x, v.y, v.z};
}
inline Vec3 from_bt(const btVector3& v) {
  return {v.x(), v.y(), v.z()};
}

// Fixed-axis roll, pitch, yaw (about x, then y, then z of the parent frame).
inline btQuaternion rpy_rotation(const Vec3& rpy) {
  btQuaternion q;
  q.setEulerZYX(rpy.z, rpy.y, rpy.x);
  return q;
}

inline btTransform to_transform(const Placement& placement) {
  return btTransform(rpy_rotation(placement.rpy_rad), to_bt(placement.position_m));
}

// AMBF paper, Algorithm 2: the rotation taking `from` onto `to` about their common
// normal. Parallel vectors give the identity; anti-parallel ones a half turn about
// an axis perpendicular to them (from x X, or from x Y when `from` lies along X).
inline btQuaternion rotation_between(btVector3 from, btVector3 to) {
  from.normalize();
  to.normalize();
  const btVector3 normal = from.cross(to);
  const btScalar cosine = btClamped(from.dot(to), btScalar(-1), btScalar(1));
  if (normal.length() < 1e-9) {
    if (cosine > 0) return btQuaternion::getIdentity();
    btVector3 perpendicular = from.cross(btVector3(1, 0, 0));
    if (perpendicular.length() < 1e-6) perpendicular = from.cross(btVector3(0, 1, 0));
    return btQuaternion(perpendicular.normalized(), SIMD_PI);
  }
  return btQuaternion(normal.normalized(), btAcos(cosine));
}

// Fixed-axis roll, pitch, yaw of a rotation (the inverse of rpy_rotation). Roll is
// taken from what is left once pitch and yaw are undone, so the three give the
// rotation back to rounding even at pitch +-pi/2, where each alone is ill-defined.
inline Vec3 rpy_of(const btMatrix3x3& r) {
  const double pitch = std::atan2(-r[2][0], std::sqrt(r[0][0] * r[0][0] + r[1][0] * r[1][0]));
  const double yaw = std::atan2(r[1][0], r[0][0]);
  btMatrix3x3 undone;
  undone.setEulerZYX(0, pitch, yaw);                // btMatrix3x3 takes x first
  const btMatrix3x3 rest = undone.transpose() * r;  // a turn about x
  return {std::atan2(rest[2][1], rest[1][1]), pitch, yaw};
}

// AMBF paper, Algorithm 3: the angle about `parent_axis` that, after the child axis
// is taken onto the parent axis the short way (rotation_between), turns the child
// to `child_in_parent` (which takes `child_axis` onto `parent_axis`).
inline double joint_offset_about(const btQuaternion& child_in_parent, const btVector3& child_axis,
                                 const btVector3& parent_axis) {
  const btQuaternion rest = child_in_parent * rotation_between(child_axis, parent_axis).inverse();
  const btVector3 about = parent_axis.normalized();
  return 2.0 *
         std::atan2(rest.x() * about.x() + rest.y() * about.y() + rest.z() * about.z(), rest.w());
}

}  // namespace afhub::physics
