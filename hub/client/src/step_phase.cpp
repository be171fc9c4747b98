// A loop in phase with the physics (see step_phase.hpp).
#include "afhub/hub/step_phase.hpp"

#include <utility>

#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/header.hpp"

namespace afhub {
namespace {

constexpr std::int64_t kLateStatePollNs = 20'000, kLateStateMarginNs = 100'000;

}  // namespace

std::int64_t grid_in_phase(const BodyState& state, std::int64_t after_ns) noexcept {
  if (after_ns < 0) return 0;
  return (state.step_due_ns > 0 ? state.step_due_ns : state.header.publish_stamp_ns) + after_ns;
}

StepPhase::StepPhase(std::int64_t after_ns, std::function<const BodyState*()> latest)
    : after_ns_(after_ns), latest_(std::move(latest)) {}

void StepPhase::attach(LoopOptions& loop, LoopCycle& cycle) {
  period_ns_ = loop.period_ns;
  if (const BodyState* state = latest_()) {
    loop.grid_origin_ns = grid_in_phase(*state, after_ns_);
    remember(*state);
  }
  cycle.deadline_ns = &deadline_ns_;
  cycle.regrid_ns = &regrid_ns_;
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

bool StepPhase::wait_for_late_step() const {
  const std::int64_t due = deadline_ns_ - after_ns_;
  const std::int64_t give_up = due + period_ns_ - kLateStateMarginNs;
  auto just_late = [&](const BodyState* state) {
    return state && state->step_due_ns > 0 && state->step_due_ns < due &&
           due - state->step_due_ns <= period_ns_;
  };
  while (just_late(latest_()) && !stop_requested() && monotonic_ns() < give_up)
    sleep_until_ns(monotonic_ns() + kLateStatePollNs);
  return true;
}

}  // namespace afhub
