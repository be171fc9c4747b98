// The physics' step log (`afhub run --step-log`) as the benches read it, and its late
// commands told apart by whether the machine held the physics back at that moment.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace afhub::bench {

// One step as the physics timed it, in us.
struct StepPhases {
  float commands = 0, physics = 0, publish = 0;
  float total() const { return commands + physics + publish; }
};

struct LoggedStep {
  std::int64_t begin_ns = 0, due_ns = 0;
  StepPhases phases;
  std::uint32_t late = 0;  // bodies under command whose command did not answer the step before
};

// How long a physics stopped with SIGTERM is given to write its step log before it is
// killed: a minute of steps takes a second.
inline constexpr int kPhysicsStopMs = 60'000;

// The steps begun in [from_ns, to_ns]. Throws afhub::Error when the file is not a step log.
std::vector<LoggedStep> read_step_log(const std::string& path, std::int64_t from_ns,
                                      std::int64_t to_ns);

// A step the physics began more than this after it was due ran behind its grid: its
// SCHED_FIFO wake-up is 30 to 100 us at p99 on the project's VM.
inline constexpr std::int64_t kBehindNs = 300'000;

struct LateCommands {
  std::uint64_t late = 0;    // body-steps whose command did not answer the step before
  std::uint64_t behind = 0;  // of those, at a step behind its grid or the step after one
  // Times the physics fell behind, and of those the ones it woke up late for, not busy
  // with the step before (the machine held it back: in such a stall every process's
  // timer fires late together, see docs/performance.md, "The 1 kHz loop").
  std::uint64_t falls = 0, woke_late = 0;
  std::uint64_t on_grid_steps = 0;  // steps neither behind nor after one
};

// A command is late for a step behind its grid, or the step after one, when the state
// it had to answer came late or a catch-up ran the two back to back.
LateCommands late_commands(std::span<const LoggedStep> steps);
// The report's line saying so for `bodies` commanded each step, "" when none was late.
std::string late_commands_text(const LateCommands& late, int bodies);

}  // namespace afhub::bench
