// iceoryx runtimes' files in /tmp (see runtime_files.hpp).
#include "runtime_files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "afhub/hub/hub_files.hpp"
#include "liveness.hpp"

namespace afhub {
namespace {

namespace fs = std::filesystem;

// iceoryx 2.0's folder for runtime sockets and locks (IOX_UDS_SOCKET_PATH_PREFIX).
const fs::path kRuntimeDir = "/tmp";
constexpr auto kStartupGrace = std::chrono::seconds(2);

// An afhub client's runtime: "afhub-<role>-<pid>" (connect_to_hub). Other programs'
// files in /tmp, RouDi's and the hub's own are never touched.
bool is_client_lock(const std::string& name) {
  return name.rfind("afhub-", 0) == 0 && name != "afhub-hub";
}

pid_t pid_suffix(const std::string& name) {
  const auto dash = name.rfind('-');
  if (dash == std::string::npos || dash + 1 == name.size()) return 0;
  pid_t pid = 0;
  for (std::size_t i = dash + 1; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return 0;
    pid = pid * 10 + (name[i] - '0');
  }
  return pid;
}

enum class LockState { kHeld, kFree, kUnreadable };

// Whether a live process holds the lock at `path`. When it is free and `remove`,
// the lock and the socket beside it are removed while this process holds the lock.
LockState probe_lock(const fs::path& path, bool remove) {
  const int fd = open_regular_file(path.string());
  if (fd < 0) return LockState::kUnreadable;
  LockState state = LockState::kHeld;
  if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
    state = LockState::kFree;
    if (remove) {
      std::error_code ignored;
      fs::remove(fs::path(path).replace_extension(""), ignored);
      fs::remove(path, ignored);
    }
  }
  close(fd);
  return state;
}

// The client runtimes' lock files: (name, path).
std::vector<std::pair<std::string, fs::path>> client_locks() {
  std::vector<std::pair<std::string, fs::path>> locks;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(kRuntimeDir, error)) {
    const fs::path& path = entry.path();
    if (path.extension() != ".lock" || !entry.is_regular_file(error)) continue;
    const std::string name = path.stem().string();
    if (is_client_lock(name)) locks.emplace_back(name, path);
  }
  std::sort(locks.begin(), locks.end());
  return locks;
}

}  // namespace

std::vector<AttachedProcess> attached_processes() {
  std::vector<AttachedProcess> attached;
  for (const auto& [name, path] : client_locks())
    if (probe_lock(path, false) == LockState::kHeld)
      attached.push_back({name, flock_holder(path).value_or(0)});
  return attached;
}

bool runtime_is_gone(const std::string& name, pid_t pid) {
  const fs::path lock = kRuntimeDir / (name + ".lock");
  // A lock file removed from under a live process (a tmp cleaner, an `rm`) says nothing
  // of the process: the pid RouDi registered does.
  std::error_code error;
  if (!fs::exists(fs::symlink_status(lock, error))) return pid > 0 && task_is_gone(pid);
  return !flock_held(lock.string());
}

bool runtime_in_hub_pid_namespace(const std::string& name, pid_t pid) {
  const std::string lock = (kRuntimeDir / (name + ".lock")).string();
  if (const std::optional<pid_t> holder = flock_holder(lock)) return *holder == pid;
  // Unlisted: held by a process this namespace cannot see, or just released (the
  // process is exiting, and is gone at the next look).
  return !flock_held(lock);
}

bool client_in_hub_pid_namespace(const std::string& name) {
  const pid_t pid = is_client_lock(name) ? pid_suffix(name) : 0;
  if (pid <= 0) return false;
  const std::optional<pid_t> holder = flock_holder((kRuntimeDir / (name + ".lock")).string());
  return holder && *holder == pid;
}

std::vector<std::string> remove_stale_runtime_files() {
  std::vector<std::string> removed;
  const auto now = fs::file_time_type::clock::now();
  for (const auto& [name, path] : client_locks()) {
    std::error_code error;
    const auto written = fs::last_write_time(path, error);
    if (error || now - written < kStartupGrace) continue;
    // Only a process that is gone: one that re-executed itself to re-attach keeps
    // its name, and its old lock, free until its runtime starts again. (A pid from
    // another pid namespace may name a live process here: its files then stay.)
    const pid_t pid = pid_suffix(name);
    if (pid <= 0 || !task_is_gone(pid)) continue;
    if (probe_lock(path, true) == LockState::kFree) removed.push_back(name);
  }
  return removed;
}

}  // namespace afhub
