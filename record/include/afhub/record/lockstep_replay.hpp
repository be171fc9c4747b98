// `afhub play --commands-into-physics`: reproduces a lockstep run from its recording.
// A new physics of the same models, started with `afhub run ... --lockstep --wait-for 1`,
// gets the recorded commands as a lockstep client, each applied at the step it took
// effect in the recording (each recorded state names the command in force, so a late
// answer is applied as late as it was); every step, each body's state is compared with
// the recorded one, field by field and bit for bit. The first state that differs is
// named: its step, its body and its field.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace afhub::mcap {

struct ReplayCheck {
  std::uint64_t steps = 0;   // steps compared
  std::uint64_t states = 0;  // body states compared
  bool diverged = false;
  std::uint64_t step = 0;  // the first step whose state differs
  std::string body;        // its body
  std::string field;       // "joints[2].position: recorded 0.31, replayed 0.30"
  std::string cut_off;     // why and where the file was cut off; empty for a whole file
};

// Needs connect_to_hub() and the physics waiting at step 0. Throws afhub::Error for a
// recording that cannot be replayed (not afhub's, another layout, not from step 0, a
// command the recorder missed) or a physics that is not in lockstep or stops stepping.
ReplayCheck replay_into_physics(const std::string& file, const std::function<bool()>& keep_going);

}  // namespace afhub::mcap
