// How an MCAP file's chunks are compressed, by the spec's names: "" (none), "lz4" (the
// LZ4 frame format) and "zstd".
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace afhub::mcap {

enum class Compression { kNone, kLz4, kZstd };

// The spec's name of `compression` ("" for none).
std::string_view compression_name(Compression compression);
// The compression named `name` in a file ("", "lz4", "zstd"), or nullopt.
std::optional<Compression> compression_named(std::string_view name);

// Compresses `in` onto the end of `out`, and says how many bytes it added. Keeps its
// codec's context between calls: one per thread.
class Compressor {
 public:
  explicit Compressor(Compression compression);
  ~Compressor();
  Compressor(const Compressor&) = delete;
  Compressor& operator=(const Compressor&) = delete;
  std::size_t append(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out);

 private:
  Compression compression_;
  void* context_ = nullptr;  // ZSTD_CCtx
};

// Decompresses `in` into `out`, which must come out exactly `out.size()` bytes;
// throws afhub::Error saying why not (`what` names the chunk).
void decompress(Compression compression, std::span<const std::uint8_t> in,
                std::span<std::uint8_t> out, const std::string& what);

// CRC-32 (the zlib polynomial, as the spec's CRC fields), continued from `crc`.
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

}  // namespace afhub::mcap
