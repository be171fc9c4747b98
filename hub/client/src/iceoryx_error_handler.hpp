// iceoryx's error handler in a process that outlives its hub (hub_loss.hpp): a fatal
// iceoryx error once the hub's memory is gone (`afhub hub stop`) is the hub's loss,
// not this process's end.
#pragma once

namespace afhub::hub_loss {

// Installs it for the rest of the process's life; call once.
void install_iceoryx_error_handler();

}  // namespace afhub::hub_loss
