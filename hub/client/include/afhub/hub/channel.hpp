// Zero-copy channel ends with latest-value semantics.
//   Writer<T>: loan a chunk in shared memory, fill it in place, publish it.
//   LatestReader<T>: read the newest valid sample in place; older ones are dropped.
// A late joiner receives the last published sample at once, or, on a state channel
// (published every period), the next one: see History.
// loan(), publish() and latest() are real-time safe: no heap, no exceptions.
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/payload_check.hpp"

namespace afhub {

// What a writer keeps for readers that subscribe after it published.
//   kKeepLast: the last sample, handed to a late joiner at once.
//   kNone: nothing; a late joiner gets the next sample. For channels written every
//     period (body and world state): a publish then costs about half as much in
//     iceoryx 2.0.3 (no history chunk to swap), and a reader waits at most a period.
enum class History { kKeepLast, kNone };

// Body and world state keep no history; every other kind keeps the last sample.
// Writers and readers both follow it, so a reader never asks for a history the
// writer does not keep (RouDi would log a warning on every such subscribe).
constexpr History history_of(PayloadKind kind) {
  return kind == PayloadKind::kBodyState || kind == PayloadKind::kWorldState ? History::kNone
                                                                             : History::kKeepLast;
}

// Untyped ends; the typed templates below are what code uses.
class RawWriter {
 public:
  RawWriter(const ChannelId& channel, PayloadKind kind)
      : RawWriter(channel, kind, history_of(kind)) {}
  RawWriter(const ChannelId& channel, PayloadKind kind, History history);
  ~RawWriter();
  RawWriter(const RawWriter&) = delete;
  RawWriter& operator=(const RawWriter&) = delete;

  // A chunk of `bytes` bytes, or nullptr when shared memory is exhausted.
  void* loan(std::uint32_t bytes) noexcept;
  // Stamps the header (layout, kind, pid, sequence, monotonic time) and publishes.
  // The caller sets header.sim_step and header.sim_time_s. Returns the stamp.
  std::int64_t publish(void* payload) noexcept;

  const ChannelId& channel() const { return channel_; }
  // Whether any reader is subscribed now: each one costs every publish.
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
  std::unique_ptr<Port> port_;
};

class RawLatestReader {
 public:
  RawLatestReader(const ChannelId& channel, PayloadKind kind);
  ~RawLatestReader();
  RawLatestReader(const RawLatestReader&) = delete;
  RawLatestReader& operator=(const RawLatestReader&) = delete;

  // The newest valid payload, or nullptr before the first one. It stays valid
  // and unchanged until the next call. Invalid payloads are refused and counted.
  const void* latest() noexcept;
  // Whether the last latest() call found a sample newer than the one before.
  bool updated() const { return updated_; }
  // The size in bytes of the payload latest() returned.
  std::uint32_t latest_bytes() const { return held_bytes_; }
  std::uint64_t refused_count() const { return refused_; }
  const ChannelId& channel() const { return channel_; }
  // A reader starts subscribed. Every subscribed reader costs the writer on each
  // publish, so one that looks only now and then can step aside in between; what
  // latest() holds stays valid.
  void subscribe() noexcept;
  void unsubscribe() noexcept;
  // Connected to the writer: every sample published from now on reaches this reader.
  bool subscribed() const noexcept;

 private:
  friend class SampleWaiter;  // waits on the port's subscriber
  struct Port;
  void report_refusal(const void* payload, PayloadError error, const char* field) noexcept;
  ChannelId channel_;
  PayloadKind kind_;
  const void* held_ = nullptr;
  const void* retired_ = nullptr;  // replaced by held_, released on the next call
  std::uint32_t held_bytes_ = 0;
  bool updated_ = false;
  std::uint64_t refused_ = 0;
  std::unique_ptr<Port> port_;
};

template <class T>
class Writer {
 public:
  explicit Writer(const ChannelId& channel, History history = history_of(T::kKind))
      : raw_(channel, T::kKind, history) {}
  // A default-initialised payload in shared memory, or nullptr when memory is exhausted.
  T* loan() noexcept { return loan(sizeof(T)); }
  // The first `bytes` bytes of a default-initialised payload: for payloads sent at
  // their real size (body_state_bytes, body_command_bytes), whose entries past their
  // count are not in the chunk. `bytes` is at most sizeof(T).
  T* loan(std::size_t bytes) noexcept {
    static const T kDefault{};  // static storage: no heap, made on the first loan
    void* chunk = raw_.loan(static_cast<std::uint32_t>(bytes));
    if (!chunk) return nullptr;
    std::memcpy(chunk, &kDefault, bytes);
    return static_cast<T*>(chunk);
  }
  void publish(T* payload) noexcept { raw_.publish(payload); }
  RawWriter& raw() { return raw_; }
  const RawWriter& raw() const { return raw_; }

 private:
  RawWriter raw_;
};

template <class T>
class LatestReader {
 public:
  explicit LatestReader(const ChannelId& channel) : raw_(channel, T::kKind) {}
  const T* latest() noexcept { return static_cast<const T*>(raw_.latest()); }
  bool updated() const { return raw_.updated(); }
  RawLatestReader& raw() { return raw_; }

 private:
  RawLatestReader raw_;
};

}  // namespace afhub
