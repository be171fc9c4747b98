// The pacing options of the loops (see loop_options.hpp).
#include "loop_options.hpp"

#include <cmath>

#include "afhub/shm_layout/error.hpp"
#include "count_option.hpp"

namespace afhub::cli {

void add_loop_rate_options(CLI::App* command, LoopRateOptions& options) {
  command->add_option("--rate", options.rate_hz, "Loop rate in Hz (default 1000)");
  add_realtime_options(command, options.realtime, "the loop");
  add_count_option(command, "--cycles", options.cycles,
                   "Stop after this many cycles (default: Ctrl-C)");
}

void set_loop_rate_options(const LoopRateOptions& options, LoopOptions& loop) {
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100'000.0))
    throw Error("--rate must be between 0 and 100000 Hz");
  set_realtime_options(options.realtime, loop);
  loop.period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.rate_hz));
  loop.max_cycles = options.cycles;
}

}  // namespace afhub::cli
