// `afhub play`'s engine: publishes a recording's states into the hub as a physics would
// (body states, the world's state, the scene a viewer draws), with their recorded timing
// scaled by a rate, or as fast as possible. Its world pauses, resumes and steps under
// `afhub world` as a physics does. Commands and devices recorded are not replayed.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace afhub::mcap {

struct PlayOptions {
  std::string file;
  double rate = 1.0;  // 2: twice as fast; 0: as fast as possible
  bool loop = false;
  double start_s = 0.0;  // from the recording's first message
  double end_s = 0.0;    // 0: to the end
  std::vector<std::string> body_globs{"*"};
};

struct PlayReport {
  std::uint64_t published = 0;
  unsigned passes = 0;           // complete passes through the range
  unsigned unmatched_globs = 0;  // --bodies globs that matched no recorded body (each said)
  std::string cut_off;           // the file was cut off there, and played up to it ("": it was not)
};

// Plays until the range ends (each pass, with options.loop, until `keep_going()` is
// false). Needs connect_to_hub(). Throws afhub::Error for a file afhub cannot play (not
// afhub's payloads, another layout id, corrupt) or bodies another process publishes.
PlayReport play(const PlayOptions& options, const std::function<bool()>& keep_going);

}  // namespace afhub::mcap
