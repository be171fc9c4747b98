// Work a step splits between the thread stepping the simulation and the helper thread
// that solves islands beside it (Simulation::share).
#pragma once

#include <algorithm>
#include <type_traits>

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

// `each(index, thread)` for every index below `count`, in items of `per_item`
// consecutive indices: work on each body or joint of a step, where each index writes
// only its own. Made on the stack where it is shared (share_each): nothing allocated.
template <class Each>
class EachIndex final : public SharedWork {
 public:
  EachIndex(int count, int per_item, Each& each)
      : count_(count), per_item_(per_item), each_(each) {}
  int items() const noexcept { return (count_ + per_item_ - 1) / per_item_; }
  void run(int item, int thread) noexcept override {
    const int last = std::min(count_, (item + 1) * per_item_);
    for (int index = item * per_item_; index < last; ++index) each_(index, thread);
  }

 private:
  int count_, per_item_;
  Each& each_;
};

// `each` over `count` indices, run by `sharer.share` (a Simulation, say).
template <class Sharer, class Each>
void share_each(Sharer& sharer, int count, int per_item, Each&& each) noexcept {
  EachIndex<std::remove_reference_t<Each>> work(count, per_item, each);
  sharer.share(work.items(), work);
}

}  // namespace afhub::physics
