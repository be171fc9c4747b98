// `afhub bridge dds`: the hub's bodies, devices and world over Cyclone DDS (bridges/dds).
// Settings come from --config FILE, then the flags given on the command line over it.
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "afhub/bridges/dds_bridge.hpp"
#include "afhub/bridges/dds_bridge_config.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

using DdsOptions = bridges::DdsBridgeOptions;

struct BridgeCliOptions {
  std::string config;
  bool best_effort = false;
  bool check = false;
  bool cpu_wake_latency_given = false;  // written (then -1 is refused)
  DdsOptions flags;
  // Each setting's flag, with how it goes over the config file's setting when given.
  std::vector<std::pair<const CLI::Option*, std::function<void(DdsOptions&)>>> overrides;
};

// A setting's flag (a file's key too): recorded with its override as it is added, so that
// no flag can be left out of the merge.
template <typename T>
CLI::Option* add_setting(CLI::App* dds, BridgeCliOptions& cli, const std::string& name,
                         T DdsOptions::*setting, const std::string& help) {
  T& flag = cli.flags.*setting;
  CLI::Option* option = nullptr;
  if constexpr (std::is_same_v<T, bool>)
    option = dds->add_flag(name, flag, help);
  else
    option = dds->add_option(name, flag, help);
  cli.overrides.emplace_back(option,
                             [setting, &flag](DdsOptions& options) { options.*setting = flag; });
  return option;
}

// The file's settings, then each flag given on the command line over them.
DdsOptions merged(const BridgeCliOptions& cli) {
  if (cli.cpu_wake_latency_given)
    check_cpu_wake_latency_option(cli.flags.cpu_wake_latency_us, true);
  DdsOptions options = cli.flags;
  if (!cli.config.empty()) {
    options = bridges::read_dds_bridge_config(cli.config);
    for (const auto& [option, override_setting] : cli.overrides)
      if (option->count() > 0) override_setting(options);
    options.latency = cli.flags.latency;  // not in a file: the flags' alone
    options.seconds = cli.flags.seconds;
  }
  if (cli.best_effort) options.reliable = false;
  options.accept_commands = options.accept_commands || options.insecure_accept_commands;
  return options;
}

}  // namespace

void register_bridge(CLI::App& app, Runner& selected) {
  auto* bridge = app.add_subcommand("bridge", "Bridge this hub to other networks.");
  bridge->require_subcommand(1);
  auto cli = std::make_shared<BridgeCliOptions>();
  DdsOptions* options = &cli->flags;
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
  add_setting(dds, *cli, "--domain", &DdsOptions::domain, "DDS domain id (default 0)");
  add_setting(dds, *cli, "--interface", &DdsOptions::interface,
              "Bind DDS to this network interface (default: CYCLONEDDS_URI's or Cyclone's "
              "choice); it replaces CYCLONEDDS_URI's inline interfaces, whose other "
              "settings (peers) still apply");
  add_setting(dds, *cli, "--bodies", &DdsOptions::body_globs,
              "Globs over body channel names, e.g. 'ambf/env/*' (default '*'): the local "
              "bodies exported and the announced bodies mirrored (a mirror takes no other "
              "name, and at most --max-mirrored)");
  add_setting(dds, *cli, "--devices", &DdsOptions::device_globs,
              "Globs over device names (channels device/<name>) to bridge, e.g. 'falcon*' "
              "(default: none). A mirrored device is listed as a device here; its "
              "DeviceCommand (force) goes back only to a bridge with --accept-commands");
  add_setting(dds, *cli, "--world", &DdsOptions::world,
              "Bridge the world: its state out (export) or in (mirror); world commands "
              "(pause, resume, step, reset) from the network are applied only with "
              "--accept-commands, under --max-command-age");
  add_setting(dds, *cli, "--export", &DdsOptions::export_bodies,
              "Publish this hub's matching bodies' (and devices', world's) states on DDS");
  add_setting(dds, *cli, "--mirror", &DdsOptions::mirror,
              "Publish remote bodies (devices, world) seen on DDS into this hub, and send "
              "the commands written to them here back over DDS");
  add_setting(dds, *cli, "--max-mirrored", &DdsOptions::max_mirrored,
              "With --mirror: mirror at most this many remote bodies and devices, so that "
              "this hub keeps room for its own (default 225, of the 4096 a hub lists); "
              "those past it, or whose joint names would not fit the hub's catalog, are "
              "refused and said once");
  add_setting(dds, *cli, "--accept-commands", &DdsOptions::accept_commands,
              "With --export and --security: apply commands from the network to local "
              "bodies, devices and the world");
  add_setting(dds, *cli, "--insecure-accept-commands", &DdsOptions::insecure_accept_commands,
              "--accept-commands without --security: any host on the DDS domain may command "
              "this hub's bodies, devices and world (each status line says so); only on a "
              "network that only trusted hosts reach");
  add_setting(dds, *cli, "--rate", &DdsOptions::rate_hz,
              "The bridge's cycle for what does not wake it (devices, the world, the "
              "catalog); bodies' states and commands cross as they arrive, newest wins "
              "(default 1000 Hz)");
  add_setting(dds, *cli, "--spin", &DdsOptions::spin,
              "Poll for this hub's states and commands instead of sleeping until one comes: "
              "no wake-up on the way out, for a bridge given a core of its own (it takes that "
              "core)");
  add_setting(dds, *cli, "--cpu-wake-latency", &DdsOptions::cpu_wake_latency_us,
              "Hold idle CPUs to wake within this many microseconds while the bridge runs "
              "(/dev/cpu_dma_latency, as cyclictest does; root): 0 keeps them polling "
              "instead of sleeping, so that each message wakes its reader at once, for an "
              "idle core's power; on a VM, where a sleeping vCPU wakes in tens of us, it "
              "brings the bridges' cost near raw DDS's (default: leave them)")
      ->each([cli](const std::string&) { cli->cpu_wake_latency_given = true; });
  add_setting(dds, *cli, "--body-rate", &DdsOptions::body_rate_hz,
              "Send each body's state at most this often, newest wins (Hz; default 0: "
              "every new state)");
  add_setting(dds, *cli, "--device-rate", &DdsOptions::device_rate_hz,
              "The same for each device's state (Hz; default 0: every new state)");
  add_setting(dds, *cli, "--world-rate", &DdsOptions::world_rate_hz,
              "The same for the world state (Hz; default 0: every new state)");
  add_setting(dds, *cli, "--reliable", &DdsOptions::reliable,
              "Reliable states and commands (default best effort; keep last 1 either way)");
  dds->add_flag("--best-effort", cli->best_effort,
                "Best-effort states and commands (overrides a config file's qos: reliable)");
  add_setting(dds, *cli, "--max-command-age", &DdsOptions::max_command_age_s,
              "Drop network commands older than this by their DDS source timestamp "
              "(default 0.05 s)");
  dds->add_flag("--latency", options->latency,
                "Report mirrored states' age from their source's publish (p50, p99, max), "
                "and on an exporter the applied commands' age by their DDS source timestamp; "
                "states' ages are only meaningful where both sides share a monotonic clock "
                "(one host), commands' where their wall clocks agree");
  add_setting(dds, *cli, "--profile", &DdsOptions::profile,
              "ros2: also publish exported bodies as ROS 2 topics rt/<prefix>/<body>/"
              "{joint_states,pose,twist,wrench} (sensor_msgs/JointState, geometry_msgs/"
              "*Stamped; sim-time stamps) and, with --accept-commands, take "
              "sensor_msgs/JointState on rt/<prefix>/<body>/joint_command");
  add_setting(dds, *cli, "--ros2-prefix", &DdsOptions::ros2_prefix,
              "With --profile ros2: a namespace before the body's channel name in ROS 2 "
              "topic names (default none: rt/<body channel>/...)");
  add_setting(dds, *cli, "--security", &DdsOptions::security_dir,
              "DDS Security: a directory holding identity_ca.pem, identity_certificate.pem, "
              "identity_private_key.pem, permissions_ca.pem, governance.p7s and "
              "permissions.p7s (bridges/dds/security/make_credentials.sh makes them)");
  dds->add_option("--seconds", options->seconds, "Stop after this many seconds (default: never)");
  dds->add_flag("--check", cli->check,
                "Print the settings (--config FILE's, the flags over them) in the file's "
                "format, check them, and exit");
  dds->callback([&selected, cli] {
    selected = [cli] {
      const DdsOptions settings = merged(*cli);
      if (!cli->check) return bridges::run_dds_bridge(settings);
      std::printf("%s", bridges::render_dds_bridge_config(settings).c_str());
      bridges::check_dds_bridge_options(settings);
      return 0;
    };
  });
}

}  // namespace afhub::cli
