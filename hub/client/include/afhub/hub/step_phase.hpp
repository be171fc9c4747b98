// A free-running loop in phase with the physics that steps its body: it wakes a set
// time after each step is due on the physics' grid (BodyState.step_due_ns), so that
// what it sends answers the newest state and arrives before the next step. Used by
// `afhub ctl`'s controllers, `afhub teleop` and Python's afhub.Loop.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>

#include "afhub/hub/sample_waiter.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/shm_layout/body_state.hpp"

namespace afhub {

// A point of a free-running loop's grid: `after_ns` after `state`'s step was due on its
// physics' grid (after it was published, when the physics is not paced by the clock);
// 0 (unaligned) when after_ns is negative.
std::int64_t grid_in_phase(const BodyState& state, std::int64_t after_ns) noexcept;

// How a loop's options say when it wakes: an offset after each step is due (ns, >= 0),
// or one of these.
inline constexpr std::int64_t kAfterStepHalfPeriod = -1;  // half the loop's period
inline constexpr std::int64_t kAfterStepUnaligned = -2;   // on the loop's own clock
// The offset those options give a loop of `period_ns`: negative for unaligned.
constexpr std::int64_t after_step_offset_ns(std::int64_t after_step_ns,
                                            std::int64_t period_ns) noexcept {
  return after_step_ns == kAfterStepHalfPeriod ? period_ns / 2 : after_step_ns;
}

class StepPhase {
 public:
  // `after_ns` (>= 0, under `loop`'s period): how long after each step is due the loop
  // wakes. `latest` gives the body's newest state, or nullptr before the first.
  // `state_reader`, when given, is the reader `latest` reads: waits for a state sleep on
  // it (a futex the physics' publish wakes); without, they poll every 20 us.
  StepPhase(std::int64_t after_ns, std::function<const BodyState*()> latest,
            RawLatestReader* state_reader = nullptr);
  ~StepPhase();

  // Puts `loop` on the physics' grid when a state is there already (otherwise the first
  // state moves it there, see follow()), and `cycle` its deadline, its re-gridding
  // and a wait: when the physics is just late (its newest state is of the step before
  // the one due `after_ns` ago), that step's state is waited for in 20 us sleeps until
  // 0.1 ms before the next step; a physics further behind (stopped, gone) is not.
  // The waits keep the loop's clock (LoopOptions::clock: a test's).
  void attach(LoopOptions& loop, LoopCycle& cycle);
  // In the cycle's work, with the state it answers: a state on a grid the loop is not
  // on moves the loop onto it: another physics (a restart, or the first state), the
  // first step due on the clock after the model as loaded (step 0 has no due time, so
  // a loop started then took the publish stamp), a physics started over in the same
  // process (its steps count again from 0: a re-exec after a hub restart).
  void follow(const BodyState& state) noexcept;
  // In the cycle's work, after answering `answered`: when its physics is behind its grid
  // (the step after `answered` is due already: after a stall the physics runs its late
  // steps back to back, waiting a moment for the answers of the loops in phase, see
  // physics/run_loop.hpp), the physics' next state as soon as it comes, to answer at
  // once. nullptr when the physics is on its grid (or so far behind that it skips to
  // it), or no state came before the loop's next cycle is near. The loop's period is
  // taken for the physics'. The wait is left out of the cycle's compute time.
  // `answered` is copied before the answer (Answered::of): answering may read the
  // body's reader again, which rewrites the state it returned before.
  struct Answered {
    std::uint64_t step = 0;
    std::int64_t step_due_ns = 0;
    static Answered of(const BodyState& state) noexcept {
      return {state.header.sim_step, state.step_due_ns};
    }
  };
  const BodyState* next_while_catching_up(Answered answered) noexcept;

 private:
  bool wait_for_late_step() const;
  // The loop's clock (LoopOptions::clock), or the real one.
  std::int64_t now_ns() const noexcept;
  void sleep_until(std::int64_t deadline_ns) const noexcept;
  void remember(const BodyState& state) noexcept;  // the grid `state` is on

  std::int64_t after_ns_;
  std::function<const BodyState*()> latest_;
  std::unique_ptr<SampleWaiter> waiter_;  // on the state's reader, when given
  std::int64_t period_ns_ = 0;
  LoopClock* clock_ = nullptr;
  std::int64_t deadline_ns_ = 0, regrid_ns_ = 0, waited_ns_ = 0;
  std::uint32_t physics_pid_ = 0;
  bool grid_from_due_ = false;  // the grid came from a due time, not a publish stamp
  std::uint64_t last_step_ = 0;
};

}  // namespace afhub
