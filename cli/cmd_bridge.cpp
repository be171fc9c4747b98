// `afhub bridge dds`: the hub's bodies over Cyclone DDS (bridges/dds).
#include <memory>

#include "afhub/bridges/dds_bridge.hpp"
#include "commands.hpp"

namespace afhub::cli {

void register_bridge(CLI::App& app, Runner& selected) {
  auto* bridge = app.add_subcommand("bridge", "Bridge this hub to other networks.");
  bridge->require_subcommand(1);
  auto options = std::make_shared<bridges::DdsBridgeOptions>();
  auto* dds = bridge->add_subcommand(
      "dds",
      "Bridge bodies over Cyclone DDS (topics afhub/body_state, afhub/body_command, "
      "afhub/body_info). Select the network interface with CYCLONEDDS_URI.");
  dds->add_option("--domain", options->domain, "DDS domain id (default 0)");
  dds->add_option("--bodies", options->body_globs,
                  "Globs over body channel names, e.g. 'ambf/env/*' (default '*')");
  dds->add_flag("--export", options->export_bodies,
                "Publish this hub's matching bodies' states on DDS");
  dds->add_flag("--mirror", options->mirror,
                "Publish remote bodies seen on DDS into this hub, and send the commands "
                "written to them here back over DDS");
  dds->add_flag("--accept-commands", options->accept_commands,
                "With --export: apply commands from the network to local bodies");
  dds->add_option("--rate", options->rate_hz,
                  "Bridge loop rate: each body crosses at most once per cycle, newest wins "
                  "(default 1000 Hz)");
  dds->add_flag("--reliable", options->reliable,
                "Reliable states and commands (default best effort, keep last 1)");
  dds->add_option("--max-command-age", options->max_command_age_s,
                  "Drop network commands older than this by their DDS source timestamp "
                  "(default 0.05 s)");
  dds->add_flag("--latency", options->latency,
                "Report mirrored states' age from their source's publish (p50, p99, max); "
                "only meaningful when both sides share a monotonic clock (one host)");
  dds->add_option("--profile", options->profile,
                  "ros2: also publish exported bodies as ROS 2 topics rt/<prefix>/<body>/"
                  "{joint_states,pose,twist,wrench} (sensor_msgs/JointState, geometry_msgs/"
                  "*Stamped; sim-time stamps) and, with --accept-commands, take "
                  "sensor_msgs/JointState on rt/<prefix>/<body>/joint_command");
  dds->add_option("--ros2-prefix", options->ros2_prefix,
                  "With --profile ros2: a namespace before the body's channel name in ROS 2 "
                  "topic names (default none: rt/<body channel>/...)");
  dds->add_option("--security", options->security_dir,
                  "DDS Security: a directory holding identity_ca.pem, identity_certificate.pem, "
                  "identity_private_key.pem, permissions_ca.pem, governance.p7s and "
                  "permissions.p7s (bridges/dds/security/make_credentials.sh makes them)");
  dds->add_option("--seconds", options->seconds, "Stop after this many seconds (default: never)");
  dds->callback(
      [&selected, options] { selected = [options] { return bridges::run_dds_bridge(*options); }; });
}

}  // namespace afhub::cli
