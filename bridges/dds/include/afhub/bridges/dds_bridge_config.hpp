// `afhub bridge dds --config FILE`: the bridge's settings in a YAML file, the same as
// its flags (flags given on the command line override the file). Example:
//   domain: 3
//   interface: eth1
//   export: true
//   accept-commands: true
//   bodies: ["ambf/env/*"]
//   devices: ["falcon*"]
//   world: true
//   qos: best-effort          # or reliable; states keep the last 1 either way
//   rate: 1000                # the bridge's loop
//   cpu-wake-latency: 0       # optional: idle CPUs poll while it runs
//   rate-limits: {bodies: 200, devices: 1000, world: 50}
//   max-command-age: 0.05
#pragma once

#include <string>

#include "afhub/bridges/dds_bridge.hpp"

namespace afhub::bridges {

// The settings of `path` over `defaults`. Throws afhub::Error naming the file, line
// and column, and what to write instead, on an unknown key or a bad value.
DdsBridgeOptions read_dds_bridge_config(const std::string& path,
                                        const DdsBridgeOptions& defaults = {});

// `options` in the file's format (what `afhub bridge dds --check` prints): read back,
// it gives the same settings.
std::string render_dds_bridge_config(const DdsBridgeOptions& options);

// Throws afhub::Error when `name` cannot be a network interface's name.
void check_interface_name(const std::string& name);
// Cyclone configuration binding DDS to interface `name`, after CYCLONEDDS_URI's own
// settings (peers, discovery) when it is set, whose inline interfaces it replaces.
// Throws afhub::Error when this machine has no such interface.
std::string interface_config(const std::string& name);
// The same from a given URI (tested without the environment).
std::string cyclone_config_with_interface(const std::string& uri, const std::string& name);

}  // namespace afhub::bridges
