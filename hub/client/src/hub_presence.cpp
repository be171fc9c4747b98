// Finding, starting and joining the hub (see hub_presence.hpp), and outliving it
// (see hub_loss.hpp).
#include "afhub/hub/hub_presence.hpp"

#include <fcntl.h>
#include <grp.h>
#include <pthread.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/header.hpp"
#include "iceoryx_hoofs/error_handling/error_handling.hpp"
#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"

namespace afhub {
namespace {

constexpr const char* kRoudiSocketPath =
    "/tmp/roudi";  // iceoryx 2.0: IOX_UDS_SOCKET_PATH_PREFIX + "roudi"
constexpr auto kAutostartTimeout = std::chrono::seconds(10);
// iceoryx 2.0's management segment: every runtime maps it read-write.
constexpr const char* kManagementSegment = "/dev/shm/iceoryx_mgmt";

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

// Starts `afhub hub` detached from this process (own session, log in `log_path`).
pid_t spawn_background_hub(const std::string& exe, const std::vector<std::string>& options,
                           const std::string& log_path) {
  pid_t pid = fork();
  if (pid < 0) throw Error(std::string("cannot start a hub: fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    setsid();
    int log = open_own_file(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
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

std::string hub_log_tail(const std::string& log_path) {
  std::ifstream in(log_path);
  std::string line, all;
  while (std::getline(in, line)) all += "  " + line + "\n";
  return all;
}

// ---- Outliving the hub (hub_loss.hpp) ----

constexpr const char* kReattachVariable = "AFHUB_REATTACH";
constexpr std::int64_t kWatchPeriodNs = 20'000'000;
constexpr std::int64_t kReattachPollNs = 10'000'000;
// A fatal iceoryx error is a lost hub only when the hub goes within this long.
constexpr std::int64_t kFatalErrorGraceNs = 3'000'000'000;

void sleep_ns(std::int64_t ns) noexcept {
  timespec pause{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  nanosleep(&pause, nullptr);
}

// What the re-exec needs, prepared when the process opts in, so that the loss path
// itself only formats one variable and calls execve.
struct LossState {
  std::string who;
  std::vector<std::string> arguments, environment;
  std::vector<char*> argv, envp;  // into the strings above; envp ends in reattach_entry
  char reattach_entry[96] = {};
  sigset_t signal_mask{};
  std::mutex hooks_mutex;
  std::vector<std::function<void()>> hooks;
};

// Never destroyed: the watcher thread may still look at it while the process exits.
LossState& loss_state() {
  static LossState* state = new LossState;
  return *state;
}

std::atomic<bool> g_armed{false};
std::atomic<bool> g_lost{false};
std::atomic<bool> g_handling{false};  // one thread handles a loss; the others wait for the exec
std::atomic<bool> g_exiting{false};   // the process is exiting on its own: never re-execute it
std::atomic<std::uint64_t> g_attached_hub{0};  // the instance of the hub attached to
std::atomic<pid_t> g_attached_hub_pid{0};
unsigned g_reattach_count = 0;  // from AFHUB_REATTACH, at the opt-in
std::uint64_t g_lost_hub = 0;   // the instance the previous image lost (0: not an afhub hub)
std::int64_t g_lost_at_ns = 0;  // when it was lost (CLOCK_MONOTONIC)

std::uint64_t hub_instance_now() noexcept {
  try {
    const std::optional<HubIdentity> hub = running_hub();
    return hub ? hub->instance : 0;
  } catch (...) {
    return 0;
  }
}

// The hub this process attached to is gone, or is going: its socket refuses, or
// another instance holds the hub lock. (A lock held by none, or unreadable for a
// moment, says nothing: a hub that died also refuses on its socket.)
bool hub_gone() noexcept {
  if (probe_roudi() != RoudiPresence::kRunning) return true;
  const std::uint64_t attached = g_attached_hub, now = hub_instance_now();
  return attached != 0 && now != 0 && now != attached;
}

std::vector<std::string> own_arguments() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> arguments;
  std::string argument;
  while (std::getline(in, argument, '\0')) arguments.push_back(argument);
  if (arguments.empty())
    throw Error(
        "cannot read this process's arguments from /proc/self/cmdline: it could not "
        "re-attach to a hub that comes back");
  return arguments;
}

[[noreturn]] void reexecute() noexcept {
  LossState& state = loss_state();
  std::snprintf(state.reattach_entry, sizeof state.reattach_entry, "%s=%u:%llu:%lld",
                kReattachVariable, g_reattach_count + 1,
                static_cast<unsigned long long>(g_attached_hub.load()),
                static_cast<long long>(monotonic_ns()));
  std::fflush(stdout);
  std::fflush(stderr);
  // Only the three standard streams go across: iceoryx's descriptors (its runtime
  // name's lock file among them) would otherwise keep their locks in the new image.
  if (close_range(3, ~0U, CLOSE_RANGE_CLOEXEC) != 0)
    for (int fd = 3; fd < 65536; ++fd) fcntl(fd, F_SETFD, FD_CLOEXEC);
  pthread_sigmask(SIG_SETMASK, &state.signal_mask, nullptr);
  execve("/proc/self/exe", state.argv.data(), state.envp.data());
  std::fprintf(stderr, "%s: cannot re-execute itself to re-attach: %s\n", state.who.c_str(),
               std::strerror(errno));
  _exit(1);
}

enum class LossHandling { kReexecuted, kOtherThread, kStopping };

// Outputs safe first, then the re-exec (unless the process is stopping anyway).
LossHandling handle_loss(const char* why) noexcept {
  if (g_handling.exchange(true)) return LossHandling::kOtherThread;
  g_lost = true;
  LossState& state = loss_state();
  char hub[32] = "";
  if (const pid_t pid = g_attached_hub_pid; pid > 0)
    std::snprintf(hub, sizeof hub, " (pid %d)", static_cast<int>(pid));
  {
    std::lock_guard<std::mutex> lock(state.hooks_mutex);
    for (const auto& hook : state.hooks) {
      try {
        hook();
      } catch (...) {
      }
    }
  }
  std::fprintf(stderr,
               "%s: the hub%s went away (%s); outputs made safe, re-attaching when a hub "
               "comes back\n",
               state.who.c_str(), hub, why);
  if (stop_requested() || g_exiting) return LossHandling::kStopping;
  reexecute();
}

// A thread that meets the loss while another one handles it waits for the exec, or,
// when the process is stopping instead, ends it.
[[noreturn]] void wait_for_reexec() noexcept {
  for (;;) {
    sleep_ns(kReattachPollNs);
    if (stop_requested() || g_exiting) _exit(0);
  }
}

void watch_hub() noexcept {
  int strikes = 0;  // two looks in a row, 20 ms apart: one failed open() is not a loss
  while (!g_lost) {
    sleep_ns(kWatchPeriodNs);
    if (g_exiting) return;
    strikes = hub_gone() ? strikes + 1 : 0;
    if (strikes < 2) continue;
    handle_loss(probe_roudi() == RoudiPresence::kRunning ? "another hub replaced it"
                                                         : "its socket no longer answers");
    return;
  }
}

// iceoryx's errors in an opted-in process. A fatal one once the hub's memory is gone
// (`afhub hub stop`) is the hub's loss, not this process's end.
void on_iceoryx_error(const iox::Error error, const std::function<void()> callback,
                      const iox::ErrorLevel level) {
  const char* name = iox::ErrorHandler::toString(error);
  const std::string& who = loss_state().who;
  if (level != iox::ErrorLevel::FATAL) {
    std::fprintf(stderr, "%s: iceoryx: %s\n", who.c_str(), name);
    if (callback) callback();
    return;
  }
  if (g_handling) wait_for_reexec();
  for (const std::int64_t give_up = monotonic_ns() + kFatalErrorGraceNs; monotonic_ns() < give_up;
       sleep_ns(kReattachPollNs)) {
    if (!hub_gone()) continue;
    char why[160];
    std::snprintf(why, sizeof why, "iceoryx: %s", name);
    if (handle_loss(why) == LossHandling::kStopping) _exit(0);
    wait_for_reexec();
  }
  std::fprintf(stderr, "%s: fatal iceoryx error %s, with the hub still up\n", who.c_str(), name);
  if (callback) callback();
  std::abort();
}

std::string group_name(gid_t gid) {
  if (const group* entry = getgrgid(gid)) return entry->gr_name;
  return "gid " + std::to_string(gid);
}

// Before iceoryx's runtime connects: it would wait on whatever answers at /tmp/roudi
// (a socket another user planted there hangs it), and abort on shared memory it may
// not open. The socket must belong to the user of the afhub hub that holds its lock,
// and this user must be let into the hub's shared memory.
void require_hub_access() {
  const std::optional<HubIdentity> hub = running_hub();
  struct stat socket_info {};
  const bool socket = lstat(kRoudiSocketPath, &socket_info) == 0 && S_ISSOCK(socket_info.st_mode);
  struct stat identity {};
  if (!hub || hub->instance == 0 ||
      stat(hub_identity_path(hub_directory()).c_str(), &identity) != 0)
    throw Error(std::string("something answers at ") + kRoudiSocketPath +
                " but no afhub hub holds its lock in " + hub_directory() +
                ": a plain iceoryx RouDi (iox-roudi), or a socket left or planted there" +
                (socket ? " (it belongs to uid " + std::to_string(socket_info.st_uid) + ")" : "") +
                ". Stop it or remove it (as its owner or root), then start `afhub hub`.");
  if (!socket || socket_info.st_uid != identity.st_uid)
    throw Error(std::string(kRoudiSocketPath) + " belongs to uid " +
                std::to_string(socket_info.st_uid) + ", not to the hub's user (uid " +
                std::to_string(identity.st_uid) +
                "): another user planted it. Remove it as root, and restart the hub.");
  // iceoryx would wait forever on a socket it may not write to.
  for (const char* path : {kManagementSegment, kRoudiSocketPath}) {
    struct stat info {};
    if (access(path, R_OK | W_OK) != 0 && errno == EACCES && stat(path, &info) == 0)
      throw Error("permission denied on " + std::string(path) + ": the hub (uid " +
                  std::to_string(info.st_uid) + ") lets only the group '" +
                  group_name(info.st_gid) + "' use it. Join that group (`sudo usermod -aG " +
                  group_name(info.st_gid) +
                  " $USER`, then log in again), or have the hub started with `afhub hub --group "
                  "GROUP` for a group of yours.");
  }
}

// After a re-exec: waits for a hub other than the one lost, never starting one.
void wait_for_new_hub(const std::string& who) {
  std::fprintf(stderr, "%s: waiting for a hub to re-attach to\n", who.c_str());
  for (;;) {
    if (stop_requested()) {
      std::fprintf(stderr, "%s: stopped while waiting for a hub\n", who.c_str());
      std::exit(0);
    }
    const std::uint64_t before = hub_instance_now();
    if (before != 0 && before != g_lost_hub && probe_roudi() == RoudiPresence::kRunning &&
        hub_instance_now() == before)
      return;
    sleep_ns(kReattachPollNs);
  }
}

}  // namespace

RoudiPresence probe_roudi() noexcept {
  int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return RoudiPresence::kRunning;  // out of descriptors: nothing known of RouDi
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, kRoudiSocketPath, sizeof address.sun_path - 1);
  int rc = connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  const int error = errno;
  close(fd);
  // Only "no socket" and "nobody listens" say that no RouDi runs. EACCES: a hub runs,
  // but this user may not use it (connect_to_hub says so); any other error says nothing.
  return rc != 0 && (error == ENOENT || error == ECONNREFUSED) ? RoudiPresence::kAbsent
                                                               : RoudiPresence::kRunning;
}

std::optional<HubIdentity> running_hub() {
  const std::string directory = hub_directory();
  const std::string lock = hub_lock_path(directory);
  if (!flock_held(lock)) return std::nullopt;
  HubIdentity hub;
  hub.pid = flock_holder(lock).value_or(0);
  // Written by the hub after it took the lock: until then, a held lock with no
  // instance is a hub starting up, not yet one to attach to.
  const int fd = open_own_file(hub_identity_path(directory), O_RDONLY);
  if (fd >= 0) {
    char text[64] = {};
    if (read(fd, text, sizeof text - 1) > 0) {
      unsigned long long instance = 0;
      int pid = 0;
      if (std::sscanf(text, "%d %llu", &pid, &instance) == 2) hub.instance = instance;
    }
    close(fd);
  }
  return hub;
}

std::optional<pid_t> running_hub_pid() {
  const std::optional<HubIdentity> hub = running_hub();
  if (!hub) return std::nullopt;
  return hub->pid;
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
  const std::string log_path = hub_log_path(own_hub_directory());
  spawn_background_hub(exe, hub_options, log_path);
  auto deadline = std::chrono::steady_clock::now() + kAutostartTimeout;
  while (probe_roudi() != RoudiPresence::kRunning) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error("started a hub (" + exe + " hub) but it did not come up within " +
                  std::to_string(kAutostartTimeout.count()) + " s; its log " + log_path +
                  " says:\n" + hub_log_tail(log_path));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  auto pid = running_hub_pid();
  std::fprintf(stderr,
               "afhub: no hub was running; started one in the background (pid %d, log %s). "
               "Stop it with `afhub hub stop`.\n",
               pid ? static_cast<int>(*pid) : -1, log_path.c_str());
}

void connect_to_hub(const std::string& role, HubPolicy policy, std::chrono::milliseconds wait,
                    const std::vector<std::string>& hub_options) {
  if (!runtime_name_storage().empty()) return;
  const bool reattaching = g_armed && g_reattach_count > 0;
  std::int64_t hub_seen_ns = 0;
  if (reattaching) {
    wait_for_new_hub(loss_state().who);
    hub_seen_ns = monotonic_ns();
  } else {
    ensure_hub(policy, wait, "afhub " + role, hub_options);
  }
  quiet_iceoryx_logs();
  std::string name = "afhub-" + role + "-" + std::to_string(getpid());
  if (name.size() > 100) throw Error("process role '" + role + "' is too long for iceoryx");
  // The image before the re-exec had this name too: its socket is ours to remove
  // (iceoryx would, with a warning).
  if (reattaching) unlink(("/tmp/" + name).c_str());
  require_hub_access();
  claim_runtime_lock_file("/tmp/" + name + ".lock");
  {
    const StopEndsBlockingCall stoppable;
    iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name));
  }
  runtime_name_storage() = name;
  count_ports_from(free_ports(std::chrono::milliseconds(500)));
  if (!g_armed) return;
  // Registered after the runtime, so that it runs before the runtime's destructor.
  std::atexit([] { g_exiting = true; });
  if (const std::optional<HubIdentity> hub = running_hub()) {
    g_attached_hub = hub->instance;
    g_attached_hub_pid = hub->pid;
  }
  if (reattaching)
    std::fprintf(stderr,
                 "%s: re-attached to the hub (pid %d), %.0f ms after it answered and %.2f s after "
                 "the last one was lost\n",
                 loss_state().who.c_str(), static_cast<int>(g_attached_hub_pid),
                 static_cast<double>(monotonic_ns() - hub_seen_ns) * 1e-6,
                 static_cast<double>(monotonic_ns() - g_lost_at_ns) * 1e-9);
  std::thread(watch_hub).detach();
}

void survive_hub_loss(const std::string& who) {
  if (g_armed) return;
  LossState& state = loss_state();
  state.who = who;
  state.arguments = own_arguments();
  if (const char* value = std::getenv(kReattachVariable)) {
    unsigned count = 0;
    unsigned long long lost_hub = 0;
    long long lost_at = 0;
    if (std::sscanf(value, "%u:%llu:%lld", &count, &lost_hub, &lost_at) == 3) {
      g_reattach_count = count;
      g_lost_hub = lost_hub;
      g_lost_at_ns = lost_at;
    }
    unsetenv(kReattachVariable);
  }
  for (char** entry = environ; *entry; ++entry) state.environment.emplace_back(*entry);
  for (std::string& argument : state.arguments) state.argv.push_back(argument.data());
  state.argv.push_back(nullptr);
  for (std::string& entry : state.environment) state.envp.push_back(entry.data());
  state.envp.push_back(state.reattach_entry);
  state.envp.push_back(nullptr);
  pthread_sigmask(SIG_SETMASK, nullptr, &state.signal_mask);
  static iox::cxx::GenericRAII handler = iox::ErrorHandler::setTemporaryErrorHandler(
      [](const iox::Error error, const std::function<void()> callback,
         const iox::ErrorLevel level) { on_iceoryx_error(error, callback, level); });
  g_armed = true;
}

void on_hub_lost(std::function<void()> make_safe) {
  LossState& state = loss_state();
  std::lock_guard<std::mutex> lock(state.hooks_mutex);
  state.hooks.push_back(std::move(make_safe));
}

bool hub_lost() noexcept {
  return g_lost.load(std::memory_order_relaxed);
}

unsigned reattach_count() noexcept {
  return g_reattach_count;
}

void quiet_iceoryx_logs() {
  iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kWarn,
                                                           iox::log::LogLevelOutput::kHideLogLevel);
}

const std::string& runtime_name() {
  return runtime_name_storage();
}

}  // namespace afhub
