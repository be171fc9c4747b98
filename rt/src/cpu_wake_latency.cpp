// Holding the CPU wake-up latency limit (see cpu_wake_latency.hpp).
#include "afhub/rt/cpu_wake_latency.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "afhub/shm_layout/error.hpp"

namespace afhub {

void check_cpu_wake_latency_option(int microseconds, bool given) {
  if (microseconds < (given ? 0 : -1) || microseconds > kMaxCpuWakeLatencyUs)
    throw Error("--cpu-wake-latency must be 0 to " + std::to_string(kMaxCpuWakeLatencyUs) +
                " microseconds");
}

bool hold_cpu_wake_latency(int microseconds, const char* who, const char* device) {
  // Left open on purpose: the request lasts as long as the file stays open.
  const int file = open(device, O_WRONLY | O_CLOEXEC);
  const std::int32_t value = microseconds;
  if (file >= 0 && write(file, &value, sizeof value) == sizeof value) return true;
  std::fprintf(stderr,
               "%s: cannot hold the CPU wake-up latency at %d us (%s: %s); running without: "
               "idle CPUs may sleep and wake late. Run as root to hold it\n",
               who, microseconds, device, std::strerror(errno));
  if (file >= 0) close(file);
  return false;
}

}  // namespace afhub
