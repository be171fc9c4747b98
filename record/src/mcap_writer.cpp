#include "afhub/record/mcap_writer.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include "afhub/record/recording_lock.hpp"
#include "afhub/shm_layout/error.hpp"
#include "mcap_bytes.hpp"

namespace afhub::mcap {
namespace {

// Writes `bytes` to `fd`; returns how many went before an error (errno says which).
std::size_t write_all(int fd, std::span<const std::uint8_t> bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  return done;
}

}  // namespace

Writer::Writer(const std::string& path, Options options)
    : path_(path), options_(std::move(options)), compressor_(options_.compression) {
  // Emptied once locked: another recorder's file is not cut under it.
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error("cannot create " + path + ": " + std::strerror(errno));
  bool emptied = false;  // a regular file of ours, now empty
  struct stat info {};
  try {
    lock_recording(fd_, path);
    if (::fstat(fd_, &info) == 0 && S_ISREG(info.st_mode)) {
      if (::ftruncate(fd_, 0) != 0)
        throw Error("cannot empty " + path + ": " + std::strerror(errno));
      emptied = true;
    }
    pending_.insert(pending_.end(), std::begin(kMagic), std::end(kMagic));
    RecordBuilder(pending_, kHeader).str(options_.profile).str(options_.library);
    write_out();   // from now on the file reads as MCAP, cut off
  } catch (...) {  // no destructor runs for an object that was never made
    // A file that could not take even its header (a full disk) is no recording: it
    // was left behind empty, and a later look took it for one cut off at its start.
    struct stat now {};
    if (emptied && ::stat(path.c_str(), &now) == 0 && now.st_ino == info.st_ino &&
        now.st_dev == info.st_dev)
      ::unlink(path.c_str());
    ::close(fd_);
    throw;
  }
}

Writer::~Writer() {
  try {
    close();
  } catch (const Error&) {
    // Reported by close() when called; a destructor cannot throw.
  }
  stop_background();
  if (fd_ >= 0) ::close(fd_);
  if (spill_fd_ >= 0) ::close(spill_fd_);
}

void Writer::background_loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return busy_ || stopping_; });
    if (!busy_) return;
    lock.unlock();
    try {
      if (!sealed_.records.empty()) write_chunk(sealed_);
      write_out();
    } catch (...) {
      error_ = std::current_exception();
    }
    lock.lock();
    busy_ = false;
    changed_.notify_all();
  }
}

void Writer::wait_idle() {
  if (!thread_.joinable()) return;
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return !busy_; });
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void Writer::stop_background() noexcept {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();  // after the chunk it was writing, if any
}

void Writer::write_schema(std::vector<std::uint8_t>& out, std::uint16_t id) const {
  const Schema& schema = schemas_[id - 1];
  RecordBuilder(out, kSchema).u16(id).str(schema.name).str(schema.encoding).bytes32(schema.data);
}

void Writer::write_channel(std::vector<std::uint8_t>& out, std::uint16_t id) const {
  const Channel& channel = channels_[id - 1];
  RecordBuilder(out, kChannel)
      .u16(id)
      .u16(channel.schema_id)
      .str(channel.topic)
      .str(channel.encoding)
      .map(channel.metadata);
}

std::uint16_t Writer::add_schema(std::string_view name, std::string_view encoding,
                                 std::span<const std::uint8_t> data) {
  wait_idle();
  if (schemas_.size() >= std::numeric_limits<std::uint16_t>::max())
    throw Error("an MCAP file holds at most 65535 schemas");
  schemas_.push_back({std::string(name), std::string(encoding), {data.begin(), data.end()}});
  const auto id = static_cast<std::uint16_t>(schemas_.size());
  write_schema(pending_, id);
  return id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, std::string_view topic,
                                  std::string_view message_encoding, const Metadata& metadata) {
  wait_idle();
  if (channels_.size() >= std::numeric_limits<std::uint16_t>::max())
    throw Error("an MCAP file holds at most 65535 channels");
  if (schema_id > schemas_.size())
    throw Error("channel " + std::string(topic) + ": no schema " + std::to_string(schema_id));
  channels_.push_back({schema_id, std::string(topic), std::string(message_encoding), metadata});
  const auto id = static_cast<std::uint16_t>(channels_.size());
  write_channel(pending_, id);
  return id;
}

void Writer::add_metadata(std::string_view name, const Metadata& metadata) {
  wait_idle();
  const std::uint64_t start = offset();
  RecordBuilder(pending_, kMetadata).str(name).map(metadata);
  metadata_indexes_.push_back({start, offset() - start, std::string(name)});
}

void Writer::write(const Message& message) {
  write(message, std::span(&message.data, 1));
}

void Writer::write(const Message& message, std::span<const std::span<const std::uint8_t>> pieces) {
  if (message.channel_id == 0 || message.channel_id > channels_.size())
    throw Error("a message on channel " + std::to_string(message.channel_id) +
                ", which was never added");
  Chunk& chunk = open_;
  if (chunk.records.empty()) chunk.start_ns = chunk.end_ns = message.log_time_ns;
  if (chunk.entries.size() <= message.channel_id) chunk.entries.resize(channels_.size() + 1);
  if (channel_counts_.size() <= message.channel_id) channel_counts_.resize(channels_.size() + 1);
  auto& entries = chunk.entries[message.channel_id];
  if (entries.empty()) chunk.channels.push_back(message.channel_id);
  entries.emplace_back(message.log_time_ns, chunk.records.size());
  {
    // Written in place, the chunk grown once: a thousand bodies make a million a second.
    std::size_t bytes = 0;
    for (const auto& piece : pieces) bytes += piece.size();
    const std::uint64_t length = 2 + 4 + 8 + 8 + bytes;
    std::size_t at = chunk.records.size();
    chunk.records.resize(at + kRecordPrefix + length);
    const auto put = [&](const void* from, std::size_t n) {
      std::memcpy(chunk.records.data() + at, from, n);  // x86-64: little-endian, as the file
      at += n;
    };
    const std::uint8_t opcode = kMessage;
    put(&opcode, 1);
    put(&length, 8);
    put(&message.channel_id, 2);
    put(&message.sequence, 4);
    put(&message.log_time_ns, 8);
    put(&message.publish_time_ns, 8);
    for (const auto& piece : pieces) put(piece.data(), piece.size());
  }
  chunk.start_ns = std::min(chunk.start_ns, message.log_time_ns);
  chunk.end_ns = std::max(chunk.end_ns, message.log_time_ns);
  if (message_count_ == 0) first_ns_ = last_ns_ = message.log_time_ns;
  first_ns_ = std::min(first_ns_, message.log_time_ns);
  last_ns_ = std::max(last_ns_, message.log_time_ns);
  ++message_count_;
  ++channel_counts_[message.channel_id];
  if (chunk.records.size() >= options_.chunk_bytes) flush_chunk();
}

void Writer::flush_chunk() {
  if (!options_.background) {
    if (!open_.records.empty()) write_chunk(open_);
    write_out();
    return;
  }
  // Started here, by the thread that writes, whose priority it takes (the recorder's
  // writing thread runs below the loops of the machine).
  if (!thread_.joinable()) thread_ = std::thread([this] { background_loop(); });
  wait_idle();
  std::swap(open_, sealed_);  // the one written before, emptied, fills next
  {
    const std::lock_guard lock(mutex_);
    busy_ = true;
  }
  changed_.notify_all();
}

void Writer::write_chunk(Chunk& chunk) {
  const std::uint64_t chunk_offset = offset();
  std::uint64_t compressed_size = 0;
  {
    RecordBuilder record(pending_, kChunk);
    // A compressed chunk's frame carries its own checksum of the records, which its
    // decompression checks (zstd's XXH64, LZ4's XXH32): the CRC-32 over them, a fifth of
    // a thousand bodies' writing time, is then left out (0: "not computed").
    record.u64(chunk.start_ns)
        .u64(chunk.end_ns)
        .u64(chunk.records.size())
        .u32(options_.compression == Compression::kNone ? crc32(chunk.records) : 0)
        .str(compression_name(options_.compression));
    const std::size_t length_at = pending_.size();
    record.u64(0);  // the records' length, known once they are compressed in place
    compressed_size = compressor_.append(chunk.records, pending_);
    std::memcpy(pending_.data() + length_at, &compressed_size, sizeof compressed_size);
  }
  const std::uint64_t chunk_length = offset() - chunk_offset;
  const std::uint64_t indexes_start = offset();
  std::sort(chunk.channels.begin(), chunk.channels.end());
  message_index_offsets_.clear();
  for (const std::uint16_t channel : chunk.channels) {
    auto& entries = chunk.entries[channel];
    message_index_offsets_.emplace_back(channel, offset());
    RecordBuilder record(pending_, kMessageIndex);
    record.u16(channel).u32(static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, offset] : entries) record.u64(time).u64(offset);
    entries.clear();  // its capacity kept for the next chunk
  }
  chunk.channels.clear();
  const std::uint64_t indexes_length = offset() - indexes_start;

  {
    RecordBuilder index(chunk_index_records_, kChunkIndex);  // its length set as it goes
    index.u64(chunk.start_ns).u64(chunk.end_ns).u64(chunk_offset).u64(chunk_length);
    index.u32(static_cast<std::uint32_t>(message_index_offsets_.size() * 10));
    for (const auto& [channel, offset] : message_index_offsets_) index.u16(channel).u64(offset);
    index.u64(indexes_length)
        .str(compression_name(options_.compression))
        .u64(compressed_size)
        .u64(chunk.records.size());
  }
  ++chunk_count_;
  chunk.records.clear();
  if (chunk_index_records_.size() >= options_.index_memory_bytes) spill_chunk_indexes();
}

// Beside the output (the disk the user chose for the recording), else in the
// temporary directory; unnamed: gone with the process however it ends.
void Writer::spill_chunk_indexes() {
  if (spill_fd_ < 0) {
    const std::filesystem::path beside = std::filesystem::absolute(path_).parent_path();
    for (const auto& dir : {beside, std::filesystem::temp_directory_path()})
      if (spill_fd_ < 0) spill_fd_ = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (spill_fd_ < 0)
      throw Error("cannot make a temporary file for " + path_ + "'s index, beside it or in " +
                  std::filesystem::temp_directory_path().string() + ": " + std::strerror(errno));
  }
  if (write_all(spill_fd_, chunk_index_records_) < chunk_index_records_.size())
    throw Error("cannot write " + path_ +
                "'s index to its temporary file: " + std::strerror(errno));
  spilled_bytes_ += chunk_index_records_.size();
  chunk_index_records_.clear();
}

void Writer::write_out() {
  if (failed_) throw Error("cannot write " + path_ + " any more: an earlier write failed");
  // A file deleted while recording takes every byte written to it with it: said, not
  // recorded on into nothing.
  if (struct stat info{}; ::fstat(fd_, &info) == 0 && S_ISREG(info.st_mode) && info.st_nlink == 0) {
    failed_ = true;
    pending_.clear();
    throw Error("cannot write " + path_ +
                ": the file was deleted while being written; what "
                "was recorded in it is gone");
  }
  const std::size_t done = write_all(fd_, pending_);
  if (done < pending_.size()) {
    // What was written stays; nothing is written after it, so that the file ends at
    // its last complete chunk plus part of one, which a reader sees as cut off.
    const int error = errno;
    failed_ = true;
    file_offset_ += done;
    written_.store(file_offset_, std::memory_order_relaxed);
    pending_.clear();
    throw Error("cannot write " + path_ + ": " + std::strerror(error) + " (" +
                options_.when_write_fails + ")");
  }
  file_offset_ += pending_.size();
  written_.store(file_offset_, std::memory_order_relaxed);
  pending_.clear();
}

void Writer::close() {
  if (closed_) return;
  wait_idle();  // its error, if any, reported here
  stop_background();
  if (failed_) return;
  closed_ = true;  // whatever happens below, once
  if (!open_.records.empty()) write_chunk(open_);
  RecordBuilder(pending_, kDataEnd).u32(0);  // 0: no data section CRC (the chunks carry theirs)
  write_out();

  // The summary, its CRC taken as it goes out.
  const std::uint64_t summary_start = offset();
  std::uint32_t crc = 0;
  const auto summary_out = [&] {
    crc = crc32(pending_, crc);
    write_out();
  };
  struct Group {
    Opcode opcode;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](Opcode opcode, auto write_records) {
    const std::uint64_t start = offset();
    write_records();
    if (offset() > start) groups.push_back({opcode, start, offset() - start});
  };
  group(kSchema, [&] {
    for (std::size_t id = 1; id <= schemas_.size(); ++id)
      write_schema(pending_, static_cast<std::uint16_t>(id));
  });
  group(kChannel, [&] {
    for (std::size_t id = 1; id <= channels_.size(); ++id)
      write_channel(pending_, static_cast<std::uint16_t>(id));
  });
  group(kStatistics, [&] {
    RecordBuilder record(pending_, kStatistics);
    record.u64(message_count_)
        .u16(static_cast<std::uint16_t>(schemas_.size()))
        .u32(static_cast<std::uint32_t>(channels_.size()))
        .u32(0)  // attachments
        .u32(static_cast<std::uint32_t>(metadata_indexes_.size()))
        .u32(chunk_count_)
        .u64(first_ns_)
        .u64(last_ns_);
    std::uint32_t counted = 0;
    for (const std::uint64_t count : channel_counts_) counted += count != 0;
    record.u32(counted * 10);
    for (std::size_t channel = 0; channel < channel_counts_.size(); ++channel)
      if (channel_counts_[channel] != 0)
        record.u16(static_cast<std::uint16_t>(channel)).u64(channel_counts_[channel]);
  });
  group(kChunkIndex, [&] {
    // What waited in the temporary file, a piece at a time, then what is in memory.
    constexpr std::size_t kPiece = 1u << 20;
    for (std::uint64_t at = 0; at < spilled_bytes_;) {
      const std::size_t start = pending_.size();
      pending_.resize(start + std::min<std::uint64_t>(kPiece, spilled_bytes_ - at));
      const ssize_t n = ::pread(spill_fd_, pending_.data() + start, pending_.size() - start,
                                static_cast<off_t>(at));
      if (n <= 0)
        throw Error("cannot read back " + path_ +
                    "'s index from its temporary file: " + std::strerror(n < 0 ? errno : EIO));
      pending_.resize(start + static_cast<std::size_t>(n));
      at += static_cast<std::uint64_t>(n);
      summary_out();
    }
    pending_.insert(pending_.end(), chunk_index_records_.begin(), chunk_index_records_.end());
  });
  group(kMetadataIndex, [&] {
    for (const MetadataIndex& index : metadata_indexes_)
      RecordBuilder(pending_, kMetadataIndex).u64(index.offset).u64(index.length).str(index.name);
  });
  const std::uint64_t summary_offset_start = offset();
  for (const Group& g : groups)
    RecordBuilder(pending_, kSummaryOffset).u8(g.opcode).u64(g.start).u64(g.length);

  // The summary CRC covers the summary and the footer up to its summary_offset_start.
  RecordBuilder(pending_, kFooter).u64(summary_start).u64(summary_offset_start).u32(0);
  crc = crc32(std::span(pending_).first(pending_.size() - 4), crc);
  std::memcpy(pending_.data() + pending_.size() - 4, &crc, sizeof crc);
  pending_.insert(pending_.end(), std::begin(kMagic), std::end(kMagic));
  write_out();
  if (::close(fd_) != 0) throw Error("cannot close " + path_ + ": " + std::strerror(errno));
  fd_ = -1;
}

}  // namespace afhub::mcap
