// The monotonic clock every afhub process stamps and paces with (monotonic_ns(),
// defined beside the payload header whose stamps use it), and sleeping to a deadline.
#pragma once

#include <cstdint>

#include "afhub/shm_layout/header.hpp"

namespace afhub {

// Sleeps until the absolute monotonic_ns() time `deadline_ns`; returns early when a
// stop signal arrives (stop_signal.hpp).
void sleep_until_ns(std::int64_t deadline_ns) noexcept;

}  // namespace afhub
