// afhub.World: the simulation's clock, read from the world state, and its commands
// (pause, resume, step N, reset), each confirmed by the world state as `afhub world`
// confirms them.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <string>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/world_action_watch.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/world.hpp"
#include "bindings.hpp"

namespace afhub::python {
namespace {

ChannelId world_channel(const std::string& name_space, std::string_view event) {
  return {std::string(kService), world_instance(name_space), std::string(event)};
}

class World {
 public:
  explicit World(const std::string& name_space)
      : reader_((require_no_nul(name_space), ensure_connected(),
                 world_channel(name_space, kStateEvent))),
        writer_(world_channel(name_space, kCommandEvent)) {
    // The simulation acts on each sequence number once: start past any number an
    // earlier writer could have used.
    writer_.raw().continue_sequence_after(static_cast<std::uint64_t>(monotonic_ns()));
  }

  // The newest world state; the world state is published every step, paused or not.
  WorldState state(double wait_s) {
    require_hub();
    const std::int64_t give_up = deadline_after(wait_s, "wait_s");
    const WorldState* state = reader_.latest();
    if (!state) {
      SignalWatch signals;
      {
        py::gil_scoped_release release;
        while (!(state = reader_.latest()) && monotonic_ns() < give_up && !signals.pending())
          sleep_until_ns(monotonic_ns() + 1'000'000);
      }
      signals.raise_if_pending();
    }
    if (!state)
      throw Error(
          "no simulation is running: nothing has published the world state for " +
          py::str(py::float_(wait_s)).cast<std::string>() +
          " s. Start one with `afhub run MODEL` (or `afhub synth`); a lockstep run waiting for "
          "its clients publishes nothing until they join");
    return *state;
  }

  // Sends `action` and waits until the world state shows it done; says what happened.
  // `steps` wide: a count past 2^32, or negative, is refused with its bounds (pybind's own
  // error named no bound).
  std::string act(WorldAction action, std::int64_t steps, double timeout_s, double hold_s = 0.0) {
    require_hub();
    const std::int64_t give_up = deadline_after(timeout_s, "timeout_s");
    if (!(hold_s == 0.0 || (hold_s >= kMinHoldS && hold_s <= kMaxPauseHoldMs / 1000.0)))
      throw py::value_error("hold_s takes 0 (paused until resumed) or 0.01 to " +
                            std::to_string(kMaxPauseHoldMs / 1000) + " s, not " +
                            py::str(py::float_(hold_s)).cast<std::string>());
    if (action == WorldAction::kStep && (steps < 1 || steps > kMaxWorldStepsPerCommand))
      throw py::value_error("step takes a number of steps from 1 to " +
                            std::to_string(kMaxWorldStepsPerCommand) +
                            "; to run on, World.resume()");
    const WorldState before = state(2.0);
    if (action == WorldAction::kStep && !under_pause(before))
      throw Error(
          "the world is running, so there is nothing to step: pause it first "
          "(World.pause()), then World.step(n)");
    WorldCommand* command = writer_.loan();
    if (!command) throw Error("shared memory is exhausted: the world command was not sent");
    command->action = action;
    command->step_count = static_cast<std::uint32_t>(steps);
    command->hold_ms = static_cast<std::uint32_t>(std::lround(hold_s * 1000.0));
    if (command->hold_ms != 0) hold_ms_ = command->hold_ms;
    if (action == WorldAction::kResume) hold_ms_ = 0;
    // Valid while this waits, a few of the world's cycles at least (a timeout of 0 would
    // have it dropped or not by chance), an hour at most (the payload check's bound).
    const std::int64_t wait_ns = std::max(give_up - monotonic_ns(), kShortestWaitNs);
    command->valid_ms = static_cast<std::uint32_t>(
        std::min<std::int64_t>(wait_ns / 1'000'000, kMaxWorldCommandValidMs));
    const std::int64_t wait_until_ns = monotonic_ns() + wait_ns + kWorldCommandShownWithinNs;
    writer_.publish(command);
    WorldActionWatch watch(action, static_cast<std::uint32_t>(steps), before, monotonic_ns());

    std::optional<std::string> done;
    SignalWatch signals;
    {
      py::gil_scoped_release release;
      while (!done && monotonic_ns() < wait_until_ns && !hub_lost() && !signals.pending()) {
        const WorldState* now = reader_.latest();
        if (now && reader_.updated()) done = watch.shown(*now);
        if (!done) sleep_until_ns(monotonic_ns() + 200'000);
      }
    }
    signals.raise_if_pending();
    if (done) return *done;
    require_hub();
    throw Error("the command was sent but the simulation did not act on it within " +
                py::str(py::float_(timeout_s)).cast<std::string>() +
                " s, and it will not later (read after that, it is dropped): is it stalled, or "
                "waiting for lockstep clients? (`afhub status`)");
  }

  // Renews this process's held pause: a command that does nothing else. One a
  // millisecond at most goes out from this process, the others are skipped: the world's
  // command queue holds 64, and a loop of hold() pushed other writers' pauses and
  // resumes out of it.
  // A hold that lapsed (the script stalled past hold_s) or was ended (a resume, a
  // restarted physics) is said: renewing it did nothing while the world ran on.
  void hold() {
    if (hold_ms_ != 0)
      // Not paused while a step(n) runs: the hold is over once nobody's pause is in force.
      if (const WorldState* now = reader_.latest();
          now && !now->paused && now->paused_by_pid == 0) {
        hold_ms_ = 0;
        throw Error(
            "this process's held pause is over (it lapsed, the script silent for longer than "
            "hold_s, or the world was resumed or restarted): the world runs. "
            "World.pause(hold_s=...) holds it again");
      }
    send_unwaited(WorldAction::kNone, kRenewalSpacingNs, hold_ms_);
  }

  // Ends this process's held pause; the world runs on unless another process holds it
  // or it was paused plainly (not waited for: the world may rightly stay paused).
  void release() {
    hold_ms_ = 0;
    send_unwaited(WorldAction::kRelease, 0, 0);
  }

 private:
  static constexpr double kMinHoldS = 0.01;  // ten renewal spacings, and a GIL's switch
  static constexpr std::int64_t kRenewalSpacingNs = 1'000'000;

  static constexpr std::int64_t kShortestWaitNs = 50'000'000;

  // Sends `action` (with `hold_ms`: a renewal takes its hold again if it lapsed while
  // others held the pause) unless this World sent one within `spacing_ns`.
  void send_unwaited(WorldAction action, std::int64_t spacing_ns, std::uint32_t hold_ms) {
    require_hub();
    const std::int64_t now = monotonic_ns();
    if (spacing_ns > 0 && now - last_sent_ns_.load(std::memory_order_relaxed) < spacing_ns) return;
    last_sent_ns_.store(now, std::memory_order_relaxed);
    WorldCommand* command = writer_.loan();
    if (!command) throw Error("shared memory is exhausted: the world command was not sent");
    command->action = action;
    command->hold_ms = hold_ms;
    writer_.publish(command);
  }

  std::atomic<std::int64_t> last_sent_ns_{0};  // hold() from any thread
  std::atomic<std::uint32_t> hold_ms_{0};      // this World's last held pause's hold

  LatestReader<WorldState> reader_;
  Writer<WorldCommand> writer_;
};

py::dict state_dict(const WorldState& s) {
  py::dict out;
  out["step"] = s.header.sim_step;
  out["time"] = s.header.sim_time_s;
  out["stamp_ns"] = s.header.publish_stamp_ns;
  out["wall_time"] = s.wall_time_s;
  out["achieved_rate_hz"] = s.achieved_rate_hz;
  out["body_count"] = s.body_count;
  out["paused"] = s.paused != 0;
  out["paused_by_pid"] = s.paused_by_pid;
  out["pause_held"] = s.pause_held != 0;
  out["lockstep"] = s.lockstep != 0;
  out["rejected_commands"] = s.rejected_commands;
  out["watchdog_expiries"] = s.watchdog_expiries;
  out["stale_commands"] = s.stale_commands;
  out["lockstep_clients"] = s.lockstep_clients;
  out["late_answers"] = s.late_answers;
  out["dropped_clients"] = s.dropped_clients;
  out["nan_recoveries"] = s.nan_recoveries;
  const auto names = [](const auto& objects, std::uint32_t count) {
    py::list list;
    for (std::uint32_t i = 0; i < std::min<std::uint32_t>(count, kMaxWorldObjects); ++i)
      list.append(std::string(name_of(objects[i].name)));
    return list;
  };
  out["lights"] = names(s.lights, s.light_count);
  out["cameras"] = names(s.cameras, s.camera_count);
  return out;
}

}  // namespace

void register_world(py::module_& module) {
  py::class_<World>(module, "World",
                    "The simulation's clock. World(namespace='') is the world of `afhub run`, "
                    "or of `afhub run --namespace NS`. Each command waits until the world "
                    "state shows it done and returns what happened, as `afhub world` prints "
                    "it; afhub.Error when no simulation runs or it did not act in time.")
      .def(py::init<const std::string&>(), py::arg("namespace") = "")
      .def(
          "state", [](World& world, double wait_s) { return state_dict(world.state(wait_s)); },
          py::arg("wait_s") = 2.0,
          "The newest world state as a dict: step, time (simulated s), stamp_ns, wall_time, "
          "achieved_rate_hz, body_count, paused, paused_by_pid (whose pause is in force, also "
          "while it runs single steps; 0 when not paused), pause_held (it lapses once that process "
          "goes quiet), lockstep, "
          "rejected_commands, "
          "watchdog_expiries, stale_commands, lockstep_clients, late_answers, "
          "dropped_clients, nan_recoveries, and the names of the world file's lights and "
          "cameras.")
      .def(
          "sim_step", [](World& world) { return world.state(2.0).header.sim_step; },
          "The step the simulation is at.")
      .def(
          "sim_time", [](World& world) { return world.state(2.0).header.sim_time_s; },
          "Simulated time, s.")
      .def(
          "pause",
          [](World& world, double timeout_s, double hold_s) {
            return world.act(WorldAction::kPause, 1, timeout_s, hold_s);
          },
          py::arg("timeout_s") = 5.0, py::arg("hold_s") = 0.0,
          "Stops stepping; states are still published. hold_s (0.01 to 60) > 0: a held "
          "pause, which lasts only while this process's world commands (step, hold) keep "
          "coming less than hold_s apart: should the script die or stall, the world runs "
          "on. Several processes' held pauses add up: it lasts while one of them holds it.")
      .def("hold", &World::hold,
           "Renews this process's held pause (pause(hold_s=...)); call it more often than "
           "hold_s, from any thread (one renewal a millisecond goes out from a World, the rest "
           "are skipped). Raises afhub.Error once the hold is over (it lapsed, or the world was "
           "resumed or restarted) and the world runs.")
      .def("release", &World::release,
           "Ends this process's held pause: the world runs on, unless another process "
           "holds it too or it was paused plainly (afhub world pause). Not waited for.")
      .def(
          "resume",
          [](World& world, double timeout_s) {
            return world.act(WorldAction::kResume, 1, timeout_s);
          },
          py::arg("timeout_s") = 5.0, "Steps again after a pause.")
      .def(
          "step",
          [](World& world, std::int64_t steps, double timeout_s) {
            return world.act(WorldAction::kStep, steps, timeout_s);
          },
          py::arg("steps") = 1, py::arg("timeout_s") = 5.0,
          "While paused, advances `steps` steps, then stays paused.")
      .def(
          "reset",
          [](World& world, double timeout_s) {
            return world.act(WorldAction::kReset, 1, timeout_s);
          },
          py::arg("timeout_s") = 5.0,
          "Puts every body back where the model starts it, clears its commands and sets the "
          "step count to 0 (paused or running, as before).");
}

}  // namespace afhub::python
