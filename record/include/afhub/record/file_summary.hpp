// What `afhub info` says of a recording: read from start to end (so that a file cut
// off is described as far as it reads), per channel its messages, times, rate and gaps.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "afhub/record/mcap_reader.hpp"

namespace afhub::mcap {

struct ChannelSummary {
  std::string topic, schema, encoding;
  Metadata metadata;
  std::uint64_t messages = 0;
  std::uint64_t first_ns = 0, last_ns = 0;  // log times
  // Places where the message sequence (a state's step, a command's sequence number)
  // did not go up by one, and the sequence numbers skipped there in all.
  std::uint64_t gaps = 0, skipped = 0;
  double rate_hz() const;
};

struct FileSummary {
  std::string path, profile, library;
  std::vector<std::string> compressions;  // distinct, of the chunks
  std::vector<std::pair<std::string, Metadata>> metadata;
  std::vector<ChannelSummary> channels;  // in file order
  std::uint64_t file_bytes = 0, messages = 0, chunks = 0;
  std::uint64_t first_ns = 0, last_ns = 0;
  bool complete = false;
  std::string cut_off;
  double duration_s() const;
};

// Throws afhub::Error for a file that is not MCAP or is corrupt.
FileSummary summarize(const std::string& path);

}  // namespace afhub::mcap
