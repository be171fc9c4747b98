// Writes an MCAP file (mcap.dev/spec): messages in compressed chunks, each followed by
// its message indexes, then a summary (schemas, channels, statistics, chunk and
// metadata indexes, summary offsets) and the footer, so that readers can seek.
// Schemas, channels and metadata go into the data section as they are added, outside
// the chunks: a file cut off (kill -9, a full disk) keeps every complete chunk readable.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <map>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "afhub/record/compression.hpp"

namespace afhub::mcap {

using Metadata = std::map<std::string, std::string>;

struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0;
  std::uint64_t publish_time_ns = 0;
  std::span<const std::uint8_t> data;
};

class Writer {
 public:
  struct Options {
    std::string profile;  // the Header's profile: "" (none), "ros2", ...
    std::string library = "afhub";
    Compression compression = Compression::kZstd;
    // A chunk is written once it holds this much: what a crash can lose at most.
    std::size_t chunk_bytes = 1u << 20;
    // Each full chunk compressed and written by a thread of the writer's own while the
    // next one fills: a thousand bodies' recorder spent half its writing thread in zstd.
    bool background = false;
    // The summary's chunk indexes held in memory; past this they wait in an unnamed
    // temporary file beside the output until close: a chunk's index names each channel
    // in it (10 bytes each), and a thousand bodies make 570 chunks of 1 MiB a second.
    std::size_t index_memory_bytes = 16u << 20;
    // What a failed write leaves, said after its cause.
    std::string when_write_fails =
        "the file keeps its complete chunks; `afhub record --recover` indexes them";
  };

  // Creates (or truncates) `path`; throws afhub::Error naming the path and the reason.
  Writer(const std::string& path, Options options);
  // Closes the file if close() was not called (an error then goes unreported).
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Ids count from 1 (0 is the spec's "no schema").
  std::uint16_t add_schema(std::string_view name, std::string_view encoding,
                           std::span<const std::uint8_t> data);
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding, const Metadata& metadata = {});
  void add_metadata(std::string_view name, const Metadata& metadata);
  // Throws afhub::Error when the disk refuses the bytes (full, gone); the file then
  // stays as it is, cut off, and nothing more is written. In the background, that
  // error comes from the next call after it.
  void write(const Message& message);
  // The same, its bytes given in pieces that the file joins (message.data unused).
  void write(const Message& message, std::span<const std::span<const std::uint8_t>> pieces);
  // Writes the open chunk, and every record before it, to the file.
  void flush_chunk();
  // The summary and footer; the file is complete afterwards.
  void close();

  // Bytes written to the file so far, and messages written.
  std::uint64_t file_bytes() const { return written_.load(std::memory_order_relaxed); }
  std::uint64_t message_count() const { return message_count_; }

 private:
  struct MetadataIndex {
    std::uint64_t offset, length;
    std::string name;
  };
  struct Channel {
    std::uint16_t schema_id;
    std::string topic, encoding;
    Metadata metadata;
  };
  struct Schema {
    std::string name, encoding;
    std::vector<std::uint8_t> data;
  };

  // A chunk's records, and each channel's (log time, offset) entries by channel id, the
  // channels it holds listed (empty vectors kept between chunks, so that a chunk
  // allocates nothing once warm).
  struct Chunk {
    std::vector<std::uint8_t> records;
    std::vector<std::vector<std::pair<std::uint64_t, std::uint64_t>>> entries;
    std::vector<std::uint16_t> channels;
    std::uint64_t start_ns = 0, end_ns = 0;
  };

  void write_schema(std::vector<std::uint8_t>& out, std::uint16_t id) const;
  void write_channel(std::vector<std::uint8_t>& out, std::uint16_t id) const;
  std::uint64_t offset() const { return file_offset_ + pending_.size(); }
  void write_chunk(Chunk& chunk);  // into pending_, and emptied
  void write_out();                // pending_ to the file
  void spill_chunk_indexes();      // chunk_index_records_ to spill_fd_
  // In the background: waits until the thread has written what it was given (the
  // file's state is this thread's again), and rethrows the error it met.
  void wait_idle();
  void stop_background() noexcept;
  void background_loop();

  std::string path_;
  Options options_;
  int fd_ = -1;
  Compressor compressor_;
  std::vector<std::uint8_t> pending_;  // file bytes not yet written: records since the last chunk
  std::uint64_t file_offset_ = 0;      // bytes written to the file
  std::atomic<std::uint64_t> written_{0};  // the same, for another thread to read

  std::vector<Schema> schemas_;  // id - 1
  std::vector<Channel> channels_;
  // The summary's chunk index records, written as each chunk is: a few bytes per channel
  // of the chunk, rather than a map per chunk held until close.
  std::vector<std::uint8_t> chunk_index_records_;
  int spill_fd_ = -1;  // the chunk index records before them
  std::uint64_t spilled_bytes_ = 0;
  std::uint32_t chunk_count_ = 0;
  std::vector<MetadataIndex> metadata_indexes_;

  Chunk open_;  // being filled
  std::vector<std::pair<std::uint16_t, std::uint64_t>> message_index_offsets_;

  std::uint64_t message_count_ = 0;
  std::uint64_t first_ns_ = 0, last_ns_ = 0;
  std::vector<std::uint64_t> channel_counts_;  // by channel id
  bool closed_ = false;
  bool failed_ = false;  // a write failed: the file is left as it is

  // The background: the chunk handed to the thread, which owns it, pending_ and the
  // file's offsets while `busy_`.
  Chunk sealed_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool busy_ = false, stopping_ = false;
  std::exception_ptr error_;
};

}  // namespace afhub::mcap
