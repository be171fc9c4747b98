#include "afhub/record/mcap_reader.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>

#include <zstd.h>

#include "afhub/record/recording_lock.hpp"
#include "afhub/shm_layout/error.hpp"
#include "mcap_bytes.hpp"

namespace afhub::mcap {

namespace {

std::string opcode_name(std::uint8_t opcode) {
  static const char* const kNames[] = {"",           "header",           "footer",
                                       "schema",     "channel",          "message",
                                       "chunk",      "message index",    "chunk index",
                                       "attachment", "attachment index", "statistics",
                                       "metadata",   "metadata index",   "summary offset",
                                       "data end"};
  if (opcode >= 1 && opcode <= 0x0F) return kNames[opcode];
  char text[32];
  std::snprintf(text, sizeof text, "opcode 0x%02x", opcode);
  return text;
}

// The file, read in order.
class File {
 public:
  // Opening a FIFO waited for a writer, for good.
  static const std::string& regular_file(const std::string& path) {
    std::error_code error;
    if (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error))
      throw Error(path + " is not a regular file; expected a recording (.mcap)");
    return path;
  }

  explicit File(const std::string& path)
      : path_(path), file_(std::fopen(regular_file(path).c_str(), "rb")) {
    if (!file_) throw Error("cannot open " + path + ": " + std::strerror(errno));
    std::error_code error;
    size_ = std::filesystem::file_size(path, error);
    if (error) throw Error("cannot read " + path + ": " + error.message());
    ends_with_footer_ = read_ending();
  }
  // Reads exactly `out.size()` bytes, or false at the end of the file.
  bool read(std::span<std::uint8_t> out) {
    if (out.empty()) return true;
    const std::size_t n = std::fread(out.data(), 1, out.size(), file_.get());
    if (n != out.size() && std::ferror(file_.get()))
      throw Error("cannot read " + path_ + ": " + std::strerror(errno));
    at_ += n;
    return n == out.size();
  }
  std::uint64_t at() const { return at_; }
  std::uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }
  // The file ends as a finished MCAP file does: a footer record, then the magic. Such a
  // file was not cut off, so a record running past its end is corruption.
  bool ends_with_footer() const { return ends_with_footer_; }

 private:
  bool read_ending() {
    constexpr std::size_t kFooterRecord = kRecordPrefix + 20;  // two offsets and a CRC
    std::uint8_t ending[kFooterRecord + sizeof kMagic];
    if (size_ < sizeof kMagic + sizeof ending) return false;
    const bool read = std::fseek(file_.get(), -static_cast<long>(sizeof ending), SEEK_END) == 0 &&
                      std::fread(ending, 1, sizeof ending, file_.get()) == sizeof ending;
    if (std::fseek(file_.get(), 0, SEEK_SET) != 0)
      throw Error("cannot read " + path_ + ": " + std::strerror(errno));
    std::uint64_t length = 0;
    std::memcpy(&length, ending + 1, sizeof length);
    return read && ending[0] == kFooter && length == 20 &&
           std::memcmp(ending + kFooterRecord, kMagic, sizeof kMagic) == 0;
  }

  std::string path_;
  struct Closer {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  std::unique_ptr<std::FILE, Closer> file_;  // closed on every error path too
  std::uint64_t size_ = 0;
  std::uint64_t at_ = 0;
  bool ends_with_footer_ = false;
};

// A chunk's uncompressed size checked against what its records can hold, before that
// much memory is taken: the same size uncompressed, what a zstd frame says it holds
// (when it says), at most 255 times the bytes of an LZ4 frame (its densest).
void check_claimed_size(Compression compression, std::span<const std::uint8_t> records,
                        std::uint64_t size, const std::string& what) {
  std::uint64_t most = records.size();
  if (compression == Compression::kLz4) most = records.size() * 255 + 65536;
  if (compression == Compression::kZstd) {
    const unsigned long long framed = ZSTD_getFrameContentSize(records.data(), records.size());
    most = framed == ZSTD_CONTENTSIZE_UNKNOWN ? kMaxRecordBytes
           : framed == ZSTD_CONTENTSIZE_ERROR ? 0
                                              : static_cast<std::uint64_t>(framed);
  }
  if (size > most || (compression == Compression::kNone && size != most))
    throw Error(what + " says it holds " + std::to_string(size) + " bytes, which its " +
                std::to_string(records.size()) + " bytes of records cannot (a corrupt file)");
}

Schema read_schema(FieldReader& fields) {
  Schema schema;
  schema.id = fields.u16("id");
  schema.name = fields.str("name");
  schema.encoding = fields.str("encoding");
  const auto data = fields.bytes32("data");
  schema.data.assign(data.begin(), data.end());
  return schema;
}

Channel read_channel(FieldReader& fields) {
  Channel channel;
  channel.id = fields.u16("id");
  channel.schema_id = fields.u16("schema_id");
  channel.topic = fields.str("topic");
  channel.message_encoding = fields.str("message_encoding");
  channel.metadata = fields.map("metadata");
  return channel;
}

Message read_message(FieldReader& fields) {
  Message message;
  message.channel_id = fields.u16("channel_id");
  message.sequence = fields.u32("sequence");
  message.log_time_ns = fields.u64("log_time");
  message.publish_time_ns = fields.u64("publish_time");
  message.data = fields.rest();
  return message;
}

class Scanner {
 public:
  Scanner(const std::string& path, Visitor& visitor) : file_(path), visitor_(visitor) {}

  ScanResult run() {
    std::uint8_t magic[sizeof kMagic];
    if (!file_.read(magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0)
      throw Error(file_.path() +
                  " is not an MCAP file: it does not start with MCAP's magic "
                  "bytes (0x89 MCAP0 \\r\\n)");
    bool first = true;
    bool data_ended = false;
    while (true) {
      const std::uint64_t at = file_.at();
      std::uint8_t prefix[kRecordPrefix];
      if (!file_.read(prefix))
        return cut("the file ends " + std::to_string(at) +
                   " bytes in, inside a record's opcode and length");
      const std::uint8_t opcode = prefix[0];
      std::uint64_t length;
      std::memcpy(&length, prefix + 1, sizeof length);
      const std::string what = opcode_name(opcode) + " record at byte " + std::to_string(at);
      const std::uint64_t left = file_.size() - file_.at();
      // Past the bound first: a cut file's last record says its true length, which
      // no writer makes this large; a length that is is corrupt, not cut.
      if (length > kMaxRecordBytes)
        throw Error(file_.path() + ": " + what + " holds " + std::to_string(length) +
                    " bytes, more than afhub reads in one record (256 MiB): a corrupt file, "
                    "or one made by a tool writing larger records");
      if (length > left) {
        const std::string overrun = what + " says it holds " + std::to_string(length) +
                                    " bytes, the file has " + std::to_string(left) + " after it";
        if (file_.ends_with_footer())
          throw Error(file_.path() + ": " + overrun +
                      ", yet the file ends with its footer: it was not cut off but is corrupt "
                      "there");
        return cut(overrun);
      }
      if (first && opcode != kHeader)
        throw Error(file_.path() + ": the first record is a " + what +
                    ", not the header the spec requires");
      first = false;
      content_.resize(length);
      if (!file_.read(content_)) return cut(what + " is cut off");
      FieldReader fields(content_, file_.path() + ": " + what);
      if (opcode == kFooter) {
        result_.indexed = fields.u64("summary_start") != 0;
        return finish(at);
      }
      if (opcode == kDataEnd) data_ended = true;
      if (!data_ended) data_record(opcode, fields, at);
    }
  }

 private:
  ScanResult cut(std::string why) {
    result_.cut_off = std::move(why);
    return result_;
  }

  ScanResult finish(std::uint64_t footer_at) {
    std::uint8_t magic[sizeof kMagic];
    if (!file_.read(magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0)
      return cut("the footer at byte " + std::to_string(footer_at) +
                 " is not followed by MCAP's closing magic bytes");
    if (file_.at() != file_.size())
      throw Error(file_.path() + ": " + std::to_string(file_.size() - file_.at()) +
                  " bytes follow the closing magic at byte " + std::to_string(file_.at()) +
                  ": not one MCAP file (two joined together?); cut them apart, e.g. with `head "
                  "-c " +
                  std::to_string(file_.at()) + "`");
    result_.complete = true;
    return result_;
  }

  void data_record(std::uint8_t opcode, FieldReader& fields, std::uint64_t at) {
    switch (opcode) {
      case kHeader: {
        std::string profile = fields.str("profile");
        visitor_.header(profile, fields.str("library"));
        break;
      }
      case kChunk:
        read_chunk(fields, at);
        break;
      default:
        inner_record(opcode, fields);
    }
  }

  // A record that may stand in the data section or inside a chunk.
  void inner_record(std::uint8_t opcode, FieldReader& fields) {
    switch (opcode) {
      case kSchema:
        visitor_.schema(read_schema(fields));
        break;
      case kChannel:
        visitor_.channel(read_channel(fields));
        break;
      case kMessage:
        ++result_.messages;
        visitor_.message(read_message(fields));
        break;
      case kMetadata: {
        std::string name = fields.str("name");
        visitor_.metadata(name, fields.map("metadata"));
        break;
      }
      default:
        break;  // indexes, attachments, records a later version adds: not needed here
    }
  }

  void read_chunk(FieldReader& fields, std::uint64_t at) {
    const std::string what = file_.path() + ": chunk at byte " + std::to_string(at);
    fields.u64("message_start_time");
    fields.u64("message_end_time");
    const std::uint64_t size = fields.u64("uncompressed_size");
    const std::uint32_t crc = fields.u32("uncompressed_crc");
    const std::string compression_text = fields.str("compression");
    const auto records = fields.take(fields.u64("records length"), "records");
    const auto compression = compression_named(compression_text);
    if (!compression)
      throw Error(what + " is compressed with \"" + compression_text +
                  "\", which afhub does not read (it reads none, lz4 and zstd)");
    if (size > kMaxRecordBytes)
      throw Error(what + " says it holds " + std::to_string(size) +
                  " bytes uncompressed, more than afhub reads in one chunk (256 MiB)");
    check_claimed_size(*compression, records, size, what);
    uncompressed_.resize(size);
    decompress(*compression, records, uncompressed_, what);
    if (crc != 0 && crc32(uncompressed_) != crc)
      throw Error(what + ": its records do not match their CRC (a corrupt file)");
    ++result_.chunks;
    visitor_.chunk(compression_text);
    std::span<const std::uint8_t> rest(uncompressed_);
    while (!rest.empty()) {
      const std::uint64_t inner_at = uncompressed_.size() - rest.size();
      FieldReader prefix(rest, what + ", record at byte " + std::to_string(inner_at) + " inside");
      const std::uint8_t opcode = prefix.u8("opcode");
      const std::uint64_t length = prefix.u64("length");
      FieldReader inner(prefix.take(length, "content"), what + ", " + opcode_name(opcode) +
                                                            " record at byte " +
                                                            std::to_string(inner_at) + " inside");
      inner_record(opcode, inner);
      rest = rest.subspan(kRecordPrefix + length);
    }
  }

  File file_;
  Visitor& visitor_;
  ScanResult result_;
  std::vector<std::uint8_t> content_, uncompressed_;
};

// Copies what it reads into a new file, its ids mapped to the writer's.
class Copier : public Visitor {
 public:
  // `original` is left as it is when the copy fails.
  Copier(const std::string& path, const std::string& original) : path_(path) {
    options_.when_write_fails = "the recovery is given up, and " + original +
                                " left as it was; it needs free space about its size";
  }
  void header(const std::string& profile, const std::string& library) override {
    options_.profile = profile;
    options_.library = library;
  }
  void chunk(std::string_view compression) override {
    // The first chunk tells how the original was compressed; records before it are held.
    if (!writer_) {
      options_.compression = *compression_named(compression);
      open();
    }
  }
  // A schema or channel another writer repeats (in each chunk) is copied once.
  void schema(const Schema& schema) override {
    if (!seen_schemas_.insert(schema.id).second) return;
    held_schemas_.push_back(schema);
    if (writer_) add(schema);
  }
  void channel(const Channel& channel) override {
    if (!seen_channels_.insert(channel.id).second) return;
    held_channels_.push_back(channel);
    if (writer_) add(channel);
  }
  void metadata(const std::string& name, const Metadata& metadata) override {
    held_metadata_.emplace_back(name, metadata);
    if (writer_) writer_->add_metadata(name, metadata);
  }
  void message(const Message& message) override {
    if (!writer_) open();  // a file without chunks
    const auto channel = channel_ids_.find(message.channel_id);
    if (channel == channel_ids_.end())
      throw Error("a message on channel " + std::to_string(message.channel_id) +
                  ", which no channel record declares");
    Message copy = message;
    copy.channel_id = channel->second;
    writer_->write(copy);
  }
  void close() {
    if (!writer_) open();
    writer_->close();
  }

 private:
  void open() {
    writer_ = std::make_unique<Writer>(path_, options_);
    for (const Schema& schema : held_schemas_) add(schema);
    for (const Channel& channel : held_channels_) add(channel);
    for (const auto& [name, metadata] : held_metadata_) writer_->add_metadata(name, metadata);
  }
  void add(const Schema& schema) {
    schema_ids_[schema.id] = writer_->add_schema(schema.name, schema.encoding, schema.data);
  }
  void add(const Channel& channel) {
    const auto schema = schema_ids_.find(channel.schema_id);
    channel_ids_[channel.id] =
        writer_->add_channel(schema == schema_ids_.end() ? 0 : schema->second, channel.topic,
                             channel.message_encoding, channel.metadata);
  }

  std::string path_;
  Writer::Options options_;
  std::unique_ptr<Writer> writer_;
  std::vector<Schema> held_schemas_;
  std::vector<Channel> held_channels_;
  std::vector<std::pair<std::string, Metadata>> held_metadata_;
  std::map<std::uint16_t, std::uint16_t> schema_ids_, channel_ids_;
  std::set<std::uint16_t> seen_schemas_, seen_channels_;
};

}  // namespace

ScanResult scan(const std::string& path, Visitor& visitor) {
  return Scanner(path, visitor).run();
}

ScanResult recover(const std::string& path) {
  // Held until the file is replaced: a recorder still writing it would go on into the
  // file replaced, unlinked.
  const int held = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);  // a FIFO too
  if (held < 0) throw Error("cannot open " + path + ": " + std::strerror(errno));
  const struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{held};
  lock_recording(held, path);
  const std::string temporary = path + ".recovering";
  ScanResult result;
  try {
    Copier copier(temporary, path);
    result = scan(path, copier);
    copier.close();
  } catch (...) {
    std::filesystem::remove(temporary);
    throw;
  }
  if ((result.complete && result.indexed) || (!result.complete && result.messages == 0)) {
    std::filesystem::remove(temporary);
    if (result.complete) return result;  // nothing to recover: the original stays as it was
    throw Error(path + ": nothing to recover: no message before it was cut off (" + result.cut_off +
                ")");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) throw Error("cannot replace " + path + " with " + temporary + ": " + error.message());
  return result;
}

}  // namespace afhub::mcap
