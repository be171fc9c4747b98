// Claiming bodies through the hub: a body has one publisher. Before a process opens
// its bodies' channels it checks that the hub has room for them and that no live
// process publishes them already; once its directory is out, the hub's catalog
// confirms that it owns them (of two processes that checked at the same moment, the
// hub keeps the first). Needs connect_to_hub() first.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

namespace afhub {

// Whether process `pid` is alive: it exists and is no zombie (dead, not yet reaped).
bool process_exists(std::uint32_t pid);
// Whether process `pid` is stopped: SIGSTOP, or a debugger holds it.
bool process_stopped(std::uint32_t pid);

// Throws afhub::Error, saying what to do, when a body in `channels` is published by
// another live process, when the catalog cannot take them all, or when iceoryx has
// fewer than `publishers` publisher ports (a block of state slots holds many bodies,
// see slot_blocks_for()), or no subscriber port (for its command slots), left. Returns
// how many bodies other live processes publish.
std::size_t check_room_for_bodies(const std::vector<std::string>& channels, std::size_t publishers);

// Throws afhub::Error naming the simulation when another live process publishes the
// state of world `world_instance` (world_instance(namespace)): two simulations of one
// world alternated in its state and both obeyed its commands. A publisher that died (a
// physics restarted at once) or stopped publishing is no owner. Reads the world state,
// waiting up to 0.3 s for it and 0.2 s for a newer one: for a process to call when others
// publish bodies. Two started at the same moment
// may both pass. `advice` ends the message.
void check_world_free(const std::string& world_instance,
                      const std::string& advice =
                          "Run this one in a namespace of its own "
                          "(--namespace NAME), or stop that one");

// Waits up to `timeout` for the catalog to list every channel as this process's.
// Throws afhub::Error naming the owner of a body another process holds, the bodies a
// full catalog refused, or, with room in the catalog, the bodies not listed in time.
void confirm_body_claims(const std::vector<std::string>& channels,
                         std::chrono::milliseconds timeout);
// How long a publisher waits for its claims: the hub merges a directory within
// milliseconds, but a hub just started on a loaded machine took over 2 s.
inline constexpr std::chrono::seconds kClaimConfirmTimeout{10};

}  // namespace afhub
