// `afhub ctl sine|hold|track`: the shipped joint controllers, each a process on the
// periodic loop (or in lockstep with the physics).
#include <cmath>
#include <memory>

#include "afhub/controllers/joint_targets.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "count_option.hpp"
#include "realtime_options.hpp"

namespace afhub::cli {
namespace {

struct CtlOptions {
  std::string body, trajectory_file;
  double amplitude_rad = 0.3;
  double period_s = 4.0;
  std::vector<int> joints;
  double rate_hz = 1000.0;
  RealtimeOptions realtime;
  bool lockstep = false;
  bool spin = false;
  std::uint64_t cycles = 0;
  double after_step_us = -1.0;
  double wait_s = 10.0;
};

ControllerOptions controller_options(const CtlOptions& options, const std::string& name) {
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100'000.0))
    throw Error("--rate must be between 0 and 100000 Hz");
  if (!(options.wait_s >= 0.0 && options.wait_s <= 1e6))
    throw Error("--wait takes a number of seconds from 0 to 1e6");
  ControllerOptions controller;
  set_realtime_options(options.realtime, controller.loop);
  controller.name = name;
  controller.wait_s = options.wait_s;
  controller.body = options.body;
  controller.lockstep = options.lockstep;
  if (options.spin && !options.lockstep)
    throw Error("--spin needs --lockstep: it is how a lockstep client waits for a step");
  controller.spin = options.spin;
  controller.loop.period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.rate_hz));
  controller.loop.max_cycles = options.cycles;
  if (options.after_step_us >= 0.0) {
    if (options.lockstep) throw Error("--after-step is for free-running loops, not --lockstep");
    if (options.after_step_us * 1e3 >= static_cast<double>(controller.loop.period_ns))
      throw Error("--after-step must be shorter than the loop's period");
    controller.after_step_ns = std::llround(options.after_step_us * 1e3);
  }
  return controller;
}

// The options every controller takes.
void add_loop_options(CLI::App* command, CtlOptions& options) {
  command->add_option("body", options.body, "Body channel name or a unique suffix of it")
      ->required();
  command->add_option("--rate", options.rate_hz, "Loop rate in Hz (default 1000)");
  add_realtime_options(command, options.realtime, "the loop");
  command->add_flag("--lockstep", options.lockstep,
                    "Answer every physics step (with `afhub run --lockstep`) instead of a clock");
  command->add_flag("--spin", options.spin,
                    "With --lockstep: poll for the next step with sched_yield instead of sleeping "
                    "until it comes (only on a core of its own: under SCHED_FIFO a yield never "
                    "lets the physics run on that core)");
  add_count_option(command, "--cycles", options.cycles,
                   "Stop after this many cycles (default: Ctrl-C)");
  command->add_option("--after-step", options.after_step_us,
                      "Wake this many microseconds after each physics step (aligns the loop "
                      "to the physics so that every command is ready for the next step)");
  command->add_option("--wait", options.wait_s,
                      "Started before the hub or the physics (a launch script), wait this many "
                      "seconds for the hub and then the body, saying so once, before failing "
                      "(default 10; 0 fails at once)");
}

}  // namespace

void register_ctl(CLI::App& app, Runner& selected) {
  auto* ctl = app.add_subcommand("ctl", "Run a shipped joint controller as a 1 kHz process.");
  ctl->require_subcommand(1);

  auto sine = std::make_shared<CtlOptions>();
  auto* sine_command = ctl->add_subcommand(
      "sine", "Each joint follows its own sinusoid around its start, phase-shifted per joint.");
  add_loop_options(sine_command, *sine);
  sine_command->add_option("--amplitude", sine->amplitude_rad,
                           "Amplitude in rad or m (default 0.3)");
  sine_command->add_option("--period", sine->period_s, "Period in seconds (default 4)");
  sine_command->add_option("--joints", sine->joints, "Joint indices to move, i,j (default: all)")
      ->delimiter(',');
  sine_command->callback([&selected, sine] {
    selected = [sine] {
      if (!std::isfinite(sine->amplitude_rad)) throw Error("--amplitude must be a finite number");
      if (!(sine->period_s > 0.0 && std::isfinite(sine->period_s)))
        throw Error("--period must be a positive number of seconds");
      for (int joint : sine->joints)
        if (joint < 0 || joint >= static_cast<int>(kMaxJointsPerBody))
          throw Error("--joints: " + std::to_string(joint) + " is not a joint index");
      return run_controller(controller_options(*sine, "ctl sine"),
                            joint_position_controller(
                                sine_targets(sine->amplitude_rad, sine->period_s, sine->joints)));
    };
  });

  auto hold = std::make_shared<CtlOptions>();
  auto* hold_command = ctl->add_subcommand("hold", "Hold every joint where it is.");
  add_loop_options(hold_command, *hold);
  hold_command->callback([&selected, hold] {
    selected = [hold] {
      return run_controller(controller_options(*hold, "ctl hold"),
                            joint_position_controller(hold_targets()));
    };
  });

  auto track = std::make_shared<CtlOptions>();
  auto* track_command = ctl->add_subcommand(
      "track", "Follow a joint trajectory: CSV rows time,q0,q1,..., interpolated linearly.");
  add_loop_options(track_command, *track);
  track_command->add_option("file", track->trajectory_file, "The trajectory CSV file")->required();
  track_command->callback([&selected, track] {
    selected = [track] {
      JointTrajectory trajectory = read_trajectory_csv(track->trajectory_file);
      return run_controller(controller_options(*track, "ctl track"),
                            joint_position_controller(track_targets(std::move(trajectory))));
    };
  });
}

}  // namespace afhub::cli
