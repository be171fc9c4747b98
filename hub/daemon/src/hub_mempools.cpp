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
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/health.hpp"
#include "afhub/shm_layout/loop_stats.hpp"
#include "afhub/shm_layout/scene.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/slot.hpp"
#include "afhub/shm_layout/soft_body.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {
namespace {

constexpr std::uint32_t round_up8(std::size_t bytes) {
  return static_cast<std::uint32_t>((bytes + 7) / 8 * 8);
}

// A pool's payload size for a slot kind's largest payload: iceoryx counts the slot's
// control block (a user header) into the payload size it picks a pool by.
constexpr std::uint32_t slot_bytes(std::size_t payload_bytes) {
  return round_up8(payload_bytes + kSlotOverheadBytes);
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
  // Body states, body commands and catalogs are loaned at their real size, and
  // iceoryx takes a chunk from the smallest pool that fits it, whatever its type: the
  // body payloads share four tiers by size, most chunks where most bodies are (up to
  // 64 joints). States and commands are slots (one chunk per writer, held by its
  // readers, plus the slot's control block): the counts leave room for kMaxBodies
  // bodies with several command writers each in the first tiers, fewer for bodies with
  // hundreds of joints below them (a rope or chain whose every link is active), and
  // for the queue samples of other kinds that fit those sizes. Catalogs and
  // directories: each holds a chunk in its writer's history, and three in each reader.
  std::vector<MempoolSpec> pools = {
      {128, 512, "world commands, small iceoryx samples"},
      {slot_bytes(body_command_bytes(64)), 4096,
       "body commands of up to 64 joints, states of bodies with few joints"},
      {slot_bytes(body_state_bytes(64)), 4096, "body states of up to 64 joints"},
      {slot_bytes(body_state_bytes(256)), 1024, "body states and commands of up to 256 joints"},
      {slot_bytes(body_state_bytes(kMaxJointsPerBody)), 256,
       "body states and commands of up to kMaxJointsPerBody joints"},
      // Each physics's world state: a slot, and, briefly, a larger one replacing it.
      {slot_bytes(sizeof(WorldState)), 2 * kMaxProcesses + 64, "world state"},
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
       "catalogs and directories of up to kMaxBodies bodies (4096 joint names, 65536 "
       "references)"},
      // The physics' scene description keeps one chunk in its history, and three in
      // each viewer.
      {round_up8(scene_description_bytes(64)), 32, "scene descriptions of up to 64 bodies"},
      {round_up8(scene_description_bytes(kMaxSceneBodies)), 8,
       "scene descriptions of up to kMaxSceneBodies bodies"},
      // A viewer's pose feed: a slot per physics (and one replacing it when the scene
      // grows).
      {slot_bytes(scene_poses_bytes(64, 512)), 32,
       "viewer pose feeds of up to 64 bodies (512 joint values)"},
      // It also takes the scene descriptions of about 8 to 20 bodies (their mesh parts
      // make them 60 to 80 KB): each physics keeps one in its history, and one that just
      // ended keeps one until RouDi has removed its port.
      {slot_bytes(scene_poses_bytes(kMaxSceneBodies, kMaxSceneJointValues)), 64,
       "viewer pose feeds of up to kMaxSceneBodies bodies (kMaxSceneJointValues joint values), "
       "scene descriptions of 8 to 20 bodies"},
      // Per soft body a node chunk in the writer's history, a loan, and three in
      // each viewer; its faces once, kept the same way.
      {round_up8(soft_body_mesh_bytes(0)), 64, "soft body node positions"},
      {round_up8(soft_body_mesh_bytes(kMaxSoftBodyFaces)), 32, "soft body faces"},
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
  // Its slots (afhub-slot) carry their control block beside the sample.
  constexpr std::uint32_t kBenchChunks = 16;
  for (std::uint32_t sample : {1u << 10, 1u << 14, 1u << 18, 1u << 20})
    for (std::uint32_t bytes : {sample, slot_bytes(sample)}) {
      auto fits = std::find_if(pools.begin(), pools.end(), [bytes](const MempoolSpec& pool) {
        return pool.payload_bytes >= bytes;
      });
      if (fits == pools.end()) {
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
