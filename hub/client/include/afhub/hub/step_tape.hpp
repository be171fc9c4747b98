// The writing end of a world's step tape (shm_layout/step_tape.hpp): the physics writes
// every step's states to its ring while a recorder reads (StepTapeReader,
// tape_reader.hpp). Real-time safe once made: no heap, no exceptions.
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "afhub/hub/tape_reader.hpp"
#include "afhub/shm_layout/step_tape.hpp"

namespace afhub {

class StepTapeWriter {
 public:
  explicit StepTapeWriter(const std::string& world_instance);
  ~StepTapeWriter();
  StepTapeWriter(const StepTapeWriter&) = delete;
  StepTapeWriter& operator=(const StepTapeWriter&) = delete;

  // Starts a step's tape when something reads it (false: nothing to write this step).
  // Publishes the ring at the first reader's first step.
  bool begin(std::uint64_t step, double time_s) noexcept;
  // Adds a body's state as published (packed: shm_layout/packed_body_state.hpp), or a
  // command as taken (`bytes` of it), after begin() said true.
  void add(PayloadKind kind, std::string_view channel, const void* payload,
           std::uint32_t bytes) noexcept;
  // Makes the step's last part whole.
  void finish() noexcept;
  // Between steps, while something reads the tape: opens the parts the next step will
  // take (as many as the last step took, up to kMaxPreparedParts) and writes over the
  // bytes the last step wrote in them. A part's lines were last read by its reader's
  // core, or have left the caches since the ring's last lap, and taking each of them back
  // during the step cost the step: publishing the example scene took 1.2 us untaped, 7.5
  // to 8.1 us taped for a reader on the other CPU, 2.0 to 2.2 us with its part readied
  // here (physics_benchmark's ExampleSceneStep/published*, when the tape was a queue).
  void prepare() noexcept;
  // An eighth of the ring: a lapped reader starts again three quarters of the ring behind
  // the writer (tape_ring::resume_after_lap), clear of the parts opened ahead. A step of
  // more parts (over two thousand 8-joint bodies) has its first ones readied.
  static constexpr std::uint32_t kMaxPreparedParts = kStepTapeRingParts / 8;

 private:
  void next_part() noexcept;
  void close_part() noexcept;
  struct Port;
  std::unique_ptr<Port> port_;
  std::uint32_t pid_;
  StepTapeRing* ring_ = nullptr;       // published once, written in place
  std::uint64_t next_ = 0;             // the ring's next part
  std::uint32_t prepared_ = 0;         // parts from next_ on opened by prepare()
  StepTape* tape_ = nullptr;           // the part being filled, the ring's next_ - 1
  std::uint32_t last_step_parts_ = 0;  // the parts the last step took
  std::uint32_t last_part_bytes_ = 0;  // the data the last of them held
  std::uint64_t sequence_ = 0;         // of the parts' headers
  std::uint64_t step_ = 0;
  double time_s_ = 0.0;
  std::uint32_t part_ = 0;
  std::uint32_t entries_ = 0;  // this step's, so far
  bool lost_ = false;          // this step lost an entry
};

// Calls `visit(PayloadKind kind, std::string_view channel, const void* payload,
// std::uint32_t bytes)` for each entry of a checked tape (check_payload), in order.
template <class Visit>
void for_each_tape_entry(const StepTape& tape, Visit&& visit) {
  std::size_t at = 0;
  for (std::uint32_t e = 0; e < tape.entry_count; ++e) {
    StepTapeEntry entry;
    std::memcpy(&entry, tape.data.data() + at, sizeof entry);
    const auto* name = reinterpret_cast<const char*>(tape.data.data() + at + sizeof entry);
    visit(entry.kind, std::string_view(name, entry.name_bytes),
          tape.data.data() + at + step_tape_payload_offset(entry.name_bytes), entry.payload_bytes);
    at += step_tape_entry_bytes(entry.name_bytes, entry.payload_bytes);
  }
}

}  // namespace afhub
