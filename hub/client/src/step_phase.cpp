// A loop in phase with the physics (see step_phase.hpp).
#include "afhub/hub/step_phase.hpp"

#include <algorithm>
#include <utility>

#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/header.hpp"

namespace afhub {
namespace {

constexpr std::int64_t kLateStatePollNs = 20'000, kLateStateMarginNs = 100'000;
// A wait for a catching-up physics' next state ends this long before the loop's next
// cycle, so that the cycle is not skipped as overrun.
constexpr std::int64_t kFollowMarginNs = 20'000;
const std::int64_t kMaxCatchUpNs = LoopOptions{}.max_catch_up_ns;

}  // namespace

std::int64_t grid_in_phase(const BodyState& state, std::int64_t after_ns) noexcept {
  if (after_ns < 0) return 0;
  return (state.step_due_ns > 0 ? state.step_due_ns : state.header.publish_stamp_ns) + after_ns;
}

StepPhase::StepPhase(std::int64_t after_ns, std::function<const BodyState*()> latest,
                     RawLatestReader* state_reader)
    : after_ns_(after_ns), latest_(std::move(latest)) {
  if (!state_reader) return;
  waiter_ = std::make_unique<SampleWaiter>();
  if (!waiter_->attach(*state_reader)) waiter_.reset();
}

StepPhase::~StepPhase() = default;

void StepPhase::attach(LoopOptions& loop, LoopCycle& cycle) {
  period_ns_ = loop.period_ns;
  clock_ = loop.clock;
  if (const BodyState* state = latest_()) {
    loop.grid_origin_ns = grid_in_phase(*state, after_ns_);
    remember(*state);
  }
  cycle.deadline_ns = &deadline_ns_;
  cycle.regrid_ns = &regrid_ns_;
  cycle.waited_ns = &waited_ns_;
  cycle.wait = [this] { return wait_for_late_step(); };
}

void StepPhase::follow(const BodyState& state) noexcept {
  if (state.header.publisher_pid != physics_pid_ || (state.step_due_ns > 0 && !grid_from_due_) ||
      state.header.sim_step < last_step_)
    regrid_ns_ = grid_in_phase(state, after_ns_);
  remember(state);
}

void StepPhase::remember(const BodyState& state) noexcept {
  physics_pid_ = state.header.publisher_pid;
  grid_from_due_ = state.step_due_ns > 0;
  last_step_ = state.header.sim_step;
}

const BodyState* StepPhase::next_while_catching_up(Answered answered) noexcept {
  // Its next step not due yet, the physics is on its grid; behind it by more than it
  // makes up, it skips to the grid (rt's LoopOptions::max_catch_up_ns, by default).
  const std::int64_t began = now_ns();
  const std::int64_t behind = began - answered.step_due_ns;
  if (answered.step_due_ns <= 0 || behind < period_ns_ || behind > kMaxCatchUpNs) return nullptr;
  // Until just before the loop's next cycle, which answers the newest state and
  // follows again: no gap in which a new state waits for the loop's grid.
  const std::int64_t until =
      deadline_ns_ + ((began - deadline_ns_) / period_ns_ + 1) * period_ns_ - kFollowMarginNs;
  const BodyState* next = nullptr;
  for (std::int64_t now = began; !stop_requested() && now < until; now = now_ns()) {
    const BodyState* state = latest_();
    if (state && state->header.sim_step != answered.step) {
      next = state;
      break;
    }
    if (waiter_)
      waiter_->wait(until - now);
    else
      sleep_until(std::min(now + kLateStatePollNs, until));
  }
  waited_ns_ += now_ns() - began;
  return next;
}

bool StepPhase::wait_for_late_step() const {
  const std::int64_t due = deadline_ns_ - after_ns_;
  const std::int64_t give_up = due + period_ns_ - kLateStateMarginNs;
  auto just_late = [&](const BodyState* state) {
    return state && state->step_due_ns > 0 && state->step_due_ns < due &&
           due - state->step_due_ns <= period_ns_;
  };
  while (just_late(latest_()) && !stop_requested() && now_ns() < give_up)
    sleep_until(now_ns() + kLateStatePollNs);
  return true;
}

std::int64_t StepPhase::now_ns() const noexcept {
  return clock_ ? clock_->now_ns() : monotonic_ns();
}

void StepPhase::sleep_until(std::int64_t deadline_ns) const noexcept {
  if (clock_)
    clock_->sleep_until_ns(deadline_ns);
  else
    sleep_until_ns(deadline_ns);
}

}  // namespace afhub
