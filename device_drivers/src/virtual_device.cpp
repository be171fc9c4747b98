// The virtual haptic device (see virtual_device.hpp).
#include "afhub/devices/virtual_device.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <sstream>

#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/input_file.hpp"
#include "afhub/yaml/number_text.hpp"
#include "afhub/yaml/yaml_reader.hpp"

namespace afhub::devices {
namespace {

// One line to the force log: write(2) of a line formatted on the stack, no allocation.
template <class... Values>
void log_line(int fd, const char* format, Values... values) noexcept {
  if (fd < 0) return;
  char line[160];
  const int n = std::snprintf(line, sizeof line, format, values...);
  const std::size_t length = std::min(static_cast<std::size_t>(std::max(n, 0)), sizeof line - 1);
  if (write(fd, line, length) < 0) {
    // a log line lost (a full disk) costs the device nothing
  }
}

constexpr std::uintmax_t kMaxTrajectoryFileBytes = 1u << 30;
constexpr double kMaxTrajectoryReachM = 10.0;  // as a circle's radius
constexpr double kMaxTrajectorySeconds = 1e7;  // 116 days, as the command line's spans

Vec3 lerp(const Vec3& a, const Vec3& b, double f) {
  return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f};
}

}  // namespace

std::vector<TrajectoryPoint> read_trajectory_csv(const std::string& path) {
  // A regular file of a bounded size (not /dev/zero, which never ends): an hour at
  // 1 kHz is about 150 MB.
  std::istringstream in(yaml::read_input_file(path, kMaxTrajectoryFileBytes, "a trajectory (CSV)"));
  std::vector<TrajectoryPoint> points;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = line.substr(0, line.find('#'));
    if (line.find_first_not_of(" \t\r,") == std::string::npos) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    std::vector<double> values;
    std::string field;
    bool numeric = true;
    while (fields >> field) {
      const std::optional<double> value = yaml::parse_finite(field);
      numeric = numeric && value;
      values.push_back(value.value_or(0.0));
    }
    const std::string where = path + ":" + std::to_string(number) + ": ";
    if (!numeric) {
      if (points.empty() && number == 1) continue;  // a line of column names
      throw Error(where + "expected numbers (t, x, y, z[, buttons[, gripper]]), found '" + line +
                  "'");
    }
    if (values.size() < 4 || values.size() > 6)
      throw Error(where + "expected 4 to 6 values (t, x, y, z[, buttons[, gripper]]), found " +
                  std::to_string(values.size()));
    // Within a desk's reach, as a circle's radius: interpolating between points near
    // the largest doubles overflowed to a pose that was not finite.
    for (int axis = 1; axis <= 3; ++axis)
      if (std::abs(values[axis]) > kMaxTrajectoryReachM)
        throw Error(where + "position " + yaml::number_text(values[axis]) + " m is beyond " +
                    yaml::number_text(kMaxTrajectoryReachM) + " m from the device's origin");
    if (values[0] < 0.0 || values[0] > kMaxTrajectorySeconds)
      throw Error(where + "time " + yaml::number_text(values[0]) + " s is outside 0 to " +
                  yaml::number_text(kMaxTrajectorySeconds) + " s");
    TrajectoryPoint point;
    point.t_s = values[0];
    point.position = {values[1], values[2], values[3]};
    if (values.size() > 4) {
      if (values[4] < 0 || values[4] > 0xffffffff || values[4] != std::floor(values[4]))
        throw Error(where + "buttons must be a bit mask (a whole number from 0), found " +
                    yaml::number_text(values[4]));
      point.buttons = static_cast<std::uint32_t>(values[4]);
    }
    if (values.size() > 5) {
      if (std::abs(values[5]) > 2 * std::numbers::pi)
        throw Error(where + "the gripper angle " + yaml::number_text(values[5]) +
                    " rad is beyond a turn (2 pi)");
      point.gripper_angle_rad = values[5];
    }
    if (!points.empty() && point.t_s <= points.back().t_s)
      throw Error(where + "time " + yaml::number_text(point.t_s) +
                  " s does not come after the line before's " +
                  yaml::number_text(points.back().t_s) + " s");
    points.push_back(point);
  }
  if (points.empty()) throw Error(path + ": the trajectory has no points");
  return points;
}

std::vector<TrajectoryPoint> circle_trajectory(double radius_m, double period_s) {
  if (!(radius_m >= 0.0 && radius_m < 10.0) || !(period_s > 0.0 && period_s < 1e6))
    throw Error("a circle needs a radius from 0 to 10 m and a period above 0 s");
  std::vector<TrajectoryPoint> points;
  constexpr int kPoints = 400;
  for (int i = 0; i <= kPoints; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / kPoints;
    TrajectoryPoint point;
    point.t_s = period_s * i / kPoints;
    point.position = {radius_m * std::cos(angle), radius_m * std::sin(angle), 0.0};
    points.push_back(point);
  }
  return points;
}

DeviceSpec VirtualDevice::default_spec(double max_force_n) {
  DeviceSpec spec;
  const std::string model = "virtual";
  std::copy(model.begin(), model.end(), spec.model.begin());
  spec.max_force_n = max_force_n;
  spec.max_stiffness_npm = 3000.0;
  spec.workspace_radius_m = 0.1;
  spec.sensed = kDeviceTranslation | kDeviceGripper;
  spec.actuated = kDeviceTranslation;
  spec.button_count = 4;
  return spec;
}

VirtualDevice::VirtualDevice(std::vector<TrajectoryPoint> trajectory, bool loop,
                             const DeviceSpec& spec, const VirtualHand& hand)
    : trajectory_(std::move(trajectory)), loop_(loop), spec_(spec), hand_(hand) {
  if (trajectory_.empty()) trajectory_.push_back({});
  position_ = trajectory_.front().position;
}

const TrajectoryPoint& VirtualDevice::point_at(double t_s, Vec3& target,
                                               Vec3& target_velocity) noexcept {
  const double span = trajectory_.back().t_s - trajectory_.front().t_s;
  double t = t_s + trajectory_.front().t_s;
  if (loop_ && span > 0.0) t = trajectory_.front().t_s + std::fmod(t_s, span);
  // The last point at or before t (binary search: no allocation).
  auto after = std::upper_bound(trajectory_.begin(), trajectory_.end(), t,
                                [](double time, const TrajectoryPoint& p) { return time < p.t_s; });
  if (after == trajectory_.begin()) {
    target = trajectory_.front().position;
    target_velocity = {};
    return trajectory_.front();
  }
  const TrajectoryPoint& before = *(after - 1);
  if (after == trajectory_.end()) {
    target = before.position;
    target_velocity = {};
    return before;
  }
  const double dt = after->t_s - before.t_s;
  target = lerp(before.position, after->position, (t - before.t_s) / dt);
  target_velocity = {(after->position.x - before.position.x) / dt,
                     (after->position.y - before.position.y) / dt,
                     (after->position.z - before.position.z) / dt};
  return before;
}

DeviceSample VirtualDevice::step(const DeviceOutput& output, double t_s) noexcept {
  Vec3 target, target_velocity;
  const TrajectoryPoint& point = point_at(t_s, target, target_velocity);
  // The hand moves by semi-implicit Euler in steps of at most 1 ms, over at most
  // 50 ms (a paused process resumes where it was, not with a jump).
  double remaining = last_t_s_ < 0.0 ? 0.0 : std::clamp(t_s - last_t_s_, 0.0, 0.05);
  last_t_s_ = t_s;
  const Vec3& force = output.wrench.force_n;
  while (remaining > 1e-12) {
    const double dt = std::min(remaining, 1e-3);
    remaining -= dt;
    const auto accelerate = [&](double& v, double x, double goal, double goal_v, double f) {
      v += dt * (hand_.stiffness_npm * (goal - x) + hand_.damping_nspm * (goal_v - v) + f) /
           hand_.mass_kg;
    };
    accelerate(velocity_.x, position_.x, target.x, target_velocity.x, force.x);
    accelerate(velocity_.y, position_.y, target.y, target_velocity.y, force.y);
    accelerate(velocity_.z, position_.z, target.z, target_velocity.z, force.z);
    position_.x += dt * velocity_.x;
    position_.y += dt * velocity_.y;
    position_.z += dt * velocity_.z;
  }
  DeviceSample sample;
  sample.pose.position_m = position_;
  sample.velocity.linear_mps = velocity_;
  sample.buttons = point.buttons;
  sample.gripper_angle_rad = point.gripper_angle_rad;
  return sample;
}

VirtualDevice::~VirtualDevice() {
  if (force_log_ >= 0) close(force_log_);
}

void VirtualDevice::log_force_to(const std::string& path) {
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0)
    throw Error(path + ": cannot open the force log: " + std::strerror(errno) +
                " (--force-log names a file to append to, in a folder that exists)");
  if (force_log_ >= 0) close(force_log_);
  force_log_ = fd;
  log_line(force_log_, "%lld open pid %d\n", static_cast<long long>(monotonic_ns()),
           static_cast<int>(getpid()));
}

DeviceSample VirtualDevice::exchange(const DeviceOutput& output) {
  const std::int64_t now = monotonic_ns();
  if (start_ns_ < 0) start_ns_ = now;
  const Vec3& f = output.wrench.force_n;
  if (const bool applying = f.x != 0.0 || f.y != 0.0 || f.z != 0.0; applying != applying_) {
    applying_ = applying;
    if (applying)
      log_line(force_log_, "%lld force %.4f %.4f %.4f\n", static_cast<long long>(now), f.x, f.y,
               f.z);
    else
      log_line(force_log_, "%lld zero\n", static_cast<long long>(now));
  }
  return step(output, static_cast<double>(now - start_ns_) * 1e-9);
}

void VirtualDevice::make_safe() noexcept {
  applying_ = false;
  log_line(force_log_, "%lld made safe\n", static_cast<long long>(monotonic_ns()));
}

}  // namespace afhub::devices
