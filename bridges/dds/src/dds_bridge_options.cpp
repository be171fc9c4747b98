// The bridge's options checked before anything starts (see dds_bridge.hpp).

#include "afhub/bridges/dds_bridge.hpp"
#include "afhub/bridges/dds_bridge_config.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "dds_entity.hpp"
#include "dds_security.hpp"

namespace afhub::bridges {

void check_dds_bridge_options(const DdsBridgeOptions& options) {
  if (!options.export_bodies && !options.mirror)
    throw Error(
        "say what to bridge: --export (this hub's bodies out), --mirror (remote "
        "bodies in), or both");
  if (options.accept_commands && !options.export_bodies)
    throw Error("--accept-commands applies commands to exported bodies: add --export");
  if (options.accept_commands && options.security_dir.empty() && !options.insecure_accept_commands)
    throw Error(
        "--accept-commands without --security lets any host on DDS domain " +
        std::to_string(options.domain) +
        " command this hub's bodies, devices and world: give --security DIR (credentials from "
        "bridges/dds/security/make_credentials.sh), or --insecure-accept-commands on a network "
        "only trusted hosts reach");
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100'000.0))
    throw Error("--rate must be between 0 and 100000 Hz");
  if (!(options.max_command_age_s > 0.0 && options.max_command_age_s <= 10.0))
    throw Error("--max-command-age must be between 0 and 10 s");
  check_cpu_wake_latency_option(options.cpu_wake_latency_us);
  if (options.domain > 232) throw Error("--domain must be 0 to 232 (DDS domain ids)");
  if (options.body_globs.empty()) throw Error("--bodies needs at least one glob");
  if (!options.profile.empty() && options.profile != "ros2")
    throw Error("--profile " + options.profile +
                ": unknown; the one profile is ros2 (afhub's own types are always published)");
  if (options.profile == "ros2" && !options.export_bodies)
    throw Error("--profile ros2 publishes exported bodies as ROS 2 topics: add --export");
  if (!options.security_dir.empty()) {
    const Qos files;  // the files, before anything starts
    add_security_properties(files.get(), options.security_dir);
  }
  for (const double rate : {options.body_rate_hz, options.device_rate_hz, options.world_rate_hz})
    if (!(rate >= 0.0 && rate <= 100'000.0))
      throw Error("--body-rate, --device-rate and --world-rate must be 0 (no limit) to 100000 Hz");
  if (options.world && options.export_bodies && options.mirror)
    throw Error(
        "--world with both --export and --mirror: a hub has one world, either its own or a "
        "remote one; run one bridge per direction");
  if (options.max_mirrored < 1 || options.max_mirrored > kMaxBodies)
    throw Error("--max-mirrored must be 1 to " + std::to_string(kMaxBodies) +
                " (the bodies a hub lists)");
  check_interface_name(options.interface);
}

}  // namespace afhub::bridges
