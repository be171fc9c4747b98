// The iceoryx ports left, as the hub's Health counts them: every new writer checks
// the publisher ports, and every new reader the subscriber ports, before it asks
// iceoryx for one, which would otherwise abort the process when none is left.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "afhub/shm_layout/slot_block.hpp"

namespace afhub {

struct FreePorts {
  std::uint32_t publishers = 0;
  std::uint32_t subscribers = 0;
};

// The subscriber ports no afhub reader takes: a process reads the hub's Health with
// them (a reader of its own for a moment) when it connects or counts afresh.
constexpr std::uint32_t kReservedSubscriberPorts = 4;

// The free ports in the hub's latest Health, waiting up to `timeout` for it (a
// reader made for the call: none stays subscribed, holding a chunk); nullopt when
// no Health came. Needs connect_to_hub() first.
std::optional<FreePorts> free_ports(std::chrono::milliseconds timeout);
std::optional<std::uint32_t> free_publisher_ports(std::chrono::milliseconds timeout);

// Counts from `free` ports (connect_to_hub() calls it with free_ports()); before it,
// or with nullopt, require_publisher_ports() and require_subscriber_ports() check
// nothing.
void count_ports_from(std::optional<FreePorts> free);
void count_publisher_ports_from(std::optional<std::uint32_t> free);
// The hub itself counts its own port pool: it has no need to read its Health.
void count_subscriber_ports_from(std::optional<std::uint32_t> free);

// Throw afhub::Error, naming `what` and saying what to do, when fewer than `count`
// ports are left by the count: the ports free at connect_to_hub(), less those this
// process took since. Readers leave kReservedSubscriberPorts free.
void require_publisher_ports(std::size_t count, const std::string& what);
void require_subscriber_ports(std::size_t count, const std::string& what);

// Chunks a process will hold for as long as it runs (a writer publishing each step
// keeps a loan, and one sample in flight), of payloads of `bytes`.
struct ChunkNeed {
  std::uint32_t bytes = 0;
  std::uint32_t count = 0;
};
// What a writer of a queue that publishes every cycle holds: a loan and a sample in
// flight.
constexpr ChunkNeed published_each_cycle(std::size_t bytes) {
  return {static_cast<std::uint32_t>(bytes), 2};
}
// What a writer of a slot (states and commands, see channel.hpp) may take: the first
// block of slots of its process for payloads of its size (shared with the process's
// other writers of the kind, so this counts high).
constexpr ChunkNeed written_as_slot(std::size_t payload_bytes) {
  return {
      static_cast<std::uint32_t>(first_slot_block_bytes(static_cast<std::uint32_t>(payload_bytes))),
      1};
}
// What the writers of a process's many slots may take: the blocks they fill, by kind
// and entry size (see slot_blocks_for()).
struct SlotWritten {
  PayloadKind kind;
  std::size_t payload_bytes;
};
std::vector<ChunkNeed> written_as_slots(const std::vector<SlotWritten>& slots);
// Throws afhub::Error, naming `what`, the pool and its size, when taking `needs` would
// leave a pool of the hub nearly empty (by the hub's latest Health, read afresh): a new
// process is refused before it takes the chunks those running publish with. Every
// process that publishes calls it before its first loan.
void require_chunks(const std::vector<ChunkNeed>& needs, const std::string& what);

// Takes a port from the count, or gives one back: this process opened or closed a
// writer (publisher) or a reader (subscriber).
void took_publisher_port() noexcept;
void gave_back_publisher_port() noexcept;
void took_subscriber_port() noexcept;
void gave_back_subscriber_port() noexcept;

}  // namespace afhub
