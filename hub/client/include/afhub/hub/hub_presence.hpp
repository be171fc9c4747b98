// Is a hub running? Answered without touching iceoryx, whose runtime would wait
// 60 s for a missing RouDi and then abort the process.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace afhub {

enum class RoudiPresence { kAbsent, kRunning };

// Probes RouDi's Unix socket (/tmp/roudi): ENOENT or ECONNREFUSED mean no RouDi.
RoudiPresence probe_roudi() noexcept;

// A running hub: its pid here (0 when it runs in a pid namespace this process cannot
// see), the random instance number it drew at start, which tells one hub from the
// next even when pids repeat across pid namespaces, and its pid namespace (0: not said).
struct HubIdentity {
  pid_t pid = 0;
  std::uint64_t instance = 0;
  std::uint64_t pid_namespace = 0;
};

// This process's pid namespace (the inode of /proc/self/ns/pid), 0 if unreadable.
std::uint64_t own_pid_namespace() noexcept;

// The running afhub hub, if one holds the lock in hub_directory() (hub_files.hpp).
std::optional<HubIdentity> running_hub();
std::optional<pid_t> running_hub_pid();

// How a process that needs a hub gets one.
enum class HubPolicy {
  kAutostart,  // start a hub in the background when none runs, and say so on stderr
  kRequire,    // fail with a message when none runs
};

// Makes sure a hub is reachable under `policy`; throws afhub::Error otherwise.
// With kRequire and a `wait`, a process started together with the hub waits up to
// `wait` for it to come up, saying so once on stderr as `who` ("afhub ctl"). With
// kAutostart, a hub started here gets `hub_options` (e.g. {"--bench-pools"}).
void ensure_hub(HubPolicy policy, std::chrono::milliseconds wait = std::chrono::milliseconds(0),
                const std::string& who = "afhub", const std::vector<std::string>& hub_options = {});

// Registers this process with the hub under "afhub-<role>-<pid>", after ensure_hub()
// (with `wait` and `hub_options`, as there). Call once per process, before opening
// any channel.
void connect_to_hub(const std::string& role, HubPolicy policy,
                    std::chrono::milliseconds wait = std::chrono::milliseconds(0),
                    const std::vector<std::string>& hub_options = {});

// iceoryx logs warnings and errors only (its default is verbose).
void quiet_iceoryx_logs();

// This process's iceoryx runtime name (empty before connect_to_hub).
const std::string& runtime_name();

}  // namespace afhub
