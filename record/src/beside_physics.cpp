// The reading loop beside the physics (see beside_physics.hpp).
#include "beside_physics.hpp"

#include <sys/stat.h>

#include <cstdio>

#include "afhub/shm_layout/step_tape.hpp"

namespace afhub::mcap {

std::optional<int> real_time_cpu_of(pid_t pid) noexcept {
  if (pid <= 0) return std::nullopt;
  char exe[64];
  std::snprintf(exe, sizeof exe, "/proc/%d/exe", static_cast<int>(pid));
  struct stat self {
  }, other{};
  if (stat("/proc/self/exe", &self) != 0 || stat(exe, &other) != 0 || self.st_dev != other.st_dev ||
      self.st_ino != other.st_ino)
    return std::nullopt;
  const int policy = sched_getscheduler(pid);
  if (policy != SCHED_FIFO && policy != SCHED_RR) return std::nullopt;
  cpu_set_t cpus;
  if (sched_getaffinity(pid, sizeof cpus, &cpus) != 0 || CPU_COUNT(&cpus) != 1) return std::nullopt;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &cpus)) return cpu;
  return std::nullopt;
}

void BesidePhysics::start(bool enabled) noexcept {
  thread_ = pthread_self();
  enabled_ = enabled && pthread_getaffinity_np(thread_, sizeof own_, &own_) == 0;
}

void BesidePhysics::follow(std::uint32_t writer_pid, std::uint32_t taken) noexcept {
  if (!enabled_) return;
  if (writer_pid == judged_pid_) {
    if (taken > kStepTapeQueue / 4) leave("the tape fell behind there");
    return;
  }
  judged_pid_ = writer_pid;
  left_ = false;
  const std::optional<int> cpu = real_time_cpu_of(static_cast<pid_t>(writer_pid));
  cpu_set_t cpus = own_;
  if (cpu && CPU_ISSET(*cpu, &own_)) {
    CPU_ZERO(&cpus);
    CPU_SET(*cpu, &cpus);
  }
  if (pthread_setaffinity_np(thread_, sizeof cpus, &cpus) != 0) return;
  cpu_ = CPU_COUNT(&cpus) == 1 ? *cpu : -1;
  if (cpu_ >= 0)
    std::fprintf(stderr,
                 "afhub record: reading on CPU %d, the physics' (pid %u, real-time there), "
                 "while it is idle: the step tape stays in that core's cache (--cpu to "
                 "choose)\n",
                 cpu_.load(), writer_pid);
}

void BesidePhysics::watch(std::int64_t now_ns) noexcept {
  const std::uint64_t turns = turns_.load(std::memory_order_relaxed);
  if (turns != watched_turns_ || cpu_ < 0) {
    watched_turns_ = turns;
    turned_ns_ = now_ns;
  } else if (now_ns - turned_ns_ > kStalledNs) {
    leave("it did not run there");
  }
}

void BesidePhysics::leave(const char* why) noexcept {
  const int cpu = cpu_.exchange(-1);
  if (cpu < 0 || left_.exchange(true)) return;
  if (pthread_setaffinity_np(thread_, sizeof own_, &own_) == 0)
    std::fprintf(stderr,
                 "afhub record: the physics leaves the reading too little time on CPU %d (%s): "
                 "reading on the other CPUs again\n",
                 cpu, why);
}

}  // namespace afhub::mcap
