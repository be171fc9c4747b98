#include "afhub/record/mcap_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>

#include "afhub/shm_layout/error.hpp"
#include "mcap_bytes.hpp"

namespace afhub::mcap {

Writer::Writer(const std::string& path, Options options)
    : path_(path), options_(std::move(options)), compressor_(options_.compression) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error("cannot create " + path + ": " + std::strerror(errno));
  pending_.insert(pending_.end(), std::begin(kMagic), std::end(kMagic));
  RecordBuilder(pending_, kHeader).str(options_.profile).str(options_.library);
  write_out();  // from now on the file reads as MCAP, cut off
}

Writer::~Writer() {
  try {
    close();
  } catch (const Error&) {
    // Reported by close() when called; a destructor cannot throw.
  }
  if (fd_ >= 0) ::close(fd_);
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
  if (schemas_.size() >= std::numeric_limits<std::uint16_t>::max())
    throw Error("an MCAP file holds at most 65535 schemas");
  schemas_.push_back({std::string(name), std::string(encoding), {data.begin(), data.end()}});
  const auto id = static_cast<std::uint16_t>(schemas_.size());
  write_schema(pending_, id);
  return id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, std::string_view topic,
                                  std::string_view message_encoding, const Metadata& metadata) {
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
  const std::uint64_t offset = file_bytes();
  RecordBuilder(pending_, kMetadata).str(name).map(metadata);
  metadata_indexes_.push_back({offset, file_bytes() - offset, std::string(name)});
}

void Writer::write(const Message& message) {
  if (message.channel_id == 0 || message.channel_id > channels_.size())
    throw Error("a message on channel " + std::to_string(message.channel_id) +
                ", which was never added");
  if (chunk_.empty()) chunk_start_ns_ = chunk_end_ns_ = message.log_time_ns;
  chunk_entries_[message.channel_id].emplace_back(message.log_time_ns, chunk_.size());
  RecordBuilder(chunk_, kMessage)
      .u16(message.channel_id)
      .u32(message.sequence)
      .u64(message.log_time_ns)
      .u64(message.publish_time_ns)
      .raw(message.data);
  chunk_start_ns_ = std::min(chunk_start_ns_, message.log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, message.log_time_ns);
  if (message_count_ == 0) first_ns_ = last_ns_ = message.log_time_ns;
  first_ns_ = std::min(first_ns_, message.log_time_ns);
  last_ns_ = std::max(last_ns_, message.log_time_ns);
  ++message_count_;
  ++channel_counts_[message.channel_id];
  if (chunk_.size() >= options_.chunk_bytes) flush_chunk();
}

void Writer::flush_chunk() {
  if (!chunk_.empty()) write_chunk();
  write_out();
}

void Writer::write_chunk() {
  ChunkIndex index{};
  index.start_ns = chunk_start_ns_;
  index.end_ns = chunk_end_ns_;
  index.offset = file_bytes();
  index.uncompressed_size = chunk_.size();
  {
    RecordBuilder record(pending_, kChunk);
    record.u64(chunk_start_ns_)
        .u64(chunk_end_ns_)
        .u64(chunk_.size())
        .u32(crc32(chunk_))
        .str(compression_name(options_.compression));
    const std::size_t length_at = pending_.size();
    record.u64(0);  // the records' length, known once they are compressed in place
    index.compressed_size = compressor_.append(chunk_, pending_);
    std::memcpy(pending_.data() + length_at, &index.compressed_size, sizeof index.compressed_size);
  }
  index.length = file_bytes() - index.offset;
  const std::uint64_t indexes_start = file_bytes();
  for (auto& [channel, entries] : chunk_entries_) {
    if (entries.empty()) continue;
    index.message_index_offsets[channel] = file_bytes();
    RecordBuilder record(pending_, kMessageIndex);
    record.u16(channel).u32(static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, offset] : entries) record.u64(time).u64(offset);
    entries.clear();  // its capacity kept for the next chunk
  }
  index.message_index_length = file_bytes() - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  chunk_.clear();
}

void Writer::write_out() {
  if (failed_) throw Error("cannot write " + path_ + " any more: an earlier write failed");
  std::size_t done = 0;
  while (done < pending_.size()) {
    const ssize_t n = ::write(fd_, pending_.data() + done, pending_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      // What was written stays; nothing is written after it, so that the file ends at
      // its last complete chunk plus part of one, which a reader sees as cut off.
      failed_ = true;
      file_offset_ += done;
      pending_.clear();
      throw Error("cannot write " + path_ + ": " + std::strerror(n < 0 ? errno : ENOSPC) +
                  " (the file keeps its complete chunks; `afhub record --recover` indexes them)");
    }
    done += static_cast<std::size_t>(n);
  }
  file_offset_ += pending_.size();
  pending_.clear();
}

void Writer::close() {
  if (closed_ || failed_) return;
  closed_ = true;  // whatever happens below, once
  if (!chunk_.empty()) write_chunk();
  RecordBuilder(pending_, kDataEnd).u32(0);  // 0: no data section CRC (the chunks carry theirs)
  write_out();  // from here on pending_ holds the summary: its CRC is taken there

  const std::uint64_t summary_start = file_bytes();
  struct Group {
    Opcode opcode;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](Opcode opcode, auto write_records) {
    const std::uint64_t start = file_bytes();
    write_records();
    if (file_bytes() > start) groups.push_back({opcode, start, file_bytes() - start});
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
        .u32(static_cast<std::uint32_t>(chunk_indexes_.size()))
        .u64(first_ns_)
        .u64(last_ns_)
        .u32(static_cast<std::uint32_t>(channel_counts_.size() * 10));
    for (const auto& [channel, count] : channel_counts_) record.u16(channel).u64(count);
  });
  group(kChunkIndex, [&] {
    for (const ChunkIndex& index : chunk_indexes_) {
      RecordBuilder record(pending_, kChunkIndex);
      record.u64(index.start_ns).u64(index.end_ns).u64(index.offset).u64(index.length);
      record.u32(static_cast<std::uint32_t>(index.message_index_offsets.size() * 10));
      for (const auto& [channel, offset] : index.message_index_offsets)
        record.u16(channel).u64(offset);
      record.u64(index.message_index_length)
          .str(compression_name(options_.compression))
          .u64(index.compressed_size)
          .u64(index.uncompressed_size);
    }
  });
  group(kMetadataIndex, [&] {
    for (const MetadataIndex& index : metadata_indexes_)
      RecordBuilder(pending_, kMetadataIndex).u64(index.offset).u64(index.length).str(index.name);
  });
  const std::uint64_t summary_offset_start = file_bytes();
  for (const Group& g : groups)
    RecordBuilder(pending_, kSummaryOffset).u8(g.opcode).u64(g.start).u64(g.length);

  // The summary CRC covers the summary and the footer up to its summary_offset_start.
  RecordBuilder(pending_, kFooter).u64(summary_start).u64(summary_offset_start).u32(0);
  const std::uint32_t crc = crc32(std::span(pending_).first(pending_.size() - 4));
  std::memcpy(pending_.data() + pending_.size() - 4, &crc, sizeof crc);
  pending_.insert(pending_.end(), std::begin(kMagic), std::end(kMagic));
  write_out();
  if (::close(fd_) != 0) throw Error("cannot close " + path_ + ": " + std::strerror(errno));
  fd_ = -1;
}

}  // namespace afhub::mcap
