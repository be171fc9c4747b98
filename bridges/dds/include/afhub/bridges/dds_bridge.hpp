// `afhub bridge dds`: the hub's bodies over Cyclone DDS (afhub's own IDL types).
//   Export: the states of local bodies matching a glob become DDS samples of topic
//   "afhub/body_state" (keyed by channel name), their joint names "afhub/body_info";
//   with accept_commands, "afhub/body_command" samples go into local command slots.
//   Devices (--devices) and the world (--world) cross the same way: dds_device_world.hpp.
//   Mirror: bodies seen on DDS are published into this hub as if local (at most
//   max_mirrored), and the commands written to them here go back out over DDS.
// Like every afhub process, the bridge outlives its hub and re-attaches to the next
// (afhub/hub/hub_loss.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace afhub::bridges {

struct DdsBridgeOptions {
  std::uint32_t domain = 0;
  std::string interface;  // bind DDS to this network interface (empty: Cyclone's choice)
  std::vector<std::string> body_globs{"*"};  // fnmatch patterns over channel names
  std::vector<std::string> device_globs;     // over device names (device/<name>); none
  bool world = false;                        // the world's state out, its commands in
  bool export_bodies = false;
  bool mirror = false;
  bool accept_commands = false;
  // Accept commands without security_dir: any host on the domain may command this hub.
  // Refused unless asked for by name (--insecure-accept-commands), and said in each status.
  bool insecure_accept_commands = false;
  double rate_hz = 1000.0;  // the bridge's loop: each body at most once per cycle
  // Poll for local states and commands (sched_yield between polls) instead of sleeping
  // until one comes: no wake-up on the way out, for a bridge given a core of its own
  // (it takes that core's CPU time, left to any other runnable thread on each poll).
  bool spin = false;
  // Hold idle CPUs to wake within this many microseconds while the bridge runs
  // (rt/cpu_wake_latency.hpp; 0: they poll, the lowest latency); -1: leave them.
  int cpu_wake_latency_us = -1;
  // Per-topic rate limits of exported states, in Hz (0: every new state, at most once
  // per cycle): newest wins, the states in between are not sent.
  double body_rate_hz = 0.0, device_rate_hz = 0.0, world_rate_hz = 0.0;
  bool reliable = false;            // default best effort, keep last 1
  double max_command_age_s = 0.05;  // older (by DDS source timestamp): dropped
  // Report the age of mirrored states by their source's CLOCK_MONOTONIC stamp: only
  // meaningful where both sides share that clock (namespaces on one host).
  bool latency = false;
  double seconds = 0.0;  // 0: until SIGINT/SIGTERM
  // "ros2": exported bodies also as ROS 2 topics rt/<ros2_prefix>/<channel>/... (see
  // bridges/dds/src/ros2_profile.hpp), joint commands in with accept_commands.
  std::string profile;
  std::string ros2_prefix;
  // DDS Security credentials (see bridges/dds/src/dds_security.hpp); empty: none.
  std::string security_dir;
  // Bodies and devices mirrored at most: leaves the rest of a hub's 4096 for its own,
  // whatever a peer announces.
  std::size_t max_mirrored = 225;
};

// Throws afhub::Error naming the option when a value is out of range.
void check_dds_bridge_options(const DdsBridgeOptions& options);

// Throws afhub::Error on bad options or when DDS cannot start; returns the exit code.
int run_dds_bridge(const DdsBridgeOptions& options);

}  // namespace afhub::bridges
