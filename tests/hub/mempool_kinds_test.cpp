// The hub's default pools by payload kind: iceoryx takes a chunk from the smallest
// pool that fits it, whatever its kind, so a kind whose sizes fall into another's
// pool uses that pool's chunks up. Body directories of a few bodies (2480 bytes for
// 8) fell into the world state's pool of 64, and 32 physics ran it out.
#include <gtest/gtest.h>

#include "afhub/hub/hub_daemon.hpp"
#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/catalog.hpp"
#include "afhub/shm_layout/limits.hpp"
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
      const MempoolSpec& pool = pool_for(pools, body_list_loan_bytes(bodies, joints, joints));
      ASSERT_TRUE(holds_body_lists(pool)) << "a list of " << bodies << " bodies and " << joints
                                          << " joints goes to the pool of " << pool.holds;
    }
  EXPECT_EQ(pool_for(pools, sizeof(WorldState)).holds, "world state");
}

TEST(MempoolKinds, EveryProcessHasRoomForItsDirectoryAndWorldState) {
  const std::vector<MempoolSpec> pools = default_mempools();
  // A chunk in its history, a loan, and up to three in the hub's reader.
  const MempoolSpec& directories = pool_for(pools, body_list_loan_bytes(1));
  EXPECT_GE(directories.chunk_count, 5 * kMaxProcesses) << directories.holds;
  // A chunk in its history and a loan: 32 physics used to run the pool of 64 out.
  EXPECT_GE(pool_for(pools, sizeof(WorldState)).chunk_count, 2 * kMaxProcesses);
}

// `afhub hub --bench-pools` (the hub `afhub bench` starts) put a 1 KiB pool of 16
// chunks below the body pools: every state of the example arm landed in it, and the
// physics published one step in two at best.
TEST(MempoolKinds, BenchPoolsLeaveTheBodiesTheirPools) {
  const std::vector<MempoolSpec> plain = default_mempools();
  const std::vector<MempoolSpec> bench = with_bench_pools(plain);
  for (std::size_t joints = 0; joints <= kMaxJointsPerBody; ++joints)
    for (std::size_t bytes : {body_state_bytes(joints), body_command_bytes(joints)}) {
      const MempoolSpec& with = pool_for(bench, bytes);
      const MempoolSpec& without = pool_for(plain, bytes);
      ASSERT_EQ(with.payload_bytes, without.payload_bytes)
          << bytes << " bytes (" << joints << " joints) go to the pool of " << with.holds;
      ASSERT_GE(with.chunk_count, without.chunk_count) << with.holds;
    }
  EXPECT_EQ(pool_for(bench, 1u << 20).payload_bytes, 1u << 20);
}

}  // namespace
}  // namespace afhub
