// Frames in Bullet's types: ADF placements as transforms, and the paper's
// Algorithm 2 (the rotation that takes one vector onto another).
#pragma once

#include <btBulletDynamicsCommon.h>

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

}  // namespace afhub::physics
