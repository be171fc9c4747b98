// The publisher ports iceoryx has left, as the hub's Health counts them: every new
// writer checks them before it asks iceoryx for a port, which would otherwise abort
// the process when none is left.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace afhub {

// The free publisher ports in the hub's latest Health, waiting up to `timeout` for it
// (a reader made for the call: none stays subscribed, holding a chunk); nullopt when
// no Health came. Needs connect_to_hub() first.
std::optional<std::uint32_t> free_publisher_ports(std::chrono::milliseconds timeout);

// Counts from `free` ports (connect_to_hub() calls it with free_publisher_ports());
// before it, or with nullopt, require_publisher_ports() checks nothing.
void count_publisher_ports_from(std::optional<std::uint32_t> free);

// Throws afhub::Error, naming `what` and saying what to do, when fewer than `count`
// ports are left by the count: the ports free at connect_to_hub(), less those this
// process took since.
void require_publisher_ports(std::size_t count, const std::string& what);

// Takes a port from the count, or gives one back: this process opened or closed a writer.
void took_publisher_port() noexcept;
void gave_back_publisher_port() noexcept;

}  // namespace afhub
