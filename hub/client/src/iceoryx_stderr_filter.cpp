// The filter on std::cerr (see iceoryx_stderr_filter.hpp).
#include "iceoryx_stderr_filter.hpp"

#include <array>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <mutex>
#include <streambuf>
#include <string_view>

#include "iceoryx_posh/mepoo/chunk_header.hpp"

namespace afhub {
namespace {

constexpr char kPoolLine[] = "Mempool [m_chunkSize = ";
// How iceoryx's lines on RouDi's socket begin: its POSIX call wrapper names the source
// file as its build saw it, and the socket's own line.
constexpr char kSourceLine[] = "./iceoryx_hoofs/";
constexpr char kSocketLine[] = "internal logic error in unix domain socket \"/tmp/roudi\"";

// Whether `line` begins as `prefix` does, as far as it goes.
template <std::size_t N>
bool could_begin(std::string_view line, const char (&prefix)[N]) {
  const std::size_t n = std::min(line.size(), N - 1);
  return line.substr(0, n) == std::string_view(prefix, n);
}

// A message to RouDi's socket that found no hub: refused, no socket, not connected.
bool hub_gone_line(std::string_view line) {
  if (line.rfind(kSocketLine, 0) == 0) return true;
  if (line.rfind(kSourceLine, 0) != 0 || line.find("unix_domain_socket.cpp:") == line.npos)
    return false;
  for (const char* errno_part : {":::  [ 111 ]", ":::  [ 2 ]", ":::  [ 107 ]"})
    if (line.find(errno_part) != line.npos) return true;
  return false;
}

class IceoryxStderrFilter : public std::streambuf {
 public:
  IceoryxStderrFilter(std::streambuf* out, std::string who) : out_(out), who_(std::move(who)) {}

 protected:
  int overflow(int ch) override {
    if (ch == traits_type::eof()) return traits_type::not_eof(ch);
    const char c = static_cast<char>(ch);
    const std::lock_guard lock(mutex_);
    put(c);
    return ch;
  }

  std::streamsize xsputn(const char* text, std::streamsize count) override {
    const std::lock_guard lock(mutex_);
    for (std::streamsize i = 0; i < count; ++i) put(text[i]);
    return count;
  }

  // std::cerr flushes after every <<: a part of a line that cannot be one of those
  // filtered goes out now, the rest at its end.
  int sync() override {
    const std::lock_guard lock(mutex_);
    if (size_ > 0 && !could_be_filtered()) pass();
    return out_->pubsync();
  }

 private:
  void put(char c) {
    line_[size_++] = c;
    if (c == '\n')
      end_line();
    else if (size_ == line_.size())
      pass();  // longer than any line filtered
  }

  bool could_be_filtered() const {
    const std::string_view line(line_.data(), size_);
    return could_begin(line, kPoolLine) || could_begin(line, kSourceLine) ||
           could_begin(line, kSocketLine);
  }

  void pass() {
    out_->sputn(line_.data(), static_cast<std::streamsize>(size_));
    size_ = 0;
  }

  void end_line() {
    line_[size_ - 1] = '\0';
    unsigned long chunk_bytes = 0, chunks = 0;
    const bool pool_line =
        std::sscanf(line_.data(), "Mempool [m_chunkSize = %lu, numberOfChunks = %lu", &chunk_bytes,
                    &chunks) == 2 &&
        std::strstr(line_.data(), "has no more space left") != nullptr;
    line_[size_ - 1] = '\n';
    if (hub_gone_line(std::string_view(line_.data(), size_ - 1))) {
      size_ = 0;
      return;
    }
    if (!pool_line) return pass();
    size_ = 0;
    if (!first_time(chunk_bytes)) return;
    const unsigned long payload_bytes = chunk_bytes - sizeof(iox::mepoo::ChunkHeader);
    char message[512];
    const int length = std::snprintf(
        message, sizeof message,
        "%s: shared memory exhausted: the hub's pool of %lu chunks of %lu bytes has none free; "
        "what this process would send in it is dropped until one is (said once per pool). "
        "`afhub status` shows the pools; stop another process, or give the hub more "
        "(`afhub hub --pool %lu:COUNT`)\n",
        who_.c_str(), chunks, payload_bytes, payload_bytes);
    out_->sputn(message, std::min<std::streamsize>(length, sizeof message - 1));
    out_->pubsync();
  }

  // Whether the pool of `chunk_bytes` is met for the first time; pools past the
  // table's room count as said.
  bool first_time(unsigned long chunk_bytes) {
    for (unsigned long& said : said_) {
      if (said == chunk_bytes) return false;
      if (said == 0) {
        said = chunk_bytes;
        return true;
      }
    }
    return false;
  }

  std::streambuf* out_;
  const std::string who_;
  std::mutex mutex_;
  std::array<char, 512> line_{};
  std::size_t size_ = 0;
  std::array<unsigned long, 64> said_{};  // the chunk sizes said, 0 for free
};

}  // namespace

void filter_iceoryx_stderr(const std::string& who) {
  static std::once_flag once;
  std::call_once(once, [&who] {
    // Never destroyed: iceoryx may write while the process ends.
    static auto* filter = new IceoryxStderrFilter(std::cerr.rdbuf(), who);
    std::cerr.rdbuf(filter);
  });
}

std::unique_ptr<std::streambuf> make_iceoryx_stderr_filter(std::streambuf* out, std::string who) {
  return std::make_unique<IceoryxStderrFilter>(out, std::move(who));
}

}  // namespace afhub
