// `afhub record`'s engine: joins the hub's channels and writes every new sample to an
// MCAP file: the bodies' states, the world's state and the scene a viewer draws, and
// with options the commands and the devices. A reading loop wakes with each step of the physics
// (its world state), copies every recorded channel's new sample into a bounded buffer and never
// waits on the disk; a writing thread drains the buffer into the file. A full buffer drops the
// sample and counts it; a body whose steps jump (the loop woke too late for one) counts
// the steps it missed. Bodies that appear later (a physics restarted) join the file.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "afhub/record/compression.hpp"
#include "afhub/rt/periodic_loop.hpp"

namespace afhub::mcap {

struct RecordOptions {
  std::string output = "afhub.mcap";
  std::vector<std::string> body_globs{"*"};  // fnmatch patterns over body channel names
  bool devices = false;                      // every device's state and command
  bool commands = false;                     // every command sent to a recorded body
  double duration_s = 0.0;  // from the first message (the start while none came); 0: until stopped
  // When the duration began, when earlier (a re-attached recorder's first file's first
  // message: the duration spans the files); 0: as above. Handed on to the next image.
  std::int64_t duration_from_ns = 0;
  Compression compression = Compression::kZstd;
  std::size_t buffer_bytes = 256u << 20;
  std::string profile;  // "" (afhub's payloads) or "ros2" (ROS 2 messages, ros2_messages.hpp)
  // The reading loop's real-time requests (its period is the physics'): under the normal
  // scheduler a busy machine can keep it asleep through a step, which is then missed.
  LoopOptions loop;
};

struct RecordProgress {
  double seconds = 0.0;  // since the first sample
  std::uint64_t channels = 0;
  std::uint64_t messages = 0;  // written to the file
  std::uint64_t file_bytes = 0;
  std::uint64_t dropped = 0;  // refused by a full buffer
  // Updates published but never read, found by their steps (states) or sequence numbers
  // (commands, devices): the reading loop slept through them.
  std::uint64_t missed = 0;
  // Commands a controller replaced before the physics took them (gaps in the commands
  // its step tape brings): they never acted, and no recorder could have read them there.
  std::uint64_t replaced = 0;
  std::uint64_t buffered_bytes = 0;
};

// Records until `keep_going()` says false or options.duration_s has passed (see there),
// reporting to `progress` about twice a second and once at the end, and to `opened` once
// the file is open and this process its one writer.
// Needs connect_to_hub(). Throws afhub::Error when the file cannot be written.
RecordProgress record(const RecordOptions& options, const std::function<bool()>& keep_going,
                      const std::function<void(const RecordProgress&)>& progress,
                      const std::function<void()>& opened = {});

}  // namespace afhub::mcap
