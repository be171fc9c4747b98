// A step's islands solved by the stepping thread and one helper thread at once. A
// world of many robots is many islands (125 eight-link arms: 125), each solved on its
// own (reserved_world.hpp), and their solve was 70 % of the step on one core.
//
// Islands share nothing the solve writes: each moves only its own bodies, contacts
// and joints, and its multibodies (a chain in reduced coordinates lies wholly in one
// island); static bodies are read, never written (Bullet writes to a kinematic body
// from every island it touches: none is made, and a world with one is solved by one
// thread). Bullet's one global written, a count of deep contacts' split-impulse
// corrections that nothing reads, may be raced on. Each thread has its own solver,
// so an island's result is the same whichever thread solves it: the step is
// bit-identical to solving them one after another.
//
// The two threads take islands from the two ends of one list, so the stepping thread
// never waits for a helper that wakes late (a sleeping vCPU took 80 to 110 us on the
// project's VM): it waits only for the island the helper is in the middle of. From the
// ends, each thread tends to solve the same islands every step, whose joints stay in
// its cache (0.94x the step of one shared counter, median of 7 interleaved rounds).
// Between steps the helper naps on a timer rather than waiting to be woken: waking it
// cost the stepping thread 40 to 50 us a step on the project's VM (await_job in the
// .cpp). It naps under the normal scheduler, so that a real-time controller on the
// other CPU is not preempted every nap, and solves under the stepping thread's
// scheduling policy and priority, on the CPUs it may run on; with one CPU allowed
// (`afhub run --cpu`), or the helper refused that priority, the stepping thread solves
// everything itself. Each island's multibodies are readied for its solve, and its
// bodies integrated after, by the thread that solves it (AroundIsland,
// reserved_world.hpp). Other work of the step that splits into items
// writing nothing in common is shared the same way (share(): the chains' mirrors and the
// joints' readings after the step, the states published).
#pragma once

#include <sched.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "afhub/physics/shared_work.hpp"
#include "constraint_solver.hpp"

namespace afhub::physics {

class ParallelIslands final : private SharedWork {
 public:
  // Fewer islands (or items of other work) than this are run by the stepping thread
  // alone: handing them over costs more than the helper takes.
  static constexpr int kMinItems = 16;
  static constexpr int kCountBits = 20;  // a job's items: fewer than 2^20 (ticket_)

  struct Island {
    int first_body, body_count;  // in the bodies array solve() is given
    btPersistentManifold** manifolds;
    int manifold_count;
    int first_constraint, constraint_count;                      // in the constraints array
    int first_multibody_constraint, multibody_constraint_count;  // in the multibody ones
  };

  // Work on an island's bodies just before and just after its solve, done by the
  // thread that solves it, while the bodies are in that thread's cache.
  class AroundIsland {
   public:
    virtual void island_to_solve(btCollisionObject** bodies, int count, int thread) noexcept = 0;
    virtual void island_solved(btCollisionObject** bodies, int count, int thread) noexcept = 0;

   protected:
    ~AroundIsland() = default;
  };

  // The helper's solver is made like the world's: ConstraintSolver(bodies, joints),
  // with the direct solve (islands are solved one at a time only with it).
  ParallelIslands(int bodies, int joints);
  ~ParallelIslands();
  ParallelIslands(const ParallelIslands&) = delete;
  ParallelIslands& operator=(const ParallelIslands&) = delete;

  // Solves every island, `own` solving those the stepping thread takes, each between
  // `around`'s two calls on the same thread; returns when all are done.
  void solve(ConstraintSolver& own, const std::vector<Island>& islands, btCollisionObject** bodies,
             btTypedConstraint** constraints, btMultiBodyConstraint** multibody_constraints,
             const btContactSolverInfo& info, AroundIsland& around) noexcept;
  // Runs every item of `work`, the stepping thread taking them from the first, the
  // helper from the last, as islands are; returns when all are done. The stepping
  // thread runs them all with fewer than kMinItems, and while the last solve() found it
  // may use one CPU only (see above), or before any solve().
  void share(int count, SharedWork& work) noexcept;
  // Islands the helper solved, and items of other work it ran, since the start.
  std::uint64_t helped() const noexcept { return helped_.load(std::memory_order_relaxed); }
  std::uint64_t shared() const noexcept { return shared_.load(std::memory_order_relaxed); }

 private:
  void run(int island, int thread) noexcept override;  // solves one island
  void help() noexcept;
  void run_shared(int count, SharedWork& work) noexcept;
  void await_job(std::uint32_t seen) const noexcept;
  void schedule_helper(bool solving) const noexcept;
  bool follow_stepping_thread() noexcept;

  // A job's items (islands, or another SharedWork's) are taken one at a time from
  // `ticket_`: its job number (the top 24 bits), the next item from the start (20 bits,
  // the stepping thread's) and one past the last left from the end (20 bits, the
  // helper's), in one word, so that a late helper can never take an item of a job that
  // has ended.
  std::atomic<std::uint64_t> ticket_{0};
  std::atomic<std::uint32_t> job_{0};  // the job's number; the helper waits for it to move
  std::atomic<int> done_{0};           // items of the job done
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> helped_{0}, shared_{0};

  // The job, written before its ticket is published, read after an item is taken.
  SharedWork* work_ = nullptr;
  // The islands being solved (run).
  ConstraintSolver* own_ = nullptr;
  const std::vector<Island>* islands_ = nullptr;
  btCollisionObject** bodies_ = nullptr;
  btTypedConstraint** constraints_ = nullptr;
  btMultiBodyConstraint** multibody_constraints_ = nullptr;
  const btContactSolverInfo* info_ = nullptr;
  AroundIsland* around_ = nullptr;

  // The stepping thread's policy, priority and CPUs, as solve() last found them and
  // applied them to the helper (-1: not yet); the first two also for the helper to read
  // (schedule_helper), published with a job.
  int policy_ = -1, priority_ = -1;
  std::atomic<int> job_policy_{SCHED_OTHER}, job_priority_{0};
  cpu_set_t cpus_{};
  bool alone_ = false;  // the stepping thread may run on one CPU only

  ConstraintSolver solver_;
  std::thread helper_;
};

}  // namespace afhub::physics
