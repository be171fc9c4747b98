// Controller processes (see controller.hpp).
#include "afhub/controllers/controller.hpp"
#include "afhub/rt/clock.hpp"

#include <sched.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_world.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/loop_stats_publisher.hpp"
#include "afhub/hub/physics_late_commands.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {
namespace {

// The physics' refusals of this process's commands, which a body's state counts with
// the last one's sender and reason: said on stderr, the first at once and then at most
// once a second, so that a controller whose commands are all refused (a target beyond
// a joint's bound) does not run on in silence. No allocation: it runs in the loop.
class RefusalNotice {
 public:
  explicit RefusalNotice(const std::string& who) : who_(who) {}

  void look(const BodyState& state) {
    const std::uint32_t count = state.refused_commands;
    const std::uint32_t newly = seen_any_ ? count - seen_ : 0;
    seen_ = count;
    seen_any_ = true;
    if (newly == 0 || state.refused_command_pid != pid_) return;
    unsaid_ += newly;
    const std::int64_t now_ns = monotonic_ns();  // read only when there is a refusal to say
    if (now_ns < next_say_ns_) return;
    const std::string_view reason = name_of(state.refusal_reason);
    std::fprintf(stderr,
                 "%s: the physics refused %llu command%s of this controller (nothing of %s was "
                 "applied), the last: %.*s\n",
                 who_.c_str(), static_cast<unsigned long long>(unsaid_), unsaid_ == 1 ? "" : "s",
                 unsaid_ == 1 ? "it" : "them", static_cast<int>(reason.size()), reason.data());
    unsaid_ = 0;
    next_say_ns_ = now_ns + 1'000'000'000;
  }

 private:
  const std::string& who_;
  const std::uint32_t pid_ = static_cast<std::uint32_t>(getpid());
  std::uint32_t seen_ = 0;
  bool seen_any_ = false;
  std::uint64_t unsaid_ = 0;
  std::int64_t next_say_ns_ = 0;
};

// Fills and publishes one command answering `state`.
void answer(BodyClient& body, const BodyState& state, const ControllerCycle& cycle, bool lockstep,
            RefusalNotice& refusals) {
  if (hub_lost()) return;  // outputs safe: no command into a hub that is gone
  refusals.look(state);
  BodyCommand* command = body.loan_command(state.joint_count);
  if (!command) return;  // shared memory exhausted: the watchdog covers a lasting shortage
  cycle(state, *command);
  command->header.sim_step = state.header.sim_step;
  command->header.sim_time_s = state.header.sim_time_s;
  command->lockstep = lockstep;
  body.publish_command(command);
}

// Free-running: every period, the newest state in, a command out.
void run_free(BodyClient& body, const ControllerOptions& options, const ControllerCycle& cycle,
              LoopTiming& timing, LoopStatsPublisher& stats, RefusalNotice& refusals) {
  LoopOptions loop = options.loop;
  const std::int64_t after_ns = after_step_offset_ns(options.after_step_ns, loop.period_ns);
  std::optional<StepPhase> phase;
  if (after_ns >= 0) {
    // The grid comes from the first state. Listed in the catalog, a body's state may
    // still take seconds to come (a hub just restarted, a loaded machine): waited for,
    // said once.
    for (std::int64_t say_at = monotonic_ns() + 3'000'000'000; !body.latest_state();) {
      if (stop_requested()) return;
      if (say_at > 0 && monotonic_ns() >= say_at) {
        std::fprintf(stderr,
                     "afhub %s: no state from %s yet after 3 s (%s its writer); still waiting: is "
                     "the physics running?\n",
                     options.name.c_str(), body.channel().c_str(),
                     body.subscribed() ? "connected to" : "not connected to");
        say_at = 0;
      }
      sleep_until_ns(monotonic_ns() + 1'000'000);
    }
    phase.emplace(
        after_ns, [&body] { return body.latest_state(); }, &body.state_reader());
  }
  PhysicsLateCommands late_commands;
  LoopCycle steps;
  if (phase) phase->attach(loop, steps);
  const auto respond = [&](const BodyState& state) {
    timing.count_late(late_commands.newly_late(state));
    if (phase) phase->follow(state);  // a new physics, on a grid of its own
    answer(body, state, cycle, false, refusals);
  };
  steps.work = [&] {
    // A physics catching up after a stall: each of its late steps answered as it comes.
    for (const BodyState* state = body.latest_state(); state;) {
      const StepPhase::Answered answered = StepPhase::Answered::of(*state);
      respond(*state);
      state = phase ? phase->next_while_catching_up(answered) : nullptr;
    }
    return true;
  };
  steps.after = [&](std::int64_t now) { stats.maybe_publish(now, timing); };
  run_periodic(loop, timing, steps);
}

// Whether the physics publishing `body` steps in lockstep, as its world state says
// (BodyWorld). nullopt when none comes within a second (a publisher of bodies without a
// world, or one stalled).
std::optional<bool> publisher_steps_in_lockstep(BodyClient& body, const std::string& channel) {
  std::optional<BodyWorld> world;
  try {
    world.emplace(channel);
  } catch (const Error&) {  // a hub short of ports: a message is not worth the controller
    return std::nullopt;
  }
  for (const std::int64_t give_up = monotonic_ns() + 1'000'000'000;
       monotonic_ns() < give_up && !stop_requested();
       std::this_thread::sleep_for(std::chrono::milliseconds(2))) {
    if (const BodyState* state = body.latest_state())
      if (const WorldState* now = world->of(*state)) return now->lockstep != 0;
  }
  return std::nullopt;
}

// What a lockstep controller says at start: whether the physics waits for it.
void say_lockstep(BodyClient& body, const std::string& channel, const std::string& who) {
  const std::optional<bool> lockstep = publisher_steps_in_lockstep(body, channel);
  if (stop_requested()) return;
  if (lockstep == true)
    std::fprintf(stderr, "%s: commanding %s in lockstep with the physics\n", who.c_str(),
                 channel.c_str());
  else
    std::fprintf(stderr,
                 "%s: answering each state of %s as it comes, but %s: it does not wait for "
                 "these answers (`afhub run --lockstep` would)\n",
                 who.c_str(), channel.c_str(),
                 lockstep.has_value()
                     ? "its physics steps on its own clock, not in lockstep"
                     : "no world state from its publisher says it steps in lockstep");
}

// Lockstep: answer each new step as soon as its state arrives, asleep on the state
// channel until then (a futex post wakes it in microseconds), or with `spin`
// polling with a yield. The sleep ends every 10 ms to publish stats and see a stop.
void run_lockstep(BodyClient& body, const ControllerOptions& options, const ControllerCycle& cycle,
                  LoopTiming& timing, LoopStatsPublisher& stats, RefusalNotice& refusals) {
  std::unique_ptr<SampleWaiter> waiter;
  if (!options.spin) {
    waiter = std::make_unique<SampleWaiter>();
    waiter->attach(body.state_reader());
  }
  bool answered_any = false;
  std::uint64_t last_step = 0;
  for (std::uint64_t done = 0;
       !stop_requested() && (options.loop.max_cycles == 0 || done < options.loop.max_cycles);) {
    const BodyState* state = body.latest_state();
    const std::int64_t now = monotonic_ns();
    stats.maybe_publish(now, timing);
    if (!state || (answered_any && state->header.sim_step == last_step)) {
      if (waiter)
        waiter->wait(10'000'000);
      else
        sched_yield();
      continue;
    }
    const std::uint64_t step = state->header.sim_step;
    // Steps skipped since the last answer went ahead without this controller.
    if (answered_any && step > last_step + 1) timing.count_late(step - last_step - 1);
    answer(body, *state, cycle, true, refusals);
    timing.record(0, monotonic_ns() - now);
    answered_any = true;
    last_step = step;
    ++done;
  }
}

}  // namespace

int run_controller(const ControllerOptions& options, const ControllerCycle& cycle,
                   LoopTiming* timing_out) {
  install_stop_signal_handlers();
  const std::string who = "afhub " + options.name;
  if (options.survive_hub_loss) survive_hub_loss(who);
  const StartupWait wait(options.wait_s);
  wait.connect_to_hub("ctl");
  const BodyEntry entry = wait.wait_for_body(options.body, who);
  const std::string channel(name_of(entry.info.channel));
  if (options.joints_needed > entry.info.joint_count)
    throw Error(options.joints_needed_by + " needs " + std::to_string(options.joints_needed) +
                " joints, and " + channel + " has " + std::to_string(entry.info.joint_count) +
                " (`afhub ls` lists each body's joints)");
  BodyClient body(entry);
  require_chunks({written_as_slot(body_command_bytes(entry.info.joint_count)),
                  published_each_cycle(sizeof(LoopStats))},
                 "this controller (commanding " + channel + ")");
  if (options.lockstep) say_lockstep(body, channel, who);  // its readers before memory is locked
  LoopTiming own_timing;  // preallocated before memory is locked and the loop starts
  LoopTiming& timing = timing_out ? *timing_out : own_timing;
  const RealtimeGrant grant = apply_realtime(options.loop, who.c_str());
  LoopStatsPublisher stats(options.name, channel, options.loop.period_ns, options.lockstep, grant);
  RefusalNotice refusals(who);
  if (options.lockstep) {
    run_lockstep(body, options, cycle, timing, stats, refusals);
  } else {
    std::fprintf(stderr, "%s: commanding %s every %.3f ms\n", who.c_str(), channel.c_str(),
                 static_cast<double>(options.loop.period_ns) * 1e-6);
    run_free(body, options, cycle, timing, stats, refusals);
  }
  return 0;
}

}  // namespace afhub
