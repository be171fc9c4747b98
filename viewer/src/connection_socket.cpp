// Finds civetweb's connection sockets by their addresses (see connection_socket.hpp).
#include "connection_socket.hpp"

#include <arpa/inet.h>
#include <civetweb.h>
#include <dirent.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <cstdlib>
#include <cstring>
#include <functional>

namespace afhub::viewer {
namespace {

// The port of an IPv4 or IPv6 address, and its address as text ("127.0.0.1").
bool describe(const sockaddr_storage& address, int& port, char (&text)[INET6_ADDRSTRLEN]) {
  if (address.ss_family == AF_INET) {
    const auto& in = reinterpret_cast<const sockaddr_in&>(address);
    port = ntohs(in.sin_port);
    return inet_ntop(AF_INET, &in.sin_addr, text, sizeof text) != nullptr;
  }
  if (address.ss_family == AF_INET6) {
    const auto& in = reinterpret_cast<const sockaddr_in6&>(address);
    port = ntohs(in.sin6_port);
    return inet_ntop(AF_INET6, &in.sin6_addr, text, sizeof text) != nullptr;
  }
  return false;
}

// Calls `found(fd, peer, peer_port)` for each connection on `server_port` until it
// returns true.
void for_each_connection(int server_port, const std::function<bool(int, const char*, int)>& found) {
  DIR* descriptors = opendir("/proc/self/fd");
  if (!descriptors) return;
  while (const dirent* entry = readdir(descriptors)) {
    char* end = nullptr;
    const long number = std::strtol(entry->d_name, &end, 10);
    const int fd = static_cast<int>(number);
    if (end == entry->d_name || *end != '\0' || fd == dirfd(descriptors)) continue;
    sockaddr_storage local{}, peer{};
    socklen_t local_size = sizeof local, peer_size = sizeof peer;
    int local_port = 0, peer_port = 0;
    char local_text[INET6_ADDRSTRLEN], peer_text[INET6_ADDRSTRLEN];
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&local), &local_size) == 0 &&
        getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &peer_size) == 0 &&
        describe(local, local_port, local_text) && describe(peer, peer_port, peer_text) &&
        local_port == server_port && found(fd, peer_text, peer_port))
      break;
  }
  closedir(descriptors);
}

ino_t inode_of(int fd) {
  struct stat info {};
  return fstat(fd, &info) == 0 ? info.st_ino : 0;
}

}  // namespace

std::vector<ServerSocket> server_sockets(int server_port) {
  std::vector<ServerSocket> sockets;
  for_each_connection(server_port, [&](int fd, const char* peer, int) {
    sockets.push_back({fd, peer, inode_of(fd)});
    return false;
  });
  return sockets;
}

int connection_socket(const mg_connection* connection, int server_port) {
  const mg_request_info* request = mg_get_request_info(connection);
  if (!request) return -1;
  int found = -1;
  for_each_connection(server_port, [&](int fd, const char* peer, int peer_port) {
    if (peer_port != request->remote_port || std::strcmp(peer, request->remote_addr) != 0)
      return false;
    found = fd;
    return true;
  });
  return found;
}

void shut_down(const ServerSocket& socket) {
  // The descriptor may have been closed and reused since it was listed.
  if (inode_of(socket.fd) == socket.inode) shutdown(socket.fd, SHUT_RDWR);
}

}  // namespace afhub::viewer
