// Is a hub running, and which (hub_presence.hpp): answered from RouDi's socket and
// the hub's lock and identity files, never through iceoryx.
#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "roudi_socket.hpp"

namespace afhub {

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
      unsigned long long instance = 0, pid_namespace = 0;
      int pid = 0;
      const int fields = std::sscanf(text, "%d %llu %llu", &pid, &instance, &pid_namespace);
      if (fields >= 2) hub.instance = instance;
      if (fields == 3) hub.pid_namespace = pid_namespace;
    }
    close(fd);
  }
  return hub;
}

std::uint64_t own_pid_namespace() noexcept {
  struct stat info {};
  return stat("/proc/self/ns/pid", &info) == 0 ? info.st_ino : 0;
}

std::optional<pid_t> running_hub_pid() {
  const std::optional<HubIdentity> hub = running_hub();
  if (!hub) return std::nullopt;
  return hub->pid;
}

}  // namespace afhub
