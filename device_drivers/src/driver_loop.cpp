// The device driver's loop (see driver_loop.hpp).
#include "afhub/devices/driver_loop.hpp"

#include <algorithm>
#include <cstdio>
#include <thread>

#include "afhub/devices/safe_request.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/rt/loop_stats_publisher.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::devices {
namespace {

// The hub-loss hook's way to the device: the loop makes it safe when asked (see
// safe_request.hpp). Never destroyed: the hook may run while the process exits.
SafeRequest& safe_request() {
  static SafeRequest* request = new SafeRequest;
  return *request;
}

// How long the hook waits for the loop: a few periods, and at least 20 ms (a loop
// descheduled on a busy machine still answers, rather than racing the hook).
std::int64_t safe_request_timeout_ns(const LoopOptions& loop) {
  return std::max<std::int64_t>(20'000'000, 10 * loop.period_ns);
}

// Runs the loop on an open device until a stop, the cycle limit or the device's
// loss. Returns what DeviceGone said, empty on a stop.
std::string drive(Device& device, const DriverOptions& options, Writer<DeviceState>& states,
                  LatestReader<DeviceCommand>& commands, LoopStatsPublisher& stats,
                  LoopTiming& timing) {
  const DeviceSpec spec = device.spec();
  SafetyLimits limits = options.safety;
  limits.cycle_ns = options.loop.period_ns;
  ForceSafety safety(spec, limits);
  std::string gone;
  // One cycle: the output decided from the newest command, the device exchanged with,
  // its state published. Returns false when the device went away.
  const auto cycle = [&](bool stopping) {
    if (safe_request().serve()) return true;  // made safe for the hub's loss: hands off
    const DeviceCommand* command = commands.latest();
    if (stopping || hub_lost()) safety.stop();
    ForceGate gate = ForceGate::kNoCommand;
    const DeviceOutput output = safety.apply(command, monotonic_ns(), gate);
    DeviceSample sample;
    try {
      sample = device.exchange(output);
    } catch (const DeviceGone& error) {
      gone = error.what();
      return false;
    }
    if (hub_lost()) return true;  // outputs safe: nothing into a hub that is gone
    DeviceState* state = states.loan();
    if (!state) return true;  // shared memory exhausted: readers see a stale stamp
    state->spec = spec;
    state->pose = sample.pose;
    state->velocity = sample.velocity;
    state->gripper_angle_rad = sample.gripper_angle_rad;
    state->buttons = sample.buttons;
    state->gate = gate;
    state->applied = output.wrench;
    state->applied_gripper_force_n = output.gripper_force_n;
    if (gate == ForceGate::kApplying) {
      state->command_sequence = command->header.sequence;
      state->command_stamp_ns = command->header.publish_stamp_ns;
    }
    states.publish(state);
    return true;
  };
  run_periodic(
      options.loop, timing, [&] { return cycle(false); },
      [&](std::int64_t now) { stats.maybe_publish(now, timing); });
  if (gone.empty()) cycle(true);  // stopping: one last cycle at zero force, published
  device.make_safe();
  return gone;
}

}  // namespace

int run_driver(const DeviceOpener& open, const DriverOptions& options) {
  install_stop_signal_handlers();
  const std::string who = "afhub device " + options.name;
  const std::string channel = device_channel_name(options.name);
  if (options.survive_hub_loss) {
    survive_hub_loss(who);
    const std::int64_t timeout_ns = safe_request_timeout_ns(options.loop);
    on_hub_lost([who, timeout_ns] {
      const std::int64_t asked = monotonic_ns();
      const MadeSafeBy by = safe_request().request(timeout_ns);
      if (by == MadeSafeBy::kRequester)
        std::fprintf(stderr,
                     "%s: the device's loop did not answer within %.0f ms (stuck in an "
                     "exchange?): made the device safe from the thread that saw the loss\n",
                     who.c_str(), static_cast<double>(timeout_ns) * 1e-6);
      else if (by == MadeSafeBy::kLoop)
        std::fprintf(stderr, "%s: the device's loop made it safe, %.1f ms after it was asked\n",
                     who.c_str(), static_cast<double>(monotonic_ns() - asked) * 1e-6);
    });
  }
  std::unique_ptr<Device> device = open();
  connect_to_hub("device", HubPolicy::kRequire,
                 std::chrono::milliseconds(static_cast<std::int64_t>(options.wait_s * 1e3)));
  Writer<DeviceState> states(body_state_channel(channel));
  LatestReader<DeviceCommand> commands(body_command_channel(channel));
  DirectoryPublisher directory;
  directory.add(make_device_entry(options.name));
  directory.publish();
  LoopTiming timing;  // preallocated before memory is locked and the loop starts
  const RealtimeGrant grant = apply_realtime(options.loop, who.c_str());
  LoopStatsPublisher stats("device " + options.name, channel, options.loop.period_ns, false, grant);
  const DeviceSpec spec = device->spec();
  std::fprintf(stderr, "%s: %s%s%s on %s, %.0f Hz, force watchdog %.1f ms, max force %.1f N\n",
               who.c_str(), spec.model.data(), spec.serial[0] ? " " : "", spec.serial.data(),
               channel.c_str(), 1e9 / static_cast<double>(options.loop.period_ns),
               static_cast<double>(options.safety.watchdog_ns) * 1e-6, spec.max_force_n);
  for (;;) {
    safe_request().attach(device.get());
    const std::string gone = drive(*device, options, states, commands, stats, timing);
    safe_request().attach(nullptr);
    if (gone.empty()) return 0;
    device.reset();
    std::fprintf(stderr, "%s: the device went away (%s); its force is zero\n", who.c_str(),
                 gone.c_str());
    if (!options.reconnect) return 1;
    std::fprintf(stderr, "%s: waiting for the device to come back (--reconnect)\n", who.c_str());
    while (!device && !stop_requested()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      try {
        device = open();
      } catch (const std::exception&) {
        // still away
      }
    }
    if (!device) return 0;
    std::fprintf(stderr, "%s: the device is back\n", who.c_str());
  }
}

}  // namespace afhub::devices
