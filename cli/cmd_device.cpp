// `afhub device run virtual|...`: a device driver as its own process on the device's
// channels (see device_drivers/).
#include <cmath>
#include <memory>

#include "afhub/devices/driver_loop.hpp"
#include "afhub/devices/virtual_device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "count_option.hpp"

namespace afhub::cli {
namespace {

struct DeviceRunOptions {
  std::string name;
  double rate_hz = 1000.0;
  int fifo_priority = 0;
  int cpu = -1;
  bool lock_memory = false;
  std::uint64_t cycles = 0;
  double watchdog_ms = 10.0;
  double ramp_s = 0.2;
  double wait_s = 10.0;
  bool reconnect = false;
  // virtual
  std::string trajectory_file;
  std::vector<double> circle;
  bool loop = false;
  double max_force_n = 10.0;
};

devices::DriverOptions driver_options(const DeviceRunOptions& options) {
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100'000.0))
    throw Error("--rate must be between 0 and 100000 Hz");
  if (options.fifo_priority < 0 || options.fifo_priority > 99)
    throw Error("--fifo takes a SCHED_FIFO priority from 1 to 99");
  if (!(options.watchdog_ms > 0.0 && options.watchdog_ms <= 1000.0))
    throw Error("--watchdog takes milliseconds from 0 (excluded) to 1000");
  if (!(options.ramp_s >= 0.0 && options.ramp_s <= 10.0))
    throw Error("--ramp takes seconds from 0 to 10");
  if (!(options.wait_s >= 0.0 && options.wait_s <= 1e6))
    throw Error("--wait takes a number of seconds from 0 to 1e6");
  devices::DriverOptions driver;
  driver.name = options.name;
  device_channel_name(driver.name);  // a bad name fails here, before the device opens
  driver.loop.period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.rate_hz));
  driver.loop.fifo_priority = options.fifo_priority;
  driver.loop.cpu = options.cpu;
  driver.loop.lock_memory = options.lock_memory;
  driver.loop.max_cycles = options.cycles;
  driver.safety.watchdog_ns = std::llround(options.watchdog_ms * 1e6);
  driver.safety.ramp_s = options.ramp_s;
  driver.wait_s = options.wait_s;
  driver.reconnect = options.reconnect;
  return driver;
}

// The options every driver takes; `name` is the device's default name.
void add_driver_options(CLI::App* command, DeviceRunOptions& options, const std::string& name) {
  options.name = name;
  command->add_option("--name", options.name,
                      "The device's name: its channels are device/<name> (default " + name + ")");
  command->add_option("--rate", options.rate_hz, "Loop rate in Hz (default 1000)");
  command->add_option("--fifo", options.fifo_priority,
                      "Run under SCHED_FIFO at this priority (1-99); says so if refused");
  command->add_option("--cpu", options.cpu, "Pin the loop to this CPU");
  command->add_flag("--lock-memory", options.lock_memory,
                    "mlockall and pre-fault, so the loop takes no page faults");
  add_count_option(command, "--cycles", options.cycles,
                   "Stop after this many cycles (default: Ctrl-C)");
  command->add_option("--watchdog", options.watchdog_ms,
                      "Zero force when no command came within this many ms (default 10)");
  command->add_option("--ramp", options.ramp_s,
                      "Seconds for the force to ramp in once enabled (default 0.2)");
  command->add_option("--wait", options.wait_s,
                      "Wait this many seconds for the hub before failing (default 10)");
  command->add_flag("--reconnect", options.reconnect,
                    "When the device goes away, wait for it to come back instead of exiting");
}

std::vector<devices::TrajectoryPoint> virtual_trajectory(const DeviceRunOptions& options) {
  if (!options.trajectory_file.empty() && !options.circle.empty())
    throw Error("give --trajectory or --circle, not both");
  if (!options.trajectory_file.empty())
    return devices::read_trajectory_csv(options.trajectory_file);
  if (!options.circle.empty()) {
    if (options.circle.size() != 2)
      throw Error("--circle takes RADIUS_M,PERIOD_S, e.g. --circle 0.02,4");
    return devices::circle_trajectory(options.circle[0], options.circle[1]);
  }
  return {devices::TrajectoryPoint{}};  // the hand rests at the origin
}

}  // namespace

void register_device(CLI::App& app, Runner& selected) {
  auto* device = app.add_subcommand(
      "device", "Haptic and input devices, each driven by its own process (device/<name>).");
  device->require_subcommand(1);
  auto* run = device->add_subcommand("run", "Run a device's driver.");
  run->require_subcommand(1);

  auto virt = std::make_shared<DeviceRunOptions>();
  auto* virtual_command = run->add_subcommand(
      "virtual",
      "A virtual haptic device: a hand of 0.2 kg pulled along a trajectory by a spring, "
      "pushed by the commanded force (for tests and for trying teleoperation without "
      "hardware).");
  add_driver_options(virtual_command, *virt, "virtual");
  virtual_command->add_option(
      "--trajectory", virt->trajectory_file,
      "CSV of t,x,y,z[,buttons[,gripper]] (s, m, bit mask, rad) for the hand to follow");
  virtual_command
      ->add_option("--circle", virt->circle,
                   "Follow a horizontal circle: RADIUS_M,PERIOD_S (repeats)")
      ->delimiter(',');
  virtual_command->add_flag("--loop", virt->loop, "Repeat the trajectory from its start");
  virtual_command->add_option("--max-force", virt->max_force_n,
                              "The most force it applies, in N (default 10)");
  virtual_command->callback([&selected, virt] {
    selected = [virt] {
      if (!(virt->max_force_n >= 0.0 && virt->max_force_n <= 1000.0))
        throw Error("--max-force takes newtons from 0 to 1000");
      const devices::DriverOptions driver = driver_options(*virt);
      auto trajectory = virtual_trajectory(*virt);
      const bool loop = virt->loop || !virt->circle.empty();
      const DeviceSpec spec = devices::VirtualDevice::default_spec(virt->max_force_n);
      return devices::run_driver(
          [trajectory, loop, spec] {
            return std::make_unique<devices::VirtualDevice>(trajectory, loop, spec);
          },
          driver);
    };
  });
}

}  // namespace afhub::cli
