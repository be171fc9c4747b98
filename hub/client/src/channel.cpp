// Zero-copy channel ends over iceoryx's untyped publisher and subscriber.
#include "afhub/hub/channel.hpp"

#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "afhub/hub/hub_health.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/slot.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "latest_slot.hpp"
#include "reader_port.hpp"
#include "slot_blocks.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>  // PREFETCHW, where the CPU has it
#endif

namespace afhub {

iox::capro::ServiceDescription describe_channel(const ChannelId& channel) {
  using iox::capro::IdString_t;
  using iox::cxx::TruncateToCapacity;
  // Names were validated on the way in; nothing here is ever truncated.
  return {IdString_t(TruncateToCapacity, channel.service.c_str()),
          IdString_t(TruncateToCapacity, channel.instance.c_str()),
          IdString_t(TruncateToCapacity, channel.event.c_str())};
}

namespace {

void require_fits(const ChannelId& channel) {
  for (const std::string* part : {&channel.service, &channel.instance, &channel.event})
    if (part->empty() || part->size() > iox::capro::IdString_t::capacity())
      throw Error("channel '" + channel.to_string() + "': '" + *part +
                  "' must have 1 to 100 characters");
}

// A state reader's copy this much older than its writer's last whole update, and the
// writer met mid-update: the update in hand is waited for, up to kTornWaitNs (see
// RawLatestReader::latest(); a writer preempted mid-update on a loaded machine once gave
// a test the world state of 1.5 s before).
constexpr std::int64_t kStaleCopyNs = 5'000'000;
constexpr std::uint32_t kCacheLineBytes = 64;

// PREFETCHW asks for a line to write: owned at once, where a plain prefetch would get
// it shared and the store would still wait for it. The CPUs that have it (AMD's, and
// Intel's since Broadwell) say so in CPUID 0x80000001, ECX bit 8; on the others the
// hint is left out.
#if defined(__x86_64__) || defined(__i386__)
bool cpu_has_prefetchw() noexcept {
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  return __get_cpuid(0x80000001, &eax, &ebx, &ecx, &edx) != 0 && (ecx & (1U << 8)) != 0;
}
const bool kHasPrefetchw = cpu_has_prefetchw();

// Written out: the compiler emits PREFETCHW only for a target that has it, and drops a
// call to a function of another target as if it did nothing.
void prefetch_for_writing(const void* line) noexcept {
  asm volatile("prefetchw %0" : : "m"(*static_cast<const char*>(line)));
}
#else
constexpr bool kHasPrefetchw = false;
void prefetch_for_writing(const void*) noexcept {}
#endif
constexpr std::int64_t kTornWaitNs = 2'000'000;

bool is_state_kind(PayloadKind kind) {
  return kind == PayloadKind::kBodyState || kind == PayloadKind::kWorldState ||
         kind == PayloadKind::kScenePoses;
}

// later - earlier > limit, for any two stamps (a foreign writer's may be anything).
bool apart_by_more_than(std::int64_t later, std::int64_t earlier, std::int64_t limit) noexcept {
  std::int64_t difference = 0;
  if (__builtin_sub_overflow(later, earlier, &difference)) return later > earlier;
  return difference > limit;
}

}  // namespace

struct RawWriter::Port {
  explicit Port(const ChannelId& channel)
      : publisher(describe_channel(channel), [] {
          iox::popo::PublisherOptions options;
          // The last sample (a queue's) or the slot, for readers that come later.
          options.historyCapacity = 1;
          return options;
        }()) {}
  iox::popo::UntypedPublisher publisher;
};

RawWriter::RawWriter(const ChannelId& channel, PayloadKind kind)
    : channel_(channel),
      kind_(kind),
      pid_(static_cast<std::uint32_t>(getpid())),
      slot_kind_(is_slot_kind(kind)) {
  require_fits(channel);
  if (slot_kind_) {
    slot_blocks::require_port_for(kind, "writing '" + channel.to_string() + "'");
    return;
  }
  require_publisher_ports(1, "writing '" + channel.to_string() + "'");
  port_ = std::make_unique<Port>(channel);
  took_publisher_port();
}

RawWriter::~RawWriter() {
  if (slot_kind_) {
    slot_blocks::release(slot_);
    return;
  }
  if (port_) gave_back_publisher_port();
}

void* RawWriter::loan(std::uint32_t bytes, bool* rewritten) noexcept {
  if (rewritten) *rewritten = false;
  if (!slot_kind_) {
    auto result = port_->publisher.loan(bytes, alignof(PayloadHeader));
    return result.has_error() ? nullptr : result.value();
  }
  if (!slot_.entry || bytes > slot_.capacity) {
    // The first loan, or a larger payload than the entry holds: a new entry, which
    // readers take in place of this writer's old one.
    const slot_blocks::Claim claimed = slot_blocks::claim(channel_, kind_, bytes);
    if (!claimed.entry) return nullptr;
    slot_blocks::release(slot_);
    slot_ = claimed;
    slot_loaned_bytes_ = 0;
  }
  if (rewritten) *rewritten = bytes <= slot_loaned_bytes_;
  slot_loaned_bytes_ = std::max(slot_loaned_bytes_, bytes);
  slot::begin_update(slot_.entry->control, bytes);
  return slot_.payload;
}

void RawWriter::prefetch_update() const noexcept {
  prefetch_update({{0, slot_loaned_bytes_}});
}

void RawWriter::prefetch_update(std::initializer_list<ByteRange> ranges) const noexcept {
  if (!slot_.entry || !kHasPrefetchw) return;
  prefetch_for_writing(&slot_.entry->control);
  const auto* payload = static_cast<const unsigned char*>(slot_.payload);  // line-aligned
  for (const ByteRange& range : ranges) {
    const std::uint32_t to = std::min(range.to, slot_loaned_bytes_);
    if (range.from >= to) continue;
    for (std::uint32_t at = range.from & ~(kCacheLineBytes - 1); at < to; at += kCacheLineBytes)
      prefetch_for_writing(payload + at);
  }
}

std::int64_t RawWriter::publish(void* payload) noexcept {
  const std::int64_t stamp_ns = monotonic_ns();
  publish(payload, stamp_ns);
  return stamp_ns;
}

void RawWriter::publish(void* payload, std::int64_t stamp_ns) noexcept {
  auto* header = static_cast<PayloadHeader*>(payload);
  header->layout_id = kLayoutId;
  header->kind = kind_;
  header->publisher_pid = pid_;
  header->sequence = ++sequence_;
  header->publish_stamp_ns = stamp_ns;
  if (slot_kind_)
    slot::end_update(slot_.entry->control, stamp_ns);
  else
    port_->publisher.publish(payload);
}

void RawWriter::release(void* payload) noexcept {
  if (!slot_kind_) port_->publisher.release(payload);
}

bool RawWriter::has_readers() const noexcept {
  if (slot_kind_) return slot_.entry && slot_.entry->readers.load(std::memory_order_relaxed) > 0;
  return port_->publisher.hasSubscribers();
}

iox::popo::SubscriberOptions newest_sample_only() noexcept {
  iox::popo::SubscriberOptions options;
  options.queueCapacity = 1;  // a newer sample replaces a queued one
  options.historyRequest = 1;
  options.queueFullPolicy = iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
  return options;
}

RawLatestReader::Port::Port(const ChannelId& channel)
    : subscriber(describe_channel(channel), newest_sample_only()) {}

RawLatestReader::RawLatestReader(const ChannelId& channel, PayloadKind kind)
    : channel_(channel),
      kind_(kind),
      slots_(is_slot_kind(kind)),
      waits_if_behind_(is_state_kind(kind)) {
  require_fits(channel);
  if (slots_) {
    directory_ = &slot_blocks::directory(kind);
    directory_->attach();
    key_ = channel.to_string();
    held_slots_ = std::make_unique<slot_blocks::Found[]>(kMaxHeldSlots);
    return;
  }
  require_subscriber_ports(1, "reading '" + channel.to_string() + "'");
  port_ = std::make_unique<Port>(channel);
  took_subscriber_port();
}

RawLatestReader::~RawLatestReader() {
  if (slots_) {
    unbind_slots();
    directory_->detach();
    return;
  }
  gave_back_subscriber_port();
  if (held_) port_->subscriber.release(held_);
  if (retired_) port_->subscriber.release(retired_);
}

const void* RawLatestReader::latest() noexcept {
  updated_ = false;
  return slots_ ? latest_slot() : latest_queued();
}

const void* RawLatestReader::latest_queued() noexcept {
  // The sample replaced by the last call is released now, while polling, rather
  // than between a new sample's arrival and its reader seeing it.
  if (retired_) port_->subscriber.release(retired_);
  retired_ = nullptr;
  for (;;) {
    auto taken = port_->subscriber.take();
    if (taken.has_error()) break;  // no more samples (or too many held: keep the current)
    const void* payload = taken.value();
    const std::uint32_t bytes =
        iox::mepoo::ChunkHeader::fromUserPayload(payload)->userPayloadSize();
    const char* field = "";
    PayloadError error = check_payload(payload, bytes, kind_, &field);
    if (error != PayloadError::kNone) {
      report_refusal(payload, bytes, field, describe(error));
      port_->subscriber.release(payload);
      continue;
    }
    if (retired_) port_->subscriber.release(retired_);
    retired_ = held_;
    held_ = payload;
    held_bytes_ = bytes;
    updated_ = true;
  }
  return held_;
}

// A slot reader costs its writer nothing: stepping aside changes only what
// subscribed() says, and it keeps reading the entries it holds.
void RawLatestReader::subscribe() noexcept {
  if (slots_)
    stepped_aside_ = false;
  else
    port_->subscriber.subscribe();
}

void RawLatestReader::unsubscribe() noexcept {
  if (slots_)
    stepped_aside_ = true;
  else
    port_->subscriber.unsubscribe();
}

bool RawLatestReader::subscribed() const noexcept {
  // Slots: every writer's entry of the kind reaches the process's directory.
  if (slots_) return !stepped_aside_ && directory_->subscribed();
  return port_->subscriber.getSubscriptionState() == iox::SubscribeState::SUBSCRIBED;
}

void RawLatestReader::unbind_slots() noexcept {
  if (held_slot_count_ > 0) directory_->unbind(held_slots_.get(), held_slot_count_);
  held_slot_count_ = 0;
}

void RawLatestReader::rebind_slots() noexcept {
  std::array<slot_blocks::Found, kMaxHeldSlots> found{};
  std::size_t count = 0;
  bound_generation_ = directory_->generation();
  try {
    count = directory_->bind(key_, found.data(), kMaxHeldSlots);
  } catch (const std::exception&) {  // a lock that failed: keep what is held
    return;
  }
  // An entry held before keeps the sequence last seen: it is not copied again. A new
  // one counts as seen at sequence 0, which it has until its writer's first update.
  std::array<std::uint32_t, kMaxHeldSlots> observed{};
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t j = 0; j < held_slot_count_; ++j)
      if (held_slots_[j].entry == found[i].entry) observed[i] = observed_[j];
  }
  unbind_slots();
  for (std::size_t i = 0; i < count; ++i) held_slots_[i] = found[i];
  observed_ = observed;
  held_slot_count_ = count;
}

bool RawLatestReader::grow_copies(std::uint32_t bytes) noexcept {
  if (bytes <= copy_capacity_) return true;
  // Once per channel, when its first (or a larger) slot arrives: not in steady state.
  std::unique_ptr<unsigned char[]> copy(new (std::nothrow) unsigned char[bytes]);
  std::unique_ptr<unsigned char[]> spare(new (std::nothrow) unsigned char[bytes]);
  if (!copy || !spare) return false;
  if (held_) std::memcpy(copy.get(), held_, held_bytes_);
  copy_ = std::move(copy);
  spare_ = std::move(spare);
  copy_capacity_ = bytes;
  if (held_) held_ = copy_.get();
  return true;
}

void RawLatestReader::prefetch() const noexcept {
  for (std::size_t i = 0; i < held_slot_count_; ++i) {
    const slot_blocks::Found& slot = held_slots_[i];
    __builtin_prefetch(&slot.entry->control);
    const auto* payload = static_cast<const unsigned char*>(slot.payload);
    const std::uint32_t bytes = std::min(std::max(held_bytes_, 1U), slot.capacity);
    for (std::uint32_t at = 0; at < bytes; at += kCacheLineBytes) __builtin_prefetch(payload + at);
  }
}

void RawLatestReader::hold_writers() noexcept {
  if (!slots_) return;
  directory_->look();
  if (directory_->generation() != bound_generation_) rebind_slots();
}

const void* RawLatestReader::latest_slot() noexcept {
  hold_writers();
  if (held_slot_count_ == 0) return held_;
  // The writer that updated last, unless the preferred writer has an update not read
  // yet: that first, the newest at the next call. The others count as looked at (a
  // wait then sleeps until one of them updates again).
  std::size_t newest = 0;
  std::int64_t newest_stamp =
      held_slots_[0].entry->control.stamp_ns.load(std::memory_order_acquire);
  for (std::size_t i = 1; i < held_slot_count_; ++i) {
    const std::int64_t stamp =
        held_slots_[i].entry->control.stamp_ns.load(std::memory_order_acquire);
    if (stamp > newest_stamp) {
      newest = i;
      newest_stamp = stamp;
    }
  }
  std::size_t chosen = newest;
  for (std::size_t i = 0; i < held_slot_count_; ++i)
    if (preferred_pid_ != 0 && held_slots_[i].writer_pid == preferred_pid_ &&
        held_slots_[i].entry->control.sequence.load(std::memory_order_acquire) != observed_[i])
      chosen = i;
  for (std::size_t i = 0; i < held_slot_count_; ++i)
    if (i != chosen && i != newest)
      observed_[i] = held_slots_[i].entry->control.sequence.load(std::memory_order_acquire);
  const slot_blocks::Found& slot = held_slots_[chosen];
  if (!grow_copies(slot.capacity)) return held_;
  std::uint32_t bytes = 0;
  SlotControl& control = slot.entry->control;
  const std::uint32_t seen = observed_[chosen];
  slot::Read read =
      slot::read(control, slot.payload, slot.capacity, spare_.get(), observed_[chosen], bytes);
  // Met mid-update for the first time (a writer killed in it is waited for once).
  if (read == slot::Read::kTorn && waits_if_behind_ && observed_[chosen] != seen &&
      apart_by_more_than(control.stamp_ns.load(std::memory_order_acquire), held_stamp_ns_,
                         kStaleCopyNs)) {
    const slot::Watch watch{&control, observed_[chosen]};
    slot::wait({&watch, 1}, kTornWaitNs);
    read = slot::read(control, slot.payload, slot.capacity, spare_.get(), observed_[chosen], bytes);
  }
  if (read != slot::Read::kCopied) return held_;
  // Checked after the copy: the writer cannot change what was checked.
  const char* field = "";
  const PayloadError error = check_payload(spare_.get(), bytes, kind_, &field);
  if (error != PayloadError::kNone) {
    report_refusal(spare_.get(), bytes, field, describe(error));
    return held_;
  }
  copy_.swap(spare_);
  held_ = copy_.get();
  held_bytes_ = bytes;
  held_stamp_ns_ = static_cast<const PayloadHeader*>(held_)->publish_stamp_ns;  // checked
  updated_ = true;
  return held_;
}

std::optional<SlotActivity> slot_activity(const ChannelId& channel, PayloadKind kind) {
  if (!is_slot_kind(kind)) return std::nullopt;
  slot_blocks::Directory& directory = slot_blocks::directory(kind);
  directory.watch();
  directory.refresh(false);
  return directory.activity(channel.to_string());
}

void release_gone_slot_writers() noexcept {
  slot_blocks::refresh_all();
}

void RawLatestReader::report_refusal(const void* payload, std::uint32_t bytes, const char* field,
                                     const char* problem) noexcept {
  // Said once per reader: a foreign writer publishes at its own rate.
  if (refused_++ > 0) return;
  PayloadHeader header{};
  if (bytes >= sizeof header) std::memcpy(&header, payload, sizeof header);
  std::fprintf(stderr,
               "afhub: refused a payload on %s/%s/%s from pid %u (layout id %016llx, this "
               "build %016llx): %s: %s (said once per reader)\n",
               channel_.service.c_str(), channel_.instance.c_str(), channel_.event.c_str(),
               header.publisher_pid, static_cast<unsigned long long>(header.layout_id),
               static_cast<unsigned long long>(kLayoutId), field, problem);
}

}  // namespace afhub
