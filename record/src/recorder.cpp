#include "afhub/record/recorder.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <ctime>
#include <exception>
#include <mutex>
#include <set>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/record/mcap_writer.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/world.hpp"
#include "record_queue.hpp"
#include "recorded_payloads.hpp"

namespace afhub::mcap {

namespace {

constexpr std::int64_t kDiscoveryPeriodNs = 250'000'000;  // new bodies join within this
constexpr std::int64_t kProgressPeriodNs = 500'000'000;
constexpr std::int64_t kIdleWaitNs = 2'000'000;  // no world state: sampled this often
constexpr int kWriterNice = 10;
constexpr std::int64_t kChunkFlushPeriodNs = 1'000'000'000;  // what a kill -9 loses at most

std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// A channel of the hub and its channel in the file.
struct Recorded {
  std::unique_ptr<RawLatestReader> reader;
  std::uint16_t channel_id = 0;
  bool per_step = false;  // a state: one message per step (a paused physics republishes it)
  bool seen = false;
  std::uint32_t publisher_pid = 0;
  std::uint64_t last = 0;  // its last step (per_step) or sequence
};

// A channel the reading loop has numbered, for the writing thread to add to the file.
struct Declared {
  std::uint16_t id;
  RecordedPayload payload;
  std::string topic;
  Metadata metadata;
};

class Session {
 public:
  Session(const RecordOptions& options)
      : options_(options),
        writer_(options.output, {options.profile, "afhub", options.compression}),
        queue_(options.buffer_bytes),
        realtime_offset_ns_(realtime_ns() - monotonic_ns()) {
    for (const RecordedPayload& payload : recorded_payloads())
      schema_ids_[payload.kind] = writer_.add_schema(payload.schema_name, kLayoutSchemaEncoding,
                                                     payload_schema_text(payload));
    writer_.add_metadata("afhub", recording_metadata());
  }

  RecordProgress run(const std::function<bool()>& keep_going,
                     const std::function<void(const RecordProgress&)>& progress) {
    std::thread writing([this] {
      // Compression gives way to the physics and to the reading loop.
      setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kWriterNice);
      write_loop();
    });
    try {
      read_loop(keep_going, progress);
    } catch (...) {
      reading_done_ = true;
      writing.join();
      throw;
    }
    reading_done_ = true;
    writing.join();
    if (write_error_) std::rethrow_exception(write_error_);
    const RecordProgress last = snapshot();
    progress(last);
    return last;
  }

 private:
  void read_loop(const std::function<bool()>& keep_going,
                 const std::function<void(const RecordProgress&)>& progress) {
    apply_realtime(options_.loop, "afhub record");
    LatestReader<WorldState> world(
        ChannelId{std::string(kService), world_instance(), std::string(kStateEvent)});
    SampleWaiter waiter;
    waiter.attach(world.raw());
    const auto world_channel = [](std::string_view event) {
      return ChannelId{std::string(kService), world_instance(), std::string(event)};
    };
    // The world's clock, and what a viewer draws (the scene once, every body's pose at
    // display rate): what `afhub play` needs to replay a run into `afhub view`.
    add(world_channel(kStateEvent), PayloadKind::kWorldState, {});
    add(world_channel(kSceneEvent), PayloadKind::kSceneDescription, {});
    add(world_channel(kScenePosesEvent), PayloadKind::kScenePoses, {});

    std::int64_t next_discovery_ns = 0, next_progress_ns = monotonic_ns() + kProgressPeriodNs;
    while (keep_going() && !write_failed_) {
      waiter.wait(kIdleWaitNs);
      const std::int64_t now = monotonic_ns();
      if (now >= next_discovery_ns) {
        discover(waiter);
        next_discovery_ns = now + kDiscoveryPeriodNs;
      }
      world.latest();  // taken, so that the waiter sleeps until the next step
      for (Recorded& recorded : recorded_) {
        const void* payload = recorded.reader->latest();
        if (payload && recorded.reader->updated())
          sample(recorded, payload, recorded.reader->latest_bytes(), now);
      }
      if (now >= next_progress_ns) {
        progress(snapshot());
        next_progress_ns = now + kProgressPeriodNs;
      }
      if (options_.duration_s > 0.0 && first_sample_ns_ != 0 &&
          now - first_sample_ns_ >= static_cast<std::int64_t>(options_.duration_s * 1e9))
        break;
    }
  }

  // Copies a new sample into the buffer, or counts it dropped when the buffer is full.
  // Its log time is when it was read (`now_ns`): the file's order, which play follows;
  // its publish time the writer's stamp.
  void sample(Recorded& recorded, const void* payload, std::uint32_t bytes,
              std::int64_t now_ns) noexcept {
    const auto& header = *static_cast<const PayloadHeader*>(payload);
    const std::uint64_t key = recorded.per_step ? header.sim_step : header.sequence;
    const bool same_writer = recorded.seen && recorded.publisher_pid == header.publisher_pid;
    if (same_writer && key == recorded.last) return;  // a paused physics' step again
    if (same_writer && key > recorded.last + 1) missed_ += key - recorded.last - 1;
    recorded.seen = true;
    recorded.publisher_pid = header.publisher_pid;
    recorded.last = key;
    if (first_sample_ns_ == 0) first_sample_ns_ = now_ns;
    QueuedMessage message;
    message.channel_id = recorded.channel_id;
    message.sequence = static_cast<std::uint32_t>(key);
    message.publish_time_ns =
        static_cast<std::uint64_t>(header.publish_stamp_ns + realtime_offset_ns_);
    message.log_time_ns = static_cast<std::uint64_t>(now_ns + realtime_offset_ns_);
    if (!queue_.push(message, {static_cast<const std::uint8_t*>(payload), bytes})) ++dropped_;
  }

  // Readers for the catalog's bodies (and devices) that match and are not recorded yet.
  void discover(SampleWaiter& waiter) {
    if (!catalog_) catalog_ = std::make_unique<CatalogReader>();
    const BodyList& list = catalog_->latest();
    for (std::uint32_t i = 0; i < list.body_count; ++i) {
      const BodyEntry entry = entry_of(list, i);
      const std::string channel(name_of(entry.info.channel));
      const bool device = entry.info.kind == ChannelKind::kDevice;
      if (device ? !options_.devices : !matches_any(channel, options_.body_globs)) continue;
      if (!known_.insert(channel).second) continue;
      std::string joints;
      for (const std::string& joint : entry.joint_names)
        joints += (joints.empty() ? "" : ",") + joint;
      const Metadata metadata = device ? Metadata{} : Metadata{{"joint_names", joints}};
      Recorded& state = add(body_state_channel(channel),
                            device ? PayloadKind::kDeviceState : PayloadKind::kBodyState, metadata);
      // A device publishes at its own rate, not the physics': its updates wake the loop.
      if (device) waiter.attach(*state.reader);
      // A command can be overwritten by the next before the next step: its writes wake
      // the loop too (a lockstep client's, answering each step, are all read so).
      if (device || options_.commands)
        waiter.attach(*add(body_command_channel(channel),
                           device ? PayloadKind::kDeviceCommand : PayloadKind::kBodyCommand,
                           metadata)
                           .reader);
    }
  }

  // A channel recorded from now on; its topic is "/<instance>/<event>", and its
  // metadata name the hub's channel, for `afhub play`.
  Recorded& add(const ChannelId& id, PayloadKind kind, Metadata metadata) {
    metadata["afhub_instance"] = id.instance;
    metadata["afhub_event"] = id.event;
    Recorded recorded;
    recorded.reader = std::make_unique<RawLatestReader>(id, kind);
    recorded.channel_id = declare(payload_of(kind), "/" + id.instance + "/" + id.event, metadata);
    recorded.per_step = kind == PayloadKind::kBodyState || kind == PayloadKind::kWorldState;
    return recorded_.emplace_back(std::move(recorded));
  }

  std::uint16_t declare(const RecordedPayload& payload, const std::string& topic,
                        const Metadata& metadata) {
    if (next_channel_id_ == 0xFFFF) throw Error("an MCAP file holds at most 65535 channels");
    const std::lock_guard lock(declared_mutex_);
    declared_.push_back({next_channel_id_, payload, topic, metadata});
    channel_count_ = next_channel_id_;
    return next_channel_id_++;
  }

  // The writing thread: declared channels, then the buffer's messages, into the file.
  void write_loop() {
    try {
      std::int64_t next_flush_ns = monotonic_ns() + kChunkFlushPeriodNs;
      while (true) {
        const bool last_round = reading_done_;
        add_declared();
        const std::size_t taken = queue_.drain([&](const QueuedMessage& m, auto data) {
          if (m.channel_id > file_channels_) add_declared();  // declared after the first call
          writer_.write({m.channel_id, m.sequence, m.log_time_ns, m.publish_time_ns, data});
        });
        messages_written_ = writer_.message_count();
        file_bytes_ = writer_.file_bytes();
        if (last_round) break;
        if (monotonic_ns() >= next_flush_ns) {
          writer_.flush_chunk();
          next_flush_ns = monotonic_ns() + kChunkFlushPeriodNs;
        }
        if (taken == 0) usleep(1000);
      }
      writer_.close();
      file_bytes_ = writer_.file_bytes();
    } catch (...) {
      write_error_ = std::current_exception();
      write_failed_ = true;
    }
  }

  void add_declared() {
    const std::lock_guard lock(declared_mutex_);
    for (const Declared& d : declared_) {
      writer_.add_channel(schema_ids_.at(d.payload.kind), d.topic, kPayloadEncoding, d.metadata);
      file_channels_ = d.id;
    }
    declared_.clear();
  }

  Metadata recording_metadata() const {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    char started[64];
    const std::time_t now = std::time(nullptr);
    std::strftime(started, sizeof started, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    return {{"layout_id", layout_id_text()},
            {"host", host},
            {"started", started},
            {"bodies", [&] {
               std::string globs;
               for (const auto& g : options_.body_globs) globs += (globs.empty() ? "" : " ") + g;
               return globs;
             }()}};
  }

  RecordProgress snapshot() const {
    RecordProgress p;
    p.seconds =
        first_sample_ns_ ? static_cast<double>(monotonic_ns() - first_sample_ns_) * 1e-9 : 0;
    p.channels = channel_count_;
    p.messages = messages_written_;
    p.file_bytes = file_bytes_;
    p.dropped = dropped_;
    p.missed = missed_;
    p.buffered_bytes = queue_.waiting_bytes();
    return p;
  }

  const RecordOptions& options_;
  Writer writer_;
  RecordQueue queue_;
  const std::int64_t realtime_offset_ns_;
  std::map<PayloadKind, std::uint16_t> schema_ids_;

  // The reading loop's.
  std::unique_ptr<CatalogReader> catalog_;
  std::vector<Recorded> recorded_;
  std::set<std::string> known_;
  std::uint16_t next_channel_id_ = 1;
  std::atomic<std::int64_t> first_sample_ns_{0};
  std::atomic<std::uint64_t> dropped_{0}, missed_{0}, channel_count_{0};

  // Between the two threads.
  std::mutex declared_mutex_;
  std::vector<Declared> declared_;
  std::atomic<bool> reading_done_{false}, write_failed_{false};
  std::exception_ptr write_error_;

  // The writing thread's.
  std::uint16_t file_channels_ = 0;
  std::atomic<std::uint64_t> messages_written_{0}, file_bytes_{0};
};

}  // namespace

RecordProgress record(const RecordOptions& options, const std::function<bool()>& keep_going,
                      const std::function<void(const RecordProgress&)>& progress) {
  if (!options.profile.empty())
    throw Error("--profile " + options.profile +
                ": not written yet; afhub records its own payloads (no --profile)");
  Session session(options);
  return session.run(keep_going, progress);
}

}  // namespace afhub::mcap
