// spawn_process (afhub/rt/process_spawn.hpp): the program's exit code and output, a
// clear error for a program that cannot start, a clean signal state, and a detached
// child in its own session, reaped so that it leaves no zombie.
#include "afhub/rt/process_spawn.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>

#include "afhub/shm_layout/error.hpp"
#include "afhub_process.hpp"

namespace afhub::test {
namespace {

int wait_exit_code(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(ProcessSpawn, RunsTheProgramWithItsOutputInAFile) {
  const std::string log =
      (std::filesystem::temp_directory_path() / ("spawn-" + std::to_string(getpid()))).string();
  SpawnOptions options;
  options.output_path = log;
  const pid_t pid = spawn_process({"/bin/sh", "-c", "echo out; echo err >&2; exit 3"}, options);
  EXPECT_EQ(wait_exit_code(pid), 3);
  EXPECT_EQ(read_file(log), "out\nerr\n");
  std::filesystem::remove(log);
}

// A predictable output path in /tmp where another user planted something: nothing is
// written through a symlink, and a FIFO never hangs the caller.
TEST(ProcessSpawn, AnOutputPathThatIsASymlinkOrAFifoIsRefused) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("spawn-planted-" + std::to_string(getpid()));
  std::filesystem::create_directories(folder);
  const std::filesystem::path target = folder / "chosen-by-another-user";
  std::filesystem::create_symlink(target, folder / "symlink.log");
  ASSERT_EQ(mkfifo((folder / "fifo.log").c_str(), 0666), 0);
  for (const char* name : {"symlink.log", "fifo.log"}) {
    SpawnOptions options;
    options.output_path = (folder / name).string();
    try {
      const pid_t pid = spawn_process({"/bin/sh", "-c", "echo planted"}, options);
      wait_exit_code(pid);
      ADD_FAILURE() << "started with its output to " << name;
    } catch (const Error& error) {
      EXPECT_TRUE(contains(error.what(), "is not a regular file of this user's")) << error.what();
      EXPECT_TRUE(contains(error.what(), name)) << error.what();
    }
  }
  EXPECT_FALSE(std::filesystem::exists(target)) << "wrote through the planted symlink";
  std::filesystem::remove_all(folder);
}

TEST(ProcessSpawn, AProgramThatCannotStartIsAnErrorNamingIt) {
  try {
    spawn_command({"afhub-no-such-program"});
    FAIL() << "started a program that does not exist";
  } catch (const Error& error) {
    EXPECT_TRUE(contains(error.what(), "cannot start afhub-no-such-program")) << error.what();
    EXPECT_TRUE(contains(error.what(), "on PATH")) << error.what();
  }
}

// A signal this thread blocks stays deliverable to the child: SIGTERM ends it.
TEST(ProcessSpawn, TheChildDoesNotInheritTheSignalMask) {
  sigset_t term, before;
  sigemptyset(&term);
  sigaddset(&term, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &term, &before);
  const pid_t pid = spawn_command({"sleep", "30"});
  pthread_sigmask(SIG_SETMASK, &before, nullptr);
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit_code(pid), 128 + SIGTERM);
}

TEST(ProcessSpawn, ADetachedChildHasItsOwnSessionAndLeavesNoZombie) {
  SpawnOptions options;
  options.search_path = true;
  options.detached = true;
  const pid_t pid = spawn_process({"sleep", "30"}, options);
  EXPECT_EQ(getsid(pid), pid);
  EXPECT_NE(getsid(pid), getsid(0));
  kill(pid, SIGTERM);
  // Reaped by the spawner's thread: the pid goes (a zombie would still answer kill 0).
  EXPECT_TRUE(
      wait_until([pid] { return kill(pid, 0) != 0 && errno == ESRCH; }, std::chrono::seconds(5)));
}

}  // namespace
}  // namespace afhub::test
