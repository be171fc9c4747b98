// A virtual haptic device, for tests and for users without hardware: a "hand" of
// some mass holding the handle, pulled along a scripted trajectory by a spring and
// a damper (the user's arm), and pushed by the force the driver applies. Force
// feedback therefore changes where the handle goes, as on a real device.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afhub/devices/device.hpp"

namespace afhub::devices {

// Where the user's hand wants the handle at time t_s, and what it presses.
struct TrajectoryPoint {
  double t_s{0.0};
  Vec3 position;
  std::uint32_t buttons{0};
  double gripper_angle_rad{0.0};
};

// A CSV trajectory: lines of `t, x, y, z[, buttons[, gripper]]` (seconds, metres, a
// button bit mask, radians), times increasing; '#' starts a comment and a first line
// of names is skipped. Throws afhub::Error naming file:line and what to fix.
std::vector<TrajectoryPoint> read_trajectory_csv(const std::string& path);

// One turn of a horizontal circle of `radius_m` around the origin in `period_s`.
std::vector<TrajectoryPoint> circle_trajectory(double radius_m, double period_s);

struct VirtualHand {
  double mass_kg = 0.2;
  double stiffness_npm = 200.0;  // the arm's pull towards the trajectory
  double damping_nspm = 10.0;
};

class VirtualDevice : public Device {
 public:
  // `loop`: the trajectory starts over at its end; otherwise it holds its last point.
  VirtualDevice(std::vector<TrajectoryPoint> trajectory, bool loop, const DeviceSpec& spec,
                const VirtualHand& hand = {});

  ~VirtualDevice() override;
  VirtualDevice(const VirtualDevice&) = delete;
  VirtualDevice& operator=(const VirtualDevice&) = delete;

  DeviceSpec spec() const override { return spec_; }
  // On the monotonic clock: the trajectory's time 0 is the first call.
  DeviceSample exchange(const DeviceOutput& output) override;
  // It applies nothing after its last exchange; noted in the force log.
  void make_safe() noexcept override;

  // Appends to `path` a line when the applied force turns non-zero or zero and when the
  // device is made safe, each stamped with monotonic_ns(), what a test of a real
  // device's force would watch: "<ns> force FX FY FZ", "<ns> zero", "<ns> made safe",
  // and "<ns> open pid PID" now. Throws afhub::Error when the file cannot be opened.
  void log_force_to(const std::string& path);

  // The same at trajectory time t_s (tests drive the clock themselves).
  DeviceSample step(const DeviceOutput& output, double t_s) noexcept;

  // The spec of a virtual device: translation and gripper sensed, translation
  // actuated up to max_force_n, 4 buttons, a 0.1 m workspace.
  static DeviceSpec default_spec(double max_force_n = 10.0);

 private:
  const TrajectoryPoint& point_at(double t_s, Vec3& target, Vec3& target_velocity) noexcept;

  std::vector<TrajectoryPoint> trajectory_;
  bool loop_;
  DeviceSpec spec_;
  VirtualHand hand_;
  Vec3 position_, velocity_;
  double last_t_s_ = -1.0;
  std::int64_t start_ns_ = -1;
  int force_log_ = -1;  // the force log's descriptor, -1: none
  bool applying_ = false;
};

}  // namespace afhub::devices
