// Processes that start together: a controller started before the hub, or before its
// body exists, waits for them (saying so once) up to --wait, then attaches; with
// nothing coming, it gives up with a clear error. Each test starts its own hub.
#include <gtest/gtest.h>
#include <signal.h>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "hub_environment.hpp"
#include "model_files.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

TEST(StartTogether, ControllerWithNoHubGivesUpAfterItsWait) {
  ASSERT_NE(probe_roudi(), RoudiPresence::kRunning) << "a hub is running before the test";
  RunResult ctl = run_afhub({"ctl", "hold", "base", "--wait", "1"}, 20s);
  EXPECT_EQ(ctl.exit_code, 1) << ctl.err;
  EXPECT_EQ(occurrences(ctl.err, "no hub is running yet; waiting up to 1 s for one"), 1) << ctl.err;
  EXPECT_TRUE(contains(ctl.err, "error: no hub came up within 1 s")) << ctl.err;
  EXPECT_TRUE(contains(ctl.err, "afhub hub")) << ctl.err;
  EXPECT_NE(probe_roudi(), RoudiPresence::kRunning) << "a controller started a hub";
  RunResult help = run_afhub({"ctl", "hold", "--help"});
  EXPECT_TRUE(contains(help.out, "--wait")) << help.out;
}

TEST(StartTogether, ControllerStartedBeforeTheHubAndThePhysicsAttaches) {
  ASSERT_NE(probe_roudi(), RoudiPresence::kRunning) << "a hub is running before the test";
  afhub::testing::ModelFolder folder;
  const std::string ctl_log = (folder.dir() / "ctl.log").string();
  const std::string run_log = (folder.dir() / "run.log").string();
  // The launch script's order at its worst: the controller first, then the hub, then
  // the physics.
  ScopedProcess controller(spawn_afhub({"ctl", "hold", "base", "--wait", "20"}, ctl_log));
  ASSERT_TRUE(wait_until([&] { return contains(read_file(ctl_log), "waiting up to 20 s"); }, 10s))
      << read_file(ctl_log);
  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  // With the hub up and no body yet, it waits for the body.
  ASSERT_TRUE(
      wait_until([&] { return contains(read_file(ctl_log), "no body 'base' is live yet"); }, 10s))
      << read_file(ctl_log);
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}, run_log));

  connect_to_hub("test", HubPolicy::kRequire);
  LatestReader<BodyCommand> commands(body_command_channel("afhub/arm/base"));
  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  EXPECT_TRUE(wait_until(
      [&] {
        const BodyCommand* command = commands.latest();
        return command &&
               command->header.publisher_pid == static_cast<std::uint32_t>(controller.pid);
      },
      10s))
      << read_file(ctl_log);
  // The physics applies its commands: every step from now on is commanded.
  EXPECT_TRUE(
      wait_until([&] { return world.latest() && world.latest()->commanded_steps > 100; }, 10s))
      << read_file(run_log);
  EXPECT_EQ(world.latest()->rejected_commands, 0u);
  EXPECT_EQ(wait_for_exit(controller, 0ms), -1) << "the controller stopped: " << read_file(ctl_log);

  const std::string said = read_file(ctl_log);
  EXPECT_EQ(occurrences(said, "waiting up to"), 2) << "once for the hub, once for the body\n"
                                                   << said;
  EXPECT_TRUE(contains(said, "commanding afhub/arm/base every 1.000 ms")) << said;
  EXPECT_EQ(controller.stop(SIGINT), 0) << read_file(ctl_log);
  EXPECT_EQ(physics.stop(), 0) << read_file(run_log);
  EXPECT_EQ(hub.stop(), 0);
}

// Ctrl-C during a wait is the user's stop, not a failure: it said "no hub came up" or
// "no body" (waited for it) and exited 1.
TEST(StartTogether, CtrlCWhileWaitingForTheHubOrABodyEndsWithZeroSayingSo) {
  ASSERT_NE(probe_roudi(), RoudiPresence::kRunning) << "a hub is running before the test";
  afhub::testing::ModelFolder folder;
  const std::string hub_wait_log = (folder.dir() / "hub_wait.log").string();
  ScopedProcess for_hub(spawn_afhub({"ctl", "hold", "base", "--wait", "20"}, hub_wait_log));
  ASSERT_TRUE(
      wait_until([&] { return contains(read_file(hub_wait_log), "waiting up to 20 s"); }, 10s))
      << read_file(hub_wait_log);
  EXPECT_EQ(for_hub.stop(SIGINT), 0) << read_file(hub_wait_log);
  EXPECT_TRUE(contains(read_file(hub_wait_log), "afhub ctl: stopped while waiting for a hub\n"))
      << read_file(hub_wait_log);

  ScopedProcess hub(start_test_hub());
  ASSERT_GT(hub.pid, 0);
  const std::string body_wait_log = (folder.dir() / "body_wait.log").string();
  ScopedProcess for_body(spawn_afhub({"ctl", "hold", "nosuch", "--wait", "20"}, body_wait_log));
  ASSERT_TRUE(wait_until(
      [&] { return contains(read_file(body_wait_log), "no body 'nosuch' is live yet"); }, 10s))
      << read_file(body_wait_log);
  EXPECT_EQ(for_body.stop(SIGINT), 0) << read_file(body_wait_log);
  const std::string said = read_file(body_wait_log);
  EXPECT_TRUE(contains(said, "afhub ctl: stopped while waiting for body 'nosuch'\n")) << said;
  EXPECT_FALSE(contains(said, "error")) << said;
  EXPECT_EQ(hub.stop(), 0);
}

}  // namespace
}  // namespace afhub::test
