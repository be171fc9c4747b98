// Write a controller in a few lines: name a body, give a function that turns its
// newest state into a command, and run it.
//
//   afhub::ControllerOptions options;
//   options.name = "my pd";
//   options.body = "kuka/link7";  // a channel name or a unique suffix of one
//   return afhub::run_controller(options, [](const afhub::BodyState& state,
//                                            afhub::BodyCommand& command) {
//     command.joint_count = state.joint_count;  // ... fill the command ...
//   });
//
// Free-running (the default), `cycle` runs every period on the periodic loop with
// the newest state. With `lockstep`, it runs once per physics step, answering that
// step, and a physics started with `afhub run --lockstep` waits for the answer.
// Either way the loop's timing is published on the stats channel (`afhub top`).
// When the hub goes away the controller stops commanding and re-attaches to the next
// hub (ControllerOptions::survive_hub_loss).
#pragma once

#include <functional>
#include <string>

#include "afhub/hub/step_phase.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"

namespace afhub {

struct ControllerOptions {
  std::string name = "controller";  // shown by `afhub top`
  std::string body;                 // the body's channel name or a unique suffix of it
  LoopOptions loop;                 // period, SCHED_FIFO, CPU, memory locking
  bool lockstep = false;            // answer every physics step instead of running on a clock
  // Lockstep: poll for the next step with sched_yield (a dedicated core) instead of
  // sleeping until it comes (iceoryx's WaitSet, a futex).
  bool spin = false;
  // Free-running: wake this long after each physics step is due (the step's deadline
  // on the physics' grid, carried by its state: BodyState.step_due_ns), so that every
  // command answers the newest state and arrives before the next step. Both loops
  // keep absolute deadlines; a restarted physics is followed to its new phase. When
  // the physics is late with a step, its state is waited for (in 20 us polls) until
  // 0.1 ms before the next step is due.
  // kHalfPeriod (the default): half the controller's period after, which leaves either
  // process's wake-up jitter the most room. kUnaligned: on the controller's own clock.
  static constexpr std::int64_t kHalfPeriod = kAfterStepHalfPeriod,
                                kUnaligned = kAfterStepUnaligned;
  std::int64_t after_step_ns = kHalfPeriod;
  // Started together with the hub and the physics (a launch script), the controller
  // waits this long for the hub and then for its body, saying so once on stderr,
  // before giving up with an error. 0: fail at once when either is missing.
  double wait_s = 10.0;
  // When the hub goes away, stop commanding, wait for a hub to come back and re-attach
  // to it, by re-executing this program with its arguments (see afhub/hub/hub_loss.hpp;
  // register more "make outputs safe" steps with on_hub_lost()). false: the process
  // ends on a lost hub, as a plain iceoryx client does.
  bool survive_hub_loss = true;
  // The body must have at least this many joints (0: any), or the controller refuses
  // to start, naming `joints_needed_by` ("--joints", "the trajectory's columns").
  std::uint32_t joints_needed = 0;
  std::string joints_needed_by;
};

// `state` is the body's newest state: this process's checked copy of its slot, valid
// until the cycle returns. `command` is written in place in the body's command slot
// in shared memory, and starts zeroed. Runs in the real-time loop: do not allocate or
// block in it.
using ControllerCycle = std::function<void(const BodyState& state, BodyCommand& command)>;

// Connects to the hub, opens the body and runs `cycle` until Ctrl-C or SIGTERM
// (or options.loop.max_cycles). Returns the process exit code; throws afhub::Error
// when there is no hub or no such body after options.wait_s. When `timing` is given, the loop
// records its timing there, for the caller to read after the return.
int run_controller(const ControllerOptions& options, const ControllerCycle& cycle,
                   LoopTiming* timing = nullptr);

}  // namespace afhub
