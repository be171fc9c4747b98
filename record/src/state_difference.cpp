#include "state_difference.hpp"

#include <cstdio>
#include <cstring>

namespace afhub::mcap {

namespace {

// Compares doubles by their bits: -0.0 and 0.0, or two NaNs, are told apart as a
// replay that is not bit-identical.
bool differ(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) != 0;
}

std::string describe(const std::string& field, double recorded, double replayed) {
  char text[160];
  std::snprintf(text, sizeof text, "%s: recorded %.17g, replayed %.17g", field.c_str(), recorded,
                replayed);
  return text;
}

#define AFHUB_COMPARE(path)                 \
  if (differ(recorded.path, replayed.path)) \
    return describe(prefix + #path, recorded.path, replayed.path);

std::string vec_difference(const std::string& prefix, const Vec3& recorded, const Vec3& replayed) {
  AFHUB_COMPARE(x)
  AFHUB_COMPARE(y)
  AFHUB_COMPARE(z)
  return "";
}

std::string pose_difference(const Pose& recorded, const Pose& replayed) {
  const std::string prefix = "pose.";
  if (auto d = vec_difference("pose.position_m.", recorded.position_m, replayed.position_m);
      !d.empty())
    return d;
  AFHUB_COMPARE(orientation.x)
  AFHUB_COMPARE(orientation.y)
  AFHUB_COMPARE(orientation.z)
  AFHUB_COMPARE(orientation.w)
  return "";
}

#undef AFHUB_COMPARE

}  // namespace

std::string state_difference(const BodyState& recorded, const BodyState& replayed) {
  if (auto d = pose_difference(recorded.pose, replayed.pose); !d.empty()) return d;
  const std::pair<const char*, std::pair<const Vec3*, const Vec3*>> vectors[] = {
      {"twist.linear_mps.", {&recorded.twist.linear_mps, &replayed.twist.linear_mps}},
      {"twist.angular_radps.", {&recorded.twist.angular_radps, &replayed.twist.angular_radps}},
      {"wrench.force_n.", {&recorded.wrench.force_n, &replayed.wrench.force_n}},
      {"wrench.torque_nm.", {&recorded.wrench.torque_nm, &replayed.wrench.torque_nm}},
      {"contact_wrench.force_n.",
       {&recorded.contact_wrench.force_n, &replayed.contact_wrench.force_n}},
      {"contact_wrench.torque_nm.",
       {&recorded.contact_wrench.torque_nm, &replayed.contact_wrench.torque_nm}},
  };
  for (const auto& [name, pair] : vectors)
    if (auto d = vec_difference(name, *pair.first, *pair.second); !d.empty()) return d;
  if (recorded.joint_count != replayed.joint_count)
    return "joint_count: recorded " + std::to_string(recorded.joint_count) + ", replayed " +
           std::to_string(replayed.joint_count);
  for (std::uint32_t j = 0; j < recorded.joint_count; ++j) {
    const JointSample& a = recorded.joints[j];
    const JointSample& b = replayed.joints[j];
    const std::string at = "joints[" + std::to_string(j) + "].";
    if (differ(a.position, b.position)) return describe(at + "position", a.position, b.position);
    if (differ(a.velocity, b.velocity)) return describe(at + "velocity", a.velocity, b.velocity);
    if (differ(a.effort, b.effort)) return describe(at + "effort", a.effort, b.effort);
  }
  if (recorded.sensor_ray_count != replayed.sensor_ray_count) return "sensor_ray_count differs";
  for (std::uint32_t r = 0; r < recorded.sensor_ray_count && r < kMaxSensorRaysPerBody; ++r)
    if (differ(recorded.sensor_distances_m[r], replayed.sensor_distances_m[r]))
      return describe("sensor_distances_m[" + std::to_string(r) + "]",
                      recorded.sensor_distances_m[r], replayed.sensor_distances_m[r]);
  if (recorded.contact_count != replayed.contact_count)
    return "contact_count: recorded " + std::to_string(recorded.contact_count) + ", replayed " +
           std::to_string(replayed.contact_count);
  return "";
}

}  // namespace afhub::mcap
