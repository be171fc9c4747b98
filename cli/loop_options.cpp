// The pacing options of the loops (see loop_options.hpp).
#include "loop_options.hpp"

#include <cmath>

#include "afhub/shm_layout/error.hpp"
#include "count_option.hpp"
#include "time_options.hpp"

namespace afhub::cli {

void add_loop_rate_options(CLI::App* command, LoopRateOptions& options) {
  command->add_option("--rate", options.rate_hz, "Loop rate in Hz (default 1000)");
  add_realtime_options(command, options.realtime, "the loop");
  add_count_option(command, "--cycles", options.cycles,
                   "Stop after this many cycles (default: Ctrl-C)");
}

void add_phase_options(CLI::App* command, PhaseOptions& options, const char* what) {
  command->add_option("--after-step", options.after_step_us,
                      std::string("Wake this many microseconds after each physics step is due "
                                  "(default: half the period), so that every ") +
                          what + " answers the newest state and is ready for the next step");
  command->add_flag("--unaligned", options.unaligned,
                    "Wake on this loop's own clock instead, out of phase with the physics");
}

std::int64_t after_step_ns(const PhaseOptions& options, std::int64_t period_ns) {
  if (options.after_step_us >= 0.0 && options.unaligned)
    throw Error("--after-step and --unaligned exclude each other: keep one");
  if (options.unaligned) return kAfterStepUnaligned;
  if (options.after_step_us < 0.0) return kAfterStepHalfPeriod;
  if (options.after_step_us * 1e3 >= static_cast<double>(period_ns))
    throw Error("--after-step must be shorter than the loop's period");
  return std::llround(options.after_step_us * 1e3);
}

void set_loop_rate_options(const LoopRateOptions& options, LoopOptions& loop) {
  loop.period_ns = period_ns_of_rate(options.rate_hz, "--rate");
  set_realtime_options(options.realtime, loop);
  loop.max_cycles = options.cycles;
}

}  // namespace afhub::cli
