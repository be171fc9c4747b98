// The physics loop of `afhub run`: a fixed step, paced in real time on rt's loop
// runner by absolute deadlines (start + k * dt, never re-based, so there is no
// drift) or run as fast as possible. After a stall (the overrun policy, as the
// controllers have it): kCatchUp runs the late steps back to back, at most
// max_catch_up_ns of them, skipping the rest, each handed off to the controllers in
// phase (hands_off); kSkip skips them all and goes on at the grid's next point. Commands in and
// states out through SimChannels when given; world commands (pause, resume, step, reset) obeyed; in
// lockstep, each step waits for the lockstep clients' answers. Measures what the report needs.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "afhub/physics/sim_channels.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/rt/latency_histogram.hpp"
#include "afhub/rt/loop_timing.hpp"
#include "afhub/rt/periodic_loop.hpp"

namespace afhub::physics {

struct RunOptions {
  bool fast = false;
  std::uint64_t steps = 0;  // stop after this many steps; 0: until a stop signal
  RealtimeGrant grant;      // what the loop's thread was granted, for its loop stats
  // Stop at the first step that made a body NaN or infinite (report.nan_detected),
  // instead of going on with the body put back (Simulation::nan_recoveries).
  bool stop_on_nan = false;
  // Start paused at step 0 (`afhub world resume` or `step` goes on): controllers and a
  // recorder join before anything moves.
  bool start_paused = false;
  // What a step that ran past later deadlines does (see above).
  OverrunPolicy overrun = OverrunPolicy::kCatchUp;
  std::int64_t max_catch_up_ns = 100'000'000;
  LoopClock* clock = nullptr;  // the loop's pacing clock; null: the real one (tests inject theirs)
};

// How one joint followed its position commands: over the steps it had one, the gap
// between the commanded position and the position the step left it at.
struct JointTracking {
  std::uint64_t steps = 0;
  double max_error = 0.0;  // rad or m
  double sum_squared_error = 0.0;
  double last_target = 0.0, last_error = 0.0;  // the last such step's
};

// One joint's largest pivot gap (how far apart the two bodies' pivots are: a closed
// loop opening) and the step that left it there (0: the model as loaded).
struct JointError {
  double max_m = 0.0;
  std::uint64_t step = 0;
};

// One step of the step log: when it began (CLOCK_MONOTONIC ns) and how long the
// loop iteration took (the step_time histogram's measure: the step and its states
// published), with the phases around it: the body commands read and applied before
// it (0 in lockstep, where the wait is for the answers), and the publishing.
struct StepSample {
  std::int64_t begin_ns = 0;
  float duration_us = 0.0F;
  float commands_us = 0.0F;
  float publish_us = 0.0F;
  std::int64_t due_ns = 0;  // its point on the grid (0 with --fast)
  std::uint32_t late = 0;   // bodies under command whose command did not answer the step before
};

struct RunReport {
  std::uint64_t steps = 0;
  double wall_time_s = 0.0;
  LatencyHistogram step_time;      // one loop iteration: step and publish (after the commands)
  LoopTiming timing;               // wake-up lateness, work time, overruns, late lockstep answers
  bool nan_detected = false;       // with stop_on_nan: the loop stopped on a NaN
  double max_joint_error_m = 0.0;  // the largest pivot gap seen, over all joints and steps
  std::vector<JointError> joint_errors;  // per joint, sized before the first step
  std::vector<JointTracking> tracking;   // per joint, sized before the first step
  // Each step's sample, up to the capacity the caller reserved before the loop (none
  // by default): the loop never grows it, so it never allocates.
  std::vector<StepSample> step_log;
};

// The step before, as the next step's hand-off judges it.
struct PreviousStep {
  std::int64_t end_ns = 0;   // when its states were out, on the loop's clock
  std::int64_t took_ns = 0;  // stepping and publishing
};

// A step's hand-off waits at most this fraction of the period.
inline constexpr std::int64_t kHandOffsPerPeriod = 5;

// Whether a step due at `due_ns`, starting at `now_ns`, first waits for the answers of
// the controllers in phase (SimChannels::await_answers_in_phase): when it is behind its
// grid (due before the step before was out, or woken over the hand-off late: after a
// stall), unless steps take longer than the hand-off. Catch-up, waits included, then
// still runs at 2.5 times the clock or more, and an overloaded physics, its steps
// filling their period, never waits.
bool hands_off(std::int64_t due_ns, std::int64_t now_ns, const PreviousStep& previous,
               std::int64_t period_ns) noexcept;

// Runs until options.steps, a stop signal, or with options.stop_on_nan a NaN (then
// report.nan_detected).
void run_loop(Simulation& sim, SimChannels* channels, const RunOptions& options, RunReport& report);

// The --report JSON: steps, times, step-time percentiles, NaN flag and recoveries,
// largest pivot gap and the joint and step it was seen at (worst_joint), final body
// poses, and per joint its position, largest pivot gap and that gap's step, and, when
// position-commanded, its tracking (steps, max and RMS error, last target and error).
// Keys are sorted.
std::string report_json(const RunReport& report, const Simulation& sim);

// The joint with the largest pivot gap over the run (the first of equals), none
// without joints.
std::optional<std::size_t> worst_joint(const RunReport& report);

// "largest joint error 0.042 m, at ambf/env/mtm/BottomArm-ArmParallel at step 1234",
// or "" without joints: `afhub run`'s end line.
std::string worst_joint_summary(const RunReport& report, const Simulation& sim);

// "2 bodies put back after a step made them NaN or infinite; first: arm/link3 at
// step 5; last: ...", or "" when none was. Said after the loop, never inside it.
std::string nan_summary(const Simulation& sim);

}  // namespace afhub::physics
