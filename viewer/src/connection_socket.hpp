// The sockets of civetweb's connections. civetweb keeps them to itself, but the viewer
// needs a page's to read its WebSocket with a cap on frames (page_socket.hpp), and to
// close the connections of an address over its limit before civetweb waits on them.
// Found among this process's descriptors by their addresses.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

struct mg_connection;

namespace afhub::viewer {

// A TCP connection accepted on the server's port.
struct ServerSocket {
  int fd = -1;
  std::string peer;  // its remote address, as text ("127.0.0.1")
  ino_t inode = 0;   // the socket's: a later socket has a larger one
};

// Every connection of this process accepted on `server_port`, in no particular order.
std::vector<ServerSocket> server_sockets(int server_port);

// The descriptor of `connection` (inside a request handler, where its request info is
// known): the one socket on `server_port` whose peer is the connection's remote address
// and port. -1 when there is none.
int connection_socket(const mg_connection* connection, int server_port);

// Shuts `socket` down (both ways), if its descriptor still holds the same socket.
void shut_down(const ServerSocket& socket);

}  // namespace afhub::viewer
