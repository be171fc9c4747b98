// Plain geometric value types used inside payloads (SI units, world frame unless named).
#pragma once

namespace afhub {

struct Vec3 {
  double x{0.0};
  double y{0.0};
  double z{0.0};
};

// Unit quaternion, Hamilton convention, stored x, y, z, w as in AMBF and ROS.
struct Quaternion {
  double x{0.0};
  double y{0.0};
  double z{0.0};
  double w{1.0};
};

struct Pose {
  Vec3 position_m;
  Quaternion orientation;
};

struct Twist {
  Vec3 linear_mps;
  Vec3 angular_radps;
};

struct Wrench {
  Vec3 force_n;
  Vec3 torque_nm;
};

}  // namespace afhub
