// The writing end of a device's tape (see device_tape.hpp).
#include "afhub/hub/device_tape.hpp"

#include <unistd.h>

#include "afhub/hub/hub_health.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "tape_ports.hpp"

namespace afhub {

struct DeviceTapeWriter::Port {
  explicit Port(const std::string& device_channel)
      : publisher(tape_service<DeviceTapeRing>(device_channel), ring_publisher_options()) {}
  iox::popo::UntypedPublisher publisher;
};

DeviceTapeWriter::DeviceTapeWriter(const std::string& device_channel)
    : pid_(static_cast<std::uint32_t>(getpid())) {
  require_publisher_ports(1, "writing the tape of '" + device_channel + "'");
  port_ = std::make_unique<Port>(device_channel);
  took_publisher_port();
}

DeviceTapeWriter::~DeviceTapeWriter() {
  gave_back_publisher_port();
}

void DeviceTapeWriter::add(const DeviceState& state, const DeviceCommand* command) noexcept {
  if (!port_->publisher.hasSubscribers()) return;
  if (!ring_ && !(ring_ = publish_ring<DeviceTapeRing>(port_->publisher, pid_))) return;
  DeviceTape& part = tape_ring::open(*ring_, next_);
  part.state = state;
  part.has_command = command && (command->header.publisher_pid != command_pid_ ||
                                 command->header.sequence != command_sequence_);
  if (part.has_command) {
    part.command = *command;
    command_pid_ = command->header.publisher_pid;
    command_sequence_ = command->header.sequence;
  }
  tape_ring::close(*ring_, next_++);
}

}  // namespace afhub
