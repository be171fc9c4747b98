// The page's world commands (see world_commander.hpp).
#include "afhub/viewer/world_commander.hpp"

#include <chrono>
#include <thread>

#include <civetweb.h>

#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub::viewer {
namespace {

// How long a page's world command waits to be shown done (and is valid).
constexpr std::uint32_t kWaitMs = 1000;

}  // namespace

WorldCommander::WorldCommander(const std::string& world)
    : writer_({std::string(kService), world, std::string(kCommandEvent)}),
      state_({std::string(kService), world, std::string(kStateEvent)}) {
  // The simulation acts on each (pid, sequence) once: start past any number an
  // earlier viewer with this pid could have used, as `afhub world` does.
  writer_.raw().continue_sequence_after(static_cast<std::uint64_t>(monotonic_ns()));
}

std::string WorldCommander::run(const std::string& query) {
  char text[16];
  const int length = mg_get_var(query.c_str(), query.size(), "action", text, sizeof text);
  const std::string action = length < 0 ? std::string() : std::string(text);
  WorldAction chosen = WorldAction::kNone;
  if (action == "pause") chosen = WorldAction::kPause;
  if (action == "resume") chosen = WorldAction::kResume;
  if (action == "step") chosen = WorldAction::kStep;
  if (action == "reset") chosen = WorldAction::kReset;
  if (chosen == WorldAction::kNone)
    return "action: one of pause, resume, step, reset; got '" + action + "'";

  std::lock_guard lock(mutex_);
  const WorldState* state = state_.latest();
  if (!state) return "no simulation is running: nothing publishes the world state";
  if (chosen == WorldAction::kStep && !under_pause(*state))
    return "the world is running, so there is nothing to step: pause it first";
  WorldCommand* command = writer_.loan();
  if (!command) return "no shared memory for a world command";
  command->action = chosen;
  command->step_count = 1;
  command->valid_ms = kWaitMs;
  const WorldState before = *state;
  writer_.publish(command);
  WorldActionWatch watch(chosen, 1, before, monotonic_ns());
  return wait_until_shown(watch);
}

// Answered once a world state shows the command done, so that a request sent after this
// one's answer finds the world changed (a step right after a pause found the world still
// running).
std::string WorldCommander::wait_until_shown(WorldActionWatch& watch) {
  for (const std::int64_t give_up =
           monotonic_ns() + std::int64_t{kWaitMs} * 1'000'000 + kWorldCommandShownWithinNs;
       monotonic_ns() < give_up; std::this_thread::sleep_for(std::chrono::microseconds(200))) {
    const WorldState* state = state_.latest();
    if (state && state_.updated() && watch.shown(*state)) return "";
  }
  return "sent, but the world has not shown it within 1 s, and will not later: the physics is "
         "stalled, or another client undid it";
}

}  // namespace afhub::viewer
