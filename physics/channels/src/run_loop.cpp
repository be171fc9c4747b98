// The physics loop and its report (see run_loop.hpp).
#include "afhub/physics/run_loop.hpp"

#include "afhub/physics/rate_meter.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/json_writer.hpp"
#include "afhub/hub/loop_stats_publisher.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/world_control.hpp"

namespace afhub::physics {
namespace {

// Each joint's pivot gap after the step: its largest so far, and the step that made it.
void record_joint_errors(const Simulation& sim, std::uint64_t step, RunReport& report) noexcept {
  for (std::size_t j = 0; j < report.joint_errors.size(); ++j) {
    const double gap = sim.joint_pivot_gap_m(j);
    JointError& error = report.joint_errors[j];
    if (gap > error.max_m) error = {gap, step};
    report.max_joint_error_m = std::max(report.max_joint_error_m, gap);
  }
}

// Each joint under a position command: how far the step left it from its target.
void record_tracking(const Simulation& sim, RunReport& report) noexcept {
  for (std::size_t j = 0; j < report.tracking.size(); ++j) {
    double target = 0.0;
    if (!sim.joint_position_target(j, target)) continue;
    JointTracking& tracking = report.tracking[j];
    const double error = sim.joint_position(j) - target;
    ++tracking.steps;
    tracking.max_error = std::max(tracking.max_error, std::abs(error));
    tracking.sum_squared_error += error * error;
    tracking.last_target = target;
    tracking.last_error = error;
  }
}

}  // namespace

bool hands_off(std::int64_t due_ns, std::int64_t now_ns, const PreviousStep& previous,
               std::int64_t period_ns) noexcept {
  const std::int64_t hand_off_ns = period_ns / kHandOffsPerPeriod;
  const bool behind = previous.end_ns > due_ns || now_ns - due_ns > hand_off_ns;
  return behind && previous.took_ns <= hand_off_ns;
}

void run_loop(Simulation& sim, SimChannels* channels, const RunOptions& options,
              RunReport& report) {
  const auto period_ns = static_cast<std::int64_t>(sim.dt_s() * 1e9);
  auto clock_ns = [&] { return options.clock ? options.clock->now_ns() : monotonic_ns(); };
  WorldControl control;
  control.paused = options.start_paused;
  if (control.paused) control.paused_by_pid = static_cast<std::uint32_t>(getpid());
  WorldCommand world_command;
  WorldControl::Lapsed lapsed_hold;  // a held pause's last holder gone quiet, to be said
  double achieved_rate_hz = 0.0;
  std::uint64_t late_counted = 0;
  report.joint_errors.resize(sim.model().joints.size());
  record_joint_errors(sim, report.steps, report);  // step 0: the model as loaded
  report.tracking.resize(sim.model().joints.size());
  // The physics loop's own timing, on its stats channel like every loop (`afhub top`).
  std::unique_ptr<LoopStatsPublisher> stats;
  if (channels)
    stats = std::make_unique<LoopStatsPublisher>("run", "", options.fast ? 0 : period_ns,
                                                 channels->lockstep(), options.grant);
  if (channels) channels->publish({0.0, 0.0, control});  // step 0: the model as loaded
  // The wait for lockstep clients before the first step is setup: the clock starts after it.
  if (channels && channels->lockstep() && !channels->wait_for_clients()) return;
  const std::int64_t start_ns = clock_ns();
  RateMeter rate;
  // Events (refused commands, expiries, lockstep joins and drops) are said from here,
  // outside the timed step, at most once a second: never from inside the step.
  std::int64_t next_report_ns = start_ns;

  // Paced on rt's loop runner: absolute deadlines start + k dt, never re-based; after
  // a stall, the overrun policy (bounded catch-up or skip); --fast: no period.
  LoopOptions pacing;
  pacing.period_ns = options.fast ? 0 : period_ns;
  pacing.overrun = options.overrun;
  pacing.max_catch_up_ns = options.max_catch_up_ns;
  pacing.clock = options.clock;
  pacing.grid_origin_ns = start_ns;
  LoopCycle cycle;
  std::int64_t commands_ns = 0;  // reading and applying this period's body commands
  PreviousStep previous;
  // Each step's deadline, published with its states: controllers wake in phase with it.
  std::int64_t step_due_ns = 0;
  cycle.deadline_ns = &step_due_ns;
  // Commands in: the world's (pause, resume, step, reset), then the bodies'; in
  // lockstep, the clients' answers to the current step.
  cycle.wait = [&] {
    commands_ns = 0;
    if (!channels || hub_lost()) return true;
    // Every world command from every writer, in order, each once.
    while (channels->next_world_command(world_command))
      if (control.apply(world_command, clock_ns())) {
        // The world, the lockstep barrier's answers and the rate window start again.
        sim.reset();
        channels->forget_commands();
        rate.restart();
      }
    if (const WorldControl::Lapsed lapsed = control.lapse(clock_ns())) lapsed_hold = lapsed;
    channels->update_world_control(control);
    if (channels->lockstep() && !control.paused) return channels->await_lockstep();
    // Behind the grid (after a stall), the controllers in phase follow the physics
    // catching up, answering each state as it comes: given time for it.
    if (!control.paused && step_due_ns > 0 &&
        hands_off(step_due_ns, clock_ns(), previous, period_ns))
      channels->await_answers_in_phase(period_ns / kHandOffsPerPeriod);
    const std::int64_t begin_ns = monotonic_ns();
    channels->apply_commands(begin_ns);
    commands_ns = monotonic_ns() - begin_ns;
    return true;
  };
  // One step, and the states out.
  cycle.work = [&] {
    // The hub is gone: hold, neither stepping nor publishing, until the re-exec.
    if (channels && hub_lost()) return true;
    const std::int64_t begin_ns = monotonic_ns();
    std::int64_t stepped_ns = begin_ns;
    const bool stepping = control.take_step();
    if (stepping) {
      sim.step();
      ++report.steps;
      record_tracking(sim, report);
      record_joint_errors(sim, report.steps, report);
      if (options.stop_on_nan && sim.nan_recoveries().count > 0) {
        report.nan_detected = true;  // said after the loop
        return false;
      }
      stepped_ns = monotonic_ns();
    }
    const std::uint64_t commanded = channels ? channels->commanded_steps() : 0;
    const std::uint64_t answered = channels ? channels->answered_steps() : 0;
    if (channels)
      channels->publish({static_cast<double>(clock_ns() - start_ns) * 1e-9, achieved_rate_hz,
                         control, pacing.period_ns > 0 ? step_due_ns : 0, pacing.period_ns});
    const std::int64_t end_ns = monotonic_ns();
    previous = {clock_ns(), end_ns - begin_ns};
    if (stepping) {
      report.step_time.record(end_ns - begin_ns);
      const auto us = [](std::int64_t ns) {
        return static_cast<float>(static_cast<double>(ns) * 1e-3);
      };
      if (report.step_log.size() < report.step_log.capacity())
        report.step_log.push_back(
            {begin_ns, us(end_ns - begin_ns), us(commands_ns), us(end_ns - stepped_ns),
             pacing.period_ns > 0 ? step_due_ns : 0,
             channels ? static_cast<std::uint32_t>((channels->commanded_steps() - commanded) -
                                                   (channels->answered_steps() - answered))
                      : 0});
    }
    return options.steps == 0 || report.steps < options.steps;
  };
  // The loop's statistics, and the achieved rate over each second.
  cycle.after = [&](std::int64_t now_ns) {
    if (stats && !hub_lost()) {
      report.timing.count_late(channels->late_answers() - late_counted);
      late_counted = channels->late_answers();
      stats->maybe_publish(now_ns, report.timing);
      channels->publish_view(now_ns);
      channels->prepare_next_step();
    }
    rate.update(now_ns, report.steps, !control.halted());
    achieved_rate_hz = rate.rate_hz();
    if (lapsed_hold) {
      std::fprintf(stderr, kPauseLapsedFormat, "afhub run", lapsed_hold.pid, lapsed_hold.hold_ms);
      lapsed_hold = {};
    }
    if (channels && now_ns >= next_report_ns) {
      channels->report_events(stderr);
      next_report_ns = now_ns + 1'000'000'000;
    }
  };
  if (options.steps == 0 || report.steps < options.steps)
    run_periodic(pacing, report.timing, cycle);
  if (channels) channels->report_events(stderr);
  report.wall_time_s = static_cast<double>(clock_ns() - start_ns) * 1e-9;
}

std::optional<std::size_t> worst_joint(const RunReport& report) {
  std::optional<std::size_t> worst;
  for (std::size_t j = 0; j < report.joint_errors.size(); ++j)
    if (!worst || report.joint_errors[j].max_m > report.joint_errors[*worst].max_m) worst = j;
  return worst;
}

std::string worst_joint_summary(const RunReport& report, const Simulation& sim) {
  const std::optional<std::size_t> worst = worst_joint(report);
  if (!worst) return "";
  const JointError& error = report.joint_errors[*worst];
  char text[160];
  std::snprintf(text, sizeof text, "largest joint error %.3g m, at %s at step %llu", error.max_m,
                sim.model().joints[*worst].channel.c_str(),
                static_cast<unsigned long long>(error.step));
  return text;
}

std::string nan_summary(const Simulation& sim) {
  const NanRecoveries& nan = sim.nan_recoveries();
  if (nan.count == 0) return "";
  auto event = [&](const NanEvent& e) {
    const Model& model = sim.model();
    return (e.soft ? model.soft_bodies[e.body].channel : model.bodies[e.body].channel) +
           " at step " + std::to_string(e.step);
  };
  std::string text = std::to_string(nan.count) + (nan.count == 1 ? " body" : " bodies") +
                     " put back after a step made them NaN or infinite; first: " + event(nan.first);
  if (nan.count > 1) text += "; last: " + event(nan.last);
  return text;
}

std::string report_json(const RunReport& report, const Simulation& sim) {
  const Model& model = sim.model();
  JsonWriter json;
  json.begin_object();
  // Bodies and joints sorted by name, so that keys are stable from run to run.
  std::map<std::string, std::size_t> bodies, joints;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) bodies[model.bodies[b].channel] = b;
  for (std::size_t j = 0; j < model.joints.size(); ++j) joints[model.joints[j].channel] = j;
  json.key("bodies").begin_object();
  for (const auto& [name, b] : bodies) {
    const Pose pose = sim.body_pose(b);
    const Quaternion& q = pose.orientation;
    json.key(name).begin_object();
    json.key("position").begin_array().value(pose.position_m.x).value(pose.position_m.y);
    json.value(pose.position_m.z).end_array();
    json.key("quaternion").begin_array().value(q.x).value(q.y).value(q.z).value(q.w).end_array();
    json.end_object();
  }
  json.end_object();
  json.key("joints").begin_object();
  for (const auto& [name, j] : joints) {
    json.key(name).begin_object();
    if (j < report.joint_errors.size()) {
      json.key("max_pivot_gap_m").value(report.joint_errors[j].max_m);
      json.key("max_pivot_gap_step")
          .value(static_cast<unsigned long long>(report.joint_errors[j].step));
    }
    json.key("position").value(sim.joint_position(j));
    if (j < report.tracking.size() && report.tracking[j].steps > 0) {
      const JointTracking& tracking = report.tracking[j];
      json.key("tracking").begin_object();
      json.key("last_error").value(tracking.last_error);
      json.key("last_target").value(tracking.last_target);
      json.key("max_error").value(tracking.max_error);
      json.key("rms_error")
          .value(std::sqrt(tracking.sum_squared_error / static_cast<double>(tracking.steps)));
      json.key("steps").value(static_cast<unsigned long long>(tracking.steps));
      json.end_object();
    }
    json.end_object();
  }
  json.end_object();
  json.key("max_joint_error_m").value(report.max_joint_error_m);
  json.key("nan_detected").value(report.nan_detected);
  json.key("nan_recoveries").value(static_cast<unsigned long long>(sim.nan_recoveries().count));
  json.key("sim_time_s").value(sim.time_s());
  json.key("step_time_us").begin_object();
  json.key("max").value(report.step_time.max_us());
  json.key("p50").value(report.step_time.percentile_us(0.50));
  json.key("p99").value(report.step_time.percentile_us(0.99));
  json.end_object();
  json.key("steps").value(static_cast<unsigned long long>(report.steps));
  json.key("wall_time_s").value(report.wall_time_s);
  if (const std::optional<std::size_t> worst = worst_joint(report)) {
    const JointError& error = report.joint_errors[*worst];
    json.key("worst_joint").begin_object();
    json.key("max_pivot_gap_m").value(error.max_m);
    json.key("name").value(model.joints[*worst].channel);
    json.key("step").value(static_cast<unsigned long long>(error.step));
    json.end_object();
  }
  json.end_object();
  return json.str() + "\n";
}

}  // namespace afhub::physics
