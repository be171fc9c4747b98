// The teleoperation process (see teleop_process.hpp).
#include "afhub/teleop/teleop_process.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/body_world.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/loop_stats_publisher.hpp"
#include "afhub/hub/process_claim.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/teleop/device_freshness.hpp"
#include "afhub/teleop/state_freshness.hpp"
#include "afhub/teleop/subtree_contact.hpp"
#include "afhub/teleop/teleop_law.hpp"

namespace afhub::teleop {
namespace {

// Device commands in flight: which device sample each answered, by its sequence, so
// that a DeviceState reporting the command's force gives the sample-to-force latency.
constexpr std::size_t kInFlight = 256;

TeleopParams params_of(const TeleopBinding& binding) {
  TeleopParams params = teleop_params(binding.spec, binding.body_gains);
  params.feedback = binding.feedback;
  return params;
}

// One device bound to one body, with everything its cycle needs made beforehand.
struct Link {
  Link(const TeleopBinding& b, const BodyEntry& entry, const TeleopOptions& options)
      : binding(&b),
        freshness(options.stale_ns, options.loop.period_ns),
        state_freshness(options.stale_ns),
        stale_ns(options.stale_ns),
        period_ns(options.loop.period_ns),
        law(params_of(b)),
        device_state(body_state_channel(device_channel_name(b.device_name))),
        device_command(body_command_channel(device_channel_name(b.device_name))),
        body(entry),
        world(entry.info.channel.data()) {
    if (!b.spec.enable_joint_control) joints = 0;
    // Contact feedback reads the states of the bodies below the root too.
    if (b.feedback != FeedbackSource::kProxy)
      for (const std::string& channel : b.subtree_bodies)
        subtree.push_back(std::make_unique<BodyClient>(channel));
    multibody_states.resize(subtree.size() + 1);
  }
  const TeleopBinding* binding;
  DeviceFreshness freshness;
  StateFreshness state_freshness;
  std::int64_t stale_ns;   // TeleopOptions::stale_ns
  std::int64_t period_ns;  // the loop's
  TeleopLaw law;
  LatestReader<DeviceState> device_state;
  Writer<DeviceCommand> device_command;
  BodyClient body;
  BodyWorld world;                                   // its pause
  ProcessClaim device_claim;                         // this process teleoperates the device
  std::vector<std::unique_ptr<BodyClient>> subtree;  // below the root: contact feedback only
  std::vector<const BodyState*> multibody_states;    // the root's, then those below: per cycle
  TeleopOutput out;
  std::size_t joints{std::numeric_limits<std::size_t>::max()};  // capped below
  std::int64_t last_cycle_ns{0};
  bool held{false};             // the device's samples are stale: the body is held
  std::uint32_t device_pid{0};  // the newest sample's driver, and its sequence there
  std::uint64_t device_sequence{0};
  bool seen_state{false};
  PhysicsLiveness physics{PhysicsLiveness::kStarting};  // not live: the device gets no force
  // Since when the force is off (not live), until the driver said so in a state: only
  // then has it seen a command without force, and ramps the force in again (a driver
  // polling slower than an outage lasted would push the whole force at once).
  std::int64_t force_off_since_ns{0};
  bool liveness_said{false};  // a change of `physics` was said: its return to live is too
  // The intervals between the body's last three states, by their stamps: a physics
  // that publishes slower than --stale (it steps slower, and publishes only when it
  // steps) went silent between each two states, said every time.
  std::uint64_t last_sequence{0};
  std::int64_t last_state_stamp_ns{0};
  std::array<std::int64_t, 3> state_gaps_ns{};
  std::size_t next_gap{0};
  bool slow_said{false};           // said once, until the physics is live again
  bool silence_unsaid{false};      // a silence taken for a slow physics' gap, not said yet
  std::uint64_t commands_sent{0};  // = the sequence of our last DeviceCommand
  std::uint64_t last_reported_command{0};
  std::array<std::int64_t, kInFlight> sample_stamp_of{};  // by command sequence % kInFlight
};

// Waits for the driver of `device_name` to publish, until give_up_ns.
void wait_for_device(Link& link, const std::string& who, std::int64_t give_up_ns) {
  const std::string& name = link.binding->device_name;
  bool said = false;
  while (!link.device_state.latest()) {
    if (stop_requested()) throw Stopped("stopped while waiting for device/" + name);
    const std::int64_t now = monotonic_ns();
    if (now >= give_up_ns)
      throw Error("no device '" + name + "' (channel device/" + name + ") for " +
                  link.binding->spec.identifier + ": start its driver, e.g. `afhub device run " +
                  "virtual --name " + name +
                  "`, or give --device NAME, or wait longer with --wait");
    if (!said) {
      std::fprintf(stderr, "%s: waiting for device/%s (%s)\n", who.c_str(), name.c_str(),
                   link.binding->spec.identifier.c_str());
      said = true;
    }
    sleep_until_ns(now + 10'000'000);
  }
}

// Who holds a device's claim, for the refusal.
std::string teleop_holding(pid_t holder) {
  if (holder == getpid()) return "this teleop already (bound twice?)";
  if (holder <= 0) return "another afhub teleop";
  const std::string pid = "pid " + std::to_string(holder);
  if (process_stopped(static_cast<std::uint32_t>(holder)))
    return pid +
           " (afhub teleop, stopped: SIGSTOP or a debugger holds it; it goes on once resumed)";
  return pid + " (afhub teleop)";
}

// One process commands a device: a second teleop on it fought the first (the palm
// pulled between their two anchors, the device at its file's maximum force). Refused
// when another teleop on this machine holds the device's claim (two started at the
// same moment both passed the look below), or while another live process goes on
// commanding it, a second at most (one stopped just before this one started is given
// that second to end; a teleop on another machine, through the DDS bridge, holds no
// claim here).
void require_device_free(Link& link) {
  const std::string channel = device_channel_name(link.binding->device_name);
  // A device's name has no '/' (channel_names.cpp).
  if (pid_t holder = 0;
      !link.device_claim.take("teleop.device." + link.binding->device_name, holder))
    throw Error(channel + " is teleoperated by " + teleop_holding(holder) +
                ": a device takes one teleoperation. Stop that one, or bind this one to another "
                "device (--device NAME)");
  // Fails closed: a teleop that could not be refused is the fight the claim prevents.
  if (!link.device_claim.unavailable().empty())
    throw Error("cannot claim " + channel + " for this teleop (" + link.device_claim.unavailable() +
                "): remove what is there, or run teleop as a member of the hub's group");
  LatestReader<DeviceCommand> commands(body_command_channel(channel));
  const std::int64_t start = monotonic_ns();
  std::uint32_t commander = 0;
  for (std::int64_t now = start; now - start < 1'000'000'000;
       sleep_until_ns(now + 2'000'000), now = monotonic_ns()) {
    const DeviceCommand* command = commands.latest();
    // A new reader finds a live writer within the hub's discovery interval (0.1 s).
    if (!command) {
      if (now - start > 300'000'000) return;
      continue;
    }
    commander = command->header.publisher_pid;
    if (commander == static_cast<std::uint32_t>(getpid()) || !process_exists(commander) ||
        now - command->header.publish_stamp_ns > 200'000'000)
      return;
  }
  throw Error(channel + " is commanded by pid " + std::to_string(commander) +
              " (another afhub teleop?): a device takes one teleoperation. Stop that one, or "
              "bind this one to another device (--device NAME)");
}

// Whether the physics publishes slower than --stale: two of its last three states came
// more than that apart (one long gap is a stall, said as such; a paused physics still
// publishes, and is said paused).
bool slower_than_stale(Link& link, const BodyState* state) {
  if (state && state->header.sequence != link.last_sequence) {
    if (link.last_state_stamp_ns > 0)
      link.state_gaps_ns[link.next_gap++ % link.state_gaps_ns.size()] =
          state->header.publish_stamp_ns - link.last_state_stamp_ns;
    link.last_sequence = state->header.sequence;
    link.last_state_stamp_ns = state->header.publish_stamp_ns;
  }
  return std::count_if(link.state_gaps_ns.begin(), link.state_gaps_ns.end(),
                       [&](std::int64_t gap) { return gap > link.stale_ns; }) >= 2;
}

void say_no_state(const Link& link, double silent_ms) {
  std::fprintf(stderr,
               "afhub teleop: no state from %s for %.0f ms (its physics stopped or died?): no "
               "force on device/%s until states come back\n",
               link.binding->body.c_str(), silent_ms, link.binding->device_name.c_str());
}

// Whether the body's physics is live (its newest state; none once there was one: a
// dead physics' channel can go away), said once at each change. A physics slower than
// --stale is said once so, with what to do, and its silences between states are not
// said, unless one outlasts three of its gaps.
void judge_body(Link& link, const BodyState* state, std::int64_t now) {
  if (state) link.seen_state = true;
  const WorldState* world = state ? link.world.of(*state) : nullptr;
  const PhysicsLiveness liveness =
      state ? link.state_freshness.judge(state->header.sequence, state->header.publish_stamp_ns,
                                         state->header.sim_step, now, world && under_pause(*world))
      : link.seen_state ? PhysicsLiveness::kSilent
                        : PhysicsLiveness::kStarting;
  const bool slow = slower_than_stale(link, state);
  std::array<std::int64_t, 3> gaps = link.state_gaps_ns;
  std::sort(gaps.begin(), gaps.end());
  const std::int64_t gap = gaps[1];  // the median: a stall among them is not the rate
  if (link.silence_unsaid && liveness == PhysicsLiveness::kSilent &&
      (!state || now - link.last_state_stamp_ns > 3 * gap)) {
    say_no_state(link, static_cast<double>(now - link.last_state_stamp_ns) * 1e-6);
    link.silence_unsaid = false;
  }
  if (liveness == link.physics) return;
  const PhysicsLiveness before = link.physics;
  link.physics = liveness;
  link.silence_unsaid = false;
  if (liveness == PhysicsLiveness::kLive) link.slow_said = false;
  if (slow && (liveness == PhysicsLiveness::kSilent || liveness == PhysicsLiveness::kStarting)) {
    link.silence_unsaid = liveness == PhysicsLiveness::kSilent;
    if (link.slow_said) return;
    const double gap_ms = static_cast<double>(gap) * 1e-6;
    std::fprintf(stderr,
                 "afhub teleop: %s publishes a state every %.0f ms, slower than --stale (%.0f ms): "
                 "its states go stale in between, so device/%s gets no force. Give teleop "
                 "--stale %.0f or more, or step the physics faster (its --dt, a lighter scene)\n",
                 link.binding->body.c_str(), gap_ms, static_cast<double>(link.stale_ns) * 1e-6,
                 link.binding->device_name.c_str(), std::ceil(gap_ms * 1.5 / 10.0) * 10.0);
    link.slow_said = true;
    link.liveness_said = true;
    return;
  }
  if (liveness == PhysicsLiveness::kStarting ||
      (liveness == PhysicsLiveness::kLive && before == PhysicsLiveness::kStarting &&
       !link.liveness_said))
    return;  // seen stepping from the start: nothing to say
  link.liveness_said = true;
  const char* name = link.binding->device_name.c_str();
  const char* body = link.binding->body.c_str();
  const double stale_ms = static_cast<double>(link.stale_ns) * 1e-6;
  if (liveness == PhysicsLiveness::kSilent)
    say_no_state(link, stale_ms);
  else if (liveness == PhysicsLiveness::kRestarted)
    std::fprintf(stderr,
                 "afhub teleop: %s's states went back to step %llu (its physics restarted or "
                 "its world was reset): no force on device/%s until it steps, then the force "
                 "ramps in\n",
                 body, static_cast<unsigned long long>(state->header.sim_step), name);
  else if (liveness == PhysicsLiveness::kPaused)
    std::fprintf(stderr,
                 "afhub teleop: %s's world is paused: no force on device/%s until it runs again "
                 "(steps by hand give none)\n",
                 body, name);
  else if (liveness == PhysicsLiveness::kNotStepping)
    std::fprintf(stderr,
                 "afhub teleop: %s has not moved a step for %.0f ms (its world is paused, or waits "
                 "for lockstep clients?): no "
                 "force on device/%s until it steps again\n",
                 body, stale_ms, name);
  else
    std::fprintf(stderr, "afhub teleop: %s's physics steps again: force on device/%s ramps in\n",
                 body, name);
}

// One cycle of one link: newest samples in, the two commands out. Returns the body's
// state the cycle answered, or nullptr.
const BodyState* cycle(Link& link, std::int64_t now, TeleopLatency* latency, std::size_t most) {
  const std::int64_t since_last_ns = link.last_cycle_ns ? now - link.last_cycle_ns : 0;
  link.last_cycle_ns = now;
  const DeviceState* device = link.device_state.latest();
  const BodyState* state = link.body.latest_state();
  if (hub_lost()) return nullptr;  // the driver's watchdog zeroes the force
  judge_body(link, state, now);
  if (link.physics != PhysicsLiveness::kLive) {
    if (link.force_off_since_ns < 0) link.force_off_since_ns = now;
  } else if (link.force_off_since_ns >= 0 && device &&
             device->header.publish_stamp_ns > link.force_off_since_ns &&
             device->gate != ForceGate::kApplying) {
    link.force_off_since_ns = -1;
  }
  if (!device || !state) return nullptr;  // the same
  if (latency && device->command_sequence > link.last_reported_command &&
      device->command_sequence <= link.commands_sent &&
      device->command_sequence + kInFlight > link.commands_sent) {
    // The first report of each command's force.
    link.last_reported_command = device->command_sequence;
    const std::int64_t sample = link.sample_stamp_of[device->command_sequence % kInFlight];
    if (latency->to_device_force.size() < most)
      latency->to_device_force.push_back(device->header.publish_stamp_ns - sample);
  }
  // A driver restarted within the stale time comes with no gap in the samples. Behind
  // the DDS bridge the pid stays the mirror's, and the numbering begins again.
  const bool new_pid = link.device_pid != 0 && device->header.publisher_pid != link.device_pid;
  const bool new_driver =
      new_pid || (link.device_pid != 0 && device->header.sequence < link.device_sequence);
  link.device_pid = device->header.publisher_pid;
  link.device_sequence = device->header.sequence;
  if (new_driver && !link.held) {
    link.law.re_anchor();
    const std::string which =
        new_pid ? "pid " + std::to_string(link.device_pid) : "its samples numbered afresh";
    std::fprintf(stderr,
                 "afhub teleop: device/%s has a new driver (%s): %s moves on from where it is, "
                 "with no jump\n",
                 link.binding->device_name.c_str(), which.c_str(), link.binding->body.c_str());
  }
  // This process itself stood still (SIGSTOP, a debugger, a starved or stalled
  // machine): meanwhile the driver took the force off, the physics let the body go, and
  // the hand moved on. The body is driven on from where it is now, as at the start (it
  // was pulled to where the hand had gone, and the device pulled the hand back), and the
  // force returns only through the driver's ramp. A driver whose watchdog outlasted the
  // gap still applies the force: that is a late cycle (restarting dropped its 3 N).
  const bool standstill = stood_still(since_last_ns, link.stale_ns, link.period_ns) &&
                          device->gate != ForceGate::kApplying;
  if (standstill) {
    link.law.restart_from(state->pose);
    link.force_off_since_ns = now;
    std::fprintf(stderr,
                 "afhub teleop: this process stood still for %.0f ms: %s is driven on from "
                 "where it is now, and the force on device/%s ramps in\n",
                 static_cast<double>(since_last_ns) * 1e-6, link.binding->body.c_str(),
                 link.binding->device_name.c_str());
  }
  // No time passed for the law across a standstill: its limits on change start over.
  const double dt = standstill ? 0.0 : static_cast<double>(since_last_ns) * 1e-9;
  if (const bool stale = link.freshness.stale(device->header.publish_stamp_ns, now);
      stale != link.held) {
    link.held = stale;
    link.law.hold(stale);
    const char* name = link.binding->device_name.c_str();
    const char* body = link.binding->body.c_str();
    if (stale)
      std::fprintf(stderr,
                   "afhub teleop: no sample from device/%s for %.0f ms (its driver stopped?): "
                   "holding %s where it is, with no force on the device, until samples come "
                   "back\n",
                   name, static_cast<double>(link.stale_ns) * 1e-6, body);
    else
      std::fprintf(stderr, "afhub teleop: device/%s is back: %s moves on from where it was held\n",
                   name, body);
  }
  link.multibody_states[0] = state;
  for (std::size_t i = 0; i < link.subtree.size(); ++i)
    link.multibody_states[i + 1] = link.subtree[i]->latest_state();
  const Wrench contact = subtree_contact_wrench(state->pose.position_m, link.multibody_states);
  link.law.step(*device, state->pose, state->twist, dt, link.out, contact);

  const std::size_t joints =
      std::min<std::size_t>({link.joints, link.binding->gripper_joints.size(), state->joint_count});
  if (BodyCommand* command = link.body.loan_command(static_cast<std::uint32_t>(joints))) {
    fill_body_command(link.out, {link.binding->gripper_joints.data(), joints},
                      link.binding->actuator_count, *command);
    limit_wrench(command->wrench, link.binding->body_limit);
    command->header.sim_step = state->header.sim_step;
    command->header.sim_time_s = state->header.sim_time_s;
    link.body.publish_command(command);
    if (latency && latency->to_body_command.size() < most)
      latency->to_body_command.push_back(monotonic_ns() - device->header.publish_stamp_ns);
  }
  if (DeviceCommand* command = link.device_command.loan()) {
    fill_device_command(
        link.out, link.physics == PhysicsLiveness::kLive && link.force_off_since_ns < 0, *command);
    link.device_command.publish(command);
    ++link.commands_sent;
    link.sample_stamp_of[link.commands_sent % kInFlight] = device->header.publish_stamp_ns;
  }
  return state;
}

}  // namespace

int run_teleop(const TeleopOptions& options, TeleopLatency* latency) {
  install_stop_signal_handlers();
  if (options.bindings.empty()) throw Error("afhub teleop: no device selected");
  const std::string who = "afhub teleop";
  if (options.survive_hub_loss) survive_hub_loss(who);
  const StartupWait wait(options.wait_s);
  wait.connect_to_hub("teleop");

  std::vector<std::unique_ptr<Link>> links;
  for (const TeleopBinding& binding : options.bindings) {
    const BodyEntry entry =
        wait.wait_for_body(binding.body, who, binding.load_hint + ", or wait longer with --wait");
    links.push_back(std::make_unique<Link>(binding, entry, options));
    wait_for_device(*links.back(), who, wait.give_up_ns());
    require_device_free(*links.back());
    std::fprintf(stderr, "%s: %s: device/%s drives %s\n", who.c_str(),
                 binding.spec.identifier.c_str(), binding.device_name.c_str(),
                 binding.body.c_str());
  }
  // Before the first loan, as the physics: teleop must not starve a running physics.
  std::vector<ChunkNeed> needs{published_each_cycle(sizeof(LoopStats))};
  for (const auto& link : links) {
    needs.push_back(written_as_slot(sizeof(DeviceCommand)));
    needs.push_back(written_as_slot(body_command_bytes(link->binding->gripper_joints.size())));
  }
  require_chunks(needs, "this teleop (" + std::to_string(links.size()) + " devices)");
  const std::size_t most = latency ? options.latency_samples : 0;
  if (latency) {
    latency->to_body_command.reserve(most);
    latency->to_device_force.reserve(most);
  }

  LoopTiming timing;
  const RealtimeGrant grant = apply_realtime(options.loop, who.c_str());
  LoopStatsPublisher stats("teleop", options.bindings.front().body, options.loop.period_ns, false,
                           grant);
  LoopOptions loop = options.loop;
  LoopCycle steps;
  // In phase with the first body's physics: each body command answers the newest state.
  std::optional<StepPhase> phase;
  BodyClient& phased = links.front()->body;
  if (const std::int64_t after_ns = after_step_offset_ns(options.after_step_ns, loop.period_ns);
      after_ns >= 0) {
    phase.emplace(
        after_ns, [&phased] { return phased.latest_state(); }, &phased.state_reader());
    phase->attach(loop, steps);
  }
  steps.work = [&] {
    // A physics catching up after a stall: each of its late states answered as it
    // comes (see controller.cpp), a cycle of every link each; the law's dt is the time
    // that passed, so its force limits hold.
    for (;;) {
      const std::int64_t now = monotonic_ns();
      const BodyState* answered = cycle(*links.front(), now, latency, most);
      StepPhase::Answered copy;
      if (phase && answered) {
        phase->follow(*answered);
        copy = StepPhase::Answered::of(*answered);
      }
      for (std::size_t i = 1; i < links.size(); ++i) cycle(*links[i], now, latency, most);
      if (!phase || !answered || !phase->next_while_catching_up(copy)) return true;
    }
  };
  steps.after = [&](std::int64_t now) { stats.maybe_publish(now, timing); };
  run_periodic(loop, timing, steps);
  return 0;
}

}  // namespace afhub::teleop
