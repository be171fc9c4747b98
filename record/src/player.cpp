#include "afhub/record/player.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/world_command_queue.hpp"
#include "afhub/record/mcap_reader.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/shm_layout/world_control.hpp"
#include "recorded_payloads.hpp"

namespace afhub::mcap {

namespace {

constexpr std::int64_t kPausedPublishNs = 10'000'000;  // a paused world still says so

// Ends a pass: the range's end, a stop, or a rewind (`afhub world reset`).
struct EndOfPass {
  bool stop;
  bool rewind = false;
};

// A recorded channel published again.
struct Replayed {
  PayloadKind kind;
  std::string topic;
  std::unique_ptr<RawWriter> writer;
};

class Player : public Visitor {
 public:
  Player(const PlayOptions& options, const std::function<bool()>& keep_going)
      : options_(options), keep_going_(keep_going), world_commands_(world_instance()) {}

  // One pass through the file's range.
  void pass() {
    pass_start_ns_ = 0;
    first_log_ns_ = 0;
    in_range_ = 0;
    cut_off_ = scan(options_.file, *this).cut_off;
    if (!layout_checked_)
      throw Error(options_.file + " holds no recording of `afhub record` (no afhub metadata" +
                  (cut_off_.empty() ? std::string(")") : "; it was cut off: " + cut_off_ + ")"));
    if (in_range_ == 0 && options_.start_s > 0.0) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "--start %g s is past the recording's last state, at %.3f s from its first",
                    options_.start_s, last_at_s_);
      throw Error(text);
    }
  }
  std::uint64_t published() const { return published_; }
  const std::string& cut_off() const { return cut_off_; }

  // A --bodies glob that matches none of the recording's bodies (a typo replayed no body
  // and said nothing), said once the first pass has seen them all.
  // Returns how many there were.
  unsigned say_unmatched_globs() const {
    if (recorded_bodies_.empty()) {  // no glob could match: the file's matter, said once
      std::fprintf(stderr,
                   "afhub play: warning: %s holds no body state (recorded with --bodies matching "
                   "none?): only the world's state was replayed\n",
                   options_.file.c_str());
      return 0;
    }
    unsigned unmatched = 0;
    for (const std::string& glob : options_.body_globs) {
      if (std::any_of(recorded_bodies_.begin(), recorded_bodies_.end(),
                      [&](const std::string& body) { return matches_any(body, {glob}); }))
        continue;
      ++unmatched;
      std::string some;  // the first four, as " (a, b, c, d, ...)"
      for (std::size_t i = 0; i < recorded_bodies_.size() && i < 4; ++i)
        some += (i ? ", " : " (") + recorded_bodies_[i];
      if (!some.empty()) some += recorded_bodies_.size() > 4 ? ", ...)" : ")";
      std::fprintf(stderr,
                   "afhub play: --bodies '%s' matches none of the recording's %zu bodies%s: "
                   "none was replayed for it (`afhub info FILE` lists them)\n",
                   glob.c_str(), recorded_bodies_.size(), some.c_str());
    }
    return unmatched;
  }

  void header(const std::string& profile, const std::string&) override {
    if (!profile.empty())
      throw Error(options_.file + " was recorded with --profile " + profile +
                  ": `afhub play` replays afhub's own recordings (no --profile)");
  }
  void metadata(const std::string& name, const Metadata& metadata) override {
    if (name != "afhub") return;
    require_this_layout(options_.file, metadata);
    layout_checked_ = true;
  }
  void schema(const Schema& schema) override {
    for (const RecordedPayload& payload : recorded_payloads())
      if (schema.name == payload.schema_name) kinds_[schema.id] = payload.kind;
  }
  void channel(const Channel& channel) override {
    if (replayed_.count(channel.id)) return;  // a later pass: set up already
    Replayed& replayed = replayed_[channel.id];
    const auto kind = kinds_.find(channel.schema_id);
    const auto instance = channel.metadata.find("afhub_instance");
    const auto event = channel.metadata.find("afhub_event");
    if (kind == kinds_.end() || instance == channel.metadata.end() ||
        event == channel.metadata.end())
      return;  // not afhub's: left out
    replayed.kind = kind->second;
    replayed.topic = channel.topic;
    switch (replayed.kind) {
      case PayloadKind::kBodyState: {
        recorded_bodies_.push_back(instance->second);
        if (!matches_any(instance->second, options_.body_globs)) return;
        check_room_for_bodies({instance->second}, 1);
        directory_.add(make_body_entry(instance->second, joint_names_in(channel.metadata)));
        directory_.publish();
        break;
      }
      case PayloadKind::kWorldState:
      case PayloadKind::kSceneDescription:
      case PayloadKind::kScenePoses:
        break;
      default:
        return;  // commands and devices: a replay drives nothing
    }
    replayed.writer = std::make_unique<RawWriter>(
        ChannelId{std::string(kService), instance->second, event->second}, replayed.kind);
  }

  void message(const Message& message) override {
    if (!layout_checked_)
      throw Error(options_.file +
                  " has no afhub metadata before its messages: not a recording "
                  "of `afhub record`");
    const auto found = replayed_.find(message.channel_id);
    if (found == replayed_.end() || !found->second.writer) return;
    Replayed& replayed = found->second;
    if (first_log_ns_ == 0) first_log_ns_ = message.log_time_ns;
    // Signed: a message logged before the first (another writer's order) is not far ahead.
    const double at_s =
        static_cast<double>(static_cast<std::int64_t>(message.log_time_ns - first_log_ns_)) * 1e-9;
    // The scene is published once by a physics: replayed whenever it comes.
    const bool once = replayed.kind == PayloadKind::kSceneDescription;
    last_at_s_ = std::max(last_at_s_, at_s);
    if (!once && at_s < options_.start_s) return;
    if (options_.end_s > 0.0 && at_s > options_.end_s) throw EndOfPass{false};
    if (!once) ++in_range_;

    const auto payload = checked_copy(message.data, replayed.kind, aligned_,
                                      options_.file + ": a message on " + replayed.topic);
    PayloadHeader header;
    std::memcpy(&header, payload.data(), sizeof header);  // checked: at least a header
    if (!once) wait_until_due(at_s, header.sim_step, replayed.kind);
    publish(replayed, payload);
    if (replayed.kind == PayloadKind::kWorldState) {
      last_world_.assign(payload.begin(), payload.end());
      world_writer_ = replayed.writer.get();
    }
  }

 private:
  void publish(Replayed& replayed, std::span<const std::uint8_t> data) {
    void* payload = replayed.writer->loan(static_cast<std::uint32_t>(data.size()));
    if (!payload) throw Error("no shared memory left to publish " + replayed.topic);
    std::memcpy(payload, data.data(), data.size());
    if (replayed.kind == PayloadKind::kWorldState) {
      // The pause is this replay's (paused-by pids of the recorded session meant nothing).
      auto* world = static_cast<WorldState*>(payload);
      world->lockstep = 0;
      pause_.describe_pause(*world);
    }
    replayed.writer->publish(payload);
    ++published_;
  }

  // Sleeps until the message at `at_s` of the recording is due, following the world
  // commands meanwhile; a new step while paused waits for a step command.
  void wait_until_due(double at_s, std::uint64_t step, PayloadKind kind) {
    const bool steps = kind == PayloadKind::kBodyState || kind == PayloadKind::kWorldState;
    const bool new_step = steps && step != current_step_;
    for (;;) {
      if (!keep_going_()) throw EndOfPass{true};
      if (hub_lost()) {  // nothing into a hub that is gone: held until the re-exec
        sleep_until_ns(monotonic_ns() + 10'000'000);
        continue;
      }
      // Looked at while it waits too: a reset or a pause during a long wait (a slow
      // --rate, a gap in the recording) waited for the next message, and timed out.
      take_world_commands();
      if (rewind_) {
        rewind_ = false;
        throw EndOfPass{false, true};
      }
      if (pause_.paused) {
        if (!new_step || steps_allowed_ > 0) break;
        publish_paused_world();
        sleep_until_ns(monotonic_ns() + 1'000'000);
        continue;
      }
      if (options_.rate == 0.0) break;
      const std::int64_t offset_ns =
          static_cast<std::int64_t>((at_s - options_.start_s) * 1e9 / options_.rate);
      const std::int64_t now = monotonic_ns();
      if (pass_start_ns_ == 0) pass_start_ns_ = now - offset_ns;
      const std::int64_t due = pass_start_ns_ + offset_ns;
      if (now >= due) break;
      sleep_until_ns(std::min(due, now + 10'000'000));
    }
    if (new_step) {
      current_step_ = step;
      if (pause_.paused) --steps_allowed_;
    }
  }

  // Pause and resume (and a held pause's holder) as the physics keeps them, and steps
  // while paused; a reset goes back to the window's start (paused, it shows its first
  // step), as a physics' reset goes back to its first state.
  void take_world_commands() {
    WorldCommand command;
    while (world_commands_.next(command)) {
      const bool was_paused = pause_.paused;
      pause_.apply(command, monotonic_ns());
      if (was_paused && !pause_.paused) run_on();  // resumed, or its last hold released
      if (command.action == WorldAction::kStep && was_paused) steps_allowed_ += command.step_count;
      if (command.action == WorldAction::kReset) {
        rewind_ = true;
        current_step_ = ~0ull;
        steps_allowed_ = pause_.paused ? 1 : 0;
      }
    }
    if (const WorldControl::Lapsed lapsed = pause_.lapse(monotonic_ns())) {
      std::fprintf(stderr, kPauseLapsedFormat, "afhub play", lapsed.pid, lapsed.hold_ms);
      run_on();
    }
  }

  void run_on() {
    pass_start_ns_ = 0;  // the next message sets the time base again
    steps_allowed_ = 0;
  }

  // While paused, the world state says so (as a physics publishes it, paused or not).
  void publish_paused_world() {
    const std::int64_t now = monotonic_ns();
    if (!world_writer_ || now < next_paused_publish_ns_) return;
    next_paused_publish_ns_ = now + kPausedPublishNs;
    auto* world = static_cast<WorldState*>(
        world_writer_->loan(static_cast<std::uint32_t>(last_world_.size())));
    if (!world) return;
    std::memcpy(world, last_world_.data(), last_world_.size());
    pause_.describe_pause(*world);
    world->paused = 1;  // its single steps are counted apart (steps_allowed_)
    world->lockstep = 0;
    world_writer_->publish(world);
  }

  const PlayOptions& options_;
  const std::function<bool()>& keep_going_;
  WorldCommandQueue world_commands_;
  DirectoryPublisher directory_;
  std::map<std::uint16_t, PayloadKind> kinds_;
  std::map<std::uint16_t, Replayed> replayed_;
  bool layout_checked_ = false;
  std::string cut_off_;
  std::uint64_t in_range_ = 0;  // states of this pass within --start and --end
  double last_at_s_ = 0.0;
  std::vector<std::uint64_t> aligned_;
  std::uint64_t published_ = 0;
  std::vector<std::string> recorded_bodies_;  // every body state channel, in file order

  std::uint64_t first_log_ns_ = 0;
  std::int64_t pass_start_ns_ = 0;  // when the range's start was (would have been) published

  WorldControl pause_;
  std::uint64_t steps_allowed_ = 0;
  std::uint64_t current_step_ = ~0ull;
  bool rewind_ = false;  // a reset came: the pass starts over
  std::vector<std::uint8_t> last_world_;
  RawWriter* world_writer_ = nullptr;
  std::int64_t next_paused_publish_ns_ = 0;
};

}  // namespace

PlayReport play(const PlayOptions& options, const std::function<bool()>& keep_going) {
  if (!(options.rate == 0.0 || (options.rate >= 1e-3 && options.rate <= 1e6)))
    throw Error(
        "--rate takes a factor from 0.001 to 1e6 (2: twice as fast), or 0: as fast as "
        "possible");
  if (!(options.start_s >= 0.0) || !(options.end_s >= 0.0) ||
      (options.end_s > 0.0 && options.end_s <= options.start_s))
    throw Error("--start and --end take seconds from the recording's start, --end after --start");
  // A replay publishes the world's state as a physics does: beside a live one of other
  // models, the two alternated in it (its step went 1807, 2203, 1847).
  check_world_free(world_instance(), "Stop that one to replay into this hub");
  Player player(options, keep_going);
  PlayReport report;
  for (;;) {
    try {
      player.pass();
    } catch (const EndOfPass& end) {
      if (end.stop) break;
      if (end.rewind) continue;
    }
    if (++report.passes == 1) report.unmatched_globs = player.say_unmatched_globs();
    // A file with nothing to play in the range, or a --bodies typo, would loop for good.
    if (!(options.loop && player.published() > 0 && report.unmatched_globs == 0 && keep_going()))
      break;
  }
  report.published = player.published();
  report.cut_off = player.cut_off();
  return report;
}

}  // namespace afhub::mcap
