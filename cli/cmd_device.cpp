// `afhub device run virtual|...`: a device driver as its own process on the device's
// channels (see device_drivers/).
#include <cmath>
#include <memory>

#include "afhub/devices/device_finder.hpp"
#include "afhub/devices/driver_loop.hpp"
#include "afhub/devices/evdev_device.hpp"
#include "afhub/devices/falcon_device.hpp"
#include "afhub/devices/virtual_device.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "format.hpp"
#include "loop_options.hpp"

namespace afhub::cli {
namespace {

struct DeviceRunOptions {
  std::string name;
  LoopRateOptions pacing;
  double watchdog_ms = 10.0;
  double ramp_s = 0.2;
  double wait_s = 10.0;
  bool reconnect = false;
  // virtual
  std::string trajectory_file;
  std::vector<double> circle;
  bool loop = false;
  double max_force_n = 10.0;
  std::string force_log;
  // falcon
  std::string serial, firmware;
  double home_timeout_s = 30.0;
  // spacemouse, gamepad
  std::string path;
  bool velocity = false;
};

// The first device of `kind` that this user can open, for a driver given no path.
std::string first_device_path(const std::string& kind) {
  const devices::DeviceScan scan = devices::find_devices();
  std::string refused;
  for (const devices::FoundDevice& found : scan.devices) {
    if (found.kind != kind) continue;
    if (found.problem.empty()) return found.path;
    refused = found.problem;
  }
  if (!refused.empty()) throw Error(refused);
  throw Error("no " + kind + " is plugged in (`afhub device list` shows what is)");
}

// `afhub device force`: commands a device's force every period until Ctrl-C.
struct ForceOptions {
  std::string name;
  std::string force = "0,0,0", torque = "0,0,0";
  double gripper_n = 0.0;
  bool disable = false;
  LoopRateOptions pacing;
  double wait_s = 0.0;  // for the hub and the device's driver
};

int run_force(const ForceOptions& options) {
  const std::vector<double> force = parse_numbers(options.force, "--force", 3);
  const std::vector<double> torque = parse_numbers(options.torque, "--torque", 3);
  if (!std::isfinite(options.gripper_n)) throw Error("--gripper must be a finite number");
  LoopOptions loop;
  set_loop_rate_options(options.pacing, loop);
  const std::string channel = device_channel_name(options.name);
  install_stop_signal_handlers();
  const StartupWait wait(options.wait_s);
  wait.connect_to_hub("device-force");
  // Commands to a device no driver serves would go nowhere, silently.
  if (wait.wait_for_body(channel, "afhub device force").info.kind != ChannelKind::kDevice)
    throw Error(channel + " is a body, not a device");
  Writer<DeviceCommand> commands(body_command_channel(channel));
  LoopTiming timing;
  run_periodic(loop, timing, [&] {
    DeviceCommand* command = commands.loan();
    if (!command) return true;
    command->wrench.force_n = {force[0], force[1], force[2]};
    command->wrench.torque_nm = {torque[0], torque[1], torque[2]};
    command->gripper_force_n = options.gripper_n;
    command->enable = options.disable ? 0 : 1;
    commands.publish(command);
    return true;
  });
  return 0;
}

devices::DriverOptions driver_options(const DeviceRunOptions& options) {
  if (!(options.watchdog_ms > 0.0 && options.watchdog_ms <= 1000.0))
    throw Error("--watchdog takes milliseconds from 0 (excluded) to 1000");
  if (!(options.ramp_s >= 0.0 && options.ramp_s <= 10.0))
    throw Error("--ramp takes seconds from 0 to 10");
  devices::DriverOptions driver;
  set_loop_rate_options(options.pacing, driver.loop);
  driver.name = options.name;
  device_channel_name(driver.name);  // a bad name fails here, before the device opens
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
  add_loop_rate_options(command, options.pacing);
  command->add_option("--watchdog", options.watchdog_ms,
                      "Zero force when no command came within this many ms (default 10)");
  command->add_option("--ramp", options.ramp_s,
                      "Seconds for the force to ramp in once enabled (default 0.2)");
  add_wait_option(command, options.wait_s, "");
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

  auto json = std::make_shared<bool>(false);
  auto* list = device->add_subcommand(
      "list",
      "The supported devices plugged in (Novint Falcon on USB; SpaceMouse and gamepads on "
      "evdev), and what keeps this user from opening one.");
  list->add_flag("--json", *json, "Print JSON instead of a table.");
  list->callback([&selected, json] {
    selected = [json] {
      const devices::DeviceScan scan = devices::find_devices();
      std::printf("%s", (*json ? devices::render_devices_json(scan) + "\n"
                               : devices::render_devices_text(scan))
                            .c_str());
      return 0;
    };
  });

  auto force = std::make_shared<ForceOptions>();
  auto* force_command = device->add_subcommand(
      "force",
      "Command a device's force every period until Ctrl-C (to try a device or its safety: "
      "the driver clamps it, ramps it in, and zeroes it 10 ms after the last command).");
  force_command
      ->add_option("name", force->name, "The device's name (its channels are device/<name>)")
      ->required();
  force_command->add_option("--force", force->force, "fx,fy,fz in N, device frame (default 0,0,0)");
  force_command->add_option("--torque", force->torque, "tx,ty,tz in N m (default 0,0,0)");
  force_command->add_option("--gripper", force->gripper_n, "Gripper force in N (default 0)");
  force_command->add_flag("--disable", force->disable, "Send the commands with force disabled");
  add_loop_rate_options(force_command, force->pacing);
  add_wait_option(force_command, force->wait_s, "the device's driver");
  force_command->callback([&selected, force] { selected = [force] { return run_force(*force); }; });
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
  virtual_command->add_option(
      "--force-log", virt->force_log,
      "Append a stamped line (monotonic ns) to this file whenever the applied force turns "
      "non-zero or zero, and when the device is made safe (to watch its force in tests)");
  auto falcon = std::make_shared<DeviceRunOptions>();
  auto* falcon_command = run->add_subcommand(
      "falcon",
      "A Novint Falcon on USB (libusb, no vendor SDK). Move its grip all the way out "
      "and back in to home it when it starts.");
  add_driver_options(falcon_command, *falcon, "falcon");
  falcon_command->add_option("--serial", falcon->serial,
                             "The Falcon's serial (default: the first)");
  falcon_command->add_option(
      "--firmware", falcon->firmware,
      "Novint's firmware image to load (a Falcon needs it once after power-up; afhub does "
      "not ship it)");
  falcon_command->add_option("--home-timeout", falcon->home_timeout_s,
                             "Seconds to wait for the homing (default 30)");
  falcon_command->callback([&selected, falcon] {
    selected = [falcon] {
      if (!(falcon->home_timeout_s > 0.0 && falcon->home_timeout_s <= 3600.0))
        throw Error("--home-timeout takes seconds from 0 to 3600");
      const devices::DriverOptions driver = driver_options(*falcon);
      devices::falcon::UsbOptions usb;
      usb.serial = falcon->serial;
      usb.firmware_path = falcon->firmware;
      const int home_cycles = static_cast<int>(falcon->home_timeout_s * 1000.0);
      bool first = true;
      return devices::run_driver(
          [usb, home_cycles, first]() mutable -> std::unique_ptr<devices::Device> {
            // The firmware stays loaded until power-off: only the first open loads it.
            devices::falcon::UsbOptions options = usb;
            if (!first) options.firmware_path.clear();
            first = false;
            auto falcon_device = devices::falcon::FalconDevice::open_usb(options);
            std::fprintf(stderr,
                         "afhub device falcon: homing: move the grip all the way out "
                         "and back in\n");
            if (!falcon_device->home(home_cycles))
              throw Error("the Falcon did not home within --home-timeout");
            return falcon_device;
          },
          driver);
    };
  });

  for (const char* kind : {"spacemouse", "gamepad"}) {
    auto evdev = std::make_shared<DeviceRunOptions>();
    const std::string what = kind;
    auto* evdev_command = run->add_subcommand(
        kind, what == "spacemouse"
                  ? "A 3Dconnexion SpaceMouse over evdev: its six axes drive a pose (or a "
                    "velocity), its buttons are buttons"
                  : "A gamepad over evdev (the Linux gamepad layout): sticks and triggers drive "
                    "a pose (or a velocity), its buttons are buttons");
    add_driver_options(evdev_command, *evdev, kind);
    evdev_command->add_option("--path", evdev->path,
                              "Its /dev/input/eventN node (default: the first found)");
    evdev_command->add_flag("--velocity", evdev->velocity,
                            "Publish the axes as a velocity, not an integrated pose");
    evdev_command->callback([&selected, evdev, what] {
      selected = [evdev, what] {
        const devices::DriverOptions driver = driver_options(*evdev);
        const std::string path = evdev->path.empty() ? first_device_path(what) : evdev->path;
        devices::EvdevOptions options;
        if (evdev->velocity) options.mode = devices::EvdevAxisMode::kVelocity;
        return devices::run_driver(
            [path, options] { return std::make_unique<devices::EvdevDevice>(path, options); },
            driver);
      };
    });
  }

  virtual_command->callback([&selected, virt] {
    selected = [virt] {
      if (!(virt->max_force_n >= 0.0 && virt->max_force_n <= 1000.0))
        throw Error("--max-force takes newtons from 0 to 1000");
      const devices::DriverOptions driver = driver_options(*virt);
      auto trajectory = virtual_trajectory(*virt);
      const bool loop = virt->loop || !virt->circle.empty();
      const DeviceSpec spec = devices::VirtualDevice::default_spec(virt->max_force_n);
      const std::string force_log = virt->force_log;
      return devices::run_driver(
          [trajectory, loop, spec, force_log] {
            auto hand = std::make_unique<devices::VirtualDevice>(trajectory, loop, spec);
            if (!force_log.empty()) hand->log_force_to(force_log);
            return hand;
          },
          driver);
    };
  });
}

}  // namespace afhub::cli
