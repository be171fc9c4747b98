#include "afhub/record/compression.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "afhub/shm_layout/error.hpp"

namespace afhub::mcap {

std::string_view compression_name(Compression compression) {
  switch (compression) {
    case Compression::kLz4:
      return "lz4";
    case Compression::kZstd:
      return "zstd";
    case Compression::kNone:
      break;
  }
  return "";
}

std::optional<Compression> compression_named(std::string_view name) {
  for (Compression c : {Compression::kNone, Compression::kLz4, Compression::kZstd})
    if (compression_name(c) == name) return c;
  return std::nullopt;
}

// zstd at -5, one of its "fast" levels, which trade ratio for speed: a recorder must keep
// up with a thousand bodies first. Measured on the project's 2-core VM (a thousand packed
// 8-joint states): level 1 compressed them to 93 bytes each but kept up with 0.7 million
// a second, -5 to 112 bytes and about 0.9 million.
constexpr int kZstdLevel = -5;

Compressor::Compressor(Compression compression) : compression_(compression) {
  if (compression_ != Compression::kZstd) return;
  auto* context = ZSTD_createCCtx();
  if (!context) throw Error("no zstd compression context (out of memory)");
  context_ = context;
  // Each frame checksums its content (XXH64): the chunk's integrity check.
  ZSTD_CCtx_setParameter(context, ZSTD_c_compressionLevel, kZstdLevel);
  ZSTD_CCtx_setParameter(context, ZSTD_c_checksumFlag, 1);
}

Compressor::~Compressor() {
  ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(context_));
}

std::size_t Compressor::append(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out) {
  const std::size_t start = out.size();
  std::size_t written = 0;
  switch (compression_) {
    case Compression::kNone:
      out.insert(out.end(), in.begin(), in.end());
      return in.size();
    case Compression::kLz4: {
      LZ4F_preferences_t preferences{};
      preferences.frameInfo.contentSize = in.size();  // lets a reader size its buffer
      preferences.frameInfo.contentChecksumFlag =
          LZ4F_contentChecksumEnabled;  // the integrity check
      out.resize(start + LZ4F_compressFrameBound(in.size(), &preferences));
      written = LZ4F_compressFrame(out.data() + start, out.size() - start, in.data(), in.size(),
                                   &preferences);
      if (LZ4F_isError(written))
        throw Error(std::string("lz4 compression failed: ") + LZ4F_getErrorName(written));
      break;
    }
    case Compression::kZstd:
      out.resize(start + ZSTD_compressBound(in.size()));
      written = ZSTD_compress2(static_cast<ZSTD_CCtx*>(context_), out.data() + start,
                               out.size() - start, in.data(), in.size());
      if (ZSTD_isError(written))
        throw Error(std::string("zstd compression failed: ") + ZSTD_getErrorName(written));
      break;
  }
  out.resize(start + written);
  return written;
}

void decompress(Compression compression, std::span<const std::uint8_t> in,
                std::span<std::uint8_t> out, const std::string& what) {
  std::size_t produced = 0;
  switch (compression) {
    case Compression::kNone:
      if (in.size() != out.size())
        throw Error(what + ": holds " + std::to_string(in.size()) + " bytes, says " +
                    std::to_string(out.size()));
      std::copy(in.begin(), in.end(), out.begin());
      return;
    case Compression::kZstd:
      produced = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
      if (ZSTD_isError(produced))
        throw Error(what + ": zstd could not decompress it: " + ZSTD_getErrorName(produced));
      break;
    case Compression::kLz4: {
      LZ4F_dctx* context = nullptr;
      if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION)))
        throw Error(what + ": no lz4 decompression context");
      std::size_t in_at = 0;
      std::size_t status = 1;
      while (status != 0 && in_at < in.size() && produced <= out.size()) {
        std::size_t out_room = out.size() - produced;
        std::size_t in_left = in.size() - in_at;
        status = LZ4F_decompress(context, out.data() + produced, &out_room, in.data() + in_at,
                                 &in_left, nullptr);
        if (LZ4F_isError(status)) {
          LZ4F_freeDecompressionContext(context);
          throw Error(what + ": lz4 could not decompress it: " + LZ4F_getErrorName(status));
        }
        produced += out_room;
        in_at += in_left;
        if (out_room == 0 && in_left == 0) break;  // no progress: output full or input cut
      }
      LZ4F_freeDecompressionContext(context);
      if (status != 0) throw Error(what + ": its lz4 frame is cut short or longer than it says");
      break;
    }
  }
  if (produced != out.size())
    throw Error(what + ": decompressed to " + std::to_string(produced) + " bytes, says " +
                std::to_string(out.size()));
}

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  // zlib takes a uInt length: feed it in pieces.
  while (!bytes.empty()) {
    const std::size_t piece = std::min<std::size_t>(bytes.size(), 1u << 30);
    crc = static_cast<std::uint32_t>(::crc32_z(crc, bytes.data(), piece));
    bytes = bytes.subspan(piece);
  }
  return crc;
}

}  // namespace afhub::mcap
