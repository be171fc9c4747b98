#include "afhub/record/recorder.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/device_tape.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/record/mcap_writer.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/world.hpp"
#include "beside_physics.hpp"
#include "record_queue.hpp"
#include "recorded_payloads.hpp"
#include "ros2_messages.hpp"
#include "sha256.hpp"

namespace afhub::mcap {

namespace {

constexpr std::int64_t kDiscoveryPeriodNs = 250'000'000;  // new bodies join within this
constexpr std::int64_t kProgressPeriodNs = 500'000'000;
constexpr std::int64_t kIdleWaitNs = 2'000'000;  // no world state: sampled this often
constexpr int kWriterNice = 10;
// A chunk of the file: every chunk's index names each channel in it (10 bytes, and a
// message index record of 15 bytes), so that at a thousand bodies 1 MiB chunks (570 a
// second) made the summary 5 % of the file; chunks still reach it at least once a
// second (kChunkFlushPeriodNs).
constexpr std::size_t kChunkBytes = 4u << 20;
constexpr std::int64_t kChunkFlushPeriodNs = 1'000'000'000;  // what a kill -9 loses at most
// An idle writing thread looks for messages this often: each wake-up is a context switch
// on a core a real-time loop may want (the reading loop hands them over every 4 ms).
constexpr useconds_t kWriterIdleUs = 5'000;
// A body the physics' step tape brought within this long is read from the tape alone.
constexpr std::int64_t kTapeFreshNs = 100'000'000;
// A physics whose tape brought nothing for this long is taken for stopped or gone: its
// bodies' commands are read from their slots again (see on_tape_only).
constexpr std::int64_t kTapeStalledNs = 2'000'000'000;
// While a tape comes, it is read every quarter of the time its ring holds at 1 kHz, and
// at least this often: 4 ms up to 18 parts a step (a thousand 8-joint bodies take 17),
// less for larger worlds.
constexpr std::int64_t kTapePollNs = 4'000'000;

std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// "sha256 <64 hex digits>, 5678 bytes" of a file, or why it could not be read.
std::string file_fingerprint(const char* path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  if (!in.eof() && !in) return std::string("unreadable: ") + std::strerror(errno);
  return "sha256 " + sha256_hex(bytes) + ", " + std::to_string(bytes.size()) + " bytes";
}

// A channel of the hub and its channel in the file.
struct Recorded {
  std::unique_ptr<RawLatestReader> reader;
  std::uint16_t channel_id = 0;
  bool per_step = false;  // a state: one message per step (a paused physics republishes it)
  bool wakes = false;     // its updates wake the reading loop
  bool once = false;      // published once (the scene): never dropped, retried
  bool retry = false;     // its last sample found the buffer full
  bool seen = false;
  std::uint32_t publisher_pid = 0;
  std::uint64_t last = 0;          // its last step (per_step) or sequence
  std::int64_t last_stamp_ns = 0;  // its last publish stamp: a writer's own clock, always newer
  PayloadKind kind{};
  std::string body;  // what the step tape names it: a body's channel, the world's instance
  // A body's command: the index in recorded_ of its body's state (none before it is
  // taken), so that the reading loop's turn looks up no name.
  std::size_t body_state = ~std::size_t{0};
  std::int64_t taped_ns = 0;  // when the step tape last brought it
  // A command: the physics takes those after its last one, if any, in steps after
  // taken_after_step (the step the tape brought it at, or its body's state's step when
  // it was read from its slot; none when that state was not seen).
  std::optional<std::uint64_t> taken_after_step;
  // A gap before a command read from its slot: whether the physics took any of it is
  // known only from the tape after the read (the physics may have stepped between the
  // recorder's last look at the tape and the read). Counted when the tape brings that
  // command, when a later one comes, or at the end (settle_slot_gap).
  struct SlotGap {
    std::uint64_t count = 0;
    std::uint64_t from = 0;                   // the sequence before the gap
    std::optional<std::uint64_t> after_step;  // the taken_after_step and tape_breaks of
    std::uint64_t tape_breaks = 0;            // the command before the gap
    bool gap_taken = false;                   // the tape brought one of the gap
  };
  std::optional<SlotGap> slot_gap;
  // A state: the step its run on the tape began at. Both counted in tape breaks
  // (tape_breaks: the count then): a run ends at a break.
  std::uint64_t taped_from_step = 0;
  std::uint64_t tape_breaks = 0;
  // A device's state: its tape (every cycle, and the commands its driver took), and the
  // index in recorded_ of its command's channel (none before it is taken).
  std::unique_ptr<DeviceTapeReader> device_tape;
  std::size_t device_command = ~std::size_t{0};
  // A device's command: its device's tape's lost() when it last brought one (none before).
  std::optional<std::uint64_t> tape_lost;
};

// A channel the reading loop has numbered, for the writing thread to add to the file.
struct Declared {
  std::uint16_t id;
  RecordedPayload payload;
  std::string topic;
  Metadata metadata;
};

class Session;
// Makes a session the one a hub loss finishes, for its lifetime.
struct ActiveSession {
  explicit ActiveSession(Session* session);
  ~ActiveSession();
  ActiveSession(const ActiveSession&) = delete;
  ActiveSession& operator=(const ActiveSession&) = delete;
};

class Session {
 public:
  Session(const RecordOptions& options)
      : options_(options),
        ros2_(options.profile == "ros2"),
        writer_(options.output, {options.profile, "afhub", options.compression, kChunkBytes, true}),
        queue_(options.buffer_bytes),
        realtime_offset_ns_(realtime_ns() - monotonic_ns()) {
    if (ros2_) {
      for (const Ros2Schema& schema : ros2_schemas())
        ros2_schema_ids_.push_back(
            writer_.add_schema(schema.name, "ros2msg",
                               {reinterpret_cast<const std::uint8_t*>(schema.definition.data()),
                                schema.definition.size()}));
    } else {
      for (const RecordedPayload& payload : recorded_payloads())
        schema_ids_[payload.kind] = writer_.add_schema(payload.schema_name, kLayoutSchemaEncoding,
                                                       payload_schema_text(payload));
    }
    writer_.add_metadata("afhub", recording_metadata());
  }

  RecordProgress run(const std::function<bool()>& keep_going,
                     const std::function<void(const RecordProgress&)>& progress) {
    const ActiveSession active(this);
    std::thread writing([this] {
      // Compression gives way to the physics and to the reading loop.
      setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kWriterNice);
      write_loop();
    });
    // The catalog is read, readers made and progress told beside the reading loop:
    // never in its way.
    std::thread discovering([this, &progress] { discover_loop(progress); });
    try {
      read_loop(keep_going);
    } catch (...) {
      reading_done_ = true;
      discovering.join();
      writing.join();
      throw;
    }
    reading_done_ = true;
    discovering.join();
    writing.join();
    if (write_error_) std::rethrow_exception(write_error_);
    if (discover_error_) std::rethrow_exception(discover_error_);
    const RecordProgress last = snapshot();
    progress(last);
    return last;
  }

 private:
  void read_loop(const std::function<bool()>& keep_going) {
    apply_realtime(options_.loop, "afhub record");
    beside_.start(options_.loop.cpu < 0 && options_.loop.fifo_priority <= 0);
    LatestReader<WorldState> world(
        ChannelId{std::string(kService), world_instance(), std::string(kStateEvent)});
    // Every step's states, kept a while: what a late wake-up would miss in the states' slots.
    StepTapeReader tape(world_instance());
    const auto taped = std::make_unique<StepTape>();
    // The loop sleeps on the slots of the world state and of the channels that wake it;
    // while a step tape comes, for kTapePollNs at most and only on the slots of devices
    // whose own tape does not come (on none when every device's does): a reader asleep
    // on a slot costs its writer a futex wake (an interrupt to the sleeper's core) every
    // update, which put the physics' step p99 at 1.5 to 5x without the recorder on the
    // 2-core VM.
    SampleWaiter waiter, untaped_waiter;
    bool devices_taped = false;  // every device's updates come on its tape
    waiter.attach(world.raw());
    const std::int64_t start_ns = monotonic_ns();
    std::int64_t taped_ns = 0;  // when a tape part last came
    std::int64_t tape_poll_ns = kTapePollNs;
    std::int64_t now = start_ns;
    while (keep_going() && !write_failed_ && !discover_failed_) {
      if (taped_ns == 0 || now - taped_ns >= kTapeFreshNs)
        waiter.wait(kIdleWaitNs);
      else if (devices_taped)
        sleep_until_ns(now + tape_poll_ns);
      else
        untaped_waiter.wait(tape_poll_ns);
      now = monotonic_ns();
      beside_.turned();
      take_discovered(waiter, untaped_waiter);
      // Taken, so that the waiter sleeps until the next step.
      const WorldState* world_state = world.latest();
      paused_at_step_ = world_state && world_state->paused
                            ? std::optional(world_state->header.sim_step)
                            : std::nullopt;
      for (std::uint32_t drained = 1; tape.next(*taped); ++drained) {
        beside_.follow(taped->header.publisher_pid, drained);
        sample_tape(*taped, now);
        taped_ns = now;
        if (taped->last_part)
          tape_poll_ns = std::min<std::int64_t>(
              kTapePollNs, kStepTapeRingParts * 1'000'000LL / 4 / (taped->part + 1));
      }
      for (Recorded& recorded : recorded_)
        if (recorded.device_tape) sample_device_tape(recorded, now);
      devices_taped = true;
      for (Recorded& recorded : recorded_) {
        const bool fresh = (recorded.taped_ns != 0 && now - recorded.taped_ns < kTapeFreshNs) ||
                           (now - taped_ns < kTapeStalledNs && on_tape_only(recorded));
        if (recorded.wakes && recorded.body.empty() && !fresh) devices_taped = false;
        if (fresh) {
          // Read from a tape; a reader that wakes the loop is still taken, or the
          // waiter would find its update new at every wait and never sleep. A state's
          // reader holds its slot, a restarted physics' too: a physics tapes only the
          // bodies whose state someone holds.
          if (recorded.wakes)
            recorded.reader->latest();
          else
            recorded.reader->hold_writers();
          continue;
        }
        const void* payload = recorded.reader->latest();
        if (payload && (recorded.reader->updated() || recorded.retry))
          sample(recorded, payload, recorded.reader->latest_bytes(), now);
      }
      // The duration counts from the first message, or from the start while none came
      // (or from an earlier file's first message: duration_from_ns).
      const std::int64_t since = options_.duration_from_ns != 0 ? options_.duration_from_ns
                                 : first_sample_ns_ != 0        ? first_sample_ns_.load()
                                                                : start_ns;
      if (options_.duration_s > 0.0 &&
          now - since >= static_cast<std::int64_t>(options_.duration_s * 1e9))
        break;
    }
    for (Recorded& recorded : recorded_)
      if (recorded.slot_gap) settle_slot_gap(recorded, std::nullopt);
  }

  // Channels the discovery found, taken when its lock is free (never waited for). A
  // device's state and every command wake the loop too: a device publishes at its own
  // rate, and a command can be overwritten by the next before the next step.
  void take_discovered(SampleWaiter& waiter, SampleWaiter& untaped_waiter) {
    if (!discovered_ready_.load(std::memory_order_acquire)) return;
    std::unique_lock lock(discovered_mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    for (Recorded& recorded : discovered_) {
      if (recorded.wakes) waiter.attach(*recorded.reader);
      if (recorded.wakes && recorded.body.empty()) untaped_waiter.attach(*recorded.reader);
      if (!recorded.body.empty()) link_body(recorded, recorded_.size());
      // A device's command is added right after its state (discover()).
      if (recorded.kind == PayloadKind::kDeviceCommand && !recorded_.empty() &&
          recorded_.back().kind == PayloadKind::kDeviceState)
        recorded_.back().device_command = recorded_.size();
      recorded_.push_back(std::move(recorded));
    }
    std::fill(tape_order_.begin(), tape_order_.end(), TapePosition{});  // a new one may be taped
    discovered_.clear();
    discovered_ready_.store(false, std::memory_order_release);
  }

  // The cycles a device's tape brought since the last look (checked by its reader): its
  // states, and the commands its driver took. A gap in those commands, with no cycle
  // lost between, is commands the driver never took (their writer replaced them first).
  void sample_device_tape(Recorded& state, std::int64_t now_ns) noexcept {
    Recorded* command =
        state.device_command < recorded_.size() ? &recorded_[state.device_command] : nullptr;
    while (state.device_tape->next(*device_cycle_)) {
      state.taped_ns = now_ns;
      sample(state, &device_cycle_->state, sizeof(DeviceState), now_ns);
      if (!command) continue;
      command->taped_ns = now_ns;
      if (!device_cycle_->has_command) continue;
      const std::uint64_t lost = state.device_tape->lost();
      sample(*command, &device_cycle_->command, sizeof(DeviceCommand), now_ns, std::nullopt,
             command->tape_lost == lost);
      command->tape_lost = lost;
    }
  }

  // The states and commands of a step tape's part, each checked as what it is (the
  // part is this process's copy), for the channels recorded.
  void sample_tape(const StepTape& tape, std::int64_t now_ns) noexcept {
    follow_tape(tape);
    std::size_t position = tape.first_entry;
    for_each_tape_entry(tape, [&](PayloadKind kind, std::string_view body, const void* payload,
                                  std::uint32_t bytes) {
      const std::size_t index = recorded_index(kind, body, position++);
      if (index >= recorded_.size()) return;               // not recorded, or not discovered yet
      const bool state = kind == PayloadKind::kBodyState;  // packed
      if ((state ? check_packed_body_state(payload, bytes) : check_payload(payload, bytes, kind)) !=
          PayloadError::kNone) {
        ++tape_breaks_;
        return;
      }
      Recorded& recorded = recorded_[index];
      if (state && (recorded.taped_ns == 0 || recorded.tape_breaks != tape_breaks_)) {
        recorded.taped_from_step = tape.header.sim_step;
        recorded.tape_breaks = tape_breaks_;
      }
      recorded.taped_ns = now_ns;
      if (state && ros2_) {  // its encoders read whole states
        const auto packed = std::span(static_cast<const std::uint8_t*>(payload), bytes);
        bytes = static_cast<std::uint32_t>(unpack_body_state(packed, *unpacked_));
        payload = unpacked_.get();
      }
      sample(recorded, payload, bytes, now_ns, tape.header.sim_step);
    });
  }

  // Counts a break in the tape: parts its ring lost (a reader further behind than it
  // holds), a step the physics cut short, a world reset. A command missing across one
  // may be the recorder's loss, not one its controller replaced.
  void follow_tape(const StepTape& tape) noexcept {
    const bool continues = tape_next_part_ == 0
                               ? tape.part == 0 && tape.header.sim_step == tape_step_ + 1
                               : tape.part == tape_next_part_ && tape.header.sim_step == tape_step_;
    if (tape_seen_ && !continues) ++tape_breaks_;
    tape_seen_ = true;
    tape_step_ = tape.header.sim_step;
    tape_next_part_ = tape.last_part ? 0 : tape.part + 1;
  }

  // The index in recorded_ of a tape's entry at `position` in its step (kNotRecorded
  // when none). A physics tapes its bodies in the same order every step (a command only
  // when it took one): what was at this position the step before is tried first, and
  // the map searched only when it was another entry.
  static constexpr std::size_t kUnknown = ~std::size_t{0}, kNotRecorded = kUnknown - 1;
  struct TapePosition {
    std::size_t index = kUnknown;
    PayloadKind kind{};
    std::uint64_t name_hash = 0;  // of a name not recorded
  };
  static std::uint64_t name_hash(std::string_view name) noexcept {
    std::uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a
    for (const char c : name) hash = (hash ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
    return hash;
  }
  std::size_t recorded_index(PayloadKind kind, std::string_view body,
                             std::size_t position) noexcept {
    if (position >= tape_order_.size()) return kNotRecorded;  // more than a world tapes
    TapePosition& cached = tape_order_[position];
    if (cached.kind == kind) {
      if (cached.index == kNotRecorded && cached.name_hash == name_hash(body)) return kNotRecorded;
      if (cached.index < recorded_.size() && recorded_[cached.index].body == body)
        return cached.index;
    }
    const auto& by_body = by_body_[tape_kind_index(kind)];
    const auto found = by_body.find(body);
    cached = {found == by_body.end() ? kNotRecorded : found->second, kind,
              found == by_body.end() ? name_hash(body) : 0};
    return cached.index;
  }

  // Copies a new sample into the buffer, or counts it dropped when the buffer is full.
  // Its log time is when it was read (`now_ns`): the file's order, which play follows;
  // its publish time the writer's stamp. `tape_step`: it came from a physics' step tape,
  // in that step. `gap_replaced`: a gap before it is commands never taken, not missed.
  void sample(Recorded& recorded, const void* payload, std::uint32_t bytes, std::int64_t now_ns,
              std::optional<std::uint64_t> tape_step = std::nullopt,
              bool gap_replaced = false) noexcept {
    PayloadHeader header;
    std::memcpy(&header, payload, sizeof header);  // checked by the reader: at least a header
    const std::uint64_t key = recorded.per_step ? header.sim_step : header.sequence;
    const bool same_writer = recorded.seen && recorded.publisher_pid == header.publisher_pid;
    // A paused physics' step again, or an update its tape brings after its slot did (or
    // the other way round). A world reset starts the steps again: that is recorded.
    if (same_writer &&
        (key == recorded.last || header.publish_stamp_ns <= recorded.last_stamp_ns)) {
      // The last one, read from its slot, now on the tape: the physics took it then.
      if (tape_step && key == recorded.last && recorded.kind == PayloadKind::kBodyCommand) {
        recorded.taken_after_step = tape_step;
        recorded.tape_breaks = tape_breaks_;
        if (recorded.slot_gap) settle_slot_gap(recorded, tape_step);
      }
      // One of the gap before it: the physics took it, and the file lacks it.
      if (tape_step && recorded.slot_gap && key > recorded.slot_gap->from && key < recorded.last)
        recorded.slot_gap->gap_taken = true;
      return;
    }
    QueuedMessage message;
    message.channel_id = recorded.channel_id;
    message.sequence = static_cast<std::uint32_t>(key);
    message.publish_time_ns =
        static_cast<std::uint64_t>(header.publish_stamp_ns + realtime_offset_ns_);
    message.log_time_ns = static_cast<std::uint64_t>(now_ns + realtime_offset_ns_);
    recorded.retry = false;
    // Packed here as the file holds it (the ROS 2 profile's encoders read whole
    // states): the buffer then holds twice the states, and is copied half as much.
    const std::span<const std::uint8_t> whole(static_cast<const std::uint8_t*>(payload), bytes);
    FilePieces pieces{whole};
    const std::size_t count = ros2_ ? 1 : pieces_for_file(whole, recorded.kind, pieces);
    if (!queue_.push(message, std::span(pieces).first(count))) {
      // Published once (the scene): tried again at the next wake until there is room.
      if (recorded.once) {
        recorded.retry = true;
        return;
      }
      ++dropped_;
    }
    // Commands missing before one the tape brought, in steps the tape covered: the
    // physics never took them (their controller replaced them first). Before one read
    // from its slot: counted later, from the tape.
    const bool command = recorded.kind == PayloadKind::kBodyCommand;
    if (recorded.slot_gap) settle_slot_gap(recorded, tape_step);
    if (same_writer && key > recorded.last + 1) {
      const std::uint64_t gap = key - recorded.last - 1;
      if (command && !tape_step)
        recorded.slot_gap = Recorded::SlotGap{.count = gap,
                                              .from = recorded.last,
                                              .after_step = recorded.taken_after_step,
                                              .tape_breaks = recorded.tape_breaks};
      else
        (gap_replaced || (command && tape_covered_since(recorded, recorded.taken_after_step,
                                                        recorded.tape_breaks, tape_step))
             ? replaced_
             : missed_) += gap;
    }
    if (command) {
      recorded.taken_after_step = tape_step ? tape_step : state_step(recorded);
      recorded.tape_breaks = tape_breaks_;
    }
    recorded.seen = true;
    recorded.publisher_pid = header.publisher_pid;
    recorded.last = key;
    recorded.last_stamp_ns = header.publish_stamp_ns;
    if (first_sample_ns_ == 0) {
      first_sample_ns_ = now_ns;
      // The next image, after a hub loss, spans its duration from here.
      if (options_.duration_from_ns == 0) carry_into_reattach(now_ns);
    }
  }

  // A command to a body on the tape of a physics that is not paused: it comes on the
  // tape when the physics takes it, however late (a physics stopped mid-step tapes the
  // command it took only when it goes on; read_loop stops waiting after
  // kTapeStalledNs). One read from its slot meanwhile may not be taken yet, and may be
  // newer than one the tape has still to bring, which would then be dropped as older.
  bool on_tape_only(const Recorded& command) const noexcept {
    return command.kind == PayloadKind::kBodyCommand && !paused_at_step_ &&
           on_tape_run(state_of(command));
  }

  // Whether a body's state has come on the tape since its last break.
  bool on_tape_run(const Recorded* state) const noexcept {
    return state && state->taped_ns != 0 && state->tape_breaks == tape_breaks_;
  }

  // Whether the tape brought every command the physics took for `command`'s body after
  // one taken after `after_step` (at `breaks` tape breaks): its body's state on the tape
  // since the step after that, with no break. On a step's tape a body's command comes before its
  // state: a run not begun yet begins at `taken_step`, the step the tape brought the
  // next command at. With neither, the physics must be paused at `after_step`.
  bool tape_covered_since(const Recorded& command, std::optional<std::uint64_t> after_step,
                          std::uint64_t breaks,
                          std::optional<std::uint64_t> taken_step) const noexcept {
    if (!after_step || breaks != tape_breaks_) return false;
    const Recorded* state = state_of(command);
    if (on_tape_run(state)) return state->taped_from_step <= *after_step + 1;
    if (taken_step) return *taken_step <= *after_step + 1;
    return paused_at_step_ == after_step;
  }

  // Counts the gap before a command read from its slot, replaced when the tape brought
  // none of it and covered the steps since the command before it (see SlotGap).
  // `taken_step`: the tape brought the command read, or a later one, at that step.
  void settle_slot_gap(Recorded& command, std::optional<std::uint64_t> taken_step) noexcept {
    const Recorded::SlotGap& gap = *command.slot_gap;
    (!gap.gap_taken && tape_covered_since(command, gap.after_step, gap.tape_breaks, taken_step)
         ? replaced_
         : missed_) += gap.count;
    command.slot_gap.reset();
  }

  // The last step of `command`'s body's state the recorder read (none before the first):
  // a command read from its slot after it is taken, if at all, in a later step.
  std::optional<std::uint64_t> state_step(const Recorded& command) const noexcept {
    const Recorded* state = state_of(command);
    if (!state || !state->seen) return std::nullopt;
    return state->last;
  }

  const Recorded* state_of(const Recorded& command) const noexcept {
    return command.body_state < recorded_.size() ? &recorded_[command.body_state] : nullptr;
  }

  // Indexes a taped channel about to be recorded_[index] by its body, and links a body's
  // command and state, whichever comes first.
  void link_body(Recorded& recorded, std::size_t index) {
    if (!by_body_[tape_kind_index(recorded.kind)].emplace(recorded.body, index).second) return;
    const bool state = recorded.kind == PayloadKind::kBodyState;
    if (!state && recorded.kind != PayloadKind::kBodyCommand) return;
    const auto& other =
        by_body_[tape_kind_index(state ? PayloadKind::kBodyCommand : PayloadKind::kBodyState)];
    const auto found = other.find(recorded.body);
    if (found == other.end()) return;
    if (state)
      recorded_[found->second].body_state = index;
    else
      recorded.body_state = found->second;
  }

  void discover_loop(const std::function<void(const RecordProgress&)>& progress) {
    try {
      // The world's clock, and what a viewer draws (the scene once, every body's pose at
      // display rate): what `afhub play` needs to replay a run into `afhub view`.
      const auto world_channel = [](std::string_view event) {
        return ChannelId{std::string(kService), world_instance(), std::string(event)};
      };
      add(world_channel(kStateEvent), PayloadKind::kWorldState, {}, false, world_instance());
      add(world_channel(kSceneEvent), PayloadKind::kSceneDescription, {}, false);
      add(world_channel(kScenePosesEvent), PayloadKind::kScenePoses, {}, false);
      CatalogReader catalog;
      std::int64_t next_progress_ns = monotonic_ns() + kProgressPeriodNs;
      while (!reading_done_) {
        discover(catalog);
        const std::int64_t next_ns = monotonic_ns() + kDiscoveryPeriodNs;
        while (!reading_done_ && monotonic_ns() < next_ns) {
          usleep(10'000);
          beside_.watch(monotonic_ns());
          if (monotonic_ns() >= next_progress_ns) {
            progress(snapshot());
            next_progress_ns += kProgressPeriodNs;
          }
        }
      }
    } catch (...) {
      discover_error_ = std::current_exception();
      discover_failed_ = true;
    }
  }

  // Readers for the catalog's bodies (and devices) that match and are not recorded yet.
  void discover(CatalogReader& catalog) {
    const BodyList& list = catalog.latest();
    std::vector<std::string> bodies;
    for (std::uint32_t i = 0; i < list.body_count; ++i) {
      const BodyEntry entry = entry_of(list, i);
      const std::string channel(name_of(entry.info.channel));
      const bool device = entry.info.kind == ChannelKind::kDevice;
      if (!device) bodies.push_back(channel);
      if (device ? !options_.devices : !matches_any(channel, options_.body_globs)) continue;
      if (!known_.insert(channel).second) continue;
      const Metadata metadata =
          device ? Metadata{} : Metadata{{"joint_names", joint_names_text(entry.joint_names)}};
      add(body_state_channel(channel), device ? PayloadKind::kDeviceState : PayloadKind::kBodyState,
          metadata, device, device ? std::string() : channel);
      if (device || options_.commands)
        add(body_command_channel(channel),
            device ? PayloadKind::kDeviceCommand : PayloadKind::kBodyCommand, metadata, true,
            device ? std::string() : channel);
    }
    say_unmatched_globs(bodies);
  }

  // A --bodies glob that matches none of the hub's bodies (a typo recorded nothing and
  // said nothing), said once, when there are bodies to match.
  void say_unmatched_globs(const std::vector<std::string>& bodies) {
    if (bodies.empty()) return;
    for (const std::string& glob : options_.body_globs) {
      if (!globs_looked_at_.insert(glob).second) continue;
      if (std::any_of(bodies.begin(), bodies.end(),
                      [&](const std::string& body) { return matches_any(body, {glob}); }))
        continue;
      std::string some;
      for (std::size_t i = 0; i < bodies.size() && i < 4; ++i) some += (i ? ", " : "") + bodies[i];
      std::fprintf(stderr,
                   "afhub record: --bodies '%s' matches none of the hub's %zu bodies (%s%s): "
                   "none is recorded for it unless such a body comes (`afhub ls` lists them)\n",
                   glob.c_str(), bodies.size(), some.c_str(), bodies.size() > 4 ? ", ..." : "");
    }
  }

  // A channel recorded from now on, handed to the reading loop (`wakes`: its updates
  // wake the loop). Its topic is "/<instance>/<event>", and its metadata name the
  // hub's channel, for `afhub play`.
  void add(const ChannelId& id, PayloadKind kind, Metadata metadata, bool wakes,
           std::string body = {}) {
    metadata["afhub_instance"] = id.instance;
    metadata["afhub_event"] = id.event;
    Recorded recorded;
    recorded.reader = std::make_unique<RawLatestReader>(id, kind);
    recorded.channel_id = declare(payload_of(kind), "/" + id.instance + "/" + id.event, metadata);
    recorded.per_step = kind == PayloadKind::kBodyState || kind == PayloadKind::kWorldState;
    recorded.wakes = wakes;
    recorded.once = kind == PayloadKind::kSceneDescription;
    recorded.kind = kind;
    recorded.body = std::move(body);
    if (kind == PayloadKind::kDeviceState)
      recorded.device_tape = std::make_unique<DeviceTapeReader>(id.instance);
    const std::lock_guard lock(discovered_mutex_);
    discovered_.push_back(std::move(recorded));
    discovered_ready_.store(true, std::memory_order_release);
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
        std::size_t taken = 0;
        {
          const std::lock_guard lock(writing_mutex_);
          if (closed_) return;  // by a hub loss (finish_on_hub_loss)
          taken = write_buffered();
          if (!last_round && monotonic_ns() >= next_flush_ns) {
            writer_.flush_chunk();
            next_flush_ns = monotonic_ns() + kChunkFlushPeriodNs;
          }
          if (last_round) {
            writer_.close();
            closed_ = true;
            file_bytes_ = writer_.file_bytes();
            return;
          }
        }
        if (taken == 0) usleep(kWriterIdleUs);
      }
    } catch (...) {
      write_error_ = std::current_exception();
      write_failed_ = true;
    }
  }

  // The declared channels, then the buffer's messages, into the file (writing_mutex_
  // held); returns how many messages.
  std::size_t write_buffered() {
    add_declared();
    const std::size_t taken = queue_.drain([&](const QueuedMessage& m, auto data) {
      if (m.channel_id >= outputs_.size()) add_declared();  // declared after the first call
      if (kinds_[m.channel_id] == PayloadKind::kSceneDescription) name_models(data);
      for (const Output& output : outputs_[m.channel_id]) {
        const Message message{output.channel, m.sequence, m.log_time_ns, m.publish_time_ns, {}};
        if (output.encode) {
          output.encode(data, encoded_);
          const std::span<const std::uint8_t> encoded(encoded_);
          writer_.write(message, std::span(&encoded, 1));
        } else {
          writer_.write(message, std::span(&data, 1));  // packed by the reading loop
        }
      }
    });
    messages_written_ = writer_.message_count();
    file_bytes_ = writer_.file_bytes();
    return taken;
  }

 public:
  // The hub is gone and this process re-executes next (hub_loss.hpp), on whichever
  // thread noticed: the file gets what was buffered, its summary and footer, so that it
  // ends complete. The writing thread, if it was writing, finishes its batch first, and
  // writes nothing after.
  void finish_on_hub_loss() noexcept {
    reading_done_ = true;
    const std::lock_guard lock(writing_mutex_);
    // The writing thread may have closed it first: it saw reading done (set above, or
    // by the reading loop ending on the loss) before this took the lock.
    if (!closed_) {
      closed_ = true;
      try {
        write_buffered();
        writer_.close();
      } catch (const std::exception& error) {
        std::fprintf(stderr, "afhub record: the hub is gone, and %s could not be closed: %s\n",
                     options_.output.c_str(), error.what());
        return;
      }
    }
    std::fprintf(stderr, "afhub record: the hub is gone: %s closed with %llu messages\n",
                 options_.output.c_str(), static_cast<unsigned long long>(writer_.message_count()));
  }

 private:
  // The model files a physics' scene names, with their sizes and SHA-256s as this
  // machine reads them now, as the file's "afhub.models" metadata (once per physics).
  void name_models(std::span<const std::uint8_t> scene) {
    PayloadHeader header;
    std::memcpy(&header, scene.data(), sizeof header);
    if (!models_named_.insert(header.publisher_pid).second) return;
    std::uint32_t count = 0;
    std::memcpy(&count, scene.data() + offsetof(SceneDescription, model_file_count), sizeof count);
    Metadata models;
    for (std::uint32_t f = 0; f < count; ++f) {  // checked by the reader: NUL-terminated
      const char* path = reinterpret_cast<const char*>(scene.data()) +
                         offsetof(SceneDescription, model_files) + f * kScenePathBufferSize;
      models[path] = file_fingerprint(path);
    }
    writer_.add_metadata("afhub.models", models);
  }

  // The file's channels for each channel declared since: one of afhub's payloads, or
  // with --profile ros2 the ROS 2 messages made of it.
  void add_declared() {
    const std::lock_guard lock(declared_mutex_);
    for (const Declared& d : declared_) {
      outputs_.resize(d.id + 1);
      kinds_.resize(d.id + 1);
      kinds_[d.id] = d.payload.kind;
      std::vector<Output>& outputs = outputs_[d.id];
      if (!ros2_) {
        outputs.push_back({writer_.add_channel(schema_ids_.at(d.payload.kind), d.topic,
                                               kPayloadEncoding, d.metadata),
                           nullptr});
        continue;
      }
      for (Ros2Output& ros2 : ros2_outputs(d.payload.kind, d.metadata.at("afhub_instance"),
                                           joint_names_in(d.metadata)))
        outputs.push_back({writer_.add_channel(ros2_schema_ids_[ros2.schema], ros2.topic, "cdr"),
                           std::move(ros2.encode)});
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
    p.replaced = replaced_;
    p.buffered_bytes = queue_.waiting_bytes();
    return p;
  }

  const RecordOptions& options_;
  const bool ros2_;
  Writer writer_;
  RecordQueue queue_;
  const std::int64_t realtime_offset_ns_;
  std::map<PayloadKind, std::uint16_t> schema_ids_;
  std::vector<std::uint16_t> ros2_schema_ids_;  // by ros2_schemas()' index

  // The reading loop's.
  std::vector<Recorded> recorded_;
  const std::unique_ptr<BodyState> unpacked_ = std::make_unique<BodyState>();  // a taped state
  const std::unique_ptr<DeviceTape> device_cycle_ = std::make_unique<DeviceTape>();
  // The index in recorded_ of each channel a tape brings, by tape_kind_index and name.
  static std::size_t tape_kind_index(PayloadKind kind) {
    return kind == PayloadKind::kBodyState ? 0 : kind == PayloadKind::kBodyCommand ? 1 : 2;
  }
  std::array<std::map<std::string, std::size_t, std::less<>>, 3> by_body_;
  // Each body's state and command, and the world's state.
  std::vector<TapePosition> tape_order_ = std::vector<TapePosition>(2 * kMaxBodies + 1);
  // The reading loop on the physics' CPU while it is idle, and the discovering thread's
  // watch that it still turns there.
  BesidePhysics beside_;
  // Where the tape is (follow_tape): the step of its last sample, the part expected next
  // (0: the next step's first), and the breaks met.
  bool tape_seen_ = false;
  std::uint64_t tape_step_ = 0;
  std::uint32_t tape_next_part_ = 0;
  std::uint64_t tape_breaks_ = 0;

  // The discovery's, and what it hands over.
  std::set<std::string> known_;
  std::set<std::string> globs_looked_at_;  // each --bodies glob, once there were bodies
  std::mutex discovered_mutex_;
  std::vector<Recorded> discovered_;
  std::atomic<bool> discovered_ready_{false}, discover_failed_{false};
  std::exception_ptr discover_error_;
  std::uint16_t next_channel_id_ = 1;
  std::atomic<std::int64_t> first_sample_ns_{0};
  std::atomic<std::uint64_t> dropped_{0}, missed_{0}, replaced_{0}, channel_count_{0};
  // The world's step while it is paused, as read at the start of the loop's turn.
  std::optional<std::uint64_t> paused_at_step_;

  // Between the threads.
  std::mutex writing_mutex_;  // held while the file is written
  bool closed_ = false;       // the file is complete (writing_mutex_)
  std::mutex declared_mutex_;
  std::vector<Declared> declared_;
  std::atomic<bool> reading_done_{false}, write_failed_{false};
  std::exception_ptr write_error_;

  // The writing thread's: for each declared channel, the file's channels it is written
  // to and how (nullptr: as it is).
  struct Output {
    std::uint16_t channel;
    Encode encode;
  };
  std::vector<std::vector<Output>> outputs_;
  std::vector<PayloadKind> kinds_;        // of each declared channel
  std::set<std::uint32_t> models_named_;  // the physics whose models are in the file
  std::vector<std::uint8_t> encoded_;
  std::atomic<std::uint64_t> messages_written_{0}, file_bytes_{0};
};

// The session a hub loss finishes (set while one runs).
std::atomic<Session*> active_session{nullptr};

ActiveSession::ActiveSession(Session* session) {
  static std::once_flag hooked;
  std::call_once(hooked, [] {
    on_hub_lost([] {
      if (Session* active = active_session.load()) active->finish_on_hub_loss();
    });
  });
  active_session = session;
}

ActiveSession::~ActiveSession() {
  active_session = nullptr;
}

}  // namespace

RecordProgress record(const RecordOptions& options, const std::function<bool()>& keep_going,
                      const std::function<void(const RecordProgress&)>& progress,
                      const std::function<void()>& opened) {
  if (!options.profile.empty() && options.profile != "ros2")
    throw Error("--profile takes ros2 (ROS 2 messages in CDR), not " + options.profile +
                "; without it afhub records its own payloads");
  Session session(options);
  if (opened) opened();
  return session.run(keep_going, progress);
}

}  // namespace afhub::mcap
