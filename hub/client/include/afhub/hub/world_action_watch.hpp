// Whether the world states read after a world command was sent show it done, and what
// to say of it: one rule for `afhub world`, Python's World and the viewer's buttons. The
// world acts on a command at its next step and shows it in the states that follow: the
// paused flag, the step count going on or back to 0. A reset from step 0 shows nothing:
// it is taken as done by the second state published after sending, which a physics
// reading its commands each period has read it by; one held by its lockstep barrier
// republishes the held state meanwhile, and reads it once the hold ends.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "afhub/shm_layout/world.hpp"

namespace afhub {

class WorldActionWatch {
 public:
  // `before`: the newest world state read before `action` was sent (with `steps` for a
  // step); `sent_ns`: monotonic_ns() once it was.
  WorldActionWatch(WorldAction action, std::uint32_t steps, const WorldState& before,
                   std::int64_t sent_ns);

  // Given each new world state in turn; once one shows the action done, what happened
  // ("paused at step 12 (t = 0.012 s)").
  std::optional<std::string> shown(const WorldState& now);

 private:
  WorldAction action_;
  std::uint32_t steps_;
  bool paused_before_;
  std::uint64_t step_before_;
  std::int64_t sent_ns_;
  std::uint64_t previous_step_;
  int states_after_sending_ = 0;
};

}  // namespace afhub
