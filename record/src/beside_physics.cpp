// The reading loop beside the physics (see beside_physics.hpp).
#include "beside_physics.hpp"

#include <sys/stat.h>

#include <cstdio>

#include "afhub/shm_layout/step_tape.hpp"

namespace afhub::mcap {

std::optional<int> only_cpu(const cpu_set_t& cpus) noexcept {
  if (CPU_COUNT(&cpus) != 1) return std::nullopt;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &cpus)) return cpu;
  return std::nullopt;
}

std::optional<int> real_time_cpu_of(pid_t pid) noexcept {
  if (pid <= 0) return std::nullopt;
  char exe[64];
  std::snprintf(exe, sizeof exe, "/proc/%d/exe", static_cast<int>(pid));
  struct stat self {};
  struct stat other {};
  if (stat("/proc/self/exe", &self) != 0 || stat(exe, &other) != 0 || self.st_dev != other.st_dev ||
      self.st_ino != other.st_ino)
    return std::nullopt;
  const int policy = sched_getscheduler(pid);
  if (policy != SCHED_FIFO && policy != SCHED_RR) return std::nullopt;
  cpu_set_t cpus;
  if (sched_getaffinity(pid, sizeof cpus, &cpus) != 0) return std::nullopt;
  return only_cpu(cpus);
}

void BesidePhysics::start(bool enabled) noexcept {
  thread_ = pthread_self();
  enabled_ =
      enabled && pthread_getaffinity_np(thread_, sizeof own_, &own_) == 0 && CPU_COUNT(&own_) > 1;
}

void BesidePhysics::follow(std::uint32_t writer_pid, std::uint32_t taken) noexcept {
  if (!enabled_) return;
  if (writer_pid == judged_pid_) {
    if (taken > kStepTapeRingParts / 4) leave("a quarter of the tape's ring waited");
    return;
  }
  judged_pid_ = writer_pid;
  const std::optional<int> found = real_time_cpu_of(static_cast<pid_t>(writer_pid));
  const int cpu = found && CPU_ISSET(*found, &own_) ? *found : -1;
  cpu_set_t cpus = own_;
  if (cpu >= 0) {
    CPU_ZERO(&cpus);
    CPU_SET(cpu, &cpus);
  }
  cpu_ = cpu;
  // Returns once this thread runs there: a CPU held by a physics that never sleeps
  // keeps it waiting until the watch moves it back.
  pthread_setaffinity_np(thread_, sizeof cpus, &cpus);
  if (cpu < 0) return;
  if (cpu_ < 0) {  // the watch moved it back before this move was made: undone
    pthread_setaffinity_np(thread_, sizeof own_, &own_);
    return;
  }
  std::fprintf(stderr,
               "afhub record: reading on CPU %d, the physics' (pid %u, real-time there), "
               "while it is idle: the step tape stays in that core's cache (--cpu to choose)\n",
               cpu, writer_pid);
}

void BesidePhysics::watch(std::int64_t now_ns) noexcept {
  const std::uint64_t turns = turns_.load(std::memory_order_relaxed);
  if (turns != watched_turns_ || cpu_ < 0) {
    watched_turns_ = turns;
    turned_ns_ = now_ns;
  } else if (now_ns - turned_ns_ > kStalledNs) {
    leave("the loop did not run there for 100 ms");
  }
}

void BesidePhysics::leave(const char* why) noexcept {
  const int cpu = cpu_.exchange(-1);
  if (cpu < 0) return;
  pthread_setaffinity_np(thread_, sizeof own_, &own_);
  std::fprintf(stderr,
               "afhub record: %s on CPU %d, the physics': reading on the recorder's other CPUs "
               "again\n",
               why, cpu);
}

}  // namespace afhub::mcap
