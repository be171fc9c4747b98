// How a simulating process obeys world commands: pause, resume, a number of single
// steps while paused, and reset (which the caller carries out on its own state); a held
// pause lapses when its holder goes quiet.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {

// What a simulating process says when a held pause lapses (printf: the process's name,
// the holder's pid, its hold in ms). No allocation: said from the loop.
inline constexpr const char* kPauseLapsedFormat =
    "%s: the world's pause held by process %u lapsed, nothing from it for %u ms (it ended or "
    "stalls): the world runs on, as AMBF's does once its throttling client goes quiet\n";

struct WorldControl {
  bool paused = false;
  std::uint32_t paused_by_pid = 0;  // whose pause is in force
  std::uint64_t steps_to_run = 0;
  // Held pauses (WorldCommand.hold_ms): each holder, and when its hold lapses unless a
  // command of its comes first. The pause lasts while one of them holds it (pid 0: free).
  struct Hold {
    std::uint32_t pid = 0;
    std::int64_t hold_ns = 0;
    std::int64_t until_ns = 0;
  };
  std::array<Hold, kMaxPauseHolders> holds{};

  // A held pause that ended because its last holder went quiet: who, and its hold.
  struct Lapsed {
    std::uint32_t pid = 0;
    std::uint32_t hold_ms = 0;
    explicit operator bool() const noexcept { return pid != 0; }
  };

  bool held() const noexcept {
    return std::any_of(holds.begin(), holds.end(), [](const Hold& h) { return h.pid != 0; });
  }

  // Returns true when the command asks for a reset. `now_ns` times a held pause.
  bool apply(const WorldCommand& command, std::int64_t now_ns) noexcept {
    const std::uint32_t pid = command.header.publisher_pid;
    for (Hold& hold : holds)
      if (hold.pid != 0 && hold.pid == pid) hold.until_ns = now_ns + hold.hold_ns;
    switch (command.action) {
      case WorldAction::kPause:  // also ends single steps still to run
        // A plain pause (a user's) takes over held ones and holds until resumed; a held
        // pause asked for while plainly paused leaves the plain one in force. Held
        // pauses add up: the world runs on once the last holder goes quiet or releases.
        if (command.hold_ms == 0) {
          holds = {};
          paused_by_pid = pid;
        } else if (!paused || held()) {
          take_hold(pid, static_cast<std::int64_t>(command.hold_ms) * 1'000'000, now_ns);
          paused_by_pid = pid;
        }
        paused = true;
        steps_to_run = 0;
        break;
      case WorldAction::kResume:
        run_on();
        break;
      case WorldAction::kRelease: {
        // The sender's hold ends: the world runs on if no other holds it. A plain pause
        // (it has no holds) stays, even the sender's own, or a DDS bridge's that carries
        // both a user's pause and a script's release.
        bool had = false;
        for (Hold& hold : holds)
          if (hold.pid == pid) {
            hold = {};
            had = true;
          }
        if (!had) break;
        if (!held())
          run_on();
        else if (paused_by_pid == pid)
          paused_by_pid = latest_holder();
        break;
      }
      case WorldAction::kStep:
        // Only while paused: steps asked for while running would otherwise pile up
        // and all run at the next pause.
        if (paused)
          steps_to_run = std::min<std::uint64_t>(
              steps_to_run + std::min(command.step_count, kMaxWorldStepsPerCommand),
              kMaxWorldStepsPerCommand);
        break;
      case WorldAction::kReset:
        steps_to_run = 0;
        return true;
      case WorldAction::kNone:
        // A renewal with its hold takes the hold again when it lapsed while others held
        // the pause (a holder stalled past its hold), so that it still holds once they
        // go; a running world is not paused by it.
        if (command.hold_ms != 0 && paused && held())
          take_hold(pid, static_cast<std::int64_t>(command.hold_ms) * 1'000'000, now_ns);
        break;
    }
    return false;
  }

  // Holders quiet for their hold let go; once none holds the pause, the world runs on
  // and the last to go quiet is returned, for the caller to say.
  Lapsed lapse(std::int64_t now_ns) noexcept {
    Lapsed lapsed;
    std::int64_t lapsed_until_ns = 0;
    for (Hold& hold : holds)
      if (hold.pid != 0 && now_ns > hold.until_ns) {
        if (!lapsed || hold.until_ns > lapsed_until_ns) {
          lapsed = {hold.pid, static_cast<std::uint32_t>(hold.hold_ns / 1'000'000)};
          lapsed_until_ns = hold.until_ns;
        }
        hold = {};
      }
    if (!lapsed) return {};
    if (held()) {
      paused_by_pid = latest_holder();
      return {};
    }
    run_on();
    return lapsed;
  }

  // What the world state says: paused only while no single steps are left to run (a
  // world running `world step N` is not standing still).
  bool halted() const noexcept { return paused && steps_to_run == 0; }

  // The world state's pause fields: paused, whose pause and whether it is held.
  void describe_pause(WorldState& world) const noexcept {
    world.paused = halted();
    world.paused_by_pid = paused ? paused_by_pid : 0;
    world.pause_held = paused && held();
  }

  // Whether to advance this cycle; a single step asked for while paused is used up.
  bool take_step() noexcept {
    if (!paused) return true;
    if (steps_to_run == 0) return false;
    --steps_to_run;
    return true;
  }

 private:
  void run_on() noexcept {
    paused = false;
    paused_by_pid = 0;
    steps_to_run = 0;
    holds = {};
  }

  // The pid's hold, renewed; a new holder takes a free place, or that of the hold
  // lapsing soonest.
  void take_hold(std::uint32_t pid, std::int64_t hold_ns, std::int64_t now_ns) noexcept {
    Hold* place = &holds[0];
    for (Hold& hold : holds) {
      if (hold.pid == pid) {
        place = &hold;
        break;
      }
      if (hold.pid == 0 || (place->pid != 0 && hold.until_ns < place->until_ns)) place = &hold;
    }
    *place = {pid, hold_ns, now_ns + hold_ns};
  }

  // The holder whose hold lasts longest (it renewed last).
  std::uint32_t latest_holder() const noexcept {
    const Hold* latest = &holds[0];
    for (const Hold& hold : holds)
      if (hold.pid != 0 && (latest->pid == 0 || hold.until_ns > latest->until_ns)) latest = &hold;
    return latest->pid;
  }
};

}  // namespace afhub
