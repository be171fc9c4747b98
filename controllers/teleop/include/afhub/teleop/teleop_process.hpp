// `afhub teleop`: one process binding each selected input device's channels
// (device/<name>, a driver process) to the root body of its simulated multibody (the
// physics' body channels). Every cycle (1 kHz by default), for each binding: the
// newest DeviceState and body state go through the TeleopLaw, and a BodyCommand (a
// kForce wrench and the gripper joints) and a DeviceCommand (force, enabled) go out.
// The device pushes only while the body's states are fresh. The loop allocates
// nothing. When the hub goes away it stops commanding (the
// driver's watchdog then zeroes the force) and re-attaches to the next hub.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afhub/hub/step_phase.hpp"
#include "afhub/rt/periodic_loop.hpp"
#include "afhub/teleop/input_device_spec.hpp"
#include "afhub/teleop/teleop_commands.hpp"
#include "afhub/teleop/teleop_law.hpp"

namespace afhub::teleop {

// One device and its body, resolved from the input device file and the multibody's
// description (by the caller: this layer does not read models).
struct TeleopBinding {
  InputDeviceSpec spec;
  std::string device_name;  // the driver's --name: channels device/<name>
  std::string body;         // the root body's channel, "<namespace>/<body>"
  // The channels of the bodies below the root: contact feedback sums their contact
  // wrenches with the root's (subtree_contact.hpp).
  std::vector<std::string> subtree_bodies;
  CartesianGains body_gains;               // the root body's own controller gains (AMBF's fallback)
  std::vector<JointRange> gripper_joints;  // the root's descendant joints, command order
  std::uint32_t actuator_count{0};
  WrenchLimit body_limit;  // what the physics accepts for the root body
  std::string load_hint;   // how to load the multibody, shown while the body is missing
  FeedbackSource feedback{FeedbackSource::kProxy};  // what the device's force renders
};

// Latency of the loop's outputs, from the device sample they answer (its publish
// stamp), in nanoseconds; kept when TeleopOptions::latency_samples > 0.
struct TeleopLatency {
  std::vector<std::int64_t> to_body_command;  // device sample -> BodyCommand published
  // device sample -> the first DeviceState reporting the force of the command that
  // answered it (DeviceState::command_sequence and its publish stamp)
  std::vector<std::int64_t> to_device_force;
};

struct TeleopOptions {
  std::vector<TeleopBinding> bindings;
  LoopOptions loop;      // period, SCHED_FIFO, CPU, memory locking, max cycles
  double wait_s = 10.0;  // for the hub, then each device and body; 0 fails at once
  bool survive_hub_loss = true;
  // A device with no new sample for this long, over as long of this loop's own cycles
  // (its driver stopped or hangs: device_freshness.hpp), releases its body: the body is held where
  // it is and the device gets no force; once samples come back the body continues from there with
  // no jump, as after a clutch. A body with no new state for this long (its physics stopped or
  // died: state_freshness.hpp) gets the device's force disabled; the driver ramps it in again
  // once states come back.
  std::int64_t stale_ns = 50'000'000;
  std::size_t latency_samples = 0;  // per kind; 0: no latency recording
  // When the loop wakes against the steps of the first binding's physics (see
  // afhub/hub/step_phase.hpp): half its period after each step is due by default, so
  // that its commands answer the newest state and arrive before the next step.
  std::int64_t after_step_ns = kAfterStepHalfPeriod;
};

// Runs until Ctrl-C, SIGTERM or loop.max_cycles. Throws afhub::Error when the hub,
// a device or a body is still missing after wait_s (naming it and how to start it).
// With `latency`, the figures recorded (options.latency_samples at most) are left there.
int run_teleop(const TeleopOptions& options, TeleopLatency* latency = nullptr);

}  // namespace afhub::teleop
