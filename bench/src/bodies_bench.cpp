// `afhub bench bodies` (see bodies_bench.hpp).
#include "afhub/bench/bodies_bench.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>

#include "afhub/bench/arms_scene.hpp"
#include "afhub/bench/bench.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/step_phase.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/percentile.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/rt/process_spawn.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/world.hpp"
#include "child_process.hpp"
#include "text_format.hpp"

namespace afhub::bench {
namespace {

// Steps after every body is first commanded that are left out: the physics' first
// answers to a controller that has just joined.
constexpr std::int64_t kSettleNs = 500'000'000;

// The run's files, removed however it ends; the physics' log stays when an error
// names it.
struct RunFiles {
  std::string scene, step_log, physics_log;
  bool keep_physics_log = false;
  ~RunFiles() {
    std::error_code ignored;
    for (const std::string* path : {&scene, &step_log}) std::filesystem::remove(*path, ignored);
    if (!keep_physics_log) std::filesystem::remove(physics_log, ignored);
  }
  Error physics_error(const std::string& what) {
    keep_physics_log = true;
    return Error(what + "; see " + physics_log);
  }
};

// One body held where its joints were first seen: a command each cycle answering its
// newest state.
struct HeldBody {
  explicit HeldBody(const std::string& channel) : client(channel) {}
  BodyClient client;
  std::vector<double> hold;  // its joints' first positions
  bool seen = false;
};

template <typename Phase>
float percentile(const std::vector<StepPhases>& steps, double q, Phase phase) {
  std::vector<float> values;
  values.reserve(steps.size());
  for (const StepPhases& step : steps) values.push_back(phase(step));
  std::sort(values.begin(), values.end());
  return percentile_of_sorted(std::span<const float>(values), q);
}

}  // namespace

BodiesResult run_bodies_bench(const BodiesOptions& options) {
  connect_to_hub("bench", HubPolicy::kRequire);
  const std::string prefix = "/tmp/afhub-bench-" + std::to_string(getpid());
  RunFiles files{prefix + "-arms.yaml", prefix + "-steps.txt", prefix + "-physics.log"};
  std::ofstream(files.scene) << arms_scene(options.arms, options.links);
  BodiesResult result;
  std::vector<std::unique_ptr<HeldBody>> bodies;
  for (const physics::BodySpec& body : physics::load_adf_files({files.scene}).bodies)
    bodies.push_back(std::make_unique<HeldBody>(body.channel));
  if (bodies.empty()) throw Error("the generated scene has no body");
  result.bodies = static_cast<int>(bodies.size());
  std::fprintf(stderr, "afhub bench: %d arms of %d links (%d bodies) at 1 kHz for %.0f s%s\n",
               options.arms, options.links, result.bodies, options.seconds,
               options.reduced_coordinates ? ", in reduced coordinates" : "");

  // The log holds every step of the run: the physics is stopped once the loop is done.
  const std::string priority = std::to_string(options.fifo_priority);
  const auto log_steps = static_cast<std::uint64_t>((options.seconds + 120.0) * 1000.0);
  std::vector<std::string> run = {this_executable(), "run",         files.scene,
                                  "--no-autostart",  "--fifo",      priority,
                                  "--lock-memory",   "--steps",     std::to_string(log_steps),
                                  "--step-log",      files.step_log};
  if (options.reduced_coordinates) run.push_back("--reduced-coordinates");
  ChildProcess physics(run, files.physics_log);
  // Every body's first state, before the loop starts (loading a thousand takes seconds).
  for (const std::int64_t give_up = monotonic_ns() + 60'000'000'000;;) {
    const bool all = std::all_of(bodies.begin(), bodies.end(),
                                 [](auto& body) { return body->client.latest_state(); });
    if (all) break;
    if (stop_requested()) throw Error("interrupted");
    if (!physics.running())
      throw files.physics_error("the physics ended (exit code " + std::to_string(physics.wait(0)) +
                                ") before publishing every body");
    if (monotonic_ns() > give_up)
      throw files.physics_error("not every body published a state within 60 s");
    sleep_until_ns(monotonic_ns() + 10'000'000);
  }

  LoopOptions loop;
  loop.fifo_priority = options.fifo_priority;
  loop.lock_memory = true;
  LoopTiming timing;
  apply_realtime(loop, "afhub bench");
  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  BodyClient& phased = bodies.front()->client;
  StepPhase phase(loop.period_ns / 2, [&phased] { return phased.latest_state(); });
  LoopCycle cycle;
  phase.attach(loop, cycle);
  std::int64_t first_ns = 0, last_ns = 0;
  const auto window_ns = static_cast<std::int64_t>(options.seconds * 1e9);
  bool settled = false, physics_gone = false;
  std::uint64_t commanded_before = 0, answered_before = 0;
  cycle.work = [&] {
    const std::int64_t begin_ns = monotonic_ns();
    if (const BodyState* state = phased.latest_state()) phase.follow(*state);
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      // A few bodies ahead, as the physics does: their slots' lines come meanwhile.
      if (b + kBodyPrefetchAhead < bodies.size()) {
        bodies[b + kBodyPrefetchAhead]->client.prefetch_state();
        bodies[b + kBodyPrefetchAhead]->client.prefetch_command_update();
      }
      HeldBody* body = bodies[b].get();
      const BodyState* state = body->client.latest_state();
      if (!state) continue;
      if (!body->seen) {  // before the loop's first cycle ends: the loop is not yet timed
        body->hold.assign(state->joint_count, 0.0);
        for (std::uint32_t j = 0; j < state->joint_count; ++j)
          body->hold[j] = state->joints[j].position;
        body->seen = true;
      }
      const auto joints = static_cast<std::uint32_t>(body->hold.size());
      BodyCommand* command = body->client.loan_command(joints);
      if (!command) {
        ++result.refused_loans;
        continue;
      }
      for (std::uint32_t j = 0; j < joints; ++j) {
        command->joints[j].type = JointCommandType::kPosition;
        command->joints[j].value = body->hold[j];
      }
      command->header.sim_step = state->header.sim_step;
      command->header.sim_time_s = state->header.sim_time_s;
      body->client.publish_command(command);
    }
    last_ns = monotonic_ns();
    if (first_ns == 0) first_ns = last_ns;  // the first cycle, which took the holds
    if (last_ns - first_ns < kSettleNs) return !stop_requested();
    if (!settled) {
      if (const WorldState* now = world.latest()) {
        commanded_before = now->commanded_steps;
        answered_before = now->answered_steps;
      }
      settled = true;
    }
    result.controller_compute.record(last_ns - begin_ns);
    // Once a second: a physics gone is not waited for until the run's end.
    if (timing.cycles() % 1000 == 999 && !physics.running()) physics_gone = true;
    // The window is --seconds of the clock, however many periods a loaded machine made
    // the loop miss (counted in cycles, it had grown to 2.2 s on a CI run).
    return !stop_requested() && !physics_gone && last_ns - first_ns < kSettleNs + window_ns;
  };
  run_periodic(loop, timing, cycle);
  if (stop_requested()) throw Error("interrupted");
  if (physics_gone)
    throw files.physics_error("the physics ended (exit code " + std::to_string(physics.wait(0)) +
                              ") during the run");
  result.controller_overruns = timing.overruns();
  if (const WorldState* now = world.latest()) {
    result.commanded_steps = now->commanded_steps - commanded_before;
    result.answered_steps = now->answered_steps - answered_before;
  }
  // SIGTERM: it writes its step log, then exits.
  const int exit_code = physics.stop(kPhysicsStopMs);
  if (exit_code != 0 && exit_code != 128 + SIGTERM)
    throw files.physics_error("the physics exited with code " + std::to_string(exit_code));
  const std::vector<LoggedStep> logged =
      read_step_log(files.step_log, first_ns + kSettleNs, last_ns);
  for (const LoggedStep& step : logged) result.steps.push_back(step.phases);
  result.late = late_commands(logged);
  result.physics_dropped = first_line_with(files.physics_log, "shared memory exhausted");
  return result;
}

std::string bodies_table(const BodiesOptions& options, const BodiesResult& result) {
  const auto& steps = result.steps;
  std::string out = format("%.0f arms of %.0f links, %.0f bodies at 1 kHz, %.0f steps measured",
                           options.arms, options.links, result.bodies, steps.size());
  if (options.reduced_coordinates) out += ", in reduced coordinates";
  out += "; one controller process commanding every body each period, in phase\n\n";
  if (steps.empty()) return out + "No step measured.\n";
  out += "Each step as the physics timed it, us      p50       p99\n";
  const auto row = [&](const char* name, auto phase) {
    char text[128];
    std::snprintf(text, sizeof text, "%-40s %7.1f   %7.1f\n", name, percentile(steps, 0.5, phase),
                  percentile(steps, 0.99, phase));
    out += text;
  };
  row("  the whole step", [](const StepPhases& s) { return s.total(); });
  row("  commands read and applied", [](const StepPhases& s) { return s.commands; });
  row("  physics (Bullet's step, joint records)", [](const StepPhases& s) { return s.physics; });
  row("  states published", [](const StepPhases& s) { return s.publish; });
  const double compute_p50 = result.controller_compute.percentile_ns(0.5) * 1e-3,
               compute_p99 = result.controller_compute.percentile_ns(0.99) * 1e-3;
  out +=
      format("The controller writing every command, us  %7.1f   %7.1f\n", compute_p50, compute_p99);
  const double in_time =
      result.commanded_steps ? 100.0 * result.answered_steps / result.commanded_steps : 0.0;
  out += format("Commands in time for the next step: %.2f %% of %.0f body-steps\n", in_time,
                result.commanded_steps);
  out += late_commands_text(result.late, result.bodies);
  if (result.refused_loans)
    out += format("Commands not written (no shared memory): %.0f\n", result.refused_loans);
  if (result.controller_overruns)
    out += format("Periods the controller missed (overruns): %.0f\n", result.controller_overruns);

  const double step_p99 = percentile(steps, 0.99, [](const StepPhases& s) { return s.total(); });
  const double step_p50 = percentile(steps, 0.5, [](const StepPhases& s) { return s.total(); });
  const double publish_p50 = percentile(steps, 0.5, [](const StepPhases& s) { return s.publish; });
  if (result.bodies < 1000) return out + "\nGoals: set for 1000 bodies or more (--arms 125)\n";
  out += "\nGoals (issue 30)\n";
  out += format("  step p99 %.0f us (goal < 1000 us): ", step_p99) +
         (step_p99 < 1000.0 ? "met\n" : "NOT met\n");
  out += format("  publishing %.1f %% of the step at the median (goal < 10 %%): ",
                100.0 * publish_p50 / step_p50) +
         (publish_p50 < 0.1 * step_p50 ? "met\n" : "NOT met\n");
  out += format("  commands in time for the next step %.1f %% (goal >= %.0f %%): ", in_time,
                100.0 * kInTimeGoal) +
         (in_time >= 100.0 * kInTimeGoal ? "met\n" : "NOT met\n");
  return out;
}

std::vector<std::string> bodies_failures(const BodiesResult& result) {
  std::vector<std::string> found;
  if (!result.physics_dropped.empty())
    found.push_back("the physics did not publish every step's states: it said \"" +
                    result.physics_dropped + "\"");
  if (result.steps.empty()) found.push_back("no step was measured");
  if (result.refused_loans)
    found.push_back("the controller could not write every command (no shared memory)");
  return found;
}

}  // namespace afhub::bench
