// The thread that notices a hub lost without any iceoryx call failing (a hub SIGKILLed
// or replaced), for a process that outlives its hub (hub_loss.hpp).
#pragma once

namespace afhub::hub_loss {

// Starts the watcher, detached: it checks the hub every 20 ms and handles its loss.
void start_hub_loss_watcher();

}  // namespace afhub::hub_loss
