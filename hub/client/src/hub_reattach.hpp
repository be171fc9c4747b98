// What connect_to_hub() does in a process that outlives its hub (hub_loss.hpp):
// after a re-exec it waits for a new hub, and once attached it watches the hub.
#pragma once

#include <cstdint>

namespace afhub::hub_loss {

// This image is a re-exec after a hub loss (opted in, with AFHUB_REATTACH set).
bool reattaching() noexcept;

// Waits for a hub other than the one lost, never starting one; a stop signal while
// it waits ends the process with exit code 0.
void wait_for_new_hub();

// Once attached (nothing unless opted in): notes the hub attached to, says so after a
// re-exec (`hub_seen_ns`: when the new hub answered), and starts the watcher.
void watch_attached_hub(std::int64_t hub_seen_ns);

}  // namespace afhub::hub_loss
