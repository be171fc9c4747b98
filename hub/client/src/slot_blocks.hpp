// Blocks of latest-value slots (shm_layout/slot_block.hpp) over iceoryx: where a
// process's slot writers get their entries, and where its slot readers find the
// entries of their channels. All blocks of a kind are published on one iceoryx
// service; a process holds a publisher per block it writes and one subscriber per
// kind it reads, whatever the number of channels. Internal to the hub client.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/slot_block.hpp"

namespace afhub::slot_blocks {

using Claim = SlotClaim;  // an entry a writer claimed

// Claims an entry for `channel` with room for `bytes`, in one of the process's blocks
// of `kind` or in a new one. Empty (entry == nullptr) when publisher ports or shared
// memory are exhausted, said once on stderr. Takes a lock: for a writer's first loan
// (or its first larger one), not for every update.
Claim claim(const ChannelId& channel, PayloadKind kind, std::uint32_t bytes) noexcept;

// Throws afhub::Error, naming `what`, when the process has no block of `kind` yet and
// iceoryx has no publisher port left for one: a writer is refused when it is made,
// rather than at its first loan.
void require_port_for(PayloadKind kind, const std::string& what);

// Lets the entry go: it keeps its last update for its readers, and is never written
// again. A block goes with its last entry.
void release(const Claim& claim) noexcept;

// One entry of a channel, as a reader finds it.
struct Found {
  SlotEntryHeader* entry = nullptr;
  const void* payload = nullptr;
  std::uint32_t capacity = 0;
  void* block = nullptr;         // the directory's, pinned while the reader holds the entry
  std::uint32_t writer_pid = 0;  // as its block's header said (checked, not proven)
};

// The blocks of one kind that this process reads, shared by its readers of that kind.
class Directory {
 public:
  explicit Directory(PayloadKind kind);
  ~Directory();
  Directory(const Directory&) = delete;
  Directory& operator=(const Directory&) = delete;

  // Readers of the kind in this process, or a caller of slot_activity() (which stays):
  // the first subscribes (throws afhub::Error when no subscriber port is left); with
  // none left the directory lets go of every block and its subscriber, so that a
  // process whose readers of a kind are gone holds none of its writers' memory.
  void attach();
  void detach() noexcept;
  // Attaches once for good (a process that asks for activity now and then).
  void watch();
  // A reader's look before it reads: refreshes at the first look of each round of the
  // process's readers (once per step for a physics reading a thousand command slots,
  // every look for a controller's one reader), and at least once per coarse tick.
  void look() noexcept;
  // Takes new blocks, scans new entries, lets go of blocks whose writers closed or
  // died: at most once per tick of the coarse monotonic clock (a few ms) unless `now`,
  // and never waiting for another thread's look. Real-time safe while nothing new
  // came; a new entry may allocate.
  void refresh(bool now) noexcept;
  // Changes whenever a refresh found entries or dropped blocks: readers look again.
  std::uint64_t generation() const noexcept { return generation_.load(std::memory_order_acquire); }
  // Up to `max` live entries of channel `key` (ChannelId::to_string()), newest update
  // first; each pins its block until unbind().
  std::size_t bind(const std::string& key, Found* out, std::size_t max);
  void unbind(const Found* found, std::size_t count) noexcept;
  // What the writer of `key`'s entry updated last tells of itself (see slot_activity()),
  // read under the directory's lock: the block cannot go meanwhile.
  std::optional<SlotActivity> activity(const std::string& key);
  bool subscribed() const noexcept;

 private:
  struct Block;
  void take_new_blocks(bool& changed) noexcept;
  void scan_entries(Block& block, bool& changed) noexcept;
  void drop_gone_blocks(bool& changed) noexcept;
  void report(const char* what) noexcept;
  void let_go() noexcept;  // every block, the index and the subscriber
  std::size_t bind_locked(const std::string& key, Found* out, std::size_t max, bool pin);

  PayloadKind kind_;
  struct Port;
  std::unique_ptr<Port> port_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Block>> blocks_;
  std::unordered_map<std::string, std::vector<Found>> index_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<std::int64_t> last_look_tick_{-1};
  std::atomic<std::uint32_t> readers_{0};
  std::atomic<std::uint32_t> looks_{0};
  std::size_t next_liveness_check_ = 0;
  std::int64_t last_liveness_tick_ = -1;
  bool reported_ = false;
  std::atomic<bool> watched_{false};
};

// The process's directory of `kind`, made (and subscribed) at the first call.
Directory& directory(PayloadKind kind);

// Refreshes every directory the process made (see channel.hpp's
// release_gone_slot_writers()).
void refresh_all() noexcept;

}  // namespace afhub::slot_blocks
