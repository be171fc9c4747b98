#include "afhub/record/lockstep_replay.hpp"

#include <signal.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iterator>
#include <map>
#include <memory>
#include <vector>

#include "afhub/hub/channel.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/record/mcap_reader.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/shm_layout/world_control.hpp"
#include "recorded_payloads.hpp"
#include "state_difference.hpp"

namespace afhub::mcap {

namespace {

constexpr std::int64_t kStepTimeoutNs = 10'000'000'000;

struct Stop {};

// The recording's channels: which are body states and commands, of which body.
class ChannelMap : public Visitor {
 public:
  explicit ChannelMap(const std::string& file) : file_(file) {}
  void header(const std::string& profile, const std::string&) override {
    if (!profile.empty())
      throw Error(file_ + " was recorded with --profile " + profile +
                  ": a replay needs afhub's own recordings (no --profile)");
  }
  void metadata(const std::string& name, const Metadata& metadata) override {
    if (name != "afhub") return;
    require_this_layout(file_, metadata);
    layout_checked_ = true;
  }
  void schema(const Schema& schema) override {
    for (const RecordedPayload& payload : recorded_payloads())
      if (schema.name == payload.schema_name) kinds_[schema.id] = payload.kind;
  }
  void channel(const Channel& channel) override {
    const auto kind = kinds_.find(channel.schema_id);
    const auto instance = channel.metadata.find("afhub_instance");
    if (kind != kinds_.end() && instance != channel.metadata.end())
      channels_[channel.id] = {kind->second, instance->second};
  }

 protected:
  // The body and kind of a message's channel, or nullptr when not afhub's.
  const std::pair<PayloadKind, std::string>* of(const Message& message) const {
    if (!layout_checked_)
      throw Error(file_ +
                  " has no afhub metadata before its messages: not a recording of "
                  "`afhub record`");
    const auto found = channels_.find(message.channel_id);
    return found == channels_.end() ? nullptr : &found->second;
  }
  // The message as a checked payload of `kind`, aligned (valid until the next call).
  std::span<const std::uint8_t> check(const Message& message, PayloadKind kind) {
    return checked_copy(message.data, kind, aligned_, file_ + ": a recorded payload");
  }
  // The message as a checked body state, copied out (the joints past its count zero).
  BodyState body_state(const Message& message) {
    const auto bytes = check(message, PayloadKind::kBodyState);
    BodyState state;
    std::memcpy(&state, bytes.data(), std::min(bytes.size(), sizeof state));
    return state;
  }

  std::string file_;

 private:
  std::vector<std::uint64_t> aligned_;
  bool layout_checked_ = false;
  std::map<std::uint16_t, PayloadKind> kinds_;
  std::map<std::uint16_t, std::pair<PayloadKind, std::string>> channels_;
};

// First pass: every recorded command, by its body and the step it answered, and when
// each took effect: the steps at which a body's recorded state shows another command
// in force (BodyState::command_answered_step). In a lockstep run that is the step
// after the one it answered, unless it came late (the physics went on without it) or
// was replaced before it was taken. One run only: a world reset or another physics
// (a body's steps going back, or another publisher) ends what is loaded.
class CommandLoader : public ChannelMap {
 public:
  using ChannelMap::ChannelMap;
  // Per body: the recorded commands by the step they answered, and the command in force
  // from each step at which it changed (-1: none).
  struct Body {
    // The different answers to each step (headers aside: their stamps differ), as
    // recorded: one in a lockstep run.
    std::map<std::uint64_t, std::vector<std::vector<std::uint8_t>>> commands;
    std::map<std::uint64_t, std::int64_t> in_force_from;
    std::int64_t last_in_force = -1;
    std::uint64_t last_step = 0;
    std::uint32_t publisher_pid = 0;  // 0: no state yet
  };
  std::map<std::string, Body> bodies;
  // The first and last steps at which a new command took effect (0: none); a command
  // let go after the last, its client gone, is past the replay's end.
  std::uint64_t first_change = 0, last_change = 0;
  bool any_command = false;
  bool run_ended = false;  // a reset or another physics came: the rest is not loaded

  void message(const Message& message) override {
    const auto* channel = of(message);
    if (!channel || run_ended) return;
    if (channel->first == PayloadKind::kBodyCommand) {
      const auto command = check(message, PayloadKind::kBodyCommand);
      PayloadHeader header;
      std::memcpy(&header, command.data(), sizeof header);  // checked: at least a header
      auto& answers = bodies[channel->second].commands[header.sim_step];
      const auto same = [&](const std::vector<std::uint8_t>& answer) {
        return std::equal(answer.begin() + sizeof header, answer.end(),
                          command.begin() + sizeof header, command.end());
      };
      if (std::none_of(answers.begin(), answers.end(), same))
        answers.emplace_back(command.begin(), command.end());
      any_command = true;
    } else if (channel->first == PayloadKind::kBodyState) {
      const BodyState recorded = body_state(message);
      Body& body = bodies[channel->second];
      const std::uint64_t step = recorded.header.sim_step;
      if (body.publisher_pid != 0 &&
          (step <= body.last_step || recorded.header.publisher_pid != body.publisher_pid)) {
        run_ended = true;
        forget_commands_from(recorded.header.publish_stamp_ns);
        return;
      }
      body.last_step = step;
      body.publisher_pid = recorded.header.publisher_pid;
      if (recorded.command_answered_step == body.last_in_force) return;
      body.in_force_from[step] = recorded.command_answered_step;
      body.last_in_force = recorded.command_answered_step;
      if (recorded.command_answered_step >= 0) {
        last_change = std::max(last_change, step);
        first_change = first_change == 0 ? step : std::min(first_change, step);
      }
    }
  }

 private:
  // The commands published once the next run began (its first state's stamp) answer
  // that run's states: recorded before its first state (the recorder finds a restarted
  // physics' slots later than a client it knows), they are not this run's.
  void forget_commands_from(std::int64_t stamp_ns) {
    for (auto& [name, body] : bodies)
      for (auto& [step, answers] : body.commands)
        std::erase_if(answers, [&](const std::vector<std::uint8_t>& answer) {
          PayloadHeader header;
          std::memcpy(&header, answer.data(), sizeof header);
          return header.publish_stamp_ns >= stamp_ns;
        });
  }
};

// Second pass: steps the physics with the commands, comparing each recorded state.
class Replayer : public ChannelMap {
 public:
  Replayer(const std::string& file, const CommandLoader& commands,
           const std::function<bool()>& keep_going)
      : ChannelMap(file),
        commands_(commands),
        keep_going_(keep_going),
        world_(ChannelId{std::string(kService), world_instance(), std::string(kStateEvent)}) {
    waiter_.attach(world_.raw());
  }

  void message(const Message& message) override {
    const auto* channel = of(message);
    if (!channel || channel->first != PayloadKind::kBodyState) return;
    const BodyState recorded = body_state(message);
    const std::uint64_t step = recorded.header.sim_step;
    if (!started_) start(step);
    while (step_ < step) advance();
    if (step < step_) return;  // a state of a step already passed (read late): not compared
    const BodyState* live = live_state(channel->second);
    if (!live || live->header.sim_step != step)
      throw Error("the physics shows no state of " + channel->second + " at step " +
                  std::to_string(step) + ": is it the model that was recorded?");
    ++result.states;
    if (const std::string difference = state_difference(recorded, *live); !difference.empty()) {
      result.diverged = true;
      result.step = step;
      result.body = channel->second;
      result.field = difference;
      throw Stop{};
    }
  }

  ReplayCheck result;

 private:
  // The physics waits at the recording's first step (a lockstep physics holds step 0
  // for its client).
  void start(std::uint64_t first_step) {
    // A world state whose physics lives (a stopped physics' last one stays readable).
    const WorldState* world = wait_for_world(
        [](const WorldState& w) {
          return ::kill(static_cast<pid_t>(w.header.publisher_pid), 0) == 0 || errno != ESRCH;
        },
        "");
    if (!world->lockstep)
      throw Error(
          "the physics is not in lockstep: start it with `afhub run MODEL --lockstep "
          "--paused`, then replay");
    if (world->header.sim_step != first_step)
      throw Error("the recording starts at step " + std::to_string(first_step) +
                  ", the physics is at step " + std::to_string(world->header.sim_step) +
                  ": a replay needs a recording from the physics' first step (start `afhub "
                  "record` before the physics steps) and a physics just started");
    if (!commands_.any_command)
      throw Error("the recording has no commands: was it recorded with --commands, in lockstep?");
    if (commands_.first_change != first_step + 1)
      throw Error(
          commands_.first_change == 0
              ? "no recorded state shows a command in force: was it recorded by this afhub?"
              : "the recorded physics took step " + std::to_string(first_step + 1) +
                    " with no command in force: a replay reproduces a run commanded from its "
                    "first step (was a command's watchdog let go while it was paused?)");
    step_ = first_step;
    started_ = true;
    resume_after_first_ = world->paused;
    physics_pid_ = world->header.publisher_pid;
  }

  // A physics started paused (`--paused`) is resumed once it holds every body's first
  // command: with --wait-for, a physics might take its first step as soon as one body's
  // command came, before the others joined the barrier. Its readers find this process's
  // commands (one block for all its bodies) within RouDi's discovery period; then every
  // body's is read within a period of its paused loop.
  void resume() {
    resume_after_first_ = false;
    // Judged on this physics' world state alone: a stopped one's last stays readable.
    const std::uint32_t pid = physics_pid_;
    wait_for_world(
        [pid](const WorldState& w) {
          return w.header.publisher_pid == pid && w.lockstep_clients > 0;
        },
        "the paused physics did not take this replay's first commands within 10 s");
    sleep_until_ns(monotonic_ns() + 20'000'000);
    // Sent until the physics runs: a queue made after a command was sent skips it.
    afhub::Writer<WorldCommand> writer(
        ChannelId{std::string(kService), world_instance(), std::string(kCommandEvent)});
    writer.raw().continue_sequence_after(static_cast<std::uint64_t>(monotonic_ns()));
    for (int tries = 0; tries < 100; ++tries) {
      if (WorldCommand* command = writer.loan()) {
        command->action = WorldAction::kResume;
        writer.publish(command);
      }
      try {
        wait_for_world(
            [pid](const WorldState& w) { return w.header.publisher_pid == pid && !w.paused; }, "",
            100'000'000);
        return;
      } catch (const Error&) {
      }
    }
    throw Error("the paused physics did not resume within 10 s");
  }

  // Answers step_ with the commands in force at the next step in the recording and
  // waits for that step. A body whose command did not change (its client was late, or
  // it sent nothing new) gets an answer that keeps its command in force.
  void advance() {
    const std::uint64_t next = step_ + 1;
    // Past the last new command the recorded physics went on without (its client
    // gone): the replay ends there.
    if (next > commands_.last_change) throw Stop{};
    for (const auto& [name, body] : commands_.bodies) {
      const auto change = body.in_force_from.upper_bound(next);
      if (change == body.in_force_from.begin()) continue;  // not commanded yet
      const std::int64_t answered = std::prev(change)->second;
      if (answered < 0)
        throw Error("the recorded physics let go of " + name + " at step " +
                    std::to_string(std::prev(change)->first) +
                    " (its command watchdog expired): a replay cannot reproduce that");
      const auto answers = body.commands.find(static_cast<std::uint64_t>(answered));
      if (answers == body.commands.end() || answers->second.empty())
        throw Error("the command to " + name + " answering step " + std::to_string(answered) +
                    ", in force at step " + std::to_string(next) +
                    ", is not in the recording (the recorder missed it): the run cannot be "
                    "reproduced from here");
      if (answers->second.size() > 1)
        throw Error("two different commands to " + name + " answered step " +
                    std::to_string(answered) + ", and one of them was in force at step " +
                    std::to_string(next) +
                    ": the recording cannot say which (a lockstep client answers each step once: "
                    "was it recorded in lockstep, with one client for the body?)");
      // What the recorded client sent new, or an answer that keeps the command in force:
      // sent again, a command is not always without effect (an actuator grabs anew).
      const auto last_sent = sent_.find(name);
      const bool keep = last_sent != sent_.end() && last_sent->second == answered;
      sent_[name] = answered;
      const std::vector<std::uint8_t>& command = answers->second.front();
      const std::size_t bytes = keep ? body_command_bytes(0) : command.size();
      RawWriter& writer = command_writer(name);
      void* payload = writer.loan(static_cast<std::uint32_t>(bytes));
      if (!payload) throw Error("no shared memory left for a command to " + name);
      if (keep)
        std::memset(payload, 0, bytes);
      else
        std::memcpy(payload, command.data(), bytes);
      auto* sent = static_cast<BodyCommand*>(payload);
      sent->header.sim_step = step_;  // the answer the replaying physics waits for
      sent->lockstep = keep ? BodyCommand::kLockstepKeep : 1;
      writer.publish(payload);
    }
    if (resume_after_first_) resume();
    const std::uint32_t pid = physics_pid_;
    const WorldState* world = wait_for_world(
        [next, pid](const WorldState& w) {
          return w.header.publisher_pid == pid && w.header.sim_step >= next;
        },
        "the physics did not take step " + std::to_string(next) +
            " within 10 s of the commands answering step " + std::to_string(step_));
    // A replay held past the physics' client timeout is not the run recorded.
    if (world->late_answers > 0)
      throw Error(
          "the physics took a step without this replay's answer (the replay was held "
          "past its --client-timeout, on a busy machine?): start it with a longer "
          "--client-timeout and replay again");
    step_ = next;
    ++result.steps;
  }

  // The world state once `done` holds; after `timeout_ns`, throws afhub::Error saying
  // `waited_for`.
  template <class Done>
  const WorldState* wait_for_world(Done done, const std::string& waited_for,
                                   std::int64_t timeout_ns = kStepTimeoutNs) {
    const std::int64_t give_up = monotonic_ns() + timeout_ns;
    while (true) {
      const WorldState* world = world_.latest();
      if (world && done(*world)) return world;
      if (!keep_going_()) throw Stop{};
      if (monotonic_ns() > give_up)
        throw Error(world ? waited_for
                          : "no physics is running: start `afhub run MODEL --lockstep --paused`, "
                            "then replay");
      waiter_.wait(1'000'000);
    }
  }

  const BodyState* live_state(const std::string& body) {
    auto& reader = states_[body];
    if (!reader) reader = std::make_unique<LatestReader<BodyState>>(body_state_channel(body));
    const std::int64_t give_up = monotonic_ns() + 1'000'000'000;  // a new reader's first copy
    const BodyState* state = reader->latest();
    while ((!state || state->header.sim_step != step_) && monotonic_ns() < give_up) {
      sleep_until_ns(monotonic_ns() + 100'000);
      state = reader->latest();
    }
    return state;
  }

  RawWriter& command_writer(const std::string& body) {
    auto& writer = commands_out_[body];
    if (!writer)
      writer = std::make_unique<RawWriter>(body_command_channel(body), PayloadKind::kBodyCommand);
    return *writer;
  }

  const CommandLoader& commands_;
  const std::function<bool()>& keep_going_;
  LatestReader<WorldState> world_;
  SampleWaiter waiter_;
  std::map<std::string, std::unique_ptr<LatestReader<BodyState>>> states_;
  std::map<std::string, std::unique_ptr<RawWriter>> commands_out_;
  std::map<std::string, std::int64_t> sent_;  // per body: what its last command answered
  bool started_ = false;
  bool resume_after_first_ = false;
  std::uint32_t physics_pid_ = 0;  // the physics replayed into
  std::uint64_t step_ = 0;
};

}  // namespace

ReplayCheck replay_into_physics(const std::string& file, const std::function<bool()>& keep_going) {
  CommandLoader commands(file);
  const std::string cut_off = scan(file, commands).cut_off;
  Replayer replayer(file, commands, keep_going);
  replayer.result.cut_off = cut_off;
  try {
    scan(file, replayer);
  } catch (const Stop&) {
  }
  return replayer.result;
}

}  // namespace afhub::mcap
