// Shared-memory pools of the hub, sized from the payload types rather than
// iceoryx's 206 MiB default, and the pool file and flags that change them. (RouDi
// keeps its introspection samples in a segment of its own, so these pools hold
// afhub payloads only.)
#include <algorithm>
#include <fstream>
#include <sstream>

#include "afhub/hub/hub_daemon.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/device_tape.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/loop_stats.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub/shm_layout/soft_body.hpp"
#include "afhub/shm_layout/step_tape.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/yaml/input_file.hpp"

namespace afhub {
namespace {

constexpr std::uint32_t round_up8(std::size_t bytes) {
  return static_cast<std::uint32_t>((bytes + 7) / 8 * 8);
}

constexpr std::uint32_t block_pool(std::size_t loan_bytes) {
  return round_up8(slot_block_pool_bytes(loan_bytes));
}

// iceoryx rejects a chunk above 4 GiB; a pool beyond this many bytes in all is
// surely a typo, and would fail only when the hub maps its segment.
constexpr double kMaxPoolBytes = 16.0 * 1024 * 1024 * 1024;

void sort_by_size(std::vector<MempoolSpec>& pools) {
  std::sort(pools.begin(), pools.end(), [](const MempoolSpec& a, const MempoolSpec& b) {
    return a.payload_bytes < b.payload_bytes;
  });
}

// Parses "<bytes> <count>" (the separator already replaced by a space); empty
// string when it is good, else what is wrong.
std::string parse_pool(const std::string& text, MempoolSpec& pool) {
  std::istringstream in(text);
  long long bytes = 0, count = 0;
  std::string rest;
  if (!(in >> bytes >> count) || (in >> rest))
    return "expected '<payload bytes> <chunk count>', two whole numbers";
  if (bytes < 8 || bytes > (1LL << 31)) return "payload bytes must be 8 .. 2147483648";
  if (count < 1 || count > 1'000'000) return "chunk count must be 1 .. 1000000";
  if (static_cast<double>(bytes) * static_cast<double>(count) > kMaxPoolBytes)
    return "the pool would take more than 16 GiB of shared memory";
  pool = {round_up8(static_cast<std::size_t>(bytes)), static_cast<std::uint32_t>(count), "user"};
  return "";
}

}  // namespace

std::vector<MempoolSpec> default_mempools() {
  // States, commands, world states, device channels and pose feeds are slots in blocks
  // (shm_layout/slot_block.hpp): a writer process's n-th block of a kind and entry size
  // fills the n-th tier, the last tier thereafter. Most processes take one 16 KiB block
  // per kind they write (a controller's commands, a driver's device state); a physics
  // of a thousand bodies five blocks, a thousand commands from 125 controllers 125
  // blocks of the first tier. Block readers hold each block once per process. In all
  // the default pools take 173 MB of /dev/shm (iceoryx's own default: 206 MB).
  // Catalogs and directories are loaned at their real size, and iceoryx takes a chunk
  // from the smallest pool that fits it, whatever its type: each holds a chunk in its
  // writer's history, and three in each reader.
  static_assert(sizeof(DeviceTapeRing) + alignof(DeviceTapeRing) <=
                    block_pool(kSlotBlockTiers[2]) &&
                sizeof(DeviceTapeRing) > block_pool(kSlotBlockTiers[1]));
  std::vector<MempoolSpec> pools = {
      {128, 512, "world commands, small iceoryx samples"},
      {block_pool(kSlotBlockTiers[0]), 1024, "first blocks of slots (a writer's first 16 KiB)"},
      {block_pool(kSlotBlockTiers[1]), 256,
       "second blocks of slots, and blocks of one state of up to kMaxJointsPerBody joints"},
      // Devices' tapes' rings (256 KB) too: a driver publishes one when a recorder first
      // reads it; 8 more chunks, for four devices recorded, each restarted once.
      {block_pool(kSlotBlockTiers[2]), 64 + 8,
       "third blocks of slots, a large scene's pose feed, devices' tapes' rings"},
      {block_pool(kSlotBlockTiers[3]), 16, "blocks of slots of a writer of hundreds of channels"},
      {round_up8(sizeof(Health)), 128, "hub health"},
      {round_up8(sizeof(LoopStats)), 256, "loop stats"},
      // Each process's directory: a chunk in its history, a loan, and the hub's reader
      // queues and holds up to three. Body lists are loaned at these sizes only
      // (kBodyListTiers): no other kind's chunks are taken by them.
      {round_up8(kBodyListTiers[0]), 5 * kMaxProcesses,
       "catalogs and directories of up to 8 bodies (64 joint names, 256 joint references)"},
      {round_up8(kBodyListTiers[1]), 32,
       "catalogs and directories of up to 64 bodies (512 joint names, 2048 references)"},
      {round_up8(kBodyListTiers[2]), 24,
       "catalogs and directories of up to kMaxBodies bodies (8192 joint names, 65536 "
       "references)"},
      // The physics' scene description keeps one chunk in its history, and three in
      // each viewer.
      {round_up8(scene_description_bytes(64)), 32, "scene descriptions of up to 64 bodies"},
      {round_up8(scene_description_bytes(kMaxSceneBodies)), 8,
       "scene descriptions of up to kMaxSceneBodies bodies"},
      // Scene descriptions of about 8 to 20 bodies (their mesh parts make them 60 to 80
      // KB): each physics keeps one in its history, and one that just ended keeps one
      // until RouDi has removed its port.
      {round_up8(scene_description_bytes(20)), 64, "scene descriptions of 8 to 20 bodies"},
      // Per soft body a node chunk in the writer's history, a loan, and three in
      // each viewer; its faces once, kept the same way.
      {round_up8(soft_body_mesh_bytes(0)), 64, "soft body node positions"},
      {round_up8(soft_body_mesh_bytes(kMaxSoftBodyFaces)), 32, "soft body faces"},
      // Step tapes' rings: a physics publishes one when a recorder first reads it, and a
      // recorder holds a restarted physics' old one until it has read it: two, 21 MB,
      // about what the queue of samples they replaced took (19.7 MB). (The hub writes
      // every page at its start: with 35 MB here a CI run on the 2-core VM had a hub
      // start and a hub stop too slow for two tests.) The iceoryx loan aligns the ring
      // to 64 bytes.
      {round_up8(sizeof(StepTapeRing) + alignof(StepTapeRing)), 2, "step tapes' rings"},
  };
  sort_by_size(pools);
  return pools;
}

std::vector<MempoolSpec> with_bench_pools(std::vector<MempoolSpec> pools) {
  // A ping and a pong channel per payload size, each holding up to five chunks (a
  // loan, the history, a queued, a held and a retired sample). Added to the pool each
  // sample would be taken from anyway: a pool of their own between two of the body
  // tiers would take the body states below it too (a 1 KiB pool of 16 chunks took
  // every state of the example arm, and the physics dropped most of its steps).
  // Its slots (afhub-slot) are each the first block of its writer.
  constexpr std::uint32_t kBenchChunks = 16;
  for (std::uint32_t sample : {1u << 10, 1u << 14, 1u << 18, 1u << 20})
    for (std::uint32_t bytes : {sample, block_pool(first_slot_block_bytes(sample))}) {
      auto fits = std::find_if(pools.begin(), pools.end(), [bytes](const MempoolSpec& pool) {
        return pool.payload_bytes >= bytes;
      });
      // Past the largest block tier the next pool up holds catalogs: one of their own.
      if (fits == pools.end() || (bytes > block_pool(kSlotBlockTiers[kSlotBlockTierCount - 1]) &&
                                  fits->payload_bytes > bytes / 4 * 5)) {
        pools.push_back(
            {bytes, kBenchChunks, "bench samples of " + std::to_string(sample >> 10) + " KiB"});
        continue;
      }
      fits->chunk_count += kBenchChunks;
      fits->holds += "; bench samples of " + std::to_string(sample >> 10) + " KiB";
    }
  sort_by_size(pools);
  return pools;
}

std::vector<MempoolSpec> read_mempool_file(const std::string& path) {
  yaml::check_input_file(path, 1u << 20, "a mempool file");  // a regular file, not /dev/zero
  std::ifstream in(path);
  if (!in) throw Error("cannot read the mempool file " + path);
  std::vector<MempoolSpec> pools;
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    line = line.substr(0, line.find('#'));
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    MempoolSpec pool{};
    if (const std::string problem = parse_pool(line, pool); !problem.empty())
      throw Error(path + ":" + std::to_string(number) + ": " + problem);
    pool.holds = path + ":" + std::to_string(number);
    pools.push_back(pool);
  }
  return pools;
}

MempoolSpec parse_mempool(const std::string& text) {
  std::string spaced = text;
  std::replace(spaced.begin(), spaced.end(), ':', ' ');
  MempoolSpec pool{};
  if (const std::string problem = parse_pool(spaced, pool); !problem.empty())
    throw Error("--pool " + text + ": " + problem + " (as BYTES:COUNT, e.g. 65536:32)");
  return pool;
}

std::vector<MempoolSpec> merge_mempools(std::vector<MempoolSpec> pools,
                                        const std::vector<MempoolSpec>& extra) {
  for (const MempoolSpec& add : extra) {
    auto same = std::find_if(pools.begin(), pools.end(), [&](const MempoolSpec& pool) {
      return pool.payload_bytes == add.payload_bytes;
    });
    if (same != pools.end())
      *same = add;
    else
      pools.push_back(add);
  }
  sort_by_size(pools);
  if (pools.size() > kMaxMempools)
    throw Error("the hub would have " + std::to_string(pools.size()) +
                " mempools; iceoryx allows " + std::to_string(kMaxMempools) +
                ". Merge sizes, or give fewer --pool options");
  return pools;
}

}  // namespace afhub
