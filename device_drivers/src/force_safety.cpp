// The driver's force rules (see force_safety.hpp).
#include "afhub/devices/force_safety.hpp"

#include <algorithm>
#include <cmath>

namespace afhub::devices {
namespace {

// `v` scaled down to at most `limit` in length: the direction is kept.
Vec3 clamp_length(const Vec3& v, double limit) noexcept {
  const double length = std::hypot(v.x, v.y, v.z);  // no overflow for huge components
  if (!std::isfinite(length) || limit <= 0.0) return {};
  const double scale = length > limit ? limit / length : 1.0;
  return {v.x * scale, v.y * scale, v.z * scale};
}

Vec3 scaled(const Vec3& v, double factor) noexcept {
  return {v.x * factor, v.y * factor, v.z * factor};
}

}  // namespace

ForceSafety::ForceSafety(const DeviceSpec& spec, const SafetyLimits& limits)
    : spec_(spec), limits_(limits) {}

DeviceOutput ForceSafety::apply(const DeviceCommand* command, std::int64_t now_ns,
                                ForceGate& gate) noexcept {
  // A stamp from the future is no fresher than a stale one: the same clock runs in
  // every process, so only a faulty writer makes one.
  const std::int64_t age_ns = command ? now_ns - command->header.publish_stamp_ns : 0;
  const bool fresh =
      age_ns + limits_.cycle_ns <= limits_.watchdog_ns && age_ns >= -limits_.watchdog_ns;
  // A driver SIGSTOPped while its client went on writing found a fresh command on
  // resuming, and pushed at once with the full force it had ramped to seconds before.
  if (last_cycle_ns_ >= 0 && now_ns - last_cycle_ns_ > limits_.watchdog_ns) applying_since_ns_ = -1;
  last_cycle_ns_ = now_ns;
  gate = stopped_           ? ForceGate::kStopping
         : !command         ? ForceGate::kNoCommand
         : !fresh           ? ForceGate::kWatchdog
         : !command->enable ? ForceGate::kDisabled
                            : ForceGate::kApplying;
  if (gate != ForceGate::kApplying) {
    applying_since_ns_ = -1;
    return {};
  }
  if (applying_since_ns_ < 0) applying_since_ns_ = now_ns;
  const double ramp =
      limits_.ramp_s > 0.0
          ? std::clamp(static_cast<double>(now_ns - applying_since_ns_) * 1e-9 / limits_.ramp_s,
                       0.0, 1.0)
          : 1.0;
  DeviceOutput output;
  output.wrench.force_n = scaled(clamp_length(command->wrench.force_n, spec_.max_force_n), ramp);
  output.wrench.torque_nm =
      scaled(clamp_length(command->wrench.torque_nm, spec_.max_torque_nm), ramp);
  const double gripper = std::isfinite(command->gripper_force_n) ? command->gripper_force_n : 0.0;
  output.gripper_force_n =
      std::clamp(gripper, -spec_.max_gripper_force_n, spec_.max_gripper_force_n) * ramp;
  return output;
}

}  // namespace afhub::devices
