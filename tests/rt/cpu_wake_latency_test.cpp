// hold_cpu_wake_latency: what it writes, its refusal, and the kernel's limit while a
// process holds it.
#include "afhub/rt/cpu_wake_latency.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace afhub {
namespace {

std::int32_t read_limit(const char* path) {
  std::int32_t value = -1;
  std::ifstream file(path, std::ios::binary);
  file.read(reinterpret_cast<char*>(&value), sizeof value);
  return file ? value : -1;
}

TEST(CpuWakeLatency, WritesTheLimitAsTheKernelReadsIt) {
  const std::string path = testing::TempDir() + "cpu_wake_latency_file";
  std::ofstream(path).close();
  ASSERT_TRUE(hold_cpu_wake_latency(250, "test", path.c_str()));
  EXPECT_EQ(read_limit(path.c_str()), 250);  // a 32-bit integer, as the device takes it
  std::filesystem::remove(path);
}

TEST(CpuWakeLatency, SaysWhyWhenRefused) {
  testing::internal::CaptureStderr();
  EXPECT_FALSE(hold_cpu_wake_latency(0, "afhub test", "/nonexistent/cpu_dma_latency"));
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("afhub test: cannot hold the CPU wake-up latency at 0 us"), std::string::npos)
      << said;
  EXPECT_NE(said.find("/nonexistent/cpu_dma_latency"), std::string::npos) << said;
  EXPECT_NE(said.find("running without"), std::string::npos) << said;
}

// The real device: the kernel's limit is 0 while a child holds it, and back to what it
// was once the child is gone, however it ended (here, SIGKILL).
TEST(CpuWakeLatency, TheKernelHoldsTheLimitUntilTheProcessEnds) {
  if (geteuid() != 0 || access(kCpuWakeLatencyDevice, R_OK | W_OK) != 0)
    GTEST_SKIP() << kCpuWakeLatencyDevice << " needs root";
  const std::int32_t before = read_limit(kCpuWakeLatencyDevice);
  if (before == 0) GTEST_SKIP() << "something on this machine already holds the limit at 0";
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const char held = hold_cpu_wake_latency(0, "child") ? 'y' : 'n';
    (void)!write(ready[1], &held, 1);
    pause();
    _exit(0);
  }
  char held = 0;
  ASSERT_EQ(read(ready[0], &held, 1), 1);
  EXPECT_EQ(held, 'y');
  EXPECT_EQ(read_limit(kCpuWakeLatencyDevice), 0);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  // Another process on this host (a bridge or controller test) may hold it for a while.
  for (int i = 0; i < 300 && read_limit(kCpuWakeLatencyDevice) != before; ++i) usleep(100'000);
  EXPECT_EQ(read_limit(kCpuWakeLatencyDevice), before);
  close(ready[0]);
  close(ready[1]);
}

}  // namespace
}  // namespace afhub
