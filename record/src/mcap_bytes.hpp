// MCAP's building blocks (mcap.dev/spec): opcodes, the little-endian field encodings a
// record is made of, and one record's fields read back with bounds checked.
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "afhub/shm_layout/error.hpp"

namespace afhub::mcap {

// 0x89 "MCAP" then the major version '0', "\r\n": at both ends of a file.
inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
// A record: opcode (1 byte), content length (8 bytes), content.
inline constexpr std::size_t kRecordPrefix = 9;

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Appends one record to `out`: the opcode, a length patched by the destructor, fields.
class RecordBuilder {
 public:
  RecordBuilder(std::vector<std::uint8_t>& out, Opcode opcode) : out_(out), start_(out.size()) {
    out_.push_back(opcode);
    u64(0);
  }
  ~RecordBuilder() {
    const std::uint64_t length = out_.size() - start_ - kRecordPrefix;
    std::memcpy(out_.data() + start_ + 1, &length, sizeof length);  // x86-64: little-endian
  }
  RecordBuilder(const RecordBuilder&) = delete;
  RecordBuilder& operator=(const RecordBuilder&) = delete;

  template <class T>
  RecordBuilder& put(T value) {
    static_assert(std::is_integral_v<T>);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
    out_.insert(out_.end(), bytes, bytes + sizeof value);
    return *this;
  }
  RecordBuilder& u8(std::uint8_t v) { return put(v); }
  RecordBuilder& u16(std::uint16_t v) { return put(v); }
  RecordBuilder& u32(std::uint32_t v) { return put(v); }
  RecordBuilder& u64(std::uint64_t v) { return put(v); }
  RecordBuilder& raw(std::span<const std::uint8_t> bytes) {
    out_.insert(out_.end(), bytes.begin(), bytes.end());
    return *this;
  }
  // String: u32 length, then the bytes.
  RecordBuilder& str(std::string_view text) {
    u32(static_cast<std::uint32_t>(text.size()));
    return raw({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
  }
  // Bytes with a u32 length prefix (a schema's data).
  RecordBuilder& bytes32(std::span<const std::uint8_t> bytes) {
    u32(static_cast<std::uint32_t>(bytes.size()));
    return raw(bytes);
  }
  // Map<string, string>: u32 byte length of the entries, then key and value strings.
  RecordBuilder& map(const std::map<std::string, std::string>& entries) {
    std::uint32_t length = 0;
    for (const auto& [key, value] : entries) length += 8 + key.size() + value.size();
    u32(length);
    for (const auto& [key, value] : entries) str(key).str(value);
    return *this;
  }

 private:
  std::vector<std::uint8_t>& out_;
  std::size_t start_;
};

// Reads one record's fields; a field that runs past the record throws afhub::Error
// naming the record (`what`, e.g. "channel record at byte 1234") and the field.
class FieldReader {
 public:
  FieldReader(std::span<const std::uint8_t> content, std::string what)
      : content_(content), what_(std::move(what)) {}

  template <class T>
  T get(const char* field) {
    T value;
    std::memcpy(&value, take(sizeof value, field).data(), sizeof value);
    return value;
  }
  std::uint8_t u8(const char* field) { return get<std::uint8_t>(field); }
  std::uint16_t u16(const char* field) { return get<std::uint16_t>(field); }
  std::uint32_t u32(const char* field) { return get<std::uint32_t>(field); }
  std::uint64_t u64(const char* field) { return get<std::uint64_t>(field); }
  std::string str(const char* field) {
    const auto bytes = take(u32(field), field);
    return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
  }
  std::span<const std::uint8_t> bytes32(const char* field) { return take(u32(field), field); }
  std::map<std::string, std::string> map(const char* field) {
    FieldReader entries(take(u32(field), field), what_ + " " + field);
    std::map<std::string, std::string> out;
    while (!entries.done()) {
      std::string key = entries.str("key");
      out[std::move(key)] = entries.str("value");
    }
    return out;
  }
  std::span<const std::uint8_t> rest() { return take(content_.size() - at_, "data"); }
  std::span<const std::uint8_t> take(std::uint64_t bytes, const char* field) {
    if (bytes > content_.size() - at_)
      throw Error(what_ + ": its field " + field + " needs " + std::to_string(bytes) +
                  " bytes, the record has " + std::to_string(content_.size() - at_) +
                  " left (a corrupt file)");
    const auto out = content_.subspan(at_, bytes);
    at_ += bytes;
    return out;
  }
  bool done() const { return at_ == content_.size(); }

 private:
  std::span<const std::uint8_t> content_;
  std::string what_;
  std::size_t at_ = 0;
};

}  // namespace afhub::mcap
