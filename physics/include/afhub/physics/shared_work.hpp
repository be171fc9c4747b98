// Work a step splits between the thread stepping the simulation and the helper thread
// that solves islands beside it (Simulation::share).
#pragma once

namespace afhub::physics {

class SharedWork {
 public:
  // Item `item` of the work, run once by thread `thread`: 0 the stepping thread, 1 the
  // helper. Items run in any order, two at a time: they must write nothing in common.
  virtual void run(int item, int thread) noexcept = 0;

 protected:
  ~SharedWork() = default;
};

// Every item of `work` run by the calling thread, as thread 0.
inline void run_alone(int count, SharedWork& work) noexcept {
  for (int item = 0; item < count; ++item) work.run(item, 0);
}

}  // namespace afhub::physics
