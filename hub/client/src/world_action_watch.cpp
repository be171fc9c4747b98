// See world_action_watch.hpp.
#include "afhub/hub/world_action_watch.hpp"

#include <cstdio>

namespace afhub {
namespace {

std::string at(const WorldState& state) {
  char text[96];
  std::snprintf(text, sizeof text, "at step %llu (t = %.3f s)",
                static_cast<unsigned long long>(state.header.sim_step), state.header.sim_time_s);
  return text;
}

}  // namespace

WorldActionWatch::WorldActionWatch(WorldAction action, std::uint32_t steps,
                                   const WorldState& before, std::int64_t sent_ns)
    : action_(action),
      steps_(steps),
      // A world running steps by hand is under its pause: a pause halts it (it was not
      // halted), a resume runs it on (it was not running).
      paused_before_(action == WorldAction::kResume ? under_pause(before) : before.paused != 0),
      step_before_(before.header.sim_step),
      sent_ns_(sent_ns),
      previous_step_(before.header.sim_step) {}

std::optional<std::string> WorldActionWatch::shown(const WorldState& now) {
  if (now.header.publish_stamp_ns > sent_ns_) ++states_after_sending_;
  switch (action_) {
    case WorldAction::kPause:
      if (now.paused) return (paused_before_ ? "already paused " : "paused ") + at(now);
      break;
    case WorldAction::kResume:
      if (!under_pause(now)) return (paused_before_ ? "resumed " : "already running ") + at(now);
      break;
    case WorldAction::kStep: {
      if (now.header.sim_step < step_before_ + steps_) break;
      const std::string stepped =
          "stepped " + std::to_string(steps_) + (steps_ == 1 ? " step" : " steps");
      if (now.paused) return stepped + ": now paused " + at(now);
      // Steps asked by another command, before or beside these, are added to them.
      if (under_pause(now)) return stepped + ", and steps asked by another run on: now " + at(now);
      return stepped + ", and the world was resumed since: now running " + at(now);
    }
    case WorldAction::kReset:
      // The step count goes back to 0; from step 0 it cannot (see the header).
      if (now.header.sim_step < previous_step_ || (step_before_ == 0 && states_after_sending_ >= 2))
        return "reset from step " + std::to_string(previous_step_) + ": now " + at(now) +
               (now.paused ? ", paused" : "");
      previous_step_ = now.header.sim_step;
      break;
    case WorldAction::kNone:
    case WorldAction::kRelease:  // not shown: another holder may rightly keep the pause
      return "";
  }
  return std::nullopt;
}

}  // namespace afhub
