// Rate and seconds options made nanoseconds. Unchecked, a period or a span past what an
// int64 of nanoseconds holds came out negative or zero: a loop at 1e-12 Hz spun at full
// speed, a 1e10 s recording ended at once. Each is refused, naming its option, outside
// bounds a loop can keep.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>

#include "afhub/rt/periodic_loop.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/yaml/yaml_reader.hpp"

namespace afhub::cli {

inline constexpr double kMaxSeconds = 1e7;  // 116 days: a run, a recording, a timeout

// The period of `rate_hz`, from kMinLoopRateHz to kMaxLoopRateHz.
inline std::int64_t period_ns_of_rate(double rate_hz, const std::string& option) {
  if (!(rate_hz >= kMinLoopRateHz && rate_hz <= kMaxLoopRateHz))
    throw Error(option + " takes a rate from " + yaml::number_text(kMinLoopRateHz) + " to " +
                yaml::number_text(kMaxLoopRateHz) + " Hz, got " + yaml::number_text(rate_hz));
  return std::llround(1e9 / rate_hz);
}

// `seconds` from `min_s` to kMaxSeconds (a duration, a timeout) in nanoseconds.
inline std::int64_t ns_of_seconds(double seconds, const std::string& option, double min_s = 0.0) {
  if (!(seconds >= min_s && seconds <= kMaxSeconds))
    throw Error(option + " takes seconds from " + yaml::number_text(min_s) + " to " +
                yaml::number_text(kMaxSeconds) + ", got " + yaml::number_text(seconds));
  return std::llround(seconds * 1e9);
}

}  // namespace afhub::cli
