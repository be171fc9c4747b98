// Whether the simulated body's physics is live: a device may push only on a physics that
// steps. Silent: the newest state's publish stamp is older than stale_ns, or this loop
// has seen no new state (a new sequence or stamp) for stale_ns by its own clock (a stamp
// from the future is no fresher): the physics stopped or died. Not stepping: states come,
// but their step has not changed for stale_ns: the world is paused (or a lockstep physics
// waits), and a device moving on would pull ever harder on a body that cannot follow.
// Paused: the body's world is under a pause (its world state, when the physics has one:
// BodyWorld). Steps by hand (`afhub world step`) move the body but do not run the world
// on: each one looked live until its step had stayed for stale_ns, and the force ramped
// in for those 50 ms. After the pause, no force until a step is seen; a reset or a new
// physics during the pause is said as Restarted then.
// Starting: states come but none has stepped yet since they (re)appeared; no force until
// one does (a teleop started against a paused world pushed for its first 50 ms).
// Restarted: the states' sequence or step went back with no silence between: a new
// physics took the channel (restarted within the stale time) or the world was reset, and
// the body is back at its initial pose, far from where the device holds it. No force for
// kRestartOffNs at least and until a step is seen (and the driver says it has had the
// force off, teleop_process.cpp), so that the driver ramps it in again (before, the full
// force of the new error came at once).
// Unlike DeviceFreshness this does not wait for the loop's own cycles: a false alarm on a
// busy machine costs a force ramp, a missed one pushes the operator's hand against a
// frozen or dead simulation.
#pragma once

#include <cstdint>

namespace afhub::teleop {

enum class PhysicsLiveness : std::uint8_t {
  kLive,
  kSilent,
  kNotStepping,
  kPaused,
  kStarting,
  kRestarted
};

// An outage a reader of the device's state sees (20 of its states at 1 kHz), short
// against an operator's reaction.
inline constexpr std::int64_t kRestartOffNs = 20'000'000;

class StateFreshness {
 public:
  explicit StateFreshness(std::int64_t stale_ns) noexcept : stale_ns_(stale_ns) {}

  // Once per cycle with the newest state's sequence, publish stamp and step, and
  // whether its world says it is paused (false for a physics with no world state).
  PhysicsLiveness judge(std::uint64_t sequence, std::int64_t stamp_ns, std::uint64_t step,
                        std::int64_t now_ns, bool world_paused = false) noexcept {
    if (sequence != sequence_ || stamp_ns != stamp_ns_ || seen_ns_ < 0) {
      if (stepped_ns_ >= 0 && (sequence < sequence_ || step < step_)) {  // no silence between
        restarted_ns_ = now_ns;
        stepped_ns_ = -1;
      }
      sequence_ = sequence;
      stamp_ns_ = stamp_ns;
      seen_ns_ = now_ns;
    }
    if (now_ns - stamp_ns > stale_ns_ || now_ns - seen_ns_ > stale_ns_) {
      stepped_ns_ = -1;    // back, it must be seen stepping again
      restarted_ns_ = -1;  // said as silent instead
      return PhysicsLiveness::kSilent;
    }
    if (world_paused) {
      was_paused_ = true;
      return PhysicsLiveness::kPaused;
    }
    if (was_paused_) {  // resumed: it must be seen stepping
      was_paused_ = false;
      stepped_ns_ = -1;
    }
    if (stepped_ns_ < 0) {
      moved_ = false;
      step_ = step;
      stepped_ns_ = now_ns;
    } else if (step != step_) {
      moved_ = true;
      step_ = step;
      stepped_ns_ = now_ns;
    }
    if (now_ns - stepped_ns_ > stale_ns_) return PhysicsLiveness::kNotStepping;
    if (restarted_ns_ >= 0 && (!moved_ || now_ns - restarted_ns_ < kRestartOffNs))
      return PhysicsLiveness::kRestarted;
    restarted_ns_ = -1;
    return moved_ ? PhysicsLiveness::kLive : PhysicsLiveness::kStarting;
  }

 private:
  std::int64_t stale_ns_;
  std::uint64_t sequence_{0};
  std::int64_t stamp_ns_{0};
  std::int64_t seen_ns_{-1};  // when this loop first saw the newest state; -1: none yet
  std::uint64_t step_{0};
  std::int64_t stepped_ns_{-1};    // when this loop first saw the newest step; -1: none yet
  bool moved_{false};              // a step seen to change since states (re)appeared
  std::int64_t restarted_ns_{-1};  // when the sequence or step went back; -1: not since
  bool was_paused_{false};         // the last judgement was kPaused
};

}  // namespace afhub::teleop
