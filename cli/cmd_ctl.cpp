// `afhub ctl sine|hold|track`: the shipped joint controllers, each a process on the
// periodic loop (or in lockstep with the physics).
#include <algorithm>
#include <cmath>
#include <memory>

#include "afhub/controllers/joint_targets.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "loop_options.hpp"
#include "time_options.hpp"

namespace afhub::cli {
namespace {

struct CtlOptions {
  std::string body, trajectory_file;
  double amplitude_rad = 0.3;
  double period_s = 4.0;
  std::vector<int> joints;
  LoopRateOptions pacing;
  bool lockstep = false;
  bool spin = false;
  PhaseOptions phase;
  double wait_s = 10.0;
};

ControllerOptions controller_options(const CtlOptions& options, const std::string& name) {
  ControllerOptions controller;
  set_loop_rate_options(options.pacing, controller.loop);
  controller.name = name;
  controller.wait_s = options.wait_s;
  controller.body = options.body;
  controller.lockstep = options.lockstep;
  if (options.spin && !options.lockstep)
    throw Error("--spin needs --lockstep: it is how a lockstep client waits for a step");
  controller.spin = options.spin;
  controller.after_step_ns = after_step_ns(options.phase, controller.loop.period_ns);
  if (options.lockstep && controller.after_step_ns != kAfterStepHalfPeriod)
    throw Error("--after-step and --unaligned are for free-running loops, not --lockstep");
  return controller;
}

// The options every controller takes.
void add_controller_options(CLI::App* command, CtlOptions& options) {
  command->add_option("body", options.body, "Body channel name or a unique suffix of it")
      ->required();
  add_loop_rate_options(command, options.pacing);
  command->add_flag("--lockstep", options.lockstep,
                    "Answer every physics step (with `afhub run --lockstep`) instead of a clock");
  command->add_flag("--spin", options.spin,
                    "With --lockstep: poll for the next step with sched_yield instead of sleeping "
                    "until it comes (only on a core of its own: under SCHED_FIFO a yield never "
                    "lets the physics run on that core)");
  add_phase_options(command, options.phase, "command");
  add_wait_option(command, options.wait_s, "the body");
}

}  // namespace

void register_ctl(CLI::App& app, Runner& selected) {
  auto* ctl = app.add_subcommand("ctl", "Run a shipped joint controller as a 1 kHz process.");
  ctl->require_subcommand(1);

  auto sine = std::make_shared<CtlOptions>();
  auto* sine_command = ctl->add_subcommand(
      "sine", "Each joint follows its own sinusoid around its start, phase-shifted per joint.");
  add_controller_options(sine_command, *sine);
  sine_command->add_option("--amplitude", sine->amplitude_rad,
                           "Amplitude in rad or m (default 0.3)");
  sine_command->add_option("--period", sine->period_s, "Period in seconds (default 4)");
  sine_command->add_option("--joints", sine->joints, "Joint indices to move, i,j (default: all)")
      ->delimiter(',');
  sine_command->callback([&selected, sine] {
    selected = [sine] {
      if (!std::isfinite(sine->amplitude_rad)) throw Error("--amplitude must be a finite number");
      ns_of_seconds(sine->period_s, "--period", 0.001);
      ControllerOptions controller = controller_options(*sine, "ctl sine");
      for (int joint : sine->joints) {
        if (joint < 0 || joint >= static_cast<int>(kMaxJointsPerBody))
          throw Error("--joints: " + std::to_string(joint) + " is not a joint index");
        controller.joints_needed =
            std::max(controller.joints_needed, static_cast<std::uint32_t>(joint) + 1);
      }
      controller.joints_needed_by = "--joints";
      return run_controller(controller, joint_position_controller(sine_targets(
                                            sine->amplitude_rad, sine->period_s, sine->joints)));
    };
  });

  auto hold = std::make_shared<CtlOptions>();
  auto* hold_command = ctl->add_subcommand("hold", "Hold every joint where it is.");
  add_controller_options(hold_command, *hold);
  hold_command->callback([&selected, hold] {
    selected = [hold] {
      return run_controller(controller_options(*hold, "ctl hold"),
                            joint_position_controller(hold_targets()));
    };
  });

  auto track = std::make_shared<CtlOptions>();
  auto* track_command = ctl->add_subcommand(
      "track", "Follow a joint trajectory: CSV rows time,q0,q1,..., interpolated linearly.");
  add_controller_options(track_command, *track);
  track_command->add_option("file", track->trajectory_file, "The trajectory CSV file")->required();
  track_command->callback([&selected, track] {
    selected = [track] {
      JointTrajectory trajectory = read_trajectory_csv(track->trajectory_file);
      ControllerOptions controller = controller_options(*track, "ctl track");
      controller.joints_needed = static_cast<std::uint32_t>(trajectory.rows.front().size());
      controller.joints_needed_by = track->trajectory_file + " (a column for each joint)";
      return run_controller(controller,
                            joint_position_controller(track_targets(std::move(trajectory))));
    };
  });
}

}  // namespace afhub::cli
