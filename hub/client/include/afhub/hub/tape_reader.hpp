// The reading end of a tape (shm_layout/tape_ring.hpp): every part in order, from the
// ring its writer published, and from a restarted writer's new ring once the old one is
// read. Real-time safe once made: no heap, no exceptions.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "afhub/shm_layout/device_tape.hpp"
#include "afhub/shm_layout/step_tape.hpp"

namespace afhub {

template <class Ring>
class TapeReader {
 public:
  using Part = typename Ring::PartType;
  // The tape of a world (`instance`: its instance) or of a device (its channel).
  explicit TapeReader(const std::string& instance);
  ~TapeReader();
  TapeReader(const TapeReader&) = delete;
  TapeReader& operator=(const TapeReader&) = delete;

  // The oldest part not read yet, copied into `out` (a step tape's used part) and
  // checked; false when none waits. Invalid parts and rings are refused (said once,
  // counted) and skipped. Parts the writer overwrote before they were read are skipped
  // and counted (lost()); a step tape's parts read show the gap too (StepTape::part,
  // header.sim_step).
  bool next(Part& out) noexcept;
  // Parts and rings refused so far.
  std::uint64_t refused() const noexcept { return refused_; }
  // Parts the writer overwrote before they were read, so far (counted up to where the
  // reader starts again).
  std::uint64_t lost() const noexcept { return lost_; }

 private:
  bool take_rings() noexcept;
  void refuse(const char* what, const char* why) noexcept;
  struct Port;
  std::unique_ptr<Port> port_;
  std::int64_t made_ns_;             // a ring made after it is read from its start
  const Ring* ring_ = nullptr;       // the ring read, held
  const Ring* next_ring_ = nullptr;  // a newer one (a restarted writer), held
  std::uint64_t cursor_ = 0;         // the next part of ring_ to read
  std::uint64_t refused_ = 0;
  std::uint64_t lost_ = 0;
};

using StepTapeReader = TapeReader<StepTapeRing>;
using DeviceTapeReader = TapeReader<DeviceTapeRing>;

}  // namespace afhub
