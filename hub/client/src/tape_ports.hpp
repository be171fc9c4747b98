// What a tape's two ends share (tape_reader.cpp, step_tape.cpp, device_tape.cpp): the
// iceoryx service a ring is published on, and its publishing. Internal to the hub client.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <utility>

#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/device_tape.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "reader_port.hpp"
#include "tape_ring.hpp"

namespace afhub {

// A kind of tape's event, and what messages call it.
struct TapeNames {
  std::string_view event;
  const char* what;
};
template <class Ring>
constexpr TapeNames tape_names();
template <>
constexpr TapeNames tape_names<StepTapeRing>() {
  return {kStepTapeEvent, "a step tape"};
}
template <>
constexpr TapeNames tape_names<DeviceTapeRing>() {
  return {kDeviceTapeEvent, "a device's tape"};
}

// The service of the tape of `instance` (a world's, a device channel's).
template <class Ring>
iox::capro::ServiceDescription tape_service(const std::string& instance) {
  return describe_channel({std::string(kService), instance, std::string(tape_names<Ring>().event)});
}

// A publisher of a tape's ring: it keeps the ring for readers that come later.
inline iox::popo::PublisherOptions ring_publisher_options() {
  iox::popo::PublisherOptions options;
  options.historyCapacity = 1;
  return options;
}

// Loans a fresh ring, published at once to be written in place after; nullptr (said
// once per process and kind of ring) when the hub's pools have none left.
template <class Ring>
Ring* publish_ring(iox::popo::UntypedPublisher& publisher, std::uint32_t writer_pid) noexcept {
  auto loaned = publisher.loan(sizeof(Ring), alignof(Ring));
  if (loaned.has_error()) {
    static bool said = false;  // a loop's every cycle would say it again
    if (!std::exchange(said, true))
      std::fprintf(stderr,
                   "afhub: no shared memory for %s's ring (%zu bytes): it is not written; see "
                   "the hub's pools (`afhub hub --help`, pools)\n",
                   tape_names<Ring>().what, sizeof(Ring));
    return nullptr;
  }
  auto* ring = static_cast<Ring*>(loaned.value());
  tape_ring::init(*ring, monotonic_ns(), writer_pid);
  publisher.publish(ring);
  return ring;
}

}  // namespace afhub
