// Blocks of slots over iceoryx (see slot_blocks.hpp).
#include "slot_blocks.hpp"

#include <signal.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <utility>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "latest_slot.hpp"

namespace afhub::slot_blocks {
namespace {

// Blocks a directory holds at most: iceoryx lets a subscriber hold 256 chunks.
constexpr std::size_t kMaxHeldBlocks = 240;

// How long a block stays readable once its writer closed it or died: a reader that
// looks within it still reads the writer's last update of each channel (a driver's
// last state, at zero force).
constexpr std::int64_t kGoneBlockGraceNs = 1'000'000'000;

iox::capro::ServiceDescription block_service(PayloadKind kind) {
  const std::string instance = std::to_string(static_cast<std::uint32_t>(kind));
  using iox::capro::IdString_t;
  using iox::cxx::TruncateToCapacity;
  return {IdString_t(kSlotBlockService), IdString_t(TruncateToCapacity, instance.c_str()),
          IdString_t(kSlotBlockEvent)};
}

void copy_name(char (&to)[kChannelNameBufferSize], const std::string& from) {
  const std::size_t length = std::min(from.size(), kChannelNameBufferSize - 1);
  std::memcpy(to, from.data(), length);
  to[length] = '\0';
}

// Whether the process `pid` is gone (signal 0 checks without sending).
bool writer_gone(std::uint32_t pid) noexcept {
  return syscall(SYS_kill, static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

std::int64_t coarse_tick() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC_COARSE, &now);
  return now.tv_sec * 1'000'000'000LL + now.tv_nsec;
}

// ---- writers ----

struct WriterBlock {
  std::unique_ptr<iox::popo::UntypedPublisher> publisher;
  SlotBlockHeader* header = nullptr;
  PayloadKind kind{};
  std::uint32_t capacity = 0;  // payload room of each entry
  std::uint32_t entries = 0;
  std::uint32_t next = 0;  // entries claimed
  std::uint32_t live = 0;  // claimed and not released
  unsigned char* entry(std::uint32_t i) const {
    return reinterpret_cast<unsigned char*>(header) + kSlotBlockHeaderBytes +
           static_cast<std::size_t>(i) * (kSlotEntryHeaderBytes + capacity);
  }
};

struct Writers {
  std::mutex mutex;
  std::vector<std::unique_ptr<WriterBlock>> blocks;
  bool said = false;
};

Writers& writers() {
  static Writers* const kWriters = new Writers;  // never destroyed: writers may outlive statics
  return *kWriters;
}

void say_once(Writers& w, const std::string& what) {
  if (w.said) return;
  w.said = true;
  std::fprintf(stderr, "afhub: %s (said once)\n", what.c_str());
}

WriterBlock* new_block(Writers& w, const ChannelId& channel, PayloadKind kind,
                       std::uint32_t capacity) {
  // The process's blocks of this kind and entry size now: the next fills a larger tier.
  const auto nth = static_cast<std::size_t>(std::count_if(
      w.blocks.begin(), w.blocks.end(),
      [&](const auto& block) { return block->kind == kind && block->capacity == capacity; }));
  const std::uint32_t entries = slot_block_entries(nth, capacity);
  const std::size_t bytes = slot_block_loan_bytes(nth, capacity);
  try {
    require_publisher_ports(1, "writing '" + channel.to_string() + "'");
  } catch (const std::exception& error) {
    say_once(w, error.what());
    return nullptr;
  }
  auto block = std::make_unique<WriterBlock>();
  block->publisher = std::make_unique<iox::popo::UntypedPublisher>(block_service(kind), [] {
    iox::popo::PublisherOptions options;
    options.historyCapacity = 1;  // the block, for readers that come later
    return options;
  }());
  took_publisher_port();
  auto loaned = block->publisher->loan(static_cast<std::uint32_t>(bytes), 64);
  if (loaned.has_error()) {
    say_once(w, "no shared memory for a block of " + std::to_string(entries) + " slots of " +
                    std::to_string(bytes) + " bytes (writing '" + channel.to_string() +
                    "'): give the hub a larger pool (--pool BYTES:COUNT)");
    block->publisher.reset();
    gave_back_publisher_port();
    return nullptr;
  }
  auto* header = new (loaned.value()) SlotBlockHeader;
  header->magic = kSlotBlockMagic;
  header->layout_id = kLayoutId;
  header->kind = kind;
  header->writer_pid = static_cast<std::uint32_t>(getpid());
  header->entry_count = entries;
  header->entry_bytes = kSlotEntryHeaderBytes + capacity;
  block->header = header;
  block->kind = kind;
  block->capacity = capacity;
  block->entries = entries;
  // Published once, before any entry: readers hold it and find entries as they come.
  block->publisher->publish(header);
  w.blocks.push_back(std::move(block));
  return w.blocks.back().get();
}

}  // namespace

Claim claim(const ChannelId& channel, PayloadKind kind, std::uint32_t bytes) noexcept {
  Writers& w = writers();
  try {
    std::lock_guard lock(w.mutex);
    const std::uint32_t capacity = slot_payload_capacity(bytes);
    WriterBlock* block = nullptr;
    for (auto& candidate : w.blocks)
      if (candidate->kind == kind && candidate->capacity == capacity &&
          candidate->next < candidate->entries)
        block = candidate.get();
    if (!block) block = new_block(w, channel, kind, capacity);
    if (!block) return {};
    auto* entry = new (block->entry(block->next)) SlotEntryHeader;
    slot::init(entry->control);
    copy_name(entry->service, channel.service);
    copy_name(entry->instance, channel.instance);
    copy_name(entry->event, channel.event);
    ++block->next;
    ++block->live;
    block->header->claimed.store(block->next, std::memory_order_release);
    return {entry, reinterpret_cast<unsigned char*>(entry) + kSlotEntryHeaderBytes, capacity};
  } catch (const std::exception& error) {  // a name or map that could not be allocated
    say_once(w, std::string("cannot claim a slot for '") + channel.service + "/" +
                    channel.instance + "/" + channel.event + "': " + error.what());
    return {};
  }
}

void require_port_for(PayloadKind kind, const std::string& what) {
  Writers& w = writers();
  {
    std::lock_guard lock(w.mutex);
    for (const auto& block : w.blocks)
      if (block->kind == kind) return;
  }
  require_publisher_ports(1, what);
}

void release(const Claim& claim) noexcept {
  if (!claim.entry) return;
  Writers& w = writers();
  std::lock_guard lock(w.mutex);
  const auto* at = reinterpret_cast<const unsigned char*>(claim.entry);
  for (auto it = w.blocks.begin(); it != w.blocks.end(); ++it) {
    WriterBlock& block = **it;
    if (at < block.entry(0) || at >= block.entry(block.entries)) continue;
    if (--block.live > 0) return;
    // Its last entry: readers let go of the chunk once they see it closed.
    block.header->closed.store(1, std::memory_order_release);
    block.publisher.reset();
    gave_back_publisher_port();
    w.blocks.erase(it);
    return;
  }
}

// ---- readers ----

struct Directory::Port {
  explicit Port(PayloadKind kind)
      : subscriber(block_service(kind), [] {
          iox::popo::SubscriberOptions options;
          options.queueCapacity = iox::MAX_SUBSCRIBER_QUEUE_CAPACITY;
          options.historyRequest = 1;  // every writer's block, when this reader comes
          options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
          return options;
        }()) {}
  iox::popo::UntypedSubscriber subscriber;
};

struct Directory::Block {
  const SlotBlockHeader* header = nullptr;
  SlotBlockGeometry geometry;
  std::uint32_t scanned = 0;  // entries indexed
  std::uint32_t users = 0;    // entries readers of this process hold
  std::int64_t gone_ns = 0;   // when found closed, or its writer dead (coarse clock)
  bool expired = false;       // gone for kGoneBlockGraceNs: readers let go of it
  unsigned char* entry(std::uint32_t i) const {
    return const_cast<unsigned char*>(reinterpret_cast<const unsigned char*>(header)) +
           kSlotBlockHeaderBytes + static_cast<std::size_t>(i) * geometry.entry_bytes;
  }
};

Directory::Directory(PayloadKind kind) : kind_(kind) {
  blocks_.reserve(kMaxHeldBlocks);
}

Directory::~Directory() {
  let_go();
}

bool Directory::subscribed() const noexcept {
  return port_ && port_->subscriber.getSubscriptionState() == iox::SubscribeState::SUBSCRIBED;
}

void Directory::let_go() noexcept {
  if (!port_) return;
  index_.clear();
  for (auto& block : blocks_) port_->subscriber.release(block->header);
  blocks_.clear();
  port_.reset();
  gave_back_subscriber_port();
  generation_.fetch_add(1, std::memory_order_acq_rel);
}

void Directory::report(const char* what) noexcept {
  if (reported_) return;
  reported_ = true;
  std::fprintf(stderr, "afhub: slots of payload kind %u: %s (said once)\n",
               static_cast<unsigned>(kind_), what);
}

void Directory::attach() {
  std::lock_guard lock(mutex_);
  if (readers_.load(std::memory_order_relaxed) == 0) {
    // A new subscriber each time: its subscription brings every writer's block now out
    // (iceoryx hands a publisher's history to a new subscription only).
    require_subscriber_ports(
        1, "reading slots of payload kind " + std::to_string(static_cast<std::uint32_t>(kind_)));
    port_ = std::make_unique<Port>(kind_);
    took_subscriber_port();
  }
  readers_.fetch_add(1, std::memory_order_relaxed);
}

void Directory::detach() noexcept {
  std::lock_guard lock(mutex_);
  if (readers_.fetch_sub(1, std::memory_order_relaxed) == 1) let_go();
}

void Directory::watch() {
  if (watched_.load()) return;
  attach();                               // may throw (no port): watched at a later call
  if (watched_.exchange(true)) detach();  // another thread's call came first
}

void Directory::look() noexcept {
  // At the first look of each round: every reader of the round sees what it found.
  const std::uint32_t readers =
      std::max<std::uint32_t>(readers_.load(std::memory_order_relaxed), 1);
  refresh(looks_.fetch_add(1, std::memory_order_relaxed) % readers == 0);
}

void Directory::refresh(bool now) noexcept {
  const std::int64_t tick = coarse_tick();
  if (!now && tick == last_look_tick_.load(std::memory_order_relaxed)) return;
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // another reader of this process is looking
  if (!port_) return;             // no reader of this kind
  last_look_tick_.store(tick, std::memory_order_relaxed);
  bool changed = false;
  take_new_blocks(changed);
  for (auto& block : blocks_) scan_entries(*block, changed);
  drop_gone_blocks(changed);
  if (changed) generation_.fetch_add(1, std::memory_order_acq_rel);
}

void Directory::take_new_blocks(bool& changed) noexcept {
  while (blocks_.size() < kMaxHeldBlocks) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) return;
    const void* chunk = taken.value();
    const std::uint32_t bytes = iox::mepoo::ChunkHeader::fromUserPayload(chunk)->userPayloadSize();
    const auto* header = static_cast<const SlotBlockHeader*>(chunk);
    Block block;
    const char* field = "";
    const SlotBlockError error = check_slot_block(*header, bytes, kind_, block.geometry, &field);
    if (error != SlotBlockError::kNone) {
      char what[256];
      std::snprintf(what, sizeof what, "refused a block: %s: %s", field, describe(error));
      report(what);
      port_->subscriber.release(chunk);
      continue;
    }
    block.header = header;
    blocks_.push_back(std::make_unique<Block>(block));
    changed = true;
  }
  if (port_->subscriber.hasData()) report("more blocks than one reader holds (240); some unseen");
}

void Directory::scan_entries(Block& block, bool& changed) noexcept {
  if (block.expired) return;
  const std::uint32_t claimed =
      std::min(block.header->claimed.load(std::memory_order_acquire), block.geometry.entry_count);
  for (; block.scanned < claimed; ++block.scanned) {
    auto* entry = reinterpret_cast<SlotEntryHeader*>(block.entry(block.scanned));
    // Copied before use: the writer may be anything. A name is bounded by its field.
    char service[kChannelNameBufferSize], instance[kChannelNameBufferSize],
        event[kChannelNameBufferSize];
    std::memcpy(service, entry->service, sizeof service);
    std::memcpy(instance, entry->instance, sizeof instance);
    std::memcpy(event, entry->event, sizeof event);
    service[sizeof service - 1] = instance[sizeof instance - 1] = event[sizeof event - 1] = '\0';
    try {
      std::string key = std::string(service) + "/" + instance + "/" + event;
      index_[std::move(key)].push_back({entry, block.entry(block.scanned) + kSlotEntryHeaderBytes,
                                        block.geometry.payload_capacity, &block,
                                        block.geometry.writer_pid});
    } catch (const std::bad_alloc&) {
      report("out of memory indexing a channel");
      return;
    }
    changed = true;
  }
}

void Directory::drop_gone_blocks(bool& changed) noexcept {
  const std::int64_t now = last_look_tick_.load(std::memory_order_relaxed);
  if (!blocks_.empty() && now != last_liveness_tick_) {
    // One writer's liveness per coarse clock tick (a system call), round the blocks.
    last_liveness_tick_ = now;
    Block& block = *blocks_[next_liveness_check_++ % blocks_.size()];
    if (block.gone_ns == 0 && writer_gone(block.geometry.writer_pid)) block.gone_ns = now;
  }
  for (auto it = blocks_.begin(); it != blocks_.end();) {
    Block& block = **it;
    if (block.gone_ns == 0 && block.header->closed.load(std::memory_order_acquire) != 0)
      block.gone_ns = now;
    if (block.gone_ns != 0 && !block.expired && now - block.gone_ns >= kGoneBlockGraceNs)
      block.expired = changed = true;  // readers see `changed`, let go, and it goes later
    if (!block.expired || block.users > 0) {
      ++it;
      continue;
    }
    for (auto& [key, found] : index_)
      std::erase_if(found, [&](const Found& f) { return f.block == &block; });
    port_->subscriber.release(block.header);
    it = blocks_.erase(it);
    changed = true;
  }
}

std::size_t Directory::bind(const std::string& key, Found* out, std::size_t max) {
  std::lock_guard lock(mutex_);
  return bind_locked(key, out, max, true);
}

std::size_t Directory::bind_locked(const std::string& key, Found* out, std::size_t max, bool pin) {
  auto it = index_.find(key);
  if (it == index_.end()) return 0;
  std::size_t count = 0;
  // Entries whose writer let go of them still count, until their block expires: their
  // last update is the channel's last word, and a live writer's newer one wins.
  for (const Found& found : it->second) {
    if (static_cast<Block*>(found.block)->expired) continue;
    if (count < max) {
      out[count++] = found;
      continue;
    }
    // Full: keep the ones updated last.
    std::size_t oldest = 0;
    for (std::size_t i = 1; i < count; ++i)
      if (out[i].entry->control.stamp_ns.load(std::memory_order_relaxed) <
          out[oldest].entry->control.stamp_ns.load(std::memory_order_relaxed))
        oldest = i;
    if (found.entry->control.stamp_ns.load(std::memory_order_relaxed) >
        out[oldest].entry->control.stamp_ns.load(std::memory_order_relaxed))
      out[oldest] = found;
  }
  for (std::size_t i = 0; i < count && pin; ++i) {
    ++static_cast<Block*>(out[i].block)->users;
    out[i].entry->readers.fetch_add(1, std::memory_order_relaxed);
  }
  return count;
}

void Directory::unbind(const Found* found, std::size_t count) noexcept {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < count; ++i) {
    --static_cast<Block*>(found[i].block)->users;
    found[i].entry->readers.fetch_sub(1, std::memory_order_relaxed);
  }
}

std::optional<SlotActivity> Directory::activity(const std::string& key) {
  Found found;
  std::lock_guard lock(mutex_);
  if (bind_locked(key, &found, 1, false) == 0) return std::nullopt;
  const SlotControl& control = found.entry->control;
  // The count and the stamp of one update: the same even sequence around the stamp.
  for (int attempt = 0; attempt < 64; ++attempt) {
    const std::uint32_t before = control.sequence.load(std::memory_order_acquire);
    const std::int64_t stamp = control.stamp_ns.load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (before & 1U || control.sequence.load(std::memory_order_relaxed) != before) continue;
    if (before == 0) return std::nullopt;  // claimed, never written
    return SlotActivity{reinterpret_cast<std::uintptr_t>(found.entry), before / 2, stamp};
  }
  return std::nullopt;  // mid-update every time: its writer died in one
}

namespace {

struct Directories {
  std::mutex mutex;
  std::map<PayloadKind, std::unique_ptr<Directory>> by_kind;
};

Directories& directories() {
  // Never destroyed: readers in static objects may outlive it.
  static Directories* const kDirectories = new Directories;
  return *kDirectories;
}

}  // namespace

Directory& directory(PayloadKind kind) {
  Directories& all = directories();
  std::lock_guard lock(all.mutex);
  auto& directory = all.by_kind[kind];
  if (!directory) directory = std::make_unique<Directory>(kind);
  return *directory;
}

void refresh_all() noexcept {
  Directories& all = directories();
  std::lock_guard lock(all.mutex);
  for (auto& [kind, directory] : all.by_kind) directory->refresh(true);
}

}  // namespace afhub::slot_blocks
