// Finding, starting and joining the hub (see hub_presence.hpp).
#include "afhub/hub/hub_presence.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string_view>
#include <thread>
#include <vector>

#include "afhub/hub/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"

namespace afhub {
namespace {

constexpr const char* kRoudiSocketPath =
    "/tmp/roudi";  // iceoryx 2.0: IOX_UDS_SOCKET_PATH_PREFIX + "roudi"
constexpr const char* kHubLogPath = "/tmp/afhub-hub.log";
constexpr auto kAutostartTimeout = std::chrono::seconds(10);

std::string& runtime_name_storage() {
  static std::string name;
  return name;
}

// The afhub executable to start a hub with: $AFHUB_EXECUTABLE, else an `afhub`
// beside this program, else the first on $PATH. Never a path fixed at build time:
// the build tree may be gone, and an install may have been moved.
std::string afhub_executable() {
  if (const char* env = std::getenv("AFHUB_EXECUTABLE"); env && *env) return env;
  std::vector<std::string> candidates;
  char self[4096];
  if (const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1); n > 0) {
    std::string dir(self, static_cast<std::size_t>(n));
    candidates.push_back(dir.substr(0, dir.rfind('/') + 1) + "afhub");
  }
  if (const char* path = std::getenv("PATH")) {
    std::string_view rest(path);
    while (!rest.empty()) {
      const auto colon = rest.find(':');
      const std::string_view dir = rest.substr(0, colon);
      if (!dir.empty()) candidates.push_back(std::string(dir) + "/afhub");
      rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
    }
  }
  for (const std::string& candidate : candidates)
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  throw Error(
      "no hub is running, and no `afhub` executable was found to start one (looked beside this "
      "program and on PATH). Start a hub with `afhub hub`, put afhub on PATH, or set "
      "AFHUB_EXECUTABLE to its path.");
}

// Starts `afhub hub` detached from this process (own session, log in /tmp).
pid_t spawn_background_hub(const std::string& exe, const std::vector<std::string>& options) {
  pid_t pid = fork();
  if (pid < 0) throw Error(std::string("cannot start a hub: fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    setsid();
    int log = open(kHubLogPath, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    int null_in = open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (log >= 0) {
      dup2(log, STDOUT_FILENO);
      dup2(log, STDERR_FILENO);
    }
    if (null_in >= 0) dup2(null_in, STDIN_FILENO);
    // A second fork so that the hub is not our child and outlives us cleanly.
    if (fork() != 0) _exit(0);
    std::vector<const char*> argv{exe.c_str(), "hub"};
    for (const std::string& option : options) argv.push_back(option.c_str());
    argv.push_back(nullptr);
    execv(exe.c_str(), const_cast<char* const*>(argv.data()));
    std::fprintf(stderr, "afhub: cannot run %s: %s\n", exe.c_str(), std::strerror(errno));
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return pid;
}

std::string hub_log_tail() {
  std::ifstream in(kHubLogPath);
  std::string line, all;
  while (std::getline(in, line)) all += "  " + line + "\n";
  return all;
}

}  // namespace

RoudiPresence probe_roudi() noexcept {
  int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return RoudiPresence::kAbsent;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, kRoudiSocketPath, sizeof address.sun_path - 1);
  int rc = connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  close(fd);
  return rc == 0 ? RoudiPresence::kRunning : RoudiPresence::kAbsent;
}

// Not "<runtime name>.lock": iceoryx locks /tmp/<runtime name>.lock for each process.
std::string hub_lock_path() {
  return "/tmp/afhub.lock";
}

std::optional<pid_t> running_hub_pid() {
  int fd = open(hub_lock_path().c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::optional<pid_t> pid;
  if (flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK) {
    char buffer[32] = {};
    ssize_t n = read(fd, buffer, sizeof buffer - 1);
    pid = n > 0 ? static_cast<pid_t>(std::atol(buffer)) : 0;
  }
  close(fd);
  return pid;
}

void ensure_hub(HubPolicy policy, std::chrono::milliseconds wait, const std::string& who,
                const std::vector<std::string>& hub_options) {
  if (probe_roudi() == RoudiPresence::kRunning) return;
  if (policy == HubPolicy::kRequire && wait.count() > 0) {
    // Probing the socket, never iceoryx: its runtime would wait 60 s, then abort.
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%g", static_cast<double>(wait.count()) * 1e-3);
    std::fprintf(stderr, "%s: no hub is running yet; waiting up to %s s for one\n", who.c_str(),
                 seconds);
    const auto deadline = std::chrono::steady_clock::now() + wait;
    while (probe_roudi() != RoudiPresence::kRunning) {
      if (stop_requested()) throw Error("stopped while waiting for a hub");
      if (std::chrono::steady_clock::now() > deadline)
        throw Error("no hub came up within " + std::string(seconds) +
                    " s. Start one with `afhub hub` (foreground), or `afhub run MODEL`, which "
                    "starts one in the background; or wait longer (--wait)");
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return;
  }
  if (policy == HubPolicy::kRequire)
    throw Error(
        "no hub is running. Start one with `afhub hub` (foreground) or let `afhub run` start one "
        "in the background.");
  std::string exe = afhub_executable();
  spawn_background_hub(exe, hub_options);
  auto deadline = std::chrono::steady_clock::now() + kAutostartTimeout;
  while (probe_roudi() != RoudiPresence::kRunning) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("started a hub (" + exe + " hub) but it did not come up within " +
                  std::to_string(kAutostartTimeout.count()) + " s; its log " + kHubLogPath +
                  " says:\n" + hub_log_tail());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  auto pid = running_hub_pid();
  std::fprintf(stderr,
               "afhub: no hub was running; started one in the background (pid %d, log %s). "
               "Stop it with `afhub hub stop`.\n",
               pid ? static_cast<int>(*pid) : -1, kHubLogPath);
}

void connect_to_hub(const std::string& role, HubPolicy policy, std::chrono::milliseconds wait,
                    const std::vector<std::string>& hub_options) {
  if (!runtime_name_storage().empty()) return;
  ensure_hub(policy, wait, "afhub " + role, hub_options);
  quiet_iceoryx_logs();
  std::string name = "afhub-" + role + "-" + std::to_string(getpid());
  if (name.size() > 100) throw Error("process role '" + role + "' is too long for iceoryx");
  iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name));
  runtime_name_storage() = name;
}

void quiet_iceoryx_logs() {
  iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kWarn,
                                                           iox::log::LogLevelOutput::kHideLogLevel);
}

const std::string& runtime_name() {
  return runtime_name_storage();
}

}  // namespace afhub
