// Whether the simulated body's states still come: a device may push only on a live
// physics. A state is stale once its publish stamp is older than stale_ns, or once
// this loop has seen no new state (a new sequence or stamp) for stale_ns by its own
// clock (a stamp from the future is no fresher). Unlike DeviceFreshness this does not
// wait for the loop's own cycles: a false alarm on a busy machine costs a force ramp,
// a missed one pushes the operator's hand against a frozen or dead simulation.
#pragma once

#include <cstdint>

namespace afhub::teleop {

class StateFreshness {
 public:
  explicit StateFreshness(std::int64_t stale_ns) noexcept : stale_ns_(stale_ns) {}

  // Once per cycle with the newest state's sequence and publish stamp: true while stale.
  bool stale(std::uint64_t sequence, std::int64_t stamp_ns, std::int64_t now_ns) noexcept {
    if (sequence != sequence_ || stamp_ns != stamp_ns_ || seen_ns_ < 0) {
      sequence_ = sequence;
      stamp_ns_ = stamp_ns;
      seen_ns_ = now_ns;
    }
    return now_ns - stamp_ns > stale_ns_ || now_ns - seen_ns_ > stale_ns_;
  }

 private:
  std::int64_t stale_ns_;
  std::uint64_t sequence_{0};
  std::int64_t stamp_ns_{0};
  std::int64_t seen_ns_{-1};  // when this loop first saw the newest state; -1: none yet
};

}  // namespace afhub::teleop
