// Reads an MCAP file from its start, record by record, with every length checked against
// the file and every chunk against its CRC: what `afhub info`, `play` and
// `record --recover` stand on. A file cut off (kill -9, a full disk) reads up to its
// last complete record; one that is not MCAP, or is corrupt, is an error naming the
// byte where it went wrong.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "afhub/record/mcap_writer.hpp"

namespace afhub::mcap {

struct Schema {
  std::uint16_t id = 0;
  std::string name, encoding;
  std::vector<std::uint8_t> data;
};

struct Channel {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  Metadata metadata;
};

// What a scan meets, in file order. Message data is valid during the call only.
class Visitor {
 public:
  virtual ~Visitor() = default;
  virtual void header(const std::string& /*profile*/, const std::string& /*library*/) {}
  virtual void schema(const Schema& /*schema*/) {}
  virtual void channel(const Channel& /*channel*/) {}
  virtual void metadata(const std::string& /*name*/, const Metadata& /*metadata*/) {}
  virtual void chunk(std::string_view /*compression*/) {}
  virtual void message(const Message& /*message*/) {}
};

struct ScanResult {
  bool complete = false;  // the data section ended and the footer and closing magic follow
  bool indexed = false;   // complete, and its footer points at a summary
  std::string cut_off;    // why the scan stopped early, where ("" when complete)
  std::uint64_t chunks = 0, messages = 0;
};

// The most a record, or a chunk decompressed, may hold for afhub to read it (it is held
// in memory): afhub writes chunks of 4 MiB, other tools a few MiB.
inline constexpr std::uint64_t kMaxRecordBytes = 256ull << 20;

// Reads `path` from the start. Throws afhub::Error for a file that cannot be opened, is
// not MCAP, or is corrupt: a record past kMaxRecordBytes, one running past the end of a
// file that ends with its footer (so was not cut off), bytes after the closing magic.
ScanResult scan(const std::string& path, Visitor& visitor);

// Rewrites `path` from its complete records: a file that was cut off gets its
// summary and index back (what it lost past its last complete chunk stays lost).
// Writes beside it and renames over it; a complete file with its summary is left as it
// is, and a corrupt one, or one with no message, is an error that leaves it too. Returns
// the scan of the original.
ScanResult recover(const std::string& path);

}  // namespace afhub::mcap
