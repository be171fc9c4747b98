// `afhub hub`'s mempools: the defaults, what the bench adds, a pool file and flags,
// and bad values refused with where they are. `--dry-run` prints them; no hub starts.
#include <gtest/gtest.h>

#include "afhub_process.hpp"
#include "model_files.hpp"

namespace afhub::test {
namespace {

TEST(HubOptions, ProductionHubCarriesNoBenchPools) {
  const RunResult plain = run_afhub({"hub", "--dry-run"});
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_TRUE(contains(plain.out, "blocks of slots")) << plain.out;
  EXPECT_FALSE(contains(plain.out, "bench samples")) << plain.out;
  const RunResult bench = run_afhub({"hub", "--dry-run", "--bench-pools"});
  ASSERT_EQ(bench.exit_code, 0) << bench.err;
  EXPECT_TRUE(contains(bench.out, "bench samples of 1024 KiB")) << bench.out;
}

TEST(HubOptions, PoolsFromFileAndFlagsAddOrResize) {
  afhub::testing::ModelFolder folder;
  const std::string file =
      folder.write("pools.txt", "# camera frames\n65536 40   # 64 KiB\n\n4194304 4\n");
  const RunResult run = run_afhub({"hub", "--dry-run", "--mempools", file, "--pool", "65536:8"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(contains(run.out, "4194304       4")) << run.out;
  // The flag comes after the file: the 64 KiB pool has its count.
  EXPECT_TRUE(contains(run.out, "65536       8")) << run.out;
  EXPECT_FALSE(contains(run.out, "65536      40")) << run.out;
}

TEST(HubOptions, BadPoolsAreRefusedWithWhere) {
  afhub::testing::ModelFolder folder;
  const std::string file = folder.write("pools.txt", "1024 16\n1024 lots\n");
  RunResult run = run_afhub({"hub", "--dry-run", "--mempools", file});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err, file + ":2: expected '<payload bytes> <chunk count>'")) << run.err;
  run = run_afhub({"hub", "--dry-run", "--pool", "64:0"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err, "--pool 64:0: chunk count must be 1 .. 1000000")) << run.err;
  run = run_afhub({"hub", "--dry-run", "--pool", "1073741824:1000"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err, "more than 16 GiB")) << run.err;
}

}  // namespace
}  // namespace afhub::test
