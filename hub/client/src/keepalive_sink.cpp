// Keep-alives to a lost hub sent nowhere (see keepalive_sink.hpp).
#include "keepalive_sink.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "roudi_socket.hpp"

namespace afhub::hub_loss {
namespace {

// iceoryx 2.0.3's IpcMessageType (ipc_interface_base.hpp): a message starts "<type>,".
constexpr const char* kKeepalive = "17,";
// TERMINATION_ACK: the farewell's own answer; to any other request, a wrong one, which
// iceoryx takes as an error rather than waiting on.
constexpr const char* kAnswer = "19,";

ino_t inode_of(int fd) noexcept {
  struct stat info {};
  return fstat(fd, &info) == 0 ? info.st_ino : 0;
}

void drain(int sink, sockaddr_un runtime) noexcept {
  const int answers = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  char message[1024];
  for (;;) {
    const ssize_t size = recv(sink, message, sizeof message, 0);
    if (size < 0 && errno == EINTR) continue;
    if (size < 0) return;
    if (static_cast<std::size_t>(size) >= std::strlen(kKeepalive) &&
        std::memcmp(message, kKeepalive, std::strlen(kKeepalive)) == 0)
      continue;
    sendto(answers, kAnswer, std::strlen(kAnswer) + 1, 0, reinterpret_cast<sockaddr*>(&runtime),
           sizeof runtime);
  }
}

}  // namespace

RoudiSocket find_roudi_socket() noexcept {
  DIR* fds = opendir("/proc/self/fd");
  if (!fds) return {};
  RoudiSocket found;
  while (const dirent* entry = readdir(fds)) {
    const int fd = std::atoi(entry->d_name);
    sockaddr_un peer{};
    socklen_t size = sizeof peer;
    if (entry->d_name[0] < '0' || entry->d_name[0] > '9' || fd == dirfd(fds) ||
        getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &size) != 0 ||
        peer.sun_family != AF_UNIX || std::strcmp(peer.sun_path, kRoudiSocketPath) != 0)
      continue;
    found = {fd, inode_of(fd)};
    break;
  }
  closedir(fds);
  return found;
}

void sink_keepalives(RoudiSocket roudi, const char* runtime_name) noexcept {
  // Still the socket found at attach time, not a file that took its number since.
  if (roudi.fd < 0 || roudi.inode == 0 || inode_of(roudi.fd) != roudi.inode) return;
  sockaddr_un runtime{};  // where iceoryx's runtime receives its answers: /tmp/<name>
  runtime.sun_family = AF_UNIX;
  if (std::snprintf(runtime.sun_path, sizeof runtime.sun_path, "/tmp/%s", runtime_name) >=
      static_cast<int>(sizeof runtime.sun_path))
    return;
  int pair[2];
  if (socketpair(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0, pair) != 0) return;
  try {
    std::thread(drain, pair[1], runtime).detach();
  } catch (...) {  // no thread: the queue would fill, and the sends fail again
    close(pair[0]);
    close(pair[1]);
    return;
  }
  dup3(pair[0], roudi.fd, O_CLOEXEC);
  close(pair[0]);
}

}  // namespace afhub::hub_loss
