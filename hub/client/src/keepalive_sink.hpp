// A process that carries on after its hub is lost (notice_hub_loss: a Python
// interpreter) keeps its iceoryx runtime, whose thread sends a keep-alive to the dead
// hub's socket every few hundred milliseconds and prints two lines of errors for each
// (measured: 20 lines in 6.5 s, for as long as the process lives).
#pragma once

namespace afhub::hub_loss {

// This process's socket to RouDi, once registered; -1 when none is found.
int find_roudi_socket() noexcept;

// Points `roudi_fd` at a socket of this process's own, drained by a thread: the
// keep-alives end there, quietly. Nothing when it cannot.
void sink_keepalives(int roudi_fd) noexcept;

}  // namespace afhub::hub_loss
