// Processes that stop and resume, or die: a process stopped for 5 s (SIGSTOP, as a
// debugger breakpoint, Ctrl-Z or a VM pause would) carries on when resumed, be it one
// of two controllers, an echo, the physics or the hub itself; a killed one is cleaned up, files in
// /tmp included; and `afhub hub stop` does not pull the hub from under attached
// processes without --force.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <filesystem>
#include <string>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

bool still_running(pid_t pid) {
  int status = 0;
  return waitpid(pid, &status, WNOHANG) == 0;
}

// Files in /tmp whose names start with `prefix`.
int files_starting_with(const std::string& prefix) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/tmp"))
    if (entry.path().filename().string().rfind(prefix, 0) == 0) ++count;
  return count;
}

TEST(Pause, KilledProcessesAreCleanedUpFilesIncluded) {
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  for (int round = 0; round < 10; ++round) {
    ScopedProcess top = spawn_afhub({"top"});
    const std::string lock = "/tmp/afhub-top-" + std::to_string(top.pid) + ".lock";
    ASSERT_TRUE(wait_until([&] { return std::filesystem::exists(lock); }, 10s)) << lock;
    top.stop(SIGKILL);
  }
  // Each killed runtime left a socket and a lock; the hub removes them.
  EXPECT_TRUE(wait_until([] { return files_starting_with("afhub-top-") == 0; }, 15s))
      << files_starting_with("afhub-top-") << " files of killed processes are left in /tmp";
  const std::string hub_log = read_file("/tmp/afhub-test-hub.log");
  EXPECT_TRUE(contains(hub_log, "is gone; removed its ports and chunks")) << hub_log;
  EXPECT_EQ(run_afhub({"hub", "stop"}).exit_code, 0);
  EXPECT_EQ(hub.stop(0), 0);
}

TEST(Pause, HubStopListsAttachedProcessesAndAsksForForce) {
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess top(spawn_afhub({"top"}));
  const std::string name = "afhub-top-" + std::to_string(top.pid);
  // Attached once its runtime holds the lock (made first, locked after: beside a busy
  // machine the file alone once let the stop through). Read from /proc/locks: a probe
  // taking the lock could fail the runtime's own.
  ASSERT_TRUE(wait_until([&] { return flock_holder("/tmp/" + name + ".lock") == top.pid; }, 10s));
  const RunResult refused = run_afhub({"hub", "stop"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_TRUE(contains(refused.err, "attached to the hub")) << refused.err;
  EXPECT_TRUE(contains(refused.err, name + " (pid " + std::to_string(top.pid) + ")"))
      << refused.err;
  EXPECT_TRUE(contains(refused.err, "afhub hub stop --force")) << refused.err;
  EXPECT_TRUE(still_running(hub.pid));
  const RunResult forced = run_afhub({"hub", "stop", "--force"});
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_EQ(hub.stop(0), 0);
}

// A lock file removed from under a live process (a tmp cleaner, an `rm`) says nothing
// of the process: the hub decides by the pid it registered, and keeps its ports.
TEST(Pause, ALiveProcessWhoseLockFileWasRemovedKeepsItsPorts) {
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  ScopedProcess top(spawn_afhub({"top"}));
  const std::string name = "afhub-top-" + std::to_string(top.pid);
  ASSERT_TRUE(wait_until([&] { return contains(run_afhub({"status"}).out, name); }, 10s));
  ASSERT_TRUE(std::filesystem::remove("/tmp/" + name + ".lock"));
  std::this_thread::sleep_for(2s);  // a hundred of the hub's liveness rounds
  const std::string gone = name + " (pid " + std::to_string(top.pid) + ") is gone";
  EXPECT_FALSE(contains(read_file("/tmp/afhub-test-hub.log"), gone))
      << read_file("/tmp/afhub-test-hub.log");
  EXPECT_TRUE(contains(run_afhub({"status"}).out, name));
  EXPECT_TRUE(still_running(top.pid));

  // Killed, it is removed all the same: by its pid.
  top.stop(SIGKILL);
  EXPECT_TRUE(wait_until([&] { return contains(read_file("/tmp/afhub-test-hub.log"), gone); }, 5s))
      << read_file("/tmp/afhub-test-hub.log");
  EXPECT_EQ(run_afhub({"hub", "stop"}).exit_code, 0);
  EXPECT_EQ(hub.stop(0), 0);
}

// Last: this test attaches itself to the hub (an iceoryx runtime lives as long as
// the process), which the tests above must not see.
TEST(Pause, StoppedProcessesCarryOnWhenResumed) {
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  connect_to_hub("pause-test", HubPolicy::kRequire);
  const std::string log = "/tmp/afhub-pause-run.log";
  ScopedProcess physics(
      spawn_afhub({"run", AFHUB_EXAMPLE_MODELS "/arm7.yaml", "--no-autostart"}, log));
  BodyClient base("afhub/arm/base");
  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  ASSERT_TRUE(wait_until([&] { return base.latest_state() && world.latest(); }, 10s))
      << read_file(log);
  // Two controllers, and an echo printing every state to a file.
  ScopedProcess controller(spawn_afhub({"ctl", "hold", "arm/base"}));
  ScopedProcess second(spawn_afhub({"ctl", "sine", "arm/link3", "--amplitude", "0.2"}));
  const std::string echo_out = "/tmp/afhub-pause-echo.log";
  ScopedProcess echo(spawn_afhub({"echo", "arm/link7"}, echo_out));
  LatestReader<BodyCommand> commands(body_command_channel("afhub/arm/base"));
  LatestReader<BodyCommand> second_commands(body_command_channel("afhub/arm/link3"));
  const auto commands_after = [](LatestReader<BodyCommand>& reader, pid_t from,
                                 std::int64_t stamp_ns) {
    const BodyCommand* command = reader.latest();
    return command && command->header.publisher_pid == static_cast<std::uint32_t>(from) &&
           command->header.publish_stamp_ns > stamp_ns;
  };
  const auto controller_commands_after = [&](std::int64_t stamp_ns) {
    return commands_after(commands, controller.pid, stamp_ns) &&
           commands_after(second_commands, second.pid, stamp_ns);
  };
  ASSERT_TRUE(wait_until([&] { return controller_commands_after(0); }, 10s));

  for (const auto& [who, pid] : {std::pair<const char*, pid_t>{"controller", controller.pid},
                                 {"second controller", second.pid},
                                 {"echo", echo.pid},
                                 {"physics", physics.pid},
                                 {"hub", hub.pid}}) {
    const std::size_t printed = read_file(echo_out).size();
    kill(pid, SIGSTOP);
    std::this_thread::sleep_for(5s);  // beyond iceoryx's 1.5 s keep-alive deadline
    kill(pid, SIGCONT);
    const std::int64_t resumed_ns = monotonic_ns();
    const std::uint64_t step = world.latest() ? world.latest()->header.sim_step : 0;
    // It carries on: the world steps, the controller's commands arrive, the hub serves.
    EXPECT_TRUE(wait_until(
        [&] { return world.latest() && world.latest()->header.sim_step > step + 500; }, 10s))
        << "the world did not go on after the " << who << " resumed\n"
        << read_file(log);
    EXPECT_TRUE(wait_until([&] { return controller_commands_after(resumed_ns); }, 10s))
        << "the controllers' commands stopped after the " << who << " resumed";
    EXPECT_TRUE(wait_until([&] { return read_file(echo_out).size() > printed + 1000; }, 10s))
        << "echo stopped printing after the " << who << " resumed";
    const RunResult ls = run_afhub({"ls"});
    EXPECT_EQ(ls.exit_code, 0) << who << ": " << ls.err
                               << (ls.exit_code == -1 ? stack_traces("afhub hub") : "");
    EXPECT_TRUE(contains(ls.out, "afhub/arm/base")) << who << ": " << ls.out;
    for (pid_t process : {hub.pid, physics.pid, controller.pid, second.pid, echo.pid})
      EXPECT_TRUE(still_running(process))
          << "pid " << process << " died after the " << who << " was stopped for 5 s";
  }
  EXPECT_EQ(echo.stop(), 0);
  EXPECT_EQ(second.stop(), 0);
  EXPECT_EQ(controller.stop(), 0);
  EXPECT_EQ(physics.stop(), 0);
  EXPECT_EQ(run_afhub({"hub", "stop", "--force"}).exit_code, 0);  // this test is attached
  EXPECT_EQ(hub.stop(0), 0);
}

}  // namespace
}  // namespace afhub::test
