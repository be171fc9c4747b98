// `afhub cmd BODY ...`: writes a command into a body's command slot at a rate until
// Ctrl-C (or once), joints by name or index, the joints left unnamed held; stops
// with the physics' reason when it refuses the command.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/physics/model.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/number_text.hpp"
#include "commands.hpp"
#include "format.hpp"
#include "time_options.hpp"

namespace afhub::cli {
namespace {

// As `ros2 topic pub`: keep sending, well inside the physics' 0.5 s watchdog.
constexpr double kDefaultRateHz = 100.0;

struct CmdOptions {
  std::string body;
  std::string force, torque, pose, joint_pos, joint_vel, joint_effort;
  std::vector<std::string> joints;  // NAME=VALUE or INDEX=VALUE, position targets
  std::string others = "hold";      // what the joints left unnamed do: hold | release
  double repeat_hz = kDefaultRateHz;
  bool once = false;
};
// The command every publish repeats, checked once against the body's catalog entry.
BodyCommand build_command(const CmdOptions& options, const BodyEntry& entry) {
  const BodyInfo& info = entry.info;
  BodyCommand command{};
  const bool cartesian_force = !options.force.empty() || !options.torque.empty();
  if (cartesian_force && !options.pose.empty())
    throw Error("--pose and --force/--torque ask for two Cartesian modes at once; give one");
  if (!options.pose.empty()) {
    auto v = parse_numbers(options.pose, "--pose", 6);
    command.cartesian_type = CartesianCommandType::kPosition;
    command.pose.position_m = {v[0], v[1], v[2]};
    command.pose.orientation = physics::rpy_to_quaternion({v[3], v[4], v[5]});
  }
  if (!options.force.empty()) {
    auto v = parse_numbers(options.force, "--force", 3);
    command.wrench.force_n = {v[0], v[1], v[2]};
  }
  if (!options.torque.empty()) {
    auto v = parse_numbers(options.torque, "--torque", 3);
    command.wrench.torque_nm = {v[0], v[1], v[2]};
  }
  struct JointFlag {
    const std::string& text;
    const char* name;
    JointCommandType type;
  };
  std::optional<JointFlag> joints;
  for (const JointFlag flag :
       {JointFlag{options.joint_pos, "--joint-pos", JointCommandType::kPosition},
        JointFlag{options.joint_vel, "--joint-vel", JointCommandType::kVelocity},
        JointFlag{options.joint_effort, "--joint-effort", JointCommandType::kEffort}}) {
    if (flag.text.empty()) continue;
    if (joints)
      throw Error(std::string(joints->name) + " and " + flag.name +
                  " both set the joints; give one (per-joint types come from one flag)");
    joints.emplace(flag);
  }
  if (joints && !options.joints.empty())
    throw Error(std::string(joints->name) +
                " and --joint both set the joints; give one (--joint NAME=VALUE, repeated, or a "
                "list)");
  if (joints) {
    auto values = parse_numbers(joints->text, joints->name, 0);
    if (values.size() > info.joint_count)
      throw Error(std::string(joints->name) + " gives " + std::to_string(values.size()) +
                  " values but body " + std::string(name_of(info.channel)) + " has " +
                  std::to_string(info.joint_count) + " joints (see `afhub ls`)");
    command.joint_count = static_cast<std::uint32_t>(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      command.joints[i].value = values[i];
      command.joints[i].type = joints->type;
    }
  }
  if (!cartesian_force && options.pose.empty() && !joints && options.joints.empty())
    throw Error(
        "nothing to command: give --joint NAME=VALUE, --force, --torque, --pose, --joint-pos, "
        "--joint-vel or --joint-effort");
  return command;
}

// --joint NAME=VALUE (or INDEX=VALUE), repeated: position targets by joint.
std::map<std::size_t, double> named_joint_targets(const CmdOptions& options, const BodyEntry& entry,
                                                  BodyClient& body) {
  const std::vector<std::string>& names = entry.joint_names;
  std::map<std::size_t, double> targets;
  for (const std::string& item : options.joints) {
    const auto equals = item.rfind('=');
    if (equals == std::string::npos || equals == 0)
      throw Error("--joint takes NAME=VALUE or INDEX=VALUE, e.g. --joint " +
                  (names.empty() ? std::string("shoulder") : names.front()) + "=0.3; got '" + item +
                  "'");
    const std::string joint = item.substr(0, equals);
    const std::string text = item.substr(equals + 1);
    const std::optional<double> value = yaml::parse_finite(text);
    if (!value)
      throw Error("--joint " + item + ": '" + text + "' is not a finite number; e.g. --joint " +
                  joint + "=0.3");
    std::size_t index = 0;
    if (joint.find_first_not_of("0123456789") == std::string::npos) {
      index = joint.size() < 6 ? std::stoul(joint) : names.size();
      if (index >= names.size())
        throw Error("--joint " + item + ": body " + std::string(name_of(entry.info.channel)) +
                    " has " + std::to_string(names.size()) + " joints, indices 0 to " +
                    std::to_string(names.size() == 0 ? 0 : names.size() - 1));
    } else {
      index = body.joint_index(joint);  // the error lists the body's joints
    }
    if (!targets.emplace(index, *value).second)
      throw Error("--joint names joint " + std::to_string(index) + " (" + names[index] + ") twice");
  }
  return targets;
}

// The body's newest state: the positions the unnamed joints hold.
BodyState current_state(BodyClient& body) {
  const std::int64_t give_up = monotonic_ns() + 2'000'000'000;
  while (!body.latest_state()) {
    if (monotonic_ns() > give_up || stop_requested())
      throw Error("no state came from " + body.channel() +
                  " in 2 s, so its joints' positions are unknown: is its simulation running "
                  "(or paused in a lockstep wait)? `--others release` commands only the joints "
                  "given");
    sleep_until_ns(monotonic_ns() + 1'000'000);
  }
  BodyState state;
  copy_body_state(*body.latest_state(), state);
  return state;
}

// Completes the joint part: named targets, then the joints left unnamed hold their
// current positions (or, with --others release, are left out of the command when
// they come after the last one given). Returns a description for stderr.
std::string complete_joints(const CmdOptions& options, const BodyEntry& entry, BodyClient& body,
                            BodyCommand& command) {
  const std::map<std::size_t, double> targets = named_joint_targets(options, entry, body);
  const std::vector<std::string>& names = entry.joint_names;
  const bool any_joint = command.joint_count > 0 || !targets.empty();
  if (!any_joint) return names.empty() ? "" : "its joints are not commanded (no joint flag given)";
  const std::uint32_t given = command.joint_count;
  std::vector<bool> named(names.size(), false);
  for (std::uint32_t i = 0; i < given; ++i) named[i] = true;
  for (const auto& [index, value] : targets) named[index] = true;
  std::size_t unnamed = 0;
  for (bool is_named : named) unnamed += !is_named;
  std::string described;
  for (const auto& [index, value] : targets) {
    char line[160];
    std::snprintf(line, sizeof line, "%s%s -> %g", described.empty() ? "" : ", ",
                  names[index].c_str(), value);
    described += line;
  }
  if (given > 0)
    described = std::string(options.joint_pos.empty()
                                ? (options.joint_vel.empty() ? "efforts on joints 0-"
                                                             : "velocities on joints 0-")
                                : "positions on joints 0-") +
                std::to_string(given - 1);
  if (options.others == "release") {
    // Only the joints up to the last one named are in the command; a gap among them
    // gets a zero effort, the nearest thing to letting go.
    std::uint32_t count = given;
    for (const auto& [index, value] : targets)
      count = std::max(count, static_cast<std::uint32_t>(index + 1));
    for (std::uint32_t i = given; i < count; ++i) {
      const auto target = targets.find(i);
      command.joints[i].type =
          target == targets.end() ? JointCommandType::kEffort : JointCommandType::kPosition;
      command.joints[i].value = target == targets.end() ? 0.0 : target->second;
    }
    command.joint_count = count;
    return described + (unnamed == 1 ? "; the joint left unnamed is released (--others release)"
                        : unnamed    ? "; the " + std::to_string(unnamed) +
                                        " joints left unnamed are released (--others release)"
                                  : "");
  }
  const BodyState state = current_state(body);
  command.joint_count = static_cast<std::uint32_t>(names.size());
  for (std::uint32_t i = given; i < names.size(); ++i) {
    const auto target = targets.find(i);
    command.joints[i].type = JointCommandType::kPosition;
    command.joints[i].value = target != targets.end()
                                  ? target->second
                                  : (i < state.joint_count ? state.joints[i].position : 0.0);
  }
  return described + (unnamed == 1 ? "; the joint left unnamed holds its current position"
                      : unnamed    ? "; the " + std::to_string(unnamed) +
                                      " joints left unnamed hold their current positions"
                                : "");
}

// The physics' refusals of this process's commands, read back from the body's state
// (BodyState::refused_commands): it refuses a command that it cannot apply, says why
// on its own stderr, and counts it in the state with the sender's pid and reason.
class RefusalWatch {
 public:
  explicit RefusalWatch(BodyClient& body)
      : body_(body), pid_(static_cast<std::uint32_t>(getpid())) {
    if (const BodyState* state = body.latest_state()) {
      seen_ = state->refused_commands;
      seen_any_ = true;
    }
  }
  // The physics' reason when it refused one of this process's commands since the
  // watch began, else empty.
  std::string refusal() {
    const BodyState* state = body_.latest_state();
    if (!state) return "";
    // A state before any seen: its refusals are new only when they name this process.
    const bool new_refusal =
        seen_any_ ? state->refused_commands != seen_ : state->refused_commands > 0;
    seen_ = state->refused_commands;
    seen_any_ = true;
    if (!new_refusal || state->refused_command_pid != pid_) return "";
    return std::string(name_of(state->refusal_reason));
  }
  // The sequence and publish stamp of the newest state (0: none yet), to wait for the
  // physics' answer.
  std::uint64_t state_sequence() {
    const BodyState* state = body_.latest_state();
    return state ? state->header.sequence : 0;
  }
  std::int64_t state_stamp_ns() {
    const BodyState* state = body_.latest_state();
    return state ? state->header.publish_stamp_ns : 0;
  }

 private:
  BodyClient& body_;
  std::uint32_t pid_;
  std::uint32_t seen_ = 0;  // the count in the last state looked at
  bool seen_any_ = false;
};

[[noreturn]] void refused(const std::string& channel, const std::string& reason) {
  throw Error("the physics refused the command for " + channel + ": " + reason +
              " (nothing of it was applied). Command values within the body's bounds; "
              "`afhub echo " +
              channel + "` shows its joints now");
}

// After --once: the physics takes up a new writer's slot when it next looks for writers
// (at most once a coarse clock tick, up to 4 ms: more steps than one at 1 kHz, many under
// load), reads commands at the start of a step and publishes states at the end; so once
// it holds the slot, the second state published after carries its answer.
void check_once(BodyClient& body, RefusalWatch& watch, const std::string& channel) {
  const auto wait_for = [&](std::int64_t limit_ns, const auto& done) {
    const std::int64_t give_up = monotonic_ns() + limit_ns;
    while (!done() && monotonic_ns() < give_up && !stop_requested())
      sleep_until_ns(monotonic_ns() + 1'000'000);
    return done();
  };
  // The slot goes when this process ends: a command no physics took is lost. (Another
  // reader of commands, the DDS bridge say, holds the slot too: with one, this can pass
  // before the physics holds it.)
  if (!wait_for(5'000'000'000, [&] { return body.command_has_readers(); })) {
    if (stop_requested())
      throw Error("stopped before a physics took the command for " + channel +
                  ": nothing of it was applied");
    throw Error("no physics took the command for " + channel +
                " within 5 s, so nothing of it was applied. Is the physics stopped or stuck? "
                "`afhub status` shows whether the world steps; send the command again once it "
                "does");
  }
  const std::int64_t taken_ns = monotonic_ns();
  constexpr std::int64_t kAnswerNs = 1'000'000'000;  // paused or gone: no answer
  wait_for(kAnswerNs, [&] { return watch.state_stamp_ns() > taken_ns; });
  const std::uint64_t first_after = watch.state_sequence();
  wait_for(kAnswerNs, [&] { return watch.state_sequence() > first_after; });
  if (const std::string reason = watch.refusal(); !reason.empty()) refused(channel, reason);
}

bool publish_once(BodyClient& body, const BodyCommand& prototype) {
  if (hub_lost()) return true;  // outputs safe: no command into a hub that is gone
  BodyCommand* command = body.loan_command(prototype.joint_count);
  if (!command) return false;
  copy_body_command(prototype, *command);
  // A command answers the newest state it has seen.
  if (const BodyState* state = body.latest_state()) {
    command->header.sim_step = state->header.sim_step;
    command->header.sim_time_s = state->header.sim_time_s;
  }
  body.publish_command(command);
  return true;
}

int run_cmd(const CmdOptions& options) {
  install_stop_signal_handlers();
  // --repeat 0 meant once before cmd kept sending by default: it still does.
  const bool once = options.once || options.repeat_hz == 0.0;
  const std::int64_t period_ns =
      once ? 0 : period_ns_of_rate(options.repeat_hz, "--repeat (--rate; 0: --once)");
  if (options.others != "hold" && options.others != "release")
    throw Error("--others takes hold or release");
  if (!once) survive_hub_loss("afhub cmd");
  connect_to_hub("cmd", HubPolicy::kRequire);
  // Re-attached after a hub loss, the body's physics may come back after this process.
  const BodyEntry entry =
      wait_for_body(options.body, "afhub cmd",
                    reattach_count() > 0 ? std::numeric_limits<std::int64_t>::max() : 0);
  // A device's driver reads forces, not body commands: none would take this one.
  if (entry.info.kind == ChannelKind::kDevice) {
    const std::string device(name_of(entry.info.channel));
    throw Error(device +
                " is a device, not a body: `afhub cmd` commands bodies (`afhub ls` lists "
                "them); `afhub device force " +
                device.substr(device.rfind('/') + 1) + " --force x,y,z` commands its force");
  }
  BodyCommand prototype = build_command(options, entry);
  BodyClient body(entry);
  const std::string joints = complete_joints(options, entry, body, prototype);
  const std::string channel(name_of(entry.info.channel));
  RefusalWatch watch(body);
  // Before the first loan, as every publisher: a command must not starve a running physics.
  require_chunks({written_as_slot(body_command_bytes(prototype.joint_count))},
                 "this command (to " + channel + ")");
  if (once) {
    if (!publish_once(body, prototype)) throw Error("shared memory exhausted: command not sent");
    check_once(body, watch, channel);
    std::fprintf(stderr,
                 "afhub cmd: sent one command to %s%s%s.\nwarning: the physics' watchdog releases "
                 "it when no new command comes within its period (0.5 s unless `afhub run "
                 "--watchdog` says otherwise); leave out --once to keep sending until Ctrl-C\n",
                 channel.c_str(), joints.empty() ? "" : ": ", joints.c_str());
    return 0;
  }
  std::fprintf(stderr, "afhub cmd: commanding %s at %g Hz until Ctrl-C%s%s\n", channel.c_str(),
               options.repeat_hz, joints.empty() ? "" : ": ", joints.c_str());
  std::int64_t next = monotonic_ns();
  std::uint64_t failed = 0;
  while (!stop_requested()) {
    if (!publish_once(body, prototype)) ++failed;
    if (const std::string reason = watch.refusal(); !reason.empty()) refused(channel, reason);
    next += period_ns;
    sleep_until_ns(next);
  }
  if (failed)
    std::fprintf(stderr, "afhub cmd: %llu commands not sent (shared memory exhausted)\n",
                 static_cast<unsigned long long>(failed));
  std::fprintf(stderr,
               "afhub cmd: stopped; the physics' watchdog releases %s after its period (0.5 s "
               "by default)\n",
               channel.c_str());
  return 0;
}

}  // namespace

void register_cmd(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<CmdOptions>();
  auto* cmd = app.add_subcommand(
      "cmd",
      "Write a command into a body's command slot, again and again (100 Hz) until Ctrl-C, as "
      "`ros2 topic pub` does: the physics' watchdog releases a body whose commands stop for its "
      "period (0.5 s by default), so a command sent once lasts only that long (--once).\n"
      "Joints: --joint NAME=VALUE (names from `afhub ls`, or INDEX=VALUE), repeated, sets "
      "position targets; the joints left unnamed hold the positions they had when cmd started "
      "(--others release lets them go instead). Without a joint flag the joints are not "
      "commanded.");
  cmd->add_option("body", options->body, "Body channel name or a unique suffix of it")->required();
  cmd->add_option("--joint,-j", options->joints,
                  "NAME=VALUE or INDEX=VALUE: a joint's position target (rad or m); repeat it "
                  "for more joints")
      ->allow_extra_args(false);
  cmd->add_option("--others", options->others,
                  "What the joints left unnamed do: hold (default: hold their current positions) "
                  "or release (no command; a gap before a named joint gets zero effort)");
  cmd->add_option("--force", options->force, "Force x,y,z in N, world frame (Cartesian FORCE)");
  cmd->add_option("--torque", options->torque,
                  "Torque x,y,z in N m, world frame (Cartesian FORCE)");
  cmd->add_option("--pose", options->pose,
                  "Target x,y,z,roll,pitch,yaw in m and rad (Cartesian POSITION)");
  cmd->add_option("--joint-pos", options->joint_pos,
                  "Position targets a,b,... for joints 0, 1, ... (rad or m)");
  cmd->add_option("--joint-vel", options->joint_vel,
                  "Velocity targets a,b,... for joints 0, 1, ... (rad/s or m/s)");
  cmd->add_option("--joint-effort", options->joint_effort,
                  "Efforts a,b,... for joints 0, 1, ... (N m or N)");
  auto* repeat = cmd->add_option("--repeat,--rate", options->repeat_hz,
                                 "Send at this rate in Hz until Ctrl-C (default 100; 0 is --once)");
  cmd->add_flag("--once", options->once,
                "Send one command and exit; the watchdog releases it after its period (0.5 s)")
      ->excludes(repeat);
  cmd->callback([&selected, options] { selected = [options] { return run_cmd(*options); }; });
}

}  // namespace afhub::cli
