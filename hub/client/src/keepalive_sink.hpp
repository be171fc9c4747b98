// A process that carries on after its hub is lost (notice_hub_loss: a Python
// interpreter) keeps its iceoryx runtime, whose thread sends a keep-alive to the dead
// hub's socket every few hundred milliseconds and prints two lines of errors for each
// (measured: 45 lines in 6.5 s, for as long as the process lives).
#pragma once

#include <sys/types.h>

namespace afhub::hub_loss {

// This process's socket to RouDi, once registered.
struct RoudiSocket {
  int fd = -1;      // -1: none found
  ino_t inode = 0;  // checked again before use: the number may name another file by then
};
RoudiSocket find_roudi_socket() noexcept;

// Points the socket at one of this process's own, read by a thread that drops the
// keep-alives and answers anything else (a request racing with the loss, the
// runtime's farewell at exit), so that no call waits for good for a hub that is gone.
// Nothing when it cannot.
void sink_keepalives(RoudiSocket roudi, const char* runtime_name) noexcept;

}  // namespace afhub::hub_loss
