// Checks, before iceoryx's runtime connects, that this process may use the hub.
#pragma once

namespace afhub {

// iceoryx would wait on whatever answers at /tmp/roudi (a socket another user planted
// there hangs it), and abort on shared memory it may not open. Throws afhub::Error,
// saying what to do, unless the socket belongs to the user of the afhub hub that holds
// its lock and this user may use the hub's shared memory.
void require_hub_access();

}  // namespace afhub
