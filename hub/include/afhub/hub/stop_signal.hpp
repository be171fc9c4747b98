// SIGINT and SIGTERM for long-running processes: a flag their loops poll, and a
// deadline-paced sleep that wakes early when asked to stop.
#pragma once

#include <cstdint>

namespace afhub {

void install_stop_signal_handlers();
bool stop_requested();

// Sleeps until the absolute CLOCK_MONOTONIC time `deadline_ns`.
void sleep_until_ns(std::int64_t deadline_ns);
std::int64_t monotonic_ns();

}  // namespace afhub
