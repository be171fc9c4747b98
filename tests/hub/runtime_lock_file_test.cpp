// iceoryx's per-process lock file in /tmp is made by afhub first, never through a
// symlink or another user's file planted where it goes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "afhub/hub/hub_files.hpp"

namespace afhub {
namespace {

namespace fs = std::filesystem;

struct Scratch {
  Scratch() {
    char pattern[] = "/tmp/afhub-lock-test-XXXXXX";
    dir = mkdtemp(pattern);
  }
  ~Scratch() { fs::remove_all(dir); }
  std::string dir;
};

TEST(RuntimeLockFile, IsCreatedAsAPrivateRegularFile) {
  Scratch scratch;
  const std::string lock = scratch.dir + "/afhub-run-1.lock";
  claim_runtime_lock_file(lock);
  struct stat info {};
  ASSERT_EQ(lstat(lock.c_str(), &info), 0);
  EXPECT_TRUE(S_ISREG(info.st_mode));
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  claim_runtime_lock_file(lock);  // one left by an earlier process of this user: kept
  EXPECT_EQ(lstat(lock.c_str(), &info), 0);
}

TEST(RuntimeLockFile, APlantedSymlinkIsRemovedAndItsTargetNeverMade) {
  Scratch scratch;
  const std::string target = scratch.dir + "/chosen-by-another-user";
  const std::string lock = scratch.dir + "/afhub-run-2.lock";
  ASSERT_EQ(symlink(target.c_str(), lock.c_str()), 0);
  ::testing::internal::CaptureStderr();
  claim_runtime_lock_file(lock);
  const std::string said = ::testing::internal::GetCapturedStderr();
  EXPECT_FALSE(fs::exists(target)) << "the symlink was followed";
  struct stat info {};
  ASSERT_EQ(lstat(lock.c_str(), &info), 0);
  EXPECT_TRUE(S_ISREG(info.st_mode));
  EXPECT_NE(said.find("a symlink owned by uid"), std::string::npos) << said;
}

TEST(RuntimeLockFile, ADirectoryOrAFifoThereIsReplaced) {
  Scratch scratch;
  const std::string as_dir = scratch.dir + "/afhub-run-3.lock";
  const std::string as_fifo = scratch.dir + "/afhub-run-4.lock";
  ASSERT_EQ(mkdir(as_dir.c_str(), 0700), 0);
  ASSERT_EQ(mkfifo(as_fifo.c_str(), 0600), 0);
  ::testing::internal::CaptureStderr();
  claim_runtime_lock_file(as_dir);
  claim_runtime_lock_file(as_fifo);
  ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(fs::is_regular_file(as_dir));
  EXPECT_TRUE(fs::is_regular_file(as_fifo));
}

// A FIFO swapped in where a lock file was (another user may write /tmp) is not opened
// for reading, which would wait for a writer forever: the hub's liveness loop would hang.
TEST(RuntimeLockFile, AFifoInPlaceOfALockNeverHangsItsReader) {
  Scratch scratch;
  const std::string fifo = scratch.dir + "/afhub-run-2.lock";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0666), 0);
  EXPECT_EQ(open_regular_file(fifo), -1);
  EXPECT_EQ(errno, EINVAL);
  EXPECT_FALSE(flock_held(fifo));
}

}  // namespace
}  // namespace afhub
