// `afhub bridge dds`: the hub's bodies, devices and world over Cyclone DDS (bridges/dds).
// Settings come from --config FILE, then the flags given on the command line over it.
#include <cstdio>
#include <memory>

#include "afhub/bridges/dds_bridge.hpp"
#include "afhub/bridges/dds_bridge_config.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct BridgeCliOptions {
  std::string config;
  bool best_effort = false;
  bool check = false;
  bridges::DdsBridgeOptions flags;
};

// The file's settings, then each flag given on the command line over them.
bridges::DdsBridgeOptions merged(CLI::App& dds, const BridgeCliOptions& cli) {
  if (cli.config.empty()) {
    bridges::DdsBridgeOptions options = cli.flags;
    if (cli.best_effort) options.reliable = false;
    options.accept_commands = options.accept_commands || options.insecure_accept_commands;
    return options;
  }
  bridges::DdsBridgeOptions options = bridges::read_dds_bridge_config(cli.config);
  const bridges::DdsBridgeOptions& f = cli.flags;
  const auto given = [&dds](const char* flag) { return dds.count(flag) > 0; };
  if (given("--domain")) options.domain = f.domain;
  if (given("--interface")) options.interface = f.interface;
  if (given("--bodies")) options.body_globs = f.body_globs;
  if (given("--devices")) options.device_globs = f.device_globs;
  if (given("--world")) options.world = true;
  if (given("--export")) options.export_bodies = true;
  if (given("--mirror")) options.mirror = true;
  if (given("--accept-commands")) options.accept_commands = true;
  if (given("--insecure-accept-commands")) options.insecure_accept_commands = true;
  if (given("--rate")) options.rate_hz = f.rate_hz;
  if (given("--spin")) options.spin = true;
  if (given("--cpu-wake-latency")) options.cpu_wake_latency_us = f.cpu_wake_latency_us;
  if (given("--body-rate")) options.body_rate_hz = f.body_rate_hz;
  if (given("--device-rate")) options.device_rate_hz = f.device_rate_hz;
  if (given("--world-rate")) options.world_rate_hz = f.world_rate_hz;
  if (given("--reliable")) options.reliable = true;
  if (given("--best-effort")) options.reliable = false;
  if (given("--max-command-age")) options.max_command_age_s = f.max_command_age_s;
  if (given("--profile")) options.profile = f.profile;
  if (given("--ros2-prefix")) options.ros2_prefix = f.ros2_prefix;
  if (given("--security")) options.security_dir = f.security_dir;
  if (given("--max-mirrored")) options.max_mirrored = f.max_mirrored;
  options.accept_commands = options.accept_commands || options.insecure_accept_commands;
  options.latency = f.latency;
  options.seconds = f.seconds;
  return options;
}

}  // namespace

void register_bridge(CLI::App& app, Runner& selected) {
  auto* bridge = app.add_subcommand("bridge", "Bridge this hub to other networks.");
  bridge->require_subcommand(1);
  auto cli = std::make_shared<BridgeCliOptions>();
  bridges::DdsBridgeOptions* options = &cli->flags;
  auto* dds = bridge->add_subcommand(
      "dds",
      "Bridge bodies, devices and the world over Cyclone DDS (topics afhub/body_state, "
      "afhub/body_command, afhub/body_info, afhub/device_state, afhub/device_command, "
      "afhub/world_state, afhub/world_command). Settings come from --config FILE (YAML, "
      "keys named as the flags: domain, interface, export, mirror, accept-commands, "
      "insecure-accept-commands, bodies, "
      "devices, world, qos: best-effort|reliable, rate, spin, cpu-wake-latency, rate-limits: "
      "{bodies, devices, world}, max-command-age, max-mirrored, profile, ros2-prefix, security), "
      "and the "
      "flags given here override the file's.");
  dds->add_option("--config", cli->config,
                  "YAML file of settings (see above); flags given here override it")
      ->check(CLI::ExistingFile);
  dds->add_option("--domain", options->domain, "DDS domain id (default 0)");
  dds->add_option("--interface", options->interface,
                  "Bind DDS to this network interface (default: CYCLONEDDS_URI's or Cyclone's "
                  "choice); it replaces CYCLONEDDS_URI's inline interfaces, whose other "
                  "settings (peers) still apply");
  dds->add_option("--bodies", options->body_globs,
                  "Globs over body channel names, e.g. 'ambf/env/*' (default '*'): the local "
                  "bodies exported and the announced bodies mirrored (a mirror takes no other "
                  "name, and at most --max-mirrored)");
  dds->add_option("--devices", options->device_globs,
                  "Globs over device names (channels device/<name>) to bridge, e.g. 'falcon*' "
                  "(default: none). A mirrored device is listed as a device here; its "
                  "DeviceCommand (force) goes back only to a bridge with --accept-commands");
  dds->add_flag("--world", options->world,
                "Bridge the world: its state out (export) or in (mirror); world commands "
                "(pause, resume, step, reset) from the network are applied only with "
                "--accept-commands, under --max-command-age");
  dds->add_flag("--export", options->export_bodies,
                "Publish this hub's matching bodies' (and devices', world's) states on DDS");
  dds->add_flag("--mirror", options->mirror,
                "Publish remote bodies (devices, world) seen on DDS into this hub, and send "
                "the commands written to them here back over DDS");
  dds->add_option("--max-mirrored", options->max_mirrored,
                  "With --mirror: mirror at most this many remote bodies and devices, so that "
                  "this hub keeps room for its own (default 225, half of the 450 a hub lists); "
                  "those past it, or whose joint names would not fit the hub's catalog, are "
                  "refused and said once");
  dds->add_flag("--accept-commands", options->accept_commands,
                "With --export and --security: apply commands from the network to local "
                "bodies, devices and the world");
  dds->add_flag("--insecure-accept-commands", options->insecure_accept_commands,
                "--accept-commands without --security: any host on the DDS domain may command "
                "this hub's bodies, devices and world (each status line says so); only on a "
                "network that only trusted hosts reach");
  dds->add_option("--rate", options->rate_hz,
                  "The bridge's cycle for what does not wake it (devices, the world, the "
                  "catalog); bodies' states and commands cross as they arrive, newest wins "
                  "(default 1000 Hz)");
  dds->add_flag("--spin", options->spin,
                "Poll for this hub's states and commands instead of sleeping until one comes: "
                "no wake-up on the way out, for a bridge given a core of its own (it takes that "
                "core)");
  dds->add_option("--cpu-wake-latency", options->cpu_wake_latency_us,
                  "Hold idle CPUs to wake within this many microseconds while the bridge runs "
                  "(/dev/cpu_dma_latency, as cyclictest does; root): 0 keeps them polling "
                  "instead of sleeping, so that each message wakes its reader at once, for an "
                  "idle core's power; on a VM, where a sleeping vCPU wakes in tens of us, it "
                  "brings the bridges' cost near raw DDS's (default: leave them)");
  dds->add_option("--body-rate", options->body_rate_hz,
                  "Send each body's state at most this often, newest wins (Hz; default 0: "
                  "every new state)");
  dds->add_option("--device-rate", options->device_rate_hz,
                  "The same for each device's state (Hz; default 0: every new state)");
  dds->add_option("--world-rate", options->world_rate_hz,
                  "The same for the world state (Hz; default 0: every new state)");
  dds->add_flag("--reliable", options->reliable,
                "Reliable states and commands (default best effort; keep last 1 either way)");
  dds->add_flag("--best-effort", cli->best_effort,
                "Best-effort states and commands (overrides a config file's qos: reliable)");
  dds->add_option("--max-command-age", options->max_command_age_s,
                  "Drop network commands older than this by their DDS source timestamp "
                  "(default 0.05 s)");
  dds->add_flag("--latency", options->latency,
                "Report mirrored states' age from their source's publish (p50, p99, max), "
                "and on an exporter the applied commands' age by their DDS source timestamp; "
                "states' ages are only meaningful where both sides share a monotonic clock "
                "(one host), commands' where their wall clocks agree");
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
  dds->add_flag("--check", cli->check,
                "Print the settings (--config FILE's, the flags over them) in the file's "
                "format, check them, and exit");
  dds->callback([&selected, cli, dds] {
    selected = [cli, dds] {
      const bridges::DdsBridgeOptions settings = merged(*dds, *cli);
      if (!cli->check) return bridges::run_dds_bridge(settings);
      std::printf("%s", bridges::render_dds_bridge_config(settings).c_str());
      bridges::check_dds_bridge_options(settings);
      return 0;
    };
  });
}

}  // namespace afhub::cli
