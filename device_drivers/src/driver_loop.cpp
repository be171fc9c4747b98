// The device driver's loop (see driver_loop.hpp).
#include "afhub/devices/driver_loop.hpp"

#include <cstdio>
#include <thread>

#include "afhub/devices/safe_request.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/device_tape.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/loop_stats_publisher.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/payload_check.hpp"

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

// How a drive ended: a stop (or the cycle limit), the device's loss, or an error of any
// other kind, with what it said.
struct DriveEnd {
  enum { kStopped, kGone, kFailed } how = kStopped;
  std::string what;
};

// The device the hub-loss hook may make safe, for as long as this object lives: no
// exception path leaves the hook a device that was freed.
class HookAttachment {
 public:
  explicit HookAttachment(Device& device) { safe_request().attach(&device); }
  ~HookAttachment() { safe_request().attach(nullptr); }
  HookAttachment(const HookAttachment&) = delete;
  HookAttachment& operator=(const HookAttachment&) = delete;
};

// A sample that is not all finite numbers (a reading gone wrong) is not published:
// readers would take it as a pose (a NaN stays in teleop's anchor for good), and every
// reader refuses such a state anyway. Said on stderr, the first at once, then counted
// at most once a second; no allocation (the loop's path).
class NonFiniteSamples {
 public:
  explicit NonFiniteSamples(const std::string& name) : name_(name) {}

  // True when `sample` is to be dropped.
  bool drop(const DeviceSample& sample, std::int64_t now_ns) noexcept {
    const char* field =
        device_reading_problem(sample.pose, sample.velocity, sample.gripper_angle_rad);
    if (!field) return false;
    ++unsaid_;
    if (now_ns >= next_say_ns_) {
      std::fprintf(stderr,
                   "afhub device %s: %llu sample%s of the device not published: %s is not a "
                   "finite number (a faulty reading; readers see the last good sample age)\n",
                   name_.c_str(), static_cast<unsigned long long>(unsaid_), unsaid_ == 1 ? "" : "s",
                   field);
      unsaid_ = 0;
      next_say_ns_ = now_ns + 1'000'000'000;
    }
    return true;
  }

 private:
  const std::string& name_;
  std::uint64_t unsaid_ = 0;
  std::int64_t next_say_ns_ = 0;
};

// Runs the loop on an open device until a stop, the cycle limit, the device's loss or
// an error. Whatever ends it, the device's force was last set to zero (but when it is
// gone) and it was made safe.
DriveEnd drive(Device& device, const DriverOptions& options, Writer<DeviceState>& states,
               LatestReader<DeviceCommand>& commands, DeviceTapeWriter& tape,
               LoopStatsPublisher& stats, LoopTiming& timing) {
  const HookAttachment attachment(device);
  const DeviceSpec spec = device.spec();
  SafetyLimits limits = options.safety;
  limits.cycle_ns = options.loop.period_ns;
  ForceSafety safety(spec, limits);
  NonFiniteSamples non_finite(options.name);
  DriveEnd end;
  // One cycle: the output decided from the newest command, the device exchanged with,
  // its state published. Returns false when the device went away or failed.
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
      end = {DriveEnd::kGone, error.what()};
      return false;
    } catch (const std::exception& error) {  // a transport error the device does not list
      end = {DriveEnd::kFailed, error.what()};
      return false;
    }
    if (hub_lost()) return true;  // outputs safe: nothing into a hub that is gone
    if (non_finite.drop(sample, monotonic_ns())) return true;
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
    tape.add(*state, command);
    return true;
  };
  try {
    run_periodic(
        options.loop, timing, [&] { return cycle(false); },
        [&](std::int64_t now) { stats.maybe_publish(now, timing); });
  } catch (const std::exception& error) {  // outside the exchange: the stats, the hub
    end = {DriveEnd::kFailed, error.what()};
  } catch (...) {
    end = {DriveEnd::kFailed, "an unknown exception"};
  }
  // One last cycle at zero force, published; the first error stays the one reported.
  if (end.how != DriveEnd::kGone) {
    const DriveEnd first = end;
    try {
      cycle(true);
    } catch (...) {
    }
    if (first.how == DriveEnd::kFailed) end = first;
  }
  device.make_safe();
  return end;
}

}  // namespace

int run_driver(const DeviceOpener& open, const DriverOptions& options) {
  install_stop_signal_handlers();
  const std::string who = "afhub device " + options.name;
  const std::string channel = device_channel_name(options.name);
  const StartupWait wait(options.wait_s);  // checked before the device opens
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
  // Opened before the hub is waited for: a driver re-executed after a hub loss holds its
  // device, safe, meanwhile.
  std::unique_ptr<Device> device = open();
  wait.connect_to_hub("device");
  // Two drivers of one name alternated in its state (the hand between two poses) and
  // both took its commands: the second is refused, naming the first (a real device's
  // second open fails first, its USB interface claimed).
  check_room_for_bodies({channel}, 0);
  require_chunks({written_as_slot(sizeof(DeviceState)), published_each_cycle(sizeof(LoopStats))},
                 "this driver (" + channel + ")");
  Writer<DeviceState> states(body_state_channel(channel));
  LatestReader<DeviceCommand> commands(body_command_channel(channel));
  DeviceTapeWriter tape(channel);  // every cycle, for a recorder
  DirectoryPublisher directory;
  directory.add(make_device_entry(options.name));
  directory.publish();
  confirm_body_claims({channel}, kClaimConfirmTimeout);
  LoopTiming timing;  // preallocated before memory is locked and the loop starts
  const RealtimeGrant grant = apply_realtime(options.loop, who.c_str());
  LoopStatsPublisher stats("device " + options.name, channel, options.loop.period_ns, false, grant);
  const DeviceSpec spec = device->spec();
  std::fprintf(stderr, "%s: %s%s%s on %s, %.0f Hz, force watchdog %.1f ms, max force %.1f N\n",
               who.c_str(), spec.model.data(), spec.serial[0] ? " " : "", spec.serial.data(),
               channel.c_str(), 1e9 / static_cast<double>(options.loop.period_ns),
               static_cast<double>(options.safety.watchdog_ns) * 1e-6, spec.max_force_n);
  for (;;) {
    const DriveEnd end = drive(*device, options, states, commands, tape, stats, timing);
    if (end.how == DriveEnd::kStopped) return 0;
    device.reset();
    if (end.how == DriveEnd::kGone)
      std::fprintf(stderr, "%s: the device went away (%s); its force is zero\n", who.c_str(),
                   end.what.c_str());
    else
      std::fprintf(stderr,
                   "%s: the device failed (%s); its force was set to zero and it was made "
                   "safe\n",
                   who.c_str(), end.what.c_str());
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
