// Keep-alives to a lost hub sent nowhere (see keepalive_sink.hpp).
#include "keepalive_sink.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "hub_loss_state.hpp"
#include "roudi_socket.hpp"

namespace afhub::hub_loss {
namespace {

// At exit the runtime says goodbye to RouDi and waits for its answer: sent into the
// sink, it would wait for good. An unconnected socket fails the send at once, as the
// dead hub's did.
void unsink_at_exit() {
  const int fd = state().roudi_fd;
  const int unconnected = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (unconnected < 0) return;
  dup3(unconnected, fd, O_CLOEXEC);
  close(unconnected);
}

}  // namespace

int find_roudi_socket() noexcept {
  DIR* fds = opendir("/proc/self/fd");
  if (!fds) return -1;
  int found = -1;
  while (const dirent* entry = readdir(fds)) {
    const int fd = std::atoi(entry->d_name);
    sockaddr_un peer{};
    socklen_t size = sizeof peer;
    if (entry->d_name[0] < '0' || entry->d_name[0] > '9' || fd == dirfd(fds) ||
        getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &size) != 0 ||
        peer.sun_family != AF_UNIX || std::strcmp(peer.sun_path, kRoudiSocketPath) != 0)
      continue;
    found = fd;
    break;
  }
  closedir(fds);
  return found;
}

void sink_keepalives(int roudi_fd) noexcept {
  int pair[2];
  if (roudi_fd < 0 || socketpair(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0, pair) != 0) return;
  try {
    std::thread([drain = pair[1]] {
      char message[512];
      while (recv(drain, message, sizeof message, 0) >= 0 || errno == EINTR) {
      }
    }).detach();
  } catch (...) {  // no thread: its queue would fill, and the sends fail again
    close(pair[0]);
    close(pair[1]);
    return;
  }
  if (dup3(pair[0], roudi_fd, O_CLOEXEC) >= 0) std::atexit(unsink_at_exit);
  close(pair[0]);
}

}  // namespace afhub::hub_loss
