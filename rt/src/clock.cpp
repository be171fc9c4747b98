// Absolute-deadline sleeping (see clock.hpp).
#include "afhub/rt/clock.hpp"

#include <time.h>

#include <cerrno>

#include "afhub/rt/stop_signal.hpp"

namespace afhub {

void sleep_until_ns(std::int64_t deadline_ns) noexcept {
  const timespec deadline{deadline_ns / 1'000'000'000, deadline_ns % 1'000'000'000};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    if (stop_requested()) return;
  }
}

}  // namespace afhub
