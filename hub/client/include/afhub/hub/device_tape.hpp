// The writing end of a device's tape (shm_layout/device_tape.hpp): its driver writes
// each cycle's state, and the command it took when that was a new one, while a recorder
// reads (DeviceTapeReader, tape_reader.hpp). Real-time safe once made: no heap, no
// exceptions.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "afhub/hub/tape_reader.hpp"
#include "afhub/shm_layout/device_tape.hpp"

namespace afhub {

class DeviceTapeWriter {
 public:
  // The tape of the device on `device_channel` ("device/<name>").
  explicit DeviceTapeWriter(const std::string& device_channel);
  ~DeviceTapeWriter();
  DeviceTapeWriter(const DeviceTapeWriter&) = delete;
  DeviceTapeWriter& operator=(const DeviceTapeWriter&) = delete;

  // A cycle's state as published, and the command it applied (nullptr: none). The
  // command goes on the tape when it is not the one the last cycle took. Nothing is
  // written while nothing reads the tape; the ring is published at the first reader's
  // first cycle.
  void add(const DeviceState& state, const DeviceCommand* command) noexcept;

 private:
  struct Port;
  std::unique_ptr<Port> port_;
  std::uint32_t pid_;
  DeviceTapeRing* ring_ = nullptr;  // published once, written in place
  std::uint64_t next_ = 0;          // the ring's next part
  // The last command taped: its writer and sequence.
  std::uint32_t command_pid_ = 0;
  std::uint64_t command_sequence_ = 0;
};

}  // namespace afhub
