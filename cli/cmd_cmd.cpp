// `afhub cmd BODY ...`: writes a command into a body's command slot, once or at a rate.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "format.hpp"

namespace afhub::cli {
namespace {

struct CmdOptions {
  std::string body;
  std::string force, torque, pose, joint_pos, joint_vel, joint_effort;
  double repeat_hz = 0.0;
};

// Fixed-axis roll, pitch, yaw (AMBF's convention) to a quaternion.
Quaternion from_rpy(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2);
  const double cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  return {sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
          cr * cp * cy + sr * sp * sy};
}

// The command every publish repeats, checked once against the body's catalog entry.
BodyCommand build_command(const CmdOptions& options, const BodyInfo& info) {
  BodyCommand command{};
  const bool cartesian_force = !options.force.empty() || !options.torque.empty();
  if (cartesian_force && !options.pose.empty())
    throw Error("--pose and --force/--torque ask for two Cartesian modes at once; give one");
  if (!options.pose.empty()) {
    auto v = parse_numbers(options.pose, "--pose", 6);
    command.cartesian_type = CartesianCommandType::kPosition;
    command.pose.position_m = {v[0], v[1], v[2]};
    command.pose.orientation = from_rpy(v[3], v[4], v[5]);
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
  if (joints) {
    auto values = parse_numbers(joints->text, joints->name, 0);
    if (values.size() > info.joint_count)
      throw Error(std::string(joints->name) + " gives " + std::to_string(values.size()) +
                  " values but body " + std::string(name_of(info.channel)) + " has " +
                  std::to_string(info.joint_count) + " joints (see `afhub ls`)");
    command.joint_count = static_cast<std::uint32_t>(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      command.joint_values[i] = values[i];
      command.joint_types[i] = joints->type;
    }
  }
  if (!cartesian_force && options.pose.empty() && !joints)
    throw Error(
        "nothing to command: give --force, --torque, --pose, --joint-pos, --joint-vel or "
        "--joint-effort");
  return command;
}

bool publish_once(BodyClient& body, const BodyCommand& prototype) {
  BodyCommand* command = body.loan_command();
  if (!command) return false;
  *command = prototype;
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
  if (options.repeat_hz < 0.0 || !std::isfinite(options.repeat_hz) || options.repeat_hz > 100'000.0)
    throw Error("--repeat must be a rate in Hz between 0 and 100000");
  connect_to_hub("cmd", HubPolicy::kRequire);
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  const BodyInfo info = catalog.resolve(options.body);
  const BodyCommand prototype = build_command(options, info);
  BodyClient body(name_of(info.channel));
  if (options.repeat_hz == 0.0) {
    if (!publish_once(body, prototype)) throw Error("shared memory exhausted: command not sent");
    return 0;
  }
  const auto period_ns = static_cast<std::int64_t>(1e9 / options.repeat_hz);
  std::int64_t next = monotonic_ns();
  std::uint64_t failed = 0;
  while (!stop_requested()) {
    if (!publish_once(body, prototype)) ++failed;
    next += period_ns;
    sleep_until_ns(next);
  }
  if (failed)
    std::fprintf(stderr, "afhub cmd: %llu commands not sent (shared memory exhausted)\n",
                 static_cast<unsigned long long>(failed));
  return 0;
}

}  // namespace

void register_cmd(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<CmdOptions>();
  auto* cmd = app.add_subcommand("cmd", "Write a command into a body's command slot.");
  cmd->add_option("body", options->body, "Body channel name or a unique suffix of it")->required();
  cmd->add_option("--force", options->force, "Force x,y,z in N, world frame (Cartesian FORCE)");
  cmd->add_option("--torque", options->torque,
                  "Torque x,y,z in N m, world frame (Cartesian FORCE)");
  cmd->add_option("--pose", options->pose,
                  "Target x,y,z,roll,pitch,yaw in m and rad (Cartesian POSITION)");
  cmd->add_option("--joint-pos", options->joint_pos, "Joint position targets a,b,... (rad or m)");
  cmd->add_option("--joint-vel", options->joint_vel,
                  "Joint velocity targets a,b,... (rad/s or m/s)");
  cmd->add_option("--joint-effort", options->joint_effort, "Joint efforts a,b,... (N m or N)");
  cmd->add_option("--repeat", options->repeat_hz,
                  "Send at this rate in Hz until Ctrl-C (default: once)");
  cmd->callback([&selected, options] { selected = [options] { return run_cmd(*options); }; });
}

}  // namespace afhub::cli
