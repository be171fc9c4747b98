// A teleoperation session for end-to-end tests, with no hardware: `afhub run` of the
// models, `afhub device run virtual` following a scripted trajectory, and `afhub teleop`
// binding the two, on the test binary's hub; with readers of the driven body and the
// device. Used with the project's own gripper and with AMBF's PR2 gripper.
#pragma once

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/percentile.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"

namespace afhub::test {

struct TeleopSetup {
  std::vector<std::string> models;       // what `afhub run` loads
  std::string devices_file;              // the input device file
  std::vector<std::string> teleop_args;  // after the file: "-d 5", "--device NAME", ...
  std::string body;                      // the driven root body's channel
  std::string device;                    // the driver's --name
  std::vector<std::string> driver_args;  // after `--name NAME`: the trajectory
  std::string log;                       // log files' prefix
};

inline void pause_ms(int ms) {
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
}

class TeleopSession {
 public:
  explicit TeleopSession(TeleopSetup setup)
      : setup_(std::move(setup)),
        physics_(spawn_afhub(run_args(), setup_.log + ".run")),
        teleop_(spawn_afhub(teleop_args(), setup_.log + ".teleop")),
        body_(body_state_channel(setup_.body)),
        device_(body_state_channel(device_channel_name(setup_.device))) {
    start_driver();
  }
  // Waits until the device applies a command's force (teleop is in the loop).
  bool wait_running() {
    using namespace std::chrono_literals;
    return wait_until(
        [&] {
          const DeviceState* d = device_.latest();
          return body_.latest() && d && d->gate == ForceGate::kApplying;
        },
        20s);
  }
  // Once teleop is in the loop, a new driver, its trajectory from its start: teleop holds
  // the palm while it has none and anchors it at the new one's first sample, so that a
  // scripted trajectory runs whole however late teleop bound (under the sanitizers it
  // once bound after a trajectory had ended). True once the new driver applies force.
  bool restart_driver_once_running() {
    using namespace std::chrono_literals;
    if (!wait_running()) return false;
    const std::string gone = "no sample from " + device_channel_name(setup_.device);
    const int gone_before = occurrences(teleop_log(), gone);
    kill_driver();
    if (!wait_until([&] { return occurrences(teleop_log(), gone) > gone_before; }, 10s))
      return false;
    const std::int64_t restarted_at = monotonic_ns();
    start_driver();
    return wait_until(
        [&] {
          const DeviceState* d = device_.latest();
          return d && d->header.publish_stamp_ns > restarted_at && d->gate == ForceGate::kApplying;
        },
        20s);
  }
  void kill_teleop() { kill(teleop_.pid, SIGKILL); }
  pid_t teleop_pid() const { return teleop_.pid; }
  // SIGSTOP, SIGCONT or SIGKILL to teleop, or to the physics.
  void signal_teleop(int signal) { kill(teleop_.pid, signal); }
  void signal_physics(int signal) { kill(physics_.pid, signal); }
  // The same to the physics, teleop and the driver, as a machine stalling them all does.
  void signal_all(int signal) {
    for (pid_t pid : {physics_.pid, teleop_.pid, driver_->pid}) kill(pid, signal);
  }
  // SIGKILLs the driver (its readers keep its last state).
  void kill_driver() {
    kill(driver_->pid, SIGKILL);
    driver_->stop();
  }
  // A new driver: its trajectory from its start.
  void start_driver() {
    std::vector<std::string> args = {"device", "run", "virtual", "--name", setup_.device};
    args.insert(args.end(), setup_.driver_args.begin(), setup_.driver_args.end());
    driver_ = std::make_unique<ScopedProcess>(spawn_afhub(args, setup_.log + ".device"));
  }
  // A new teleoperation process, bound to the running driver.
  void restart_teleop() {
    teleop_.stop();
    teleop_.pid = spawn_afhub(teleop_args(), setup_.log + ".teleop");
  }
  // The newest device state not seen before, or nullptr.
  const DeviceState* new_device_state() {
    const DeviceState* d = device_.latest();
    return d && device_.updated() ? d : nullptr;
  }
  const BodyState& body() { return *body_.latest(); }
  const DeviceState& device() { return *device_.latest(); }
  std::string teleop_log() { return read_file(setup_.log + ".teleop"); }
  std::string log_prefix() const { return setup_.log; }
  std::string logs() {
    return "run: " + read_file(setup_.log + ".run") + "\nteleop: " + teleop_log() +
           "\ndevice: " + read_file(setup_.log + ".device");
  }
  std::vector<std::string> teleop_args() const {
    std::vector<std::string> args = {"teleop", setup_.devices_file};
    args.insert(args.end(), setup_.teleop_args.begin(), setup_.teleop_args.end());
    return args;
  }

 private:
  std::vector<std::string> run_args() const {
    std::vector<std::string> args = {"run"};
    args.insert(args.end(), setup_.models.begin(), setup_.models.end());
    args.push_back("--no-autostart");
    return args;
  }

  TeleopSetup setup_;
  ScopedProcess physics_, teleop_;
  std::unique_ptr<ScopedProcess> driver_;
  LatestReader<BodyState> body_;
  LatestReader<DeviceState> device_;
};

// Where the body went against where the scaled device went, over pairs of samples.
// Judged only while the system runs: a pair is left out when the body's or the
// device's state was stale as it was read (the physics or the driver descheduled on a
// busy machine: the body then lags the device for real, and is not teleoperation's
// error), and so is every pair for kSettleReads reads after one, while the body
// catches up.
struct Following {
  Vec3 body_mean, device_mean;
  double body_radius{0.0};       // mean horizontal distance from body_mean
  double rms{0.0}, worst{0.0};   // of body - body_mean - scale (device - device_mean)
  double median{0.0}, p99{0.0};  // of the same
  int judged{0}, left_out{0};    // pairs
  double stalest_ms{0.0};        // the oldest state read, body or device
};

// A state older than this as it is read was not published on time (1 kHz publishers;
// a 20 ms lag of the palm moving at 0.31 m/s is 6 mm of deviation, within the bounds).
constexpr std::int64_t kLateStateNs = 20'000'000;
constexpr int kSettleReads = 150;  // 300 ms

// Samples the body and the device every 2 ms `count` times and compares them.
inline Following measure_following(TeleopSession& session, double scale, int count) {
  struct Pair {
    Vec3 body, device;
  };
  std::vector<Pair> pairs;
  Following f;
  int settling = 0;
  for (int i = 0; i < count; ++i) {
    const BodyState& body = session.body();
    const DeviceState& device = session.device();
    const std::int64_t now = monotonic_ns();
    const std::int64_t age =
        std::max(now - body.header.publish_stamp_ns, now - device.header.publish_stamp_ns);
    f.stalest_ms = std::max(f.stalest_ms, static_cast<double>(age) * 1e-6);
    settling = age > kLateStateNs ? kSettleReads : std::max(settling - 1, 0);
    if (settling > 0)
      ++f.left_out;
    else
      pairs.push_back({body.pose.position_m, device.pose.position_m});
    pause_ms(2);
  }
  f.judged = static_cast<int>(pairs.size());
  if (pairs.empty()) return f;
  for (const Pair& p : pairs) {
    f.body_mean = {f.body_mean.x + p.body.x, f.body_mean.y + p.body.y, f.body_mean.z + p.body.z};
    f.device_mean = {f.device_mean.x + p.device.x, f.device_mean.y + p.device.y,
                     f.device_mean.z + p.device.z};
  }
  const double n = static_cast<double>(pairs.size());
  f.body_mean = {f.body_mean.x / n, f.body_mean.y / n, f.body_mean.z / n};
  f.device_mean = {f.device_mean.x / n, f.device_mean.y / n, f.device_mean.z / n};
  double square_sum = 0.0;
  std::vector<double> errors;
  for (const Pair& p : pairs) {
    const double ex = (p.body.x - f.body_mean.x) - scale * (p.device.x - f.device_mean.x);
    const double ey = (p.body.y - f.body_mean.y) - scale * (p.device.y - f.device_mean.y);
    const double ez = (p.body.z - f.body_mean.z) - scale * (p.device.z - f.device_mean.z);
    const double e2 = ex * ex + ey * ey + ez * ez;
    f.worst = std::max(f.worst, std::sqrt(e2));
    errors.push_back(std::sqrt(e2));
    square_sum += e2;
    f.body_radius += std::hypot(p.body.x - f.body_mean.x, p.body.y - f.body_mean.y) / n;
  }
  f.rms = std::sqrt(square_sum / n);
  std::sort(errors.begin(), errors.end());
  f.median = percentile_of_sorted<double>(errors, 0.5);
  f.p99 = percentile_of_sorted<double>(errors, 0.99);
  return f;
}

// The clutch trajectory (rows t, x, y, z, buttons): out 2 cm; button 0 held while the
// hand goes back to 0; released; then 1 cm out again.
inline const char* const kClutchTrajectory =
    "0,0,0,0,0\n1,0,0,0,0\n2,0.02,0,0,0\n2.5,0.02,0,0,1\n3.5,0,0,0,1\n4.5,0,0,0,0\n"
    "5.5,0,0,0,0\n6.5,0.01,0,0,0\n8,0.01,0,0,0\n";

// The body's x along that trajectory.
struct ClutchRun {
  double before_clutch{0.0};    // as the clutch is pressed
  double held_drift{0.0};       // largest move from there while it is held
  double hand_at_release{0.0};  // the device's x as it is let go
  double released{0.0};         // the body's x then
  double jump{0.0};             // largest move from there over the next 0.8 s
  double after{0.0};            // 0.5 s after the hand has gone 1 cm out again
};

// Runs a session started on kClutchTrajectory through it; false when the clutch was
// never pressed or the hand never went out again.
inline bool run_clutch(TeleopSession& session, ClutchRun& run) {
  using namespace std::chrono_literals;
  if (!wait_until([&] { return (session.device().buttons & 1U) != 0; }, 20s)) return false;
  run.before_clutch = session.body().pose.position_m.x;
  while (session.device().buttons & 1U) {
    run.held_drift =
        std::max(run.held_drift, std::abs(session.body().pose.position_m.x - run.before_clutch));
    pause_ms(2);
  }
  run.hand_at_release = session.device().pose.position_m.x;
  run.released = session.body().pose.position_m.x;
  for (int i = 0; i < 400; ++i) {
    run.jump = std::max(run.jump, std::abs(session.body().pose.position_m.x - run.released));
    pause_ms(2);
  }
  if (!wait_until([&] { return session.device().pose.position_m.x > 0.0099; }, 20s)) return false;
  pause_ms(500);
  run.after = session.body().pose.position_m.x;
  return true;
}

}  // namespace afhub::test
