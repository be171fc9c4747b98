// `afhub synth`: publishes synthetic bodies at a fixed rate, the stand-in for a
// physics process. Joints follow a sinusoid, or the position, velocity or effort
// commands written to the body (as a unit-inertia joint) while commands keep coming.
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/hub/world_command_queue.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub/shm_layout/world_control.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "count_option.hpp"
#include "time_options.hpp"

namespace afhub::cli {
namespace {

constexpr double kCommandTimeoutS = 0.5;  // AMBF's watchdog: back to the sinusoid after this

struct SynthOptions {
  std::string name_space = "synth";
  unsigned bodies = 3;
  unsigned joints = 4;
  double rate_hz = 1000.0;
  double seconds = 0.0;  // 0: until Ctrl-C
  bool no_autostart = false;
};

struct SyntheticJoint {
  double position = 0.0;
  double velocity = 0.0;
};

struct SyntheticBody {
  std::unique_ptr<BodyPublisher> channel;
  std::vector<SyntheticJoint> joints;
  double last_command_time_s = -1e9;
};

void step_body(SyntheticBody& body, std::size_t index, double t, double dt) {
  const BodyCommand* command = body.channel->latest_command();
  if (command && body.channel->command_updated()) body.last_command_time_s = t;
  const bool commanded = command && t - body.last_command_time_s < kCommandTimeoutS;
  for (std::size_t j = 0; j < body.joints.size(); ++j) {
    SyntheticJoint& joint = body.joints[j];
    const double previous = joint.position;
    if (commanded && j < command->joint_count) {
      const double value = command->joints[j].value;
      switch (command->joints[j].type) {
        case JointCommandType::kPosition:
          joint.position += (value - joint.position) * 0.05;
          break;
        case JointCommandType::kVelocity:
          joint.position += value * dt;
          break;
        case JointCommandType::kEffort:
          joint.position += (joint.velocity + value * dt) * dt;
          break;
      }
    } else {
      joint.position = 0.5 * std::sin(2.0 * M_PI * 0.5 * t + 0.7 * static_cast<double>(j + index));
    }
    joint.velocity = (joint.position - previous) / dt;
  }
}

// Returns the state published (this process's own slot), or nullptr when there was no room.
const BodyState* publish_body(SyntheticBody& body, std::size_t index, std::uint64_t step, double t,
                              std::int64_t stamp_ns) {
  BodyState* state = body.channel->loan_state(static_cast<std::uint32_t>(body.joints.size()));
  if (!state) return nullptr;
  const double radius = 0.1 * static_cast<double>(index + 1);
  const double angle = 2.0 * M_PI * 0.2 * t;
  state->header.sim_step = step;
  state->header.sim_time_s = t;
  state->pose.position_m = {radius * std::cos(angle), radius * std::sin(angle),
                            0.05 * static_cast<double>(index)};
  state->pose.orientation = {0.0, 0.0, std::sin(angle / 2), std::cos(angle / 2)};
  state->twist.linear_mps = {-radius * std::sin(angle) * 2.0 * M_PI * 0.2,
                             radius * std::cos(angle) * 2.0 * M_PI * 0.2, 0.0};
  state->twist.angular_radps = {0.0, 0.0, 2.0 * M_PI * 0.2};
  state->mass_kg = 1.0;
  state->principal_inertia_kgm2 = {0.01, 0.01, 0.01};
  for (std::size_t j = 0; j < body.joints.size(); ++j) {
    state->joints[j].position = body.joints[j].position;
    state->joints[j].velocity = body.joints[j].velocity;
  }
  body.channel->publish_state(state, stamp_ns);
  return state;
}

int run_synth(const SynthOptions& options) {
  ns_of_seconds(options.seconds, "--seconds (0: until Ctrl-C)");  // -1 ran for good
  if (options.bodies == 0 || options.bodies > kMaxBodies)
    throw Error("--bodies must be between 1 and " + std::to_string(kMaxBodies));
  if (options.joints > kMaxJointsPerBody)
    throw Error("--joints must be at most " + std::to_string(kMaxJointsPerBody));
  const std::int64_t period_ns = period_ns_of_rate(options.rate_hz, "--rate");
  install_stop_signal_handlers();
  survive_hub_loss("afhub synth");
  connect_to_hub("synth", hub_policy(options.no_autostart));

  std::vector<std::string> channels;
  for (unsigned i = 0; i < options.bodies; ++i)
    channels.push_back(body_channel_name(options.name_space, "body" + std::to_string(i)));
  // The blocks of the bodies' state slots, the world state's, the step tape's, the
  // directory's.
  check_room_for_bodies(
      channels, slot_blocks_for(channels.size(),
                                static_cast<std::uint32_t>(body_state_bytes(options.joints))) +
                    3);
  DirectoryPublisher directory;
  std::vector<SyntheticBody> bodies(options.bodies);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const std::string& channel = channels[i];
    std::vector<std::string> joint_names;
    for (unsigned j = 0; j < options.joints; ++j)
      joint_names.push_back("body" + std::to_string(i) + "-joint" + std::to_string(j));
    directory.add(make_body_entry(channel, joint_names));
    bodies[i].channel = std::make_unique<BodyPublisher>(channel);
    bodies[i].joints.resize(options.joints);
  }
  // Before the first loan, as the physics: a synth must not starve a running physics.
  std::vector<SlotWritten> slots(bodies.size(),
                                 {PayloadKind::kBodyState, body_state_bytes(options.joints)});
  slots.push_back({PayloadKind::kWorldState, sizeof(WorldState)});
  require_chunks(written_as_slots(slots),
                 "this synth (" + std::to_string(bodies.size()) + " bodies)");
  directory.publish();
  confirm_body_claims(channels, kClaimConfirmTimeout);
  Writer<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  WorldCommandQueue world_commands{std::string(kWorldInstance)};
  StepTapeWriter tape{std::string(kWorldInstance)};  // as the physics, for a recorder

  const double dt = 1.0 / options.rate_hz;
  const std::int64_t start_ns = monotonic_ns();
  std::int64_t next_ns = start_ns;
  std::uint64_t step = 0;
  WorldCommand world_command;
  WorldControl control;
  std::uint64_t rate_window_step = 0;
  std::int64_t rate_window_ns = start_ns;
  double achieved_rate_hz = 0.0;
  while (!stop_requested()) {
    if (hub_lost()) {  // outputs safe: nothing more is published until the re-exec
      sleep_until_ns(monotonic_ns() + period_ns);
      continue;
    }
    while (world_commands.next(world_command))
      if (control.apply(world_command, monotonic_ns())) step = 0;
    if (const WorldControl::Lapsed lapsed = control.lapse(monotonic_ns()))
      std::fprintf(stderr, kPauseLapsedFormat, "afhub synth", lapsed.pid, lapsed.hold_ms);
    // Published every period, paused or not, like the physics: the state
    // channels keep no history for late joiners.
    const bool stepping = control.take_step();
    const double t = static_cast<double>(step) * dt;
    const bool taping = stepping && tape.begin(step, t);
    // As the physics: one stamp for the step's states, and on the tape the bodies
    // someone reads.
    const std::int64_t stamp_ns = monotonic_ns();
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      if (stepping) step_body(bodies[i], i, t, dt);
      const BodyState* state = publish_body(bodies[i], i, step, t, stamp_ns);
      if (state && taping && bodies[i].channel->has_state_readers())
        tape.add(PayloadKind::kBodyState, channels[i], state,
                 static_cast<std::uint32_t>(body_state_bytes(options.joints)));
    }

    if (WorldState* state = world.loan()) {
      state->header.sim_step = step;
      state->header.sim_time_s = t;
      state->wall_time_s = static_cast<double>(monotonic_ns() - start_ns) * 1e-9;
      state->achieved_rate_hz = achieved_rate_hz;
      state->body_count = static_cast<std::uint32_t>(bodies.size());
      control.describe_pause(*state);
      world.publish(state);
      if (taping)
        tape.add(PayloadKind::kWorldState, std::string(kWorldInstance), state, sizeof *state);
    }
    if (taping) tape.finish();
    if (stepping) ++step;
    next_ns += period_ns;
    if (next_ns - rate_window_ns >= 1'000'000'000) {
      achieved_rate_hz = static_cast<double>(step - rate_window_step) * 1e9 /
                         static_cast<double>(next_ns - rate_window_ns);
      rate_window_step = step;
      rate_window_ns = next_ns;
    }
    if (options.seconds > 0.0 && static_cast<double>(next_ns - start_ns) * 1e-9 >= options.seconds)
      break;
    sleep_until_ns(next_ns);
  }
  return 0;
}

}  // namespace

void register_synth(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<SynthOptions>();
  auto* synth = app.add_subcommand(
      "synth",
      "Publish synthetic bodies at a fixed rate (a stand-in for physics): joints follow a "
      "sinusoid, or the commands written to them.");
  synth->add_option("--namespace", options->name_space,
                    "Namespace of the bodies (default 'synth')");
  add_count_option(synth, "--bodies", options->bodies, "Number of bodies (default 3)");
  add_count_option(synth, "--joints", options->joints, "Joints per body (default 4)");
  synth->add_option("--rate", options->rate_hz, "Steps per second (default 1000)");
  synth->add_option("--seconds", options->seconds,
                    "Stop after this many seconds (default: until Ctrl-C)");
  add_no_autostart_option(synth, options->no_autostart);
  synth->callback([&selected, options] { selected = [options] { return run_synth(*options); }; });
}

}  // namespace afhub::cli
