// `afhub world pause|resume|step N|reset`: controls the simulation's clock from the
// command line. Each writes one WorldCommand, then reads the world state until the
// simulation has acted on it, and says what happened.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/world_action_watch.hpp"
#include "afhub/hub/world_command_queue.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/yaml/number_text.hpp"
#include "commands.hpp"
#include "connection_options.hpp"
#include "count_option.hpp"

namespace afhub::cli {
namespace {

struct WorldOptions {
  std::uint32_t steps = 1;
  double timeout_s = 5.0;
  std::string name_space;  // the world of a physics run with --namespace
};

ChannelId world_channel(const WorldOptions& options, std::string_view event) {
  return {std::string(kService), world_instance(options.name_space), std::string(event)};
}

// The world state is published every step, paused or not, and keeps no history:
// a reader gets the next one.
WorldState first_world_state(LatestReader<WorldState>& reader) {
  const std::int64_t give_up = monotonic_ns() + 2'000'000'000;
  while (!reader.latest()) {
    if (monotonic_ns() > give_up || stop_requested())
      throw Error(
          "no simulation is running, or it is stalled: nothing has published the world state "
          "for 2 s. Start one "
          "with `afhub run MODEL` (or `afhub synth`); a lockstep run waiting for its clients "
          "publishes nothing until they join");
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return *reader.latest();
}

// Whether `later`, from another writer, undoes what `mine` did: the world can act on
// both between two of its states, and then no state shows mine.
bool undoes(WorldAction later, WorldAction mine) {
  switch (mine) {
    case WorldAction::kPause:
      return later == WorldAction::kResume;
    case WorldAction::kResume:
      return later == WorldAction::kPause;
    case WorldAction::kStep:  // a pause ends the steps still to run
      return later == WorldAction::kPause || later == WorldAction::kResume ||
             later == WorldAction::kReset;
    default:
      return false;
  }
}

const char* done(WorldAction action) {
  switch (action) {
    case WorldAction::kPause:
      return "paused";
    case WorldAction::kResume:
      return "resumed";
    case WorldAction::kStep:
      return "stepped";
    case WorldAction::kReset:
      return "reset";
    default:
      return "acted";
  }
}

// Another writer's command that came after this process's and undoes it, as the world's
// command queue has them: the world acts on them in that order, so once it has published
// two states after the later one, it has acted on both.
class UndoneBy {
 public:
  UndoneBy(const WorldOptions& options, WorldAction mine)
      : commands_(world_instance(options.name_space)), mine_(mine) {}
  void sent(std::uint64_t sequence) { sequence_ = sequence; }
  // Reads the commands that came; true once `state` is the second state published
  // after an undoing command.
  bool by_now(const WorldState& state) {
    for (WorldCommand command; commands_.next(command);) {
      if (command.header.publisher_pid == pid_ && command.header.sequence == sequence_)
        mine_seen_ = true;
      else if (mine_seen_ && !undone_ && undoes(command.action, mine_))
        undone_ = command;
    }
    if (undone_ && state.header.publish_stamp_ns > undone_->header.publish_stamp_ns)
      ++states_since_;
    return states_since_ >= 2;
  }
  const WorldCommand& command() const { return *undone_; }

 private:
  WorldCommandQueue commands_;
  WorldAction mine_;
  std::uint32_t pid_ = static_cast<std::uint32_t>(getpid());
  std::uint64_t sequence_ = 0;
  bool mine_seen_ = false;
  std::optional<WorldCommand> undone_;
  int states_since_ = 0;
};

int run_world(WorldAction action, const WorldOptions& options) {
  if (!(options.timeout_s > 0.0 && options.timeout_s <= 3600.0))
    throw Error("--timeout takes a number of seconds from 0 to 3600");
  if (action == WorldAction::kStep &&
      (options.steps == 0 || options.steps > kMaxWorldStepsPerCommand))
    throw Error("step takes a number of steps from 1 to " +
                std::to_string(kMaxWorldStepsPerCommand) +
                " (1000 s at 1 kHz); to run on, `afhub world resume`");
  install_stop_signal_handlers();
  connect_to_hub("world", HubPolicy::kRequire);
  LatestReader<WorldState> reader(world_channel(options, kStateEvent));
  const WorldState before = first_world_state(reader);
  if (action == WorldAction::kStep && !under_pause(before))
    throw Error(
        "the world is running, so there is nothing to step: pause it first (`afhub world "
        "pause`), then `afhub world step N`");

  UndoneBy undone(options, action);  // made first: it reads this process's command too
  Writer<WorldCommand> writer(world_channel(options, kCommandEvent));
  // The simulation acts on each sequence number once: start past any number an
  // earlier `afhub world` could have used.
  const auto sequence = static_cast<std::uint64_t>(monotonic_ns());
  writer.raw().continue_sequence_after(sequence);
  WorldCommand* command = writer.loan();
  if (!command) throw Error("shared memory is exhausted: the world command was not sent");
  command->action = action;
  command->step_count = options.steps;
  command->valid_ms = static_cast<std::uint32_t>(std::ceil(options.timeout_s * 1000.0));
  writer.publish(command);
  undone.sent(sequence + 1);

  WorldActionWatch watch(action, options.steps, before, monotonic_ns());
  std::int64_t give_up = monotonic_ns() + static_cast<std::int64_t>(options.timeout_s * 1e9) +
                         kWorldCommandShownWithinNs;
  // Steps take their time: once the world steps them, the wait lasts while it does (a
  // step longer than --timeout failed, saying the world had not acted).
  std::uint64_t stepping_at = before.header.sim_step;
  while (monotonic_ns() < give_up) {
    const WorldState* state = reader.latest();
    if (stop_requested()) {
      if (action == WorldAction::kStep && state && state->header.sim_step > before.header.sim_step)
        throw Stopped("stopped waiting at step " + std::to_string(state->header.sim_step) +
                      ": the world runs the rest of the steps on (`afhub world pause` ends them)");
      throw Stopped(
          "stopped waiting: the command was sent, and the world acts on it if it "
          "reads it within --timeout");
    }
    if (state && reader.updated()) {
      if (action == WorldAction::kStep && state->header.sim_step > stepping_at) {
        stepping_at = state->header.sim_step;
        give_up = std::max(give_up, monotonic_ns() + 2'000'000'000);
      }
      if (const std::optional<std::string> said = watch.shown(*state)) {
        std::printf("%s\n", said->c_str());
        return 0;
      }
      if (undone.by_now(*state)) {
        std::printf(
            "%s, and undone since by another process (pid %u: %s): now %s at step %llu "
            "(t = %.3f s)\n",
            done(action), undone.command().header.publisher_pid, done(undone.command().action),
            state->paused ? "paused" : "running",
            static_cast<unsigned long long>(state->header.sim_step), state->header.sim_time_s);
        return 0;
      }
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  if (stepping_at > before.header.sim_step)
    throw Error("the world stepped from step " + std::to_string(before.header.sim_step) + " to " +
                std::to_string(stepping_at) + " of the " + std::to_string(options.steps) +
                " steps asked, then stalled for 2 s: is the simulation stopped, or waiting for "
                "lockstep clients? (`afhub status`)");
  throw Error("the command was sent but the simulation did not act on it within " +
              yaml::number_text(options.timeout_s) +
              " s, and it will not later (read after that, it is dropped): is the simulation "
              "stalled, or waiting for lockstep clients? (`afhub status`)");
}

}  // namespace

void register_world(CLI::App& app, Runner& selected) {
  auto* world = app.add_subcommand(
      "world",
      "Control the running simulation's clock: pause, resume, step N while paused, reset. "
      "Each waits until the simulation has acted (read back from its world state) and says "
      "what happened; it fails when no simulation runs.");
  world->require_subcommand(1);
  struct Action {
    const char* name;
    const char* help;
    WorldAction action;
  };
  for (const Action& entry :
       {Action{"pause", "Stop stepping; states are still published every period.",
               WorldAction::kPause},
        Action{"resume", "Step again in real time (or lockstep) after a pause.",
               WorldAction::kResume},
        Action{"step", "While paused, advance N steps (default 1), then stay paused.",
               WorldAction::kStep},
        Action{"reset",
               "Put every body back where the model starts it, clear its commands and set the "
               "step count to 0 (paused or running, as before).",
               WorldAction::kReset}}) {
    auto options = std::make_shared<WorldOptions>();
    auto* command = world->add_subcommand(entry.name, entry.help);
    if (entry.action == WorldAction::kStep)
      add_count_option(command, "N", options->steps, "Number of steps (default 1)");
    add_world_namespace_option(command, options->name_space);
    command->add_option("--timeout", options->timeout_s,
                        "Fail when the simulation has not acted within this many seconds "
                        "(default 5)");
    const WorldAction action = entry.action;
    command->callback([&selected, options, action] {
      selected = [options, action] { return run_world(action, *options); };
    });
  }
}

}  // namespace afhub::cli
