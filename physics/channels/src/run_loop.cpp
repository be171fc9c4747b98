// The physics loop and its report (see run_loop.hpp).
#include "afhub/physics/run_loop.hpp"
#include "afhub/rt/clock.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>

#include "afhub/hub/json_writer.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/rt/loop_stats_publisher.hpp"
#include "afhub/shm_layout/world_control.hpp"

namespace afhub::physics {
namespace {

double largest_pivot_gap(const Simulation& sim) noexcept {
  double largest = 0.0;
  for (std::size_t j = 0; j < sim.model().joints.size(); ++j)
    largest = std::max(largest, sim.joint_pivot_gap_m(j));
  return largest;
}

}  // namespace

void run_loop(Simulation& sim, SimChannels* channels, const RunOptions& options,
              RunReport& report) {
  const auto period_ns = static_cast<std::int64_t>(sim.dt_s() * 1e9);
  std::int64_t start_ns = monotonic_ns();
  std::int64_t next_ns = start_ns;
  WorldControl control;
  std::uint64_t rate_window_step = 0;
  std::int64_t rate_window_ns = start_ns;
  double achieved_rate_hz = 0.0;
  std::uint64_t late_counted = 0;
  report.max_joint_error_m = std::max(report.max_joint_error_m, largest_pivot_gap(sim));
  // The physics loop's own timing, on its stats channel like every loop (`afhub top`).
  std::unique_ptr<LoopStatsPublisher> stats;
  if (channels)
    stats = std::make_unique<LoopStatsPublisher>("run", "", options.fast ? 0 : period_ns,
                                                 channels->lockstep(), options.grant);
  if (channels) channels->publish(0.0, 0.0, false);  // step 0: the model as loaded
  while (!stop_requested() && (options.steps == 0 || report.steps < options.steps)) {
    if (channels) {
      if (const WorldCommand* command = channels->new_world_command())
        if (control.apply(*command)) sim.reset();
      if (channels->lockstep() && !control.paused) {
        if (!channels->await_lockstep()) break;  // stopped while waiting
        // The wait for clients before the first step is setup: the clock starts after it.
        if (report.steps == 0) start_ns = next_ns = rate_window_ns = monotonic_ns();
      } else {
        channels->apply_commands(monotonic_ns());
      }
    }
    const std::int64_t begin_ns = monotonic_ns();
    const bool stepping = control.take_step();
    if (stepping) {
      sim.step();
      ++report.steps;
      report.max_joint_error_m = std::max(report.max_joint_error_m, largest_pivot_gap(sim));
      if (!sim.all_finite()) {
        report.nan_detected = true;
        std::fprintf(stderr,
                     "afhub run: the simulation became NaN or infinite at step %llu; stopping. "
                     "Lower the gains or --dt, or check masses and inertias\n",
                     static_cast<unsigned long long>(sim.step_count()));
        break;
      }
    }
    if (channels)
      channels->publish(static_cast<double>(monotonic_ns() - start_ns) * 1e-9, achieved_rate_hz,
                        control.paused);
    const std::int64_t end_ns = monotonic_ns();
    if (stepping) report.step_time.record(static_cast<double>(end_ns - begin_ns) * 1e-3);
    if (stats) {
      report.timing.record(options.fast ? 0 : std::max<std::int64_t>(0, begin_ns - next_ns),
                           end_ns - begin_ns);
      // Behind schedule: the next steps run back to back until the clock is caught up.
      if (!options.fast && end_ns > next_ns + period_ns) report.timing.count_overruns(1);
      report.timing.count_late(channels->late_answers() - late_counted);
      late_counted = channels->late_answers();
      stats->maybe_publish(end_ns, report.timing);
    }

    next_ns += period_ns;
    if (next_ns - rate_window_ns >= 1'000'000'000) {
      achieved_rate_hz = static_cast<double>(report.steps - rate_window_step) * 1e9 /
                         static_cast<double>(monotonic_ns() - rate_window_ns);
      rate_window_step = report.steps;
      rate_window_ns = monotonic_ns();
    }
    if (!options.fast) sleep_until_ns(next_ns);
  }
  report.wall_time_s = static_cast<double>(monotonic_ns() - start_ns) * 1e-9;
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
  for (const auto& [name, j] : joints)
    json.key(name).begin_object().key("position").value(sim.joint_position(j)).end_object();
  json.end_object();
  json.key("max_joint_error_m").value(report.max_joint_error_m);
  json.key("nan_detected").value(report.nan_detected);
  json.key("sim_time_s").value(sim.time_s());
  json.key("step_time_us").begin_object();
  json.key("max").value(report.step_time.max_us());
  json.key("p50").value(report.step_time.percentile_us(0.50));
  json.key("p99").value(report.step_time.percentile_us(0.99));
  json.end_object();
  json.key("steps").value(static_cast<unsigned long long>(report.steps));
  json.key("wall_time_s").value(report.wall_time_s);
  json.end_object();
  return json.str() + "\n";
}

}  // namespace afhub::physics
