// The pacing options of the loops (see loop_options.hpp).
#include "loop_options.hpp"

#include <cmath>
#include <cstdio>

#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/yaml_reader.hpp"
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
  if (options.after_step_us && options.unaligned)
    throw Error("--after-step and --unaligned exclude each other: keep one");
  if (options.unaligned) return kAfterStepUnaligned;
  if (!options.after_step_us) return kAfterStepHalfPeriod;
  // NaN and negative offsets were taken as "not given" or rounded to garbage.
  const double us = *options.after_step_us;
  if (!(us >= 0.0 && us * 1e3 < static_cast<double>(period_ns))) {
    char text[160];
    std::snprintf(text, sizeof text, "--after-step takes 0 up to the loop's period (%g us), not %s",
                  period_ns * 1e-3, yaml::number_text(us).c_str());
    throw Error(text);
  }
  return std::llround(us * 1e3);
}

void set_loop_rate_options(const LoopRateOptions& options, LoopOptions& loop) {
  loop.period_ns = period_ns_of_rate(options.rate_hz, "--rate");
  set_realtime_options(options.realtime, loop);
  loop.max_cycles = options.cycles;
}

}  // namespace afhub::cli
