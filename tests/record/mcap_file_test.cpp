// afhub's MCAP writer and reader against each other: every message back as written,
// with each compression; a file cut off reads up to its last complete chunk and
// `recover` gives it its index again; bad files are errors naming what and where.
// (tests/record/mcap_check reads the writer's files with an independent reader.)
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

#include <filesystem>
#include <fstream>

#include "afhub/record/mcap_reader.hpp"
#include "afhub/record/mcap_writer.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/world.hpp"
#include "recorded_payloads.hpp"
#include "sha256.hpp"

namespace afhub::mcap {
namespace {

namespace fs = std::filesystem;

struct Collected : Visitor {
  std::string profile;
  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  std::vector<std::pair<std::string, Metadata>> metadata_records;
  std::vector<std::string> chunk_compressions;
  struct Received {
    std::uint16_t channel;
    std::uint32_t sequence;
    std::uint64_t log_time;
    std::vector<std::uint8_t> data;
  };
  std::vector<Received> messages;

  void header(const std::string& p, const std::string&) override { profile = p; }
  void schema(const Schema& s) override { schemas.push_back(s); }
  void channel(const Channel& c) override { channels.push_back(c); }
  void metadata(const std::string& name, const Metadata& m) override {
    metadata_records.emplace_back(name, m);
  }
  void chunk(std::string_view compression) override {
    chunk_compressions.emplace_back(compression);
  }
  void message(const Message& m) override {
    messages.push_back({m.channel_id, m.sequence, m.log_time_ns, {m.data.begin(), m.data.end()}});
  }
};

// A payload that differs per message: a lost, repeated or shifted byte shows.
std::vector<std::uint8_t> payload(std::uint32_t channel, std::uint32_t sequence) {
  std::vector<std::uint8_t> data(100 + (sequence * 7 + channel) % 400);
  for (std::size_t i = 0; i < data.size(); ++i)
    data[i] = static_cast<std::uint8_t>(i * 31 + sequence * 17 + channel);
  return data;
}

class McapFile : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() / ("mcap_file_test_" + std::to_string(getpid()));
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }
  std::string path(const std::string& name) const { return (directory_ / name).string(); }

  // Two channels, `messages` messages each, in chunks of 16 KiB (compressed and written
  // by the writer's own thread, or not; their indexes held in memory up to
  // `index_memory_bytes`).
  void write_sample(const std::string& file, Compression compression, std::uint32_t messages,
                    bool background = false, std::size_t index_memory_bytes = 16u << 20) {
    Writer writer(file, {"afhub", "afhub", compression, 16 * 1024, background, index_memory_bytes});
    const std::uint8_t schema_text[] = {'s', 'c', 'h', 'e', 'm', 'a'};
    const auto schema = writer.add_schema("afhub.BodyState", "afhub-layout", schema_text);
    const auto a = writer.add_channel(schema, "/arm/base/state", "afhub", {{"joints", "3"}});
    writer.add_metadata("afhub", {{"layout_id", "42"}});
    const auto b = writer.add_channel(schema, "/arm/tool/state", "afhub");
    for (std::uint32_t s = 1; s <= messages; ++s)
      for (std::uint16_t channel : {a, b}) {
        const auto data = payload(channel, s);
        writer.write({channel, s, 1'000'000ull * s, 1'000'000ull * s + 5, data});
      }
    writer.close();
  }

  void expect_sample(const Collected& read, std::uint32_t messages) {
    ASSERT_EQ(read.messages.size(), 2u * messages);
    for (std::uint32_t s = 1; s <= messages; ++s)
      for (std::uint16_t channel : {1, 2}) {
        const auto& m = read.messages[2 * (s - 1) + (channel - 1)];
        ASSERT_EQ(m.channel, channel);
        ASSERT_EQ(m.sequence, s);
        ASSERT_EQ(m.log_time, 1'000'000ull * s);
        ASSERT_EQ(m.data, payload(channel, s)) << "channel " << channel << " message " << s;
      }
  }

  fs::path directory_;
};

TEST_F(McapFile, EveryMessageComesBackAsWrittenWithEachCompression) {
  for (const bool background : {false, true})
    for (Compression compression : {Compression::kNone, Compression::kLz4, Compression::kZstd}) {
      SCOPED_TRACE(std::string(compression_name(compression)) +
                   (background ? " in the background" : ""));
      const std::string file = path("sample.mcap");
      write_sample(file, compression, 2000, background);
      Collected read;
      const ScanResult result = scan(file, read);
      EXPECT_TRUE(result.complete) << result.cut_off;
      EXPECT_EQ(result.messages, 4000u);
      EXPECT_GT(result.chunks, 10u);
      EXPECT_EQ(read.profile, "afhub");
      ASSERT_EQ(read.schemas.size(), 1u);
      EXPECT_EQ(read.schemas[0].name, "afhub.BodyState");
      ASSERT_EQ(read.channels.size(), 2u);
      EXPECT_EQ(read.channels[0].topic, "/arm/base/state");
      EXPECT_EQ(read.channels[0].metadata.at("joints"), "3");
      ASSERT_EQ(read.metadata_records.size(), 1u);
      EXPECT_EQ(read.metadata_records[0].second.at("layout_id"), "42");
      for (const auto& c : read.chunk_compressions) EXPECT_EQ(c, compression_name(compression));
      expect_sample(read, 2000);
    }
}

std::string file_bytes(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST_F(McapFile, ChunkIndexesThatWaitedInATemporaryFileMakeTheSameFile) {
  // Held in memory, or written to the temporary file after every chunk (a byte is
  // past the bound): the same bytes, summary and its CRC included.
  for (const bool background : {false, true}) {
    SCOPED_TRACE(background ? "in the background" : "in the caller's thread");
    write_sample(path("held.mcap"), Compression::kZstd, 3000, background);
    write_sample(path("spilled.mcap"), Compression::kZstd, 3000, background, 1);
    const std::string held = file_bytes(path("held.mcap"));
    EXPECT_GT(held.size(), 100'000u);
    EXPECT_TRUE(held == file_bytes(path("spilled.mcap")));
    Collected read;
    const ScanResult result = scan(path("spilled.mcap"), read);
    EXPECT_TRUE(result.complete) << result.cut_off;
    EXPECT_GT(result.chunks, 10u);
    expect_sample(read, 3000);
  }
}

TEST_F(McapFile, AFileCutOffReadsToItsLastCompleteChunkAndRecoverGivesItsIndexBack) {
  const std::string file = path("cut.mcap");
  write_sample(file, Compression::kZstd, 3000);
  Collected whole;
  const ScanResult full = scan(file, whole);
  ASSERT_TRUE(full.complete);
  // Cut in the middle of the data: what a kill -9 leaves.
  fs::resize_file(file, fs::file_size(file) * 3 / 5);
  Collected partial;
  const ScanResult cut = scan(file, partial);
  EXPECT_FALSE(cut.complete);
  // Said where: inside a chunk, or inside the prefix of the record after one.
  EXPECT_TRUE(cut.cut_off.find("chunk record at byte") != std::string::npos ||
              cut.cut_off.find("inside a record's opcode and length") != std::string::npos)
      << cut.cut_off;
  EXPECT_GT(cut.messages, 1000u);
  EXPECT_LT(cut.messages, full.messages);
  ASSERT_EQ(partial.messages.size(), cut.messages);
  for (std::size_t i = 0; i < partial.messages.size(); ++i)
    ASSERT_EQ(partial.messages[i].data, whole.messages[i].data) << "message " << i;

  const ScanResult original = recover(file);
  EXPECT_EQ(original.messages, cut.messages);
  Collected recovered;
  const ScanResult after = scan(file, recovered);
  EXPECT_TRUE(after.complete) << after.cut_off;
  EXPECT_EQ(after.messages, cut.messages);
  EXPECT_EQ(recovered.channels.size(), 2u);
  EXPECT_EQ(recovered.metadata_records.size(), 1u);
  EXPECT_FALSE(fs::exists(file + ".recovering"));
}

TEST_F(McapFile, ADiskThatFillsUpLeavesAFileCutOffNotCorrupt) {
  for (const bool background : {false, true}) {
    SCOPED_TRACE(background ? "in the background" : "in the caller's thread");
    // The file size limit stands for a full disk: a write past it fails (EFBIG). In the
    // background the failed write is said by the next call after it.
    const std::string file = path("full.mcap");
    signal(SIGXFSZ, SIG_IGN);
    rlimit before{};
    getrlimit(RLIMIT_FSIZE, &before);
    rlimit small = before;
    small.rlim_cur = 100 * 1024 + 123;  // within a chunk
    std::string error;
    {
      Writer writer(file, {"afhub", "afhub", Compression::kNone, 16 * 1024, background});
      const auto schema = writer.add_schema("s", "e", {});
      const auto channel = writer.add_channel(schema, "/t", "afhub");
      setrlimit(RLIMIT_FSIZE, &small);
      try {
        for (std::uint32_t s = 1; s <= 3000; ++s) {
          const auto data = payload(channel, s);
          writer.write({channel, s, s, s, data});
        }
      } catch (const Error& e) {
        error = e.what();
      }
      setrlimit(RLIMIT_FSIZE, &before);  // room again when the writer is destroyed
    }
    EXPECT_NE(error.find("cannot write"), std::string::npos) << error;
    EXPECT_LE(fs::file_size(file), small.rlim_cur);
    Collected read;
    const ScanResult cut = scan(file, read);  // no CRC error: nothing was written twice
    EXPECT_FALSE(cut.complete);
    EXPECT_GT(cut.messages, 100u);
    for (std::size_t i = 0; i < read.messages.size(); ++i)
      ASSERT_EQ(read.messages[i].data, payload(1, static_cast<std::uint32_t>(i + 1)));
    EXPECT_EQ(recover(file).messages, cut.messages);
  }
}

// A disk full before the header went: the writer is refused, and leaves no empty file
// behind that a later look would take for a recording cut off at its start.
TEST_F(McapFile, ADiskFullAtTheStartLeavesNoFile) {
  const std::string file = path("none.mcap");
  signal(SIGXFSZ, SIG_IGN);
  rlimit before{};
  getrlimit(RLIMIT_FSIZE, &before);
  rlimit none = before;
  none.rlim_cur = 0;
  setrlimit(RLIMIT_FSIZE, &none);
  std::string error;
  try {
    Writer writer(file, {"afhub", "afhub", Compression::kNone, 16 * 1024, false});
  } catch (const Error& e) {
    error = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &before);
  EXPECT_NE(error.find("cannot write"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(file));
}

// The message of the afhub::Error `scan` throws for `file`, or "" when it throws none.
std::string scan_error(const std::string& file) {
  Collected read;
  try {
    scan(file, read);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

void overwrite(const std::string& file, std::uint64_t at, const std::vector<std::uint8_t>& bytes) {
  std::fstream out(file, std::ios::in | std::ios::out | std::ios::binary);
  out.seekp(static_cast<std::streamoff>(at));
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

TEST_F(McapFile, BadFilesAreErrorsSayingWhatAndWhere) {
  const std::string file = path("bad.mcap");
  { std::ofstream(file) << "not an mcap file at all"; }
  EXPECT_NE(scan_error(file).find("is not an MCAP file"), std::string::npos) << scan_error(file);
  { std::ofstream out(file); }
  EXPECT_NE(scan_error(file).find("is not an MCAP file"), std::string::npos);
  EXPECT_NE(scan_error(path("missing.mcap")).find("cannot open"), std::string::npos);

  // The header's length made absurd: corrupt, whether the file ends or not.
  write_sample(file, Compression::kNone, 10);
  overwrite(file, 9, {0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x7f});
  EXPECT_NE(scan_error(file).find("header record at byte 8 holds 9223372036854775807 bytes, more "
                                  "than afhub reads in one record"),
            std::string::npos)
      << scan_error(file);

  // A byte flipped inside the first chunk's records: its CRC says so.
  write_sample(file, Compression::kNone, 100);
  Collected clean;
  scan(file, clean);
  std::ifstream in(file, std::ios::binary);
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  const auto& needle = clean.messages[3].data;
  const auto found = std::search(bytes.begin(), bytes.end(), needle.begin(), needle.end());
  ASSERT_NE(found, bytes.end());
  overwrite(file, static_cast<std::uint64_t>(found - bytes.begin()) + 10,
            {static_cast<std::uint8_t>(needle[10] ^ 0xff)});
  EXPECT_NE(scan_error(file).find("do not match their CRC"), std::string::npos) << scan_error(file);

  // A byte flipped in the middle of a compressed chunk: its frame's checksum (or its
  // structure) says so. The frame starts with its magic, after the u64 of its length.
  for (const auto& [compression, magic] :
       {std::pair{Compression::kZstd, std::vector<std::uint8_t>{0x28, 0xb5, 0x2f, 0xfd}},
        std::pair{Compression::kLz4, std::vector<std::uint8_t>{0x04, 0x22, 0x4d, 0x18}}}) {
    write_sample(file, compression, 100);
    std::ifstream packed_in(file, std::ios::binary);
    const std::vector<std::uint8_t> packed((std::istreambuf_iterator<char>(packed_in)), {});
    const auto frame = std::search(packed.begin(), packed.end(), magic.begin(), magic.end());
    ASSERT_NE(frame, packed.end()) << compression_name(compression);
    const auto at = static_cast<std::uint64_t>(frame - packed.begin());
    std::uint64_t frame_bytes = 0;
    std::memcpy(&frame_bytes, packed.data() + at - 8, sizeof frame_bytes);
    ASSERT_GT(frame_bytes, 16u);
    overwrite(file, at + frame_bytes / 2,
              {static_cast<std::uint8_t>(packed[at + frame_bytes / 2] ^ 0x5a)});
    EXPECT_NE(scan_error(file).find("could not decompress"), std::string::npos)
        << compression_name(compression) << ": " << scan_error(file);
  }

  // A first record that is not a header.
  write_sample(file, Compression::kNone, 10);
  overwrite(file, 8, {0x05});
  EXPECT_NE(scan_error(file).find("not the header the spec requires"), std::string::npos)
      << scan_error(file);
}

// A record running past the end is a cut only in a file that does not end with its
// footer; in one that does, it is corruption, and --recover leaves the file as it is
// (it rewrote it from the records before, losing the rest). So do bytes after the end.
TEST_F(McapFile, AFinishedFileWithALengthTooLongIsCorruptNotCutAndRecoverKeepsIt) {
  const std::string file = path("finished.mcap");
  write_sample(file, Compression::kZstd, 3000);
  const std::string whole = file_bytes(file);
  ASSERT_TRUE(recover(file).complete);  // left as it is
  EXPECT_EQ(file_bytes(file), whole);

  // The first chunk's length one byte more than the rest of the file holds.
  std::uint64_t chunk_at = 0;
  for (std::uint64_t at = 8;;) {  // walk the records to the first chunk
    std::uint64_t length = 0;
    std::memcpy(&length, whole.data() + at + 1, sizeof length);
    if (whole[at] == 0x06) {
      chunk_at = at;
      break;
    }
    at += 9 + length;
  }
  const std::uint64_t past = whole.size() - chunk_at - 9 + 1;
  std::vector<std::uint8_t> length(8);
  std::memcpy(length.data(), &past, sizeof past);
  overwrite(file, chunk_at + 1, length);
  const std::string corrupt = file_bytes(file);
  const std::string error = scan_error(file);
  EXPECT_NE(error.find("chunk record at byte " + std::to_string(chunk_at) + " says it holds"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("ends with its footer: it was not cut off but is corrupt"),
            std::string::npos)
      << error;
  EXPECT_THROW(recover(file), Error);
  EXPECT_EQ(file_bytes(file), corrupt);
  EXPECT_FALSE(fs::exists(file + ".recovering"));

  // The same file cut short of its footer: then the same length is a cut.
  fs::resize_file(file, whole.size() - 100);
  Collected read;
  const ScanResult cut = scan(file, read);
  EXPECT_FALSE(cut.complete);
  EXPECT_NE(cut.cut_off.find("chunk record at byte " + std::to_string(chunk_at)), std::string::npos)
      << cut.cut_off;

  // Two recordings joined: not one file.
  { std::ofstream(file, std::ios::binary) << whole << whole; }
  EXPECT_NE(scan_error(file).find(std::to_string(whole.size()) +
                                  " bytes follow the closing magic at byte " +
                                  std::to_string(whole.size())),
            std::string::npos)
      << scan_error(file);
  EXPECT_THROW(recover(file), Error);
  EXPECT_EQ(fs::file_size(file), 2 * whole.size());

  // MCAP's magic alone: nothing to recover (it became an empty recording), left as it is.
  { std::ofstream(file, std::ios::binary) << whole.substr(0, 8); }
  EXPECT_THROW(recover(file), Error);
  EXPECT_EQ(fs::file_size(file), 8u);

  // Complete, but its footer points at no summary: recover gives it one.
  { std::ofstream(file, std::ios::binary) << whole; }
  overwrite(file, whole.size() - 8 - 20, std::vector<std::uint8_t>(8, 0));  // summary_start
  Collected unindexed;
  const ScanResult before = scan(file, unindexed);
  EXPECT_TRUE(before.complete);
  EXPECT_FALSE(before.indexed);
  EXPECT_TRUE(recover(file).complete);
  Collected reindexed;
  const ScanResult after = scan(file, reindexed);
  EXPECT_TRUE(after.indexed);
  EXPECT_EQ(after.messages, before.messages);
}

TEST_F(McapFile, AChunkOfAnUnknownCompressionIsAnErrorNamingIt) {
  const std::string file = path("brotli.mcap");
  write_sample(file, Compression::kLz4, 10);
  std::ifstream in(file, std::ios::binary);
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string lz4 = "lz4";
  const auto found = std::search(bytes.begin(), bytes.end(), lz4.begin(), lz4.end());
  ASSERT_NE(found, bytes.end());
  overwrite(file, static_cast<std::uint64_t>(found - bytes.begin()), {'b', 'r', 'o'});
  EXPECT_NE(scan_error(file).find("compressed with \"bro\""), std::string::npos)
      << scan_error(file);
}

// A body state in the file leaves out its unused arrays and reads back as it was: with
// and without sensor rays, with and without a refusal reason, with none and many joints.
TEST(RecordedPayloads, AStateIsPackedForTheFileAndReadsBackAsItWas) {
  for (const std::uint32_t rays : {0u, 3u, static_cast<std::uint32_t>(kMaxSensorRaysPerBody)})
    for (const bool refused : {false, true})
      for (const std::uint32_t joints : {0u, 8u, 300u}) {
        SCOPED_TRACE(::testing::Message()
                     << rays << " rays, refused " << refused << ", " << joints << " joints");
        auto state = std::make_unique<BodyState>();
        state->header.layout_id = kLayoutId;
        state->header.kind = PayloadKind::kBodyState;
        state->header.sim_step = 41;
        state->pose.position_m = {1, 2, 3};
        state->sensor_ray_count = rays;
        for (std::uint32_t r = 0; r < rays; ++r) {
          state->sensor_distances_m[r] = 0.5 + r;
          state->sensor_ranges_m[r] = 2.0 + r;
        }
        if (refused) std::strcpy(state->refusal_reason.data(), "joint 2: NaN");
        state->joint_count = joints;
        for (std::uint32_t j = 0; j < joints; ++j) state->joints[j].position = 0.25 * j;
        const std::span<const std::uint8_t> published(
            reinterpret_cast<const std::uint8_t*>(state.get()), body_state_bytes(joints));

        FilePieces pieces;
        std::vector<std::uint8_t> in_file;
        const std::size_t count = pieces_for_file(published, PayloadKind::kBodyState, pieces);
        for (std::size_t p = 0; p < count; ++p)
          in_file.insert(in_file.end(), pieces[p].begin(), pieces[p].end());
        const std::size_t left_out = (kMaxSensorRaysPerBody - rays) * 2 * sizeof(double) +
                                     (refused ? 0
                                              : offsetof(BodyState, sensor_distances_m) -
                                                    offsetof(BodyState, refusal_reason));
        EXPECT_EQ(in_file.size(), published.size() - left_out);
        std::vector<std::uint64_t> aligned;
        const auto read = checked_copy(in_file, PayloadKind::kBodyState, aligned, "a state");
        ASSERT_EQ(read.size(), published.size());
        EXPECT_TRUE(std::equal(read.begin(), read.end(), published.begin()));
      }

  // Other payloads, and a state not of this layout's size, are kept as they are.
  FilePieces pieces;
  const std::vector<std::uint8_t> odd(body_state_bytes(0) + 3, 0);
  ASSERT_EQ(pieces_for_file(odd, PayloadKind::kBodyState, pieces), 1u);
  EXPECT_EQ(pieces[0].data(), odd.data());
  EXPECT_EQ(pieces[0].size(), odd.size());
  const std::vector<std::uint8_t> world(sizeof(WorldState), 0);
  ASSERT_EQ(pieces_for_file(world, PayloadKind::kWorldState, pieces), 1u);
  EXPECT_EQ(pieces[0].size(), world.size());
}

// FIPS 180-4's examples: one block, two blocks of padding, a million bytes.
TEST(Sha256, MatchesTheStandardsExamples) {
  const auto of = [](const std::string& text) {
    return sha256_hex({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
  };
  EXPECT_EQ(of(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(of("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(of("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(of(std::string(1'000'000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

}  // namespace
}  // namespace afhub::mcap
