// The recorder's reading loop beside the physics. A physics pinned to one CPU under a
// real-time policy (`afhub run --fifo P --cpu N`) leaves that CPU idle between its
// steps. Run there under the normal scheduler, the reading loop reads the step tape out
// of the cache the physics wrote it into; from another core it pulls the tape's lines
// over, and the physics pays for taking them back at its next write. On the project's
// 2-core VM this halved what the recorder adds to the step's median (docs/performance.md).
// The loop leaves that CPU for good when the tape's queue fills there or the loop stops
// turning (a physics with no idle time left), and judges a restarted physics afresh.
#pragma once

#include <pthread.h>
#include <sched.h>
#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <optional>

namespace afhub::mcap {

// The one CPU in `cpus`, if it holds one only.
std::optional<int> only_cpu(const cpu_set_t& cpus) noexcept;

// The one CPU the process `pid` may run on, when it runs under SCHED_FIFO or SCHED_RR
// and is an afhub process (this one's executable; a pid from another pid namespace may
// still name another afhub process here, which costs nothing but the gain); nothing
// otherwise, or when this process may not read its /proc entry (another user's).
std::optional<int> real_time_cpu_of(pid_t pid) noexcept;

class BesidePhysics {
 public:
  // By the reading loop's thread, which it then moves. Off when the loop's CPU or
  // real-time priority was chosen (a real-time loop on the physics' CPU would take it
  // from the physics), or when the loop may run on one CPU only.
  void start(bool enabled) noexcept;
  // By the reading loop, each turn.
  void turned() noexcept { turns_.fetch_add(1, std::memory_order_relaxed); }
  // By the reading loop, with each tape sample's writer and how many samples it has
  // taken this turn: onto a new writer's CPU (real_time_cpu_of), or back to the CPUs it
  // had; back for good when a quarter of the tape's queue was waiting.
  void follow(std::uint32_t writer_pid, std::uint32_t taken) noexcept;
  // By another thread, often: the loop back to its CPUs for good when it has not turned
  // for kStalledNs on the physics' CPU, also while its move there waits for that CPU
  // (a physics under SCHED_FIFO that never sleeps).
  void watch(std::int64_t now_ns) noexcept;

  static constexpr std::int64_t kStalledNs = 100'000'000;  // the loop turns every 4 ms

 private:
  void leave(const char* why) noexcept;

  bool enabled_ = false;
  pthread_t thread_{};
  cpu_set_t own_{};
  std::uint32_t judged_pid_ = 0;
  // The physics' CPU while the loop is on it, or moving there; -1 otherwise. Set before
  // the move, so that the watch can undo a move that waits for a CPU that never frees.
  std::atomic<int> cpu_{-1};
  std::atomic<std::uint64_t> turns_{0};
  std::uint64_t watched_turns_ = 0;  // the watching thread's
  std::int64_t turned_ns_ = 0;
};

}  // namespace afhub::mcap
