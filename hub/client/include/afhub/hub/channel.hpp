// Zero-copy channel ends with latest-value semantics.
//   Writer<T>: loan a payload in shared memory, fill it in place, publish it.
//   LatestReader<T>: the newest valid payload; older ones are dropped.
// Two transports, by payload kind (is_slot_kind, shm_layout/slot.hpp):
//   - States and commands are latest-value slots: the writer claims an entry in a
//     block of slots (shm_layout/slot_block.hpp) that its process published once, and
//     updates it in place under a seqlock; a reader holds the block and copies the
//     payload out, then checks the copy. No lock is shared and a reader costs the
//     writer nothing. A late joiner gets the current value at once. A process takes a
//     port per block, not per channel: a world of thousands of bodies fits iceoryx's.
//   - Every other kind is a queue of iceoryx samples: each publish sends a new chunk,
//     read in place; the writer keeps the last one for late joiners.
// loan(), publish() and latest() are real-time safe: no heap, no exceptions.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <new>
#include <optional>
#include <string>

#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/payload_check.hpp"

namespace afhub {

struct SlotEntryHeader;
namespace slot_blocks {
struct Found;
class Directory;
}  // namespace slot_blocks

// A slot writer's entry in its process's block (see slot_blocks.hpp).
struct SlotClaim {
  SlotEntryHeader* entry = nullptr;
  void* payload = nullptr;
  std::uint32_t capacity = 0;
};

// Untyped ends; the typed templates below are what code uses.
class RawWriter {
 public:
  RawWriter(const ChannelId& channel, PayloadKind kind);
  ~RawWriter();
  RawWriter(const RawWriter&) = delete;
  RawWriter& operator=(const RawWriter&) = delete;

  // A payload of `bytes` bytes to fill, or nullptr when shared memory is exhausted.
  // On a slot the same one every time (while `bytes` fits it), its update begun.
  // `rewritten`, when given, says whether all `bytes` hold this writer's own last
  // update (a slot's entry, loaned before at least this size) rather than anything.
  void* loan(std::uint32_t bytes, bool* rewritten = nullptr) noexcept;
  // Stamps the header (layout, kind, pid, sequence, monotonic time) and publishes.
  // The caller sets header.sim_step and header.sim_time_s. Returns the stamp.
  std::int64_t publish(void* payload) noexcept;
  // The same with a monotonic time read by the caller before it filled the payload:
  // one read for many payloads published together (a physics' step).
  void publish(void* payload, std::int64_t stamp_ns) noexcept;

  // Gives back a payload loaned and not published (queue kinds).
  void release(void* payload) noexcept;

  const ChannelId& channel() const { return channel_; }
  // Slot kinds: asks the CPU for the lines the next update writes (its control and as
  // many payload bytes as the largest loan so far), to own them by the time it does.
  // A hint for a loop over many writers: what another core read of the last update
  // costs a round trip per line, and asked for a few writers ahead those trips overlap.
  void prefetch_update() const noexcept;
  // The same for these payload bytes only, each [from, to): a writer that leaves the
  // other lines as they were leaves them in the readers' caches too.
  struct ByteRange {
    std::uint32_t from, to;
  };
  void prefetch_update(std::initializer_list<ByteRange> ranges) const noexcept;
  // Whether any reader is subscribed now (on a queue, each one costs every publish).
  bool has_readers() const noexcept;
  // The next publish carries sequence `last` + 1. A short-lived writer of commands
  // that readers act on once per sequence number (world commands) starts from a
  // number no earlier process used, e.g. the monotonic clock.
  void continue_sequence_after(std::uint64_t last) noexcept { sequence_ = last; }

 private:
  struct Port;
  ChannelId channel_;
  PayloadKind kind_;
  std::uint32_t pid_;  // read once: getpid() is a system call
  std::uint64_t sequence_ = 0;
  std::unique_ptr<Port> port_;  // queue kinds
  bool slot_kind_;
  SlotClaim slot_;                       // slot kinds: the entry written, claimed at the first loan
  std::uint32_t slot_loaned_bytes_ = 0;  // the largest loan of slot_ so far
};

class RawLatestReader {
 public:
  RawLatestReader(const ChannelId& channel, PayloadKind kind);
  ~RawLatestReader();
  RawLatestReader(const RawLatestReader&) = delete;
  RawLatestReader& operator=(const RawLatestReader&) = delete;

  // The newest valid payload, or nullptr before the first one. It stays valid
  // and unchanged until the next call. Invalid payloads are refused and counted.
  // From a slot it is this reader's checked copy. A writer met mid-update leaves the
  // copy before, with one exception: a reader of states (bodies', the world's, the
  // scene's poses: the physics writes them) whose copy is over 5 ms older than the
  // writer's last whole update, one that missed the updates of 5 ms, waits for the
  // update in hand, up to 2 ms, once per update met; so a reader that looks now and
  // then does not get a copy of seconds ago unless the writer stays in its update
  // longer. A reader that keeps up never waits, and neither does one of commands (the
  // physics, which must not wait on a writer of lower priority).
  const void* latest() noexcept;
  // Slot kinds: takes up a writer that came (or went) since the last look without
  // reading anything, so that writers see this reader (has_readers()) between reads.
  void hold_writers() noexcept;
  // Slot kinds: asks the CPU for the lines latest() reads first (each held entry's
  // control and the payload bytes of the last copy), as prefetch_update() does for a
  // writer: a hint, with no effect on what latest() returns.
  void prefetch() const noexcept;
  // Slot kinds with several writers: an update of the writer of process `pid` (0: none)
  // is returned before a newer one of another writer, which the next call returns. A
  // lockstep client's answer is then never hidden by another writer's command.
  void prefer_writer(std::uint32_t pid) noexcept { preferred_pid_ = pid; }
  // Whether the last latest() call found a sample newer than the one before.
  bool updated() const { return updated_; }
  // The size in bytes of the payload latest() returned.
  std::uint32_t latest_bytes() const { return held_bytes_; }
  std::uint64_t refused_count() const { return refused_; }
  const ChannelId& channel() const { return channel_; }
  // A reader starts subscribed. On a queue every subscribed reader costs the writer
  // on each publish, so one that looks only now and then can step aside in between;
  // what latest() holds stays valid. A slot reader costs its writer nothing: stepping
  // aside changes only what subscribed() says.
  void subscribe() noexcept;
  void unsubscribe() noexcept;
  // Connected: every sample published from now on (queues), every writer's slot
  // (slot kinds, through the process's directory of the kind) reaches this reader.
  bool subscribed() const noexcept;

 private:
  friend class SampleWaiter;  // waits on the port's subscriber and the held slots
  struct Port;
  // A channel has one writer of state; commands may come from a few (a controller, a
  // teleop, a script), each its own slot, the newest update taken.
  static constexpr std::size_t kMaxHeldSlots = 4;
  const void* latest_queued() noexcept;
  const void* latest_slot() noexcept;
  // Takes the channel's entries anew from the directory (a writer came or went).
  void rebind_slots() noexcept;
  void unbind_slots() noexcept;
  bool grow_copies(std::uint32_t bytes) noexcept;
  void report_refusal(const void* payload, std::uint32_t bytes, const char* field,
                      const char* problem) noexcept;
  ChannelId channel_;
  PayloadKind kind_;
  bool slots_;            // is_slot_kind(kind_)
  bool waits_if_behind_;  // a state kind (see latest())
  const void* held_ = nullptr;
  const void* retired_ = nullptr;  // replaced by held_, released on the next call
  std::uint32_t held_bytes_ = 0;
  std::int64_t held_stamp_ns_ = 0;  // slots: the held copy's publish stamp
  bool updated_ = false;
  std::uint64_t refused_ = 0;
  std::unique_ptr<Port> port_;  // queue kinds
  // Slot kinds: the process's directory of the kind, this channel's key in it, the
  // entries held (and the sequence of each when this reader last looked).
  slot_blocks::Directory* directory_ = nullptr;
  std::string key_;
  std::uint64_t bound_generation_ = ~0ULL;
  bool stepped_aside_ = false;  // unsubscribe()d
  std::unique_ptr<slot_blocks::Found[]> held_slots_;
  std::array<std::uint32_t, kMaxHeldSlots> observed_{};
  std::size_t held_slot_count_ = 0;
  std::uint32_t preferred_pid_ = 0;  // prefer_writer()
  // The checked copy latest() returns, and the buffer the next copy goes to.
  std::unique_ptr<unsigned char[]> copy_, spare_;
  std::uint32_t copy_capacity_ = 0;
};

// What a slot's writer tells of itself in its entry (slot kinds only): how many
// updates it made (modulo 2^31) and the stamp of the last. Read in place, without
// holding the entry: the caller is not counted as a reader, nothing is copied. The
// entry updated last when several writers share the channel; nullopt when none has
// written it yet. Not for the steady-state loop (it takes the directory's lock).
struct SlotActivity {
  std::uintptr_t writer = 0;  // tells a restarted writer's entry from the last one
  std::uint32_t updates = 0;
  std::int64_t last_stamp_ns = 0;
};
std::optional<SlotActivity> slot_activity(const ChannelId& channel, PayloadKind kind);

// Lets go of the blocks of slots whose writers closed them or died, for a process
// that reads slots only now and then (the hub): a reader's latest() does it anyway.
void release_gone_slot_writers() noexcept;

template <class T>
class Writer {
 public:
  explicit Writer(const ChannelId& channel) : raw_(channel, T::kKind) {}
  // A default-initialised payload in shared memory, or nullptr when memory is exhausted.
  T* loan() noexcept { return loan(sizeof(T)); }
  // The first `bytes` bytes of a default-initialised payload: for payloads sent at
  // their real size (body_state_bytes, body_command_bytes), whose entries past their
  // count are not in the chunk. `bytes` is at most sizeof(T).
  T* loan(std::size_t bytes) noexcept {
    void* chunk = raw_.loan(static_cast<std::uint32_t>(bytes));
    if (!chunk) return nullptr;
    std::memcpy(chunk, &default_payload(), bytes);
    return static_cast<T*>(chunk);
  }
  // As loan(bytes), but a slot's entry keeps this writer's last update instead of being
  // filled with defaults again: for a writer that sets every field it uses at every
  // update (the physics' thousand body states a step spare a kilobyte of stores each).
  T* loan_rewritten(std::size_t bytes) noexcept {
    bool rewritten = false;
    void* chunk = raw_.loan(static_cast<std::uint32_t>(bytes), &rewritten);
    if (!chunk) return nullptr;
    if (!rewritten) std::memcpy(chunk, &default_payload(), bytes);
    return static_cast<T*>(chunk);
  }
  void publish(T* payload) noexcept { raw_.publish(payload); }
  void publish(T* payload, std::int64_t stamp_ns) noexcept { raw_.publish(payload, stamp_ns); }
  RawWriter& raw() { return raw_; }
  const RawWriter& raw() const { return raw_; }

 private:
  static const T& default_payload() noexcept {
    static const T kDefault{};  // static storage: no heap, made on the first loan
    return kDefault;
  }
  RawWriter raw_;
};

template <class T>
class LatestReader {
 public:
  explicit LatestReader(const ChannelId& channel) : raw_(channel, T::kKind) {}
  const T* latest() noexcept { return static_cast<const T*>(raw_.latest()); }
  bool updated() const { return raw_.updated(); }
  RawLatestReader& raw() { return raw_; }
  const RawLatestReader& raw() const { return raw_; }

 private:
  RawLatestReader raw_;
};

}  // namespace afhub
