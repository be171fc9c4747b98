// Joining the hub (connect_to_hub, hub_presence.hpp): this process's iceoryx runtime.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>

#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/header.hpp"
#include "hub_access.hpp"
#include "hub_reattach.hpp"
#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"
#include "iceoryx_stderr_filter.hpp"
#include "registration_guard.hpp"

namespace afhub {
namespace {

// Whether the hub, when this process sees its pid, is stopped (SIGSTOP, a debugger).
std::optional<pid_t> stopped_hub() {
  const std::optional<pid_t> pid = running_hub_pid();
  if (!pid || *pid <= 0 || !process_stopped(static_cast<std::uint32_t>(*pid))) return std::nullopt;
  return pid;
}

// A stopped hub does not answer registration: iceoryx waited 60 s for it, then aborted.
// Waited for up to `wait` instead (a stop signal ends the wait and the process, exit
// 0), then refused naming it.
void wait_while_hub_stopped(const std::string& who, std::chrono::milliseconds wait) {
  const StopEndsBlockingCall stoppable;
  const std::int64_t give_up = monotonic_ns() + static_cast<std::int64_t>(wait.count()) * 1'000'000;
  for (bool said = false; const std::optional<pid_t> pid = stopped_hub();) {
    const std::string hub = "the hub (pid " + std::to_string(*pid) +
                            ") is stopped (SIGSTOP, or a "
                            "debugger holds it), so it cannot register this process";
    if (monotonic_ns() >= give_up)
      throw Error(hub + ": let it run on (`kill -CONT " + std::to_string(*pid) +
                  "`) and try again");
    if (!said)
      std::fprintf(stderr, "%s: %s; waiting up to %.3g s for it to run on\n", who.c_str(),
                   hub.c_str(), static_cast<double>(wait.count()) * 1e-3);
    said = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::string& runtime_name_storage() {
  static std::string name;
  return name;
}

}  // namespace

void connect_to_hub(const std::string& role, HubPolicy policy, std::chrono::milliseconds wait,
                    const std::vector<std::string>& hub_options) {
  if (!runtime_name_storage().empty()) return;
  const bool reattaching = hub_loss::reattaching();
  std::int64_t hub_seen_ns = 0;
  if (reattaching) {
    hub_loss::wait_for_new_hub();
    hub_seen_ns = monotonic_ns();
  } else {
    ensure_hub(policy, wait, "afhub " + role, hub_options);
  }
  quiet_iceoryx_logs();
  filter_iceoryx_stderr("afhub " + role);
  // A pid is unique only in its pid namespace: a process in another than the hub's (a
  // container's pid 1 beside another's) names its namespace too (iceoryx refused the
  // second of two same names).
  const std::optional<HubIdentity> hub = running_hub();
  const std::uint64_t pid_namespace = own_pid_namespace();
  const bool elsewhere = hub && hub->pid_namespace != 0 && pid_namespace != hub->pid_namespace;
  const std::string name = "afhub-" + role + "-" +
                           (elsewhere ? "ns" + std::to_string(pid_namespace) + "-" : "") +
                           std::to_string(getpid());
  if (name.size() > 100) throw Error("process role '" + role + "' is too long for iceoryx");
  // The image before the re-exec had this name too: its socket is ours to remove
  // (iceoryx would, with a warning).
  if (reattaching) unlink(("/tmp/" + name).c_str());
  require_hub_access();
  if (!reattaching) wait_while_hub_stopped("afhub " + role, wait);
  claim_runtime_lock_file("/tmp/" + name + ".lock");
  {
    const StopEndsBlockingCall stoppable;
    // Past the first port too: a hub killed between the registration and it left the
    // port's request to RouDi waiting for good, deaf to Ctrl-C (a fault-injection run:
    // hubs killed and restarted 30 to 110 ms apart, 1 round in 14).
    const RegistrationGuard guard("afhub " + role);
    iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name));
    runtime_name_storage() = name;
    count_ports_from(free_ports(std::chrono::milliseconds(500)));
  }
  hub_loss::watch_attached_hub(hub_seen_ns);
}

// Fatal messages only: iceoryx logs an error at each failed loan ("unable to acquire a
// chunk"), each step of a loop out of chunks; its errors reach on_iceoryx_error, which
// says each kind once (a full pool's own line, and those of a hub gone, written to
// std::cerr: filter_iceoryx_stderr).
void quiet_iceoryx_logs() {
  iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kFatal,
                                                           iox::log::LogLevelOutput::kHideLogLevel);
}

const std::string& runtime_name() {
  return runtime_name_storage();
}

}  // namespace afhub
