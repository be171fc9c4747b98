// The hub's default pools by payload kind: iceoryx takes a chunk from the smallest
// pool that fits it, whatever its kind, so a kind whose sizes fall into another's
// pool uses that pool's chunks up. Body directories of a few bodies (2480 bytes for
// 8) fell into the world state's pool of 64, and 32 physics ran it out.
#include <gtest/gtest.h>

#include "afhub/hub/hub_daemon.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/device.hpp"
#include "afhub/shm_layout/limits.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub {
namespace {

// The pool iceoryx would take a chunk of `bytes` from.
const MempoolSpec& pool_for(const std::vector<MempoolSpec>& pools, std::size_t bytes) {
  for (const MempoolSpec& pool : pools)
    if (pool.payload_bytes >= bytes) return pool;
  return pools.back();
}

bool holds_body_lists(const MempoolSpec& pool) {
  return pool.holds.find("catalogs and directories") != std::string::npos;
}

TEST(MempoolKinds, BodyListsTakeOnlyBodyListChunks) {
  const std::vector<MempoolSpec> pools = default_mempools();
  for (std::size_t bodies = 0; bodies <= kMaxBodies; ++bodies)
    for (std::size_t joints : {std::size_t{0}, 4 * bodies}) {
      // A list past the largest tier is refused before it is loaned (hub/client/src/bodies.cpp).
      if (body_list_bytes(bodies, joints, joints) > kBodyListTiers.back()) continue;
      const MempoolSpec& pool = pool_for(pools, body_list_loan_bytes(bodies, joints, joints));
      ASSERT_TRUE(holds_body_lists(pool)) << "a list of " << bodies << " bodies and " << joints
                                          << " joints goes to the pool of " << pool.holds;
    }
}

TEST(MempoolKinds, EveryProcessHasRoomForItsDirectoryAndWorldState) {
  const std::vector<MempoolSpec> pools = default_mempools();
  // A chunk in its history, a loan, and up to three in the hub's reader.
  const MempoolSpec& directories = pool_for(pools, body_list_loan_bytes(1));
  EXPECT_GE(directories.chunk_count, 5 * kMaxProcesses) << directories.holds;
  // Its first block of slots for its world state (and one for its body states): 32
  // physics used to run the world state's pool of 64 out.
  EXPECT_GE(pool_for(pools, first_slot_block_bytes(sizeof(WorldState))).chunk_count,
            2 * kMaxProcesses);
}

// iceoryx aborts the process that loans a chunk no pool can hold: every block a writer
// may loan (any joint count, any tier) fits a pool of slot blocks.
TEST(MempoolKinds, EveryBlockOfSlotsFitsAPoolOfBlocks) {
  const std::vector<MempoolSpec> pools = default_mempools();
  std::vector<std::size_t> payloads = {sizeof(WorldState), sizeof(DeviceState),
                                       sizeof(DeviceCommand),
                                       scene_poses_bytes(kMaxSceneBodies, kMaxSceneJointValues)};
  for (std::size_t joints = 0; joints <= kMaxJointsPerBody; ++joints) {
    payloads.push_back(body_state_bytes(joints));
    payloads.push_back(body_command_bytes(joints));
  }
  for (std::size_t bytes : payloads) {
    const std::uint32_t capacity = slot_payload_capacity(static_cast<std::uint32_t>(bytes));
    for (std::size_t nth = 0; nth <= kSlotBlockTierCount; ++nth) {
      const std::size_t block = slot_block_loan_bytes(nth, capacity);
      ASSERT_LE(slot_block_bytes(slot_block_entries(nth, capacity), capacity), block);
      const MempoolSpec& pool = pool_for(pools, block);
      ASSERT_GE(pool.payload_bytes, slot_block_pool_bytes(block))
          << "no pool for a block of " << bytes << "-byte slots";
      ASSERT_NE(pool.holds.find("blocks of slots"), std::string::npos)
          << "a block of " << bytes << "-byte slots goes to the pool of " << pool.holds;
    }
  }
}

// `afhub hub --bench-pools` (the hub `afhub bench` starts) put a 1 KiB pool of 16
// chunks below the body pools: every state of the example arm landed in it, and the
// physics published one step in two at best. Now the bodies' blocks of slots keep
// their pools too.
TEST(MempoolKinds, BenchPoolsLeaveTheBodiesTheirPools) {
  const std::vector<MempoolSpec> plain = default_mempools();
  const std::vector<MempoolSpec> bench = with_bench_pools(plain);
  for (std::size_t joints = 0; joints <= kMaxJointsPerBody; ++joints)
    for (std::size_t bytes : {first_slot_block_bytes(body_state_bytes(joints)),
                              first_slot_block_bytes(body_command_bytes(joints))}) {
      const MempoolSpec& with = pool_for(bench, bytes);
      const MempoolSpec& without = pool_for(plain, bytes);
      ASSERT_EQ(with.payload_bytes, without.payload_bytes)
          << bytes << " bytes (" << joints << " joints) go to the pool of " << with.holds;
      ASSERT_GE(with.chunk_count, without.chunk_count) << with.holds;
    }
  EXPECT_NE(pool_for(bench, 1u << 20).holds.find("bench samples of 1024 KiB"), std::string::npos);
  const MempoolSpec& largest_slot =
      pool_for(bench, slot_block_pool_bytes(first_slot_block_bytes(1u << 20)));
  EXPECT_GE(largest_slot.payload_bytes, slot_block_pool_bytes(first_slot_block_bytes(1u << 20)));
  EXPECT_FALSE(holds_body_lists(largest_slot)) << "1 MiB bench slots would take catalog chunks";
}

}  // namespace
}  // namespace afhub
