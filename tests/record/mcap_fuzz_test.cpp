// A fuzz test of afhub's MCAP reading: recordings written by afhub's writer (each
// compression), mutated deterministically (bytes flipped, a length or a size made huge or
// zero, bytes inserted or deleted, the file cut short), are read by `scan`, described by
// `summarize` and rewritten by `recover`. Each must read, or fail with an afhub::Error;
// a recovered file must read back complete. Anything else, or a crash, is a finding.
// AFHUB_FUZZ_CASES sets the number of cases (default 1500), AFHUB_FUZZ_SEED the seed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "afhub/record/file_summary.hpp"
#include "afhub/record/mcap_reader.hpp"
#include "afhub/record/mcap_writer.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::mcap {
namespace {

namespace fs = std::filesystem;

std::uint64_t from_environment(const char* name, std::uint64_t fallback) {
  const char* text = std::getenv(name);
  return text && *text ? std::strtoull(text, nullptr, 10) : fallback;
}

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// A small recording: two channels, metadata, chunks of 2 KiB.
std::vector<std::uint8_t> seed(const fs::path& dir, Compression compression) {
  const fs::path path = dir / "seed.mcap";
  {
    Writer writer(path.string(), {"afhub", "afhub", compression, 2048});
    const std::uint8_t text[] = {'s'};
    const auto schema = writer.add_schema("afhub.BodyState", "afhub-layout", text);
    const auto a = writer.add_channel(schema, "/a/state", "afhub", {{"joint_names", "j1,j2"}});
    writer.add_metadata("afhub", {{"layout_id", "0x1"}});
    const auto b = writer.add_channel(schema, "/b/state", "afhub");
    for (std::uint32_t s = 1; s <= 60; ++s)
      for (std::uint16_t channel : {a, b}) {
        std::vector<std::uint8_t> data(40 + s % 50, static_cast<std::uint8_t>(s * channel));
        writer.write({channel, s, 1000ull * s, 1000ull * s, data});
      }
    writer.close();
  }
  return read_bytes(path);
}

void mutate(std::vector<std::uint8_t>& bytes, std::mt19937_64& random) {
  auto at = [&] { return std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(random); };
  const int kind = std::uniform_int_distribution<int>(0, 5)(random);
  switch (kind) {
    case 0:  // a few bytes flipped
      for (int i = 0; i < 1 + static_cast<int>(random() % 4); ++i)
        bytes[at()] ^= 1u << (random() % 8);
      break;
    case 1: {  // a length or size: huge, zero, or off by a little
      const std::size_t where = at();
      const std::uint64_t values[] = {~0ull, 1ull << 40, 0, 1ull << 28, 7};
      const std::uint64_t value = values[random() % 5];
      for (std::size_t i = 0; i < 8 && where + i < bytes.size(); ++i)
        bytes[where + i] = static_cast<std::uint8_t>(value >> (8 * i));
      break;
    }
    case 2:  // cut short
      bytes.resize(at());
      break;
    case 3:  // bytes inserted
      bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(at()), 1 + random() % 16,
                   static_cast<std::uint8_t>(random()));
      break;
    case 4: {  // bytes deleted
      const std::size_t from = at();
      bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(from),
                  bytes.begin() + static_cast<std::ptrdiff_t>(
                                      std::min(bytes.size(), from + 1 + random() % 16)));
      break;
    }
    default:  // a 32-bit count or length made huge
      for (std::size_t i = 0, where = at(); i < 4 && where + i < bytes.size(); ++i)
        bytes[where + i] = 0xff;
  }
  if (bytes.empty()) bytes.push_back(0x89);
}

TEST(McapFuzz, EveryMutantReadsOrFailsWithAnAfhubError) {
  const fs::path dir = fs::temp_directory_path() / ("mcap_fuzz_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::vector<std::vector<std::uint8_t>> seeds = {
      seed(dir, Compression::kNone), seed(dir, Compression::kLz4), seed(dir, Compression::kZstd)};
  std::mt19937_64 random(from_environment("AFHUB_FUZZ_SEED", 20261129));
  const std::uint64_t cases = from_environment("AFHUB_FUZZ_CASES", 1500);
  const fs::path mutant = dir / "mutant.mcap";
  std::uint64_t read = 0, refused = 0, recovered = 0;
  for (std::uint64_t c = 0; c < cases; ++c) {
    std::vector<std::uint8_t> bytes = seeds[c % seeds.size()];
    for (int m = 0; m < 1 + static_cast<int>(random() % 3); ++m) mutate(bytes, random);
    write_bytes(mutant, bytes);
    SCOPED_TRACE("case " + std::to_string(c));
    try {
      Visitor ignore;
      scan(mutant.string(), ignore);
      summarize(mutant.string());
      ++read;
      recover(mutant.string());
      const FileSummary again = summarize(mutant.string());
      EXPECT_TRUE(again.complete) << again.cut_off;
      ++recovered;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()), "");
      ++refused;
    } catch (const std::exception& other) {
      write_bytes(dir / ("finding_" + std::to_string(c) + ".mcap"), bytes);
      ADD_FAILURE() << "not an afhub::Error: " << other.what();
    }
  }
  std::printf("%llu mutants: %llu read (%llu recovered), %llu refused with an error\n",
              static_cast<unsigned long long>(cases), static_cast<unsigned long long>(read),
              static_cast<unsigned long long>(recovered), static_cast<unsigned long long>(refused));
  EXPECT_GT(read, cases / 10) << "the mutations hardly ever leave a file that reads";
  EXPECT_GT(refused, cases / 10) << "the mutations hardly ever make a file that fails";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace afhub::mcap
