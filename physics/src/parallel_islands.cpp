#include "parallel_islands.hpp"

#include <pthread.h>
#include <sys/prctl.h>
#include <time.h>

#include <chrono>

namespace afhub::physics {
namespace {

constexpr std::uint64_t kFieldMask = (std::uint64_t{1} << ParallelIslands::kCountBits) - 1;
constexpr std::uint64_t kJobMask = (std::uint64_t{1} << (64 - 2 * ParallelIslands::kCountBits)) - 1;
constexpr int kSpinsBeforeYield = 4096;  // 0.1 to 0.3 ms of pauses: a few islands
// Between jobs the helper first spins this long (a step's jobs follow each other
// closely: the islands, then the chains' mirrors and the joints' readings), then naps
// this long at a time (await_job), for this long at most.
constexpr std::chrono::nanoseconds kSpin{30'000};
constexpr std::chrono::nanoseconds kNap{20'000};
constexpr std::chrono::milliseconds kNapping{20};

}  // namespace

ParallelIslands::ParallelIslands(int bodies, int joints) : solver_(bodies, joints) {
  solver_.enable_direct_solve();
  helper_ = std::thread([this] {
    prctl(PR_SET_TIMERSLACK, 1000);  // its naps end on time, not up to 50 us late
    help();
  });
  pthread_setname_np(helper_.native_handle(), "afhub-islands");  // as top and perf show it
}

ParallelIslands::~ParallelIslands() {
  stopping_.store(true);
  job_.fetch_add(1);
  job_.notify_one();
  helper_.join();
}

void ParallelIslands::run(int island, int thread) noexcept {
  const Island& i = (*islands_)[island];
  ConstraintSolver& solver = thread == 0 ? *own_ : solver_;
  around_->island_to_solve(bodies_ + i.first_body, i.body_count, thread);
  // A multibody solver reads the group's multibody constraints, which only this sets.
  solver.solveMultiBodyGroup(
      bodies_ + i.first_body, i.body_count, i.manifolds, i.manifold_count,
      i.constraint_count ? constraints_ + i.first_constraint : nullptr, i.constraint_count,
      i.multibody_constraint_count ? multibody_constraints_ + i.first_multibody_constraint
                                   : nullptr,
      i.multibody_constraint_count, *info_, nullptr, nullptr);
  around_->island_solved(bodies_ + i.first_body, i.body_count, thread);
  if (thread != 0) helped_.fetch_add(1, std::memory_order_relaxed);
}

// The stepping thread's scheduling and CPUs, given to the helper when they change (the
// real-time loop sets them after the world is built); false if it may use one CPU only.
bool ParallelIslands::follow_stepping_thread() noexcept {
  sched_param param{};
  int policy = 0;
  cpu_set_t cpus;
  if (pthread_getschedparam(pthread_self(), &policy, &param) != 0 ||
      pthread_getaffinity_np(pthread_self(), sizeof cpus, &cpus) != 0)
    return false;
  if (policy == policy_ && param.sched_priority == priority_ && CPU_EQUAL(&cpus, &cpus_))
    return !alone_;
  policy_ = policy;
  priority_ = param.sched_priority;
  job_policy_.store(policy, std::memory_order_relaxed);
  job_priority_.store(param.sched_priority, std::memory_order_relaxed);
  cpus_ = cpus;
  // A helper refused the stepping thread's priority could wait behind it on its CPU
  // while it waits for the helper's island: then the stepping thread solves alone.
  alone_ = CPU_COUNT(&cpus) < 2 ||
           pthread_setschedparam(helper_.native_handle(), policy, &param) != 0 ||
           pthread_setaffinity_np(helper_.native_handle(), sizeof cpus, &cpus) != 0;
  return !alone_;
}

void ParallelIslands::solve(ConstraintSolver& own, const std::vector<Island>& islands,
                            btCollisionObject** bodies, btTypedConstraint** constraints,
                            btMultiBodyConstraint** multibody_constraints,
                            const btContactSolverInfo& info, AroundIsland& around) noexcept {
  const int count = static_cast<int>(islands.size());
  own_ = &own;
  islands_ = &islands;
  bodies_ = bodies;
  constraints_ = constraints;
  multibody_constraints_ = multibody_constraints;
  info_ = &info;
  around_ = &around;
  // The stepping thread's scheduling is looked up once a step, here (system calls).
  if (count < kMinItems || !follow_stepping_thread()) {
    run_alone(count, *this);
    return;
  }
  run_shared(count, *this);
}

void ParallelIslands::share(int count, SharedWork& work) noexcept {
  if (count < kMinItems || policy_ < 0 || alone_)
    run_alone(count, work);
  else
    run_shared(count, work);
}

void ParallelIslands::run_shared(int count, SharedWork& work) noexcept {
  if (count >= static_cast<int>(kFieldMask)) {
    run_alone(count, work);
    return;
  }
  work_ = &work;
  const std::uint32_t job = job_.load(std::memory_order_relaxed) + 1;
  done_.store(0, std::memory_order_relaxed);
  // Front: the next item from the start (this thread's); back: one past the last left
  // from the end (the helper's). Each thread tends to get the same items every step,
  // whose data stay in its cache.
  ticket_.store((std::uint64_t{job} << (2 * kCountBits)) | (std::uint64_t(count)),
                std::memory_order_release);
  job_.store(job, std::memory_order_release);
  job_.notify_one();
  std::uint64_t ticket = ticket_.load(std::memory_order_acquire);
  for (;;) {
    const std::uint64_t front = (ticket >> kCountBits) & kFieldMask, back = ticket & kFieldMask;
    if (front >= back) break;
    if (!ticket_.compare_exchange_weak(ticket, ticket + (std::uint64_t{1} << kCountBits),
                                       std::memory_order_acq_rel))
      continue;
    work.run(static_cast<int>(front), 0);
    done_.fetch_add(1, std::memory_order_release);
    ticket = ticket_.load(std::memory_order_acquire);
  }
  // Only the item the helper is in the middle of, if any, is left. Should the helper
  // have been moved onto this thread's CPU, spinning would keep it off: yield.
  for (int spins = 0; done_.load(std::memory_order_acquire) < count;) {
    if (spins < kSpinsBeforeYield) {
      ++spins;
      __builtin_ia32_pause();
    } else {
      sched_yield();
    }
  }
}

// Returns once job_ has moved on from `seen`. Waking a thread asleep on a futex cost
// the stepping thread 40 to 50 us a step on the project's VM (the interrupt to the
// halted vCPU goes through the hypervisor), so between jobs the helper naps in short
// timed sleeps, which end on its own CPU's timer, and the stepping thread's
// notify_one() finds no one waiting and makes no system call. Sleeping until shortly
// before the next job was due instead (jobs come once a step) cost less CPU but made
// the step's p99 worse: a long sleep lets the vCPU halt, and it wakes late. After
// kNapping without a job (a paused or slow world) it sleeps until notified.
void ParallelIslands::await_job(std::uint32_t seen) const noexcept {
  const auto start = std::chrono::steady_clock::now();
  while (job_.load(std::memory_order_acquire) == seen) {
    const auto waited = std::chrono::steady_clock::now() - start;
    if (waited < kSpin) {
      __builtin_ia32_pause();
      continue;
    }
    if (waited > kNapping) {
      job_.wait(seen, std::memory_order_acquire);
      return;
    }
    const timespec nap{0, kNap.count()};
    nanosleep(&nap, nullptr);
  }
}

// Under a real-time stepping thread, the helper takes its policy and priority only
// while it solves (follow_stepping_thread gave them, proving it may): napping at that
// priority would preempt whatever runs on the other CPU, a 1 kHz controller say, every
// kNap. Napping under the normal scheduler, it waits for such a controller instead,
// and the stepping thread solves the islands it does not come for.
void ParallelIslands::schedule_helper(bool solving) const noexcept {
  const int policy = job_policy_.load(std::memory_order_relaxed);
  if (policy != SCHED_FIFO && policy != SCHED_RR) return;
  sched_param param{};
  param.sched_priority = solving ? job_priority_.load(std::memory_order_relaxed) : 0;
  pthread_setschedparam(pthread_self(), solving ? policy : SCHED_OTHER, &param);
}

void ParallelIslands::help() noexcept {
  std::uint32_t seen = 0;
  for (;;) {
    schedule_helper(false);
    await_job(seen);
    if (stopping_.load()) return;
    seen = job_.load(std::memory_order_acquire);
    schedule_helper(true);
    std::uint64_t ticket = ticket_.load(std::memory_order_acquire);
    for (;;) {
      const std::uint64_t front = (ticket >> kCountBits) & kFieldMask, back = ticket & kFieldMask;
      // Another job's ticket (a later one: this wake was late), or none left.
      if ((ticket >> (2 * kCountBits)) != (seen & kJobMask) || front >= back) break;
      if (ticket_.compare_exchange_weak(ticket, ticket - 1, std::memory_order_acq_rel)) {
        work_->run(static_cast<int>(back - 1), 1);
        if (work_ != this) shared_.fetch_add(1, std::memory_order_relaxed);
        done_.fetch_add(1, std::memory_order_release);
        ticket = ticket_.load(std::memory_order_acquire);
      }
    }
  }
}

}  // namespace afhub::physics
