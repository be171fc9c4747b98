// `afhub run` end to end against a hub: the KUKA on its channels, commands that
// move it, refused NaN commands counted in the world state, the watchdog, the
// launch file with -l, the report, and real-time pacing.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/run_loop.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kDescriptions = AFHUB_SHARED_MODELS "/descriptions/";
const std::string kKuka = kDescriptions + "multi-bodies/robots/blender-kuka.yaml";

TEST(Run, KukaOnChannelsObeysCommandsRefusesNanAndTripsTheWatchdog) {
  SKIP_WITHOUT_SHARED_MODELS();
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kKuka, "--no-autostart"}, log));
  BodyClient base("ambf/env/base");
  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  ASSERT_TRUE(wait_until([&] { return base.latest_state() && world.latest(); }, 10s))
      << read_file(log);
  ASSERT_EQ(base.latest_state()->joint_count, 7u);

  // A NaN command is refused and counted, and nothing moves.
  BodyCommand* bad = base.loan_command(kMaxJointsPerBody);
  ASSERT_NE(bad, nullptr);
  bad->joint_count = 1;
  bad->joints[0].type = JointCommandType::kPosition;
  bad->joints[0].value = std::nan("");
  base.publish_command(bad);
  ASSERT_TRUE(wait_until([&] { return world.latest()->rejected_commands == 1; }, 2s));
  EXPECT_TRUE(std::isfinite(base.latest_state()->joints[0].position));
  RunResult status = run_afhub({"status", "--json"});
  EXPECT_TRUE(contains(status.out, "\"rejected_commands\":1")) << status.out;

  // Position commands at 200 Hz for 2 s bring every joint to its target.
  const double targets[7] = {0.4, -0.3, 0.2, 0.5, -0.4, 0.3, 0.6};
  const auto until = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < until) {
    BodyCommand* command = base.loan_command(kMaxJointsPerBody);
    ASSERT_NE(command, nullptr);
    command->joint_count = 7;
    for (int j = 0; j < 7; ++j) {
      command->joints[j].type = JointCommandType::kPosition;
      command->joints[j].value = targets[j];
    }
    base.publish_command(command);
    std::this_thread::sleep_for(5ms);
  }
  const BodyState* state = base.latest_state();
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(state->joints[j].position, targets[j], 0.01) << j;

  // Commands stop: the watchdog engages after 0.5 s and says so once.
  ASSERT_TRUE(wait_until([&] { return world.latest()->watchdog_expiries == 1; }, 2s));
  EXPECT_EQ(physics.stop(), 0);
  const std::string output = read_file(log);
  EXPECT_TRUE(contains(output, "refused a command for ambf/env/base: a joint value is NaN"))
      << output;
  EXPECT_TRUE(contains(output, "no command for ambf/env/base in 0.500 s")) << output;
}

// A body gone NaN: the loop goes on with it put back, and the report and the summary
// say which body and step; --stop-on-nan (stop_on_nan) stops at that step instead.
// (A NaN force through set_input, which takes it unchecked: files and commands
// that could cause one are refused by the loader and the command checks.)
TEST(Run, ANanBodyIsPutBackUnlessStopOnNan) {
  const physics::Model model = physics::load_adf_files({AFHUB_EXAMPLE_MODELS "/arm7.yaml"});
  std::size_t link = 0;
  while (model.bodies[link].channel != "afhub/arm/link3") ++link;
  physics::BodyInput poison;
  poison.wrench.force_n = {std::nan(""), 0, 0};
  for (const bool stop : {false, true}) {
    physics::Simulation sim(model, 0.001);
    sim.set_input(link, poison);
    physics::RunOptions options;
    options.fast = true;
    options.steps = 200;
    options.stop_on_nan = stop;
    physics::RunReport report;
    physics::run_loop(sim, nullptr, options, report);
    EXPECT_EQ(report.nan_detected, stop);
    EXPECT_EQ(report.steps, stop ? 1u : 200u);
    EXPECT_TRUE(sim.all_finite());
    const std::string summary = physics::nan_summary(sim);
    // The NaN spreads through the arm's joints within the step: the arm is put back.
    EXPECT_TRUE(contains(summary,
                         "bodies put back after a step made them NaN or infinite; "
                         "first: afhub/arm/base at step 1; last: afhub/arm/link7 at "
                         "step 1"))
        << summary;
    EXPECT_TRUE(contains(physics::report_json(report, sim), "\"nan_recoveries\":")) << stop;
  }
}

TEST(Run, LaunchFileWithIndexRunsRealTimeAndReports) {
  SKIP_WITHOUT_SHARED_MODELS();
  afhub::testing::ModelFolder folder;
  const std::string report = (folder.dir() / "report.json").string();
  RunResult run = run_afhub({"run", "--launch", kDescriptions + "launch.yaml", "-l", "10",
                             "--steps", "2000", "--report", report, "--no-autostart"},
                            30s);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string json = read_file(report);
  EXPECT_EQ(json_number(json, "steps"), 2000);
  EXPECT_NEAR(json_number(json, "sim_time_s"), 2.0, 1e-9);
  // Absolute deadlines: never faster than real time. (How much slower depends on this
  // shared machine's load, so it is not asserted; the pacing itself is tested on an
  // injected clock in tests/rt/periodic_loop_test.cpp.)
  EXPECT_GE(json_number(json, "wall_time_s"), 1.999);
  EXPECT_LT(json_number(json, "max_joint_error_m"), 0.002);
  EXPECT_TRUE(contains(json, "\"nan_detected\":false")) << json;
  for (const char* key : {"\"ambf/env/l1\":{\"position\":[", "\"ambf/env/Plane\"",
                          "\"ambf/env/l1-l4\":{\"position\":", "\"step_time_us\":{\"max\":",
                          "\"p50\":", "\"p99\":", "\"quaternion\":["})
    EXPECT_TRUE(contains(json, key)) << key << " in " << json;
}

TEST(Run, MissingModelOfALaunchFileIsReportedWhereItIsListed) {
  SKIP_WITHOUT_SHARED_MODELS();
  RunResult run =
      run_afhub({"run", "--launch", kDescriptions + "launch.yaml", "-l", "3", "--offline"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err,
                       "launch.yaml:10:5: error: multibody config #3 "
                       "'./multi-bodies/robots/blender-raven2.yaml' not found"))
      << run.err;
  RunResult beyond =
      run_afhub({"run", "--launch", kDescriptions + "launch.yaml", "-l", "40", "--offline"});
  EXPECT_EQ(beyond.exit_code, 1);
  EXPECT_TRUE(contains(beyond.err, "model index 40 (-l) is beyond 'multibody configs'"))
      << beyond.err;
  RunResult no_model = run_afhub({"run", "--offline"});
  EXPECT_EQ(no_model.exit_code, 1);
  EXPECT_TRUE(contains(no_model.err, "nothing to simulate")) << no_model.err;
}

// `--lockstep --wait-for N` says every 2 s whom it still waits for, and
// `--wait-timeout S` gives up with an error. (No client ever comes: only the
// messages and the exit code are checked, not how long anything took.)
TEST(Run, LockstepWaitSaysWhomItWaitsForAndGivesUpAfterTheTimeout) {
  afhub::testing::ModelFolder folder;
  const std::string ball =
      folder.write("ball.yaml",
                   "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1\n  shape: sphere\n"
                   "  geometry: {radius: 0.05}\n");
  RunResult run = run_afhub(
      {"run", ball, "--no-autostart", "--lockstep", "--wait-for", "1", "--wait-timeout", "3"},
      120s);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_TRUE(contains(run.err, "waiting for 1 lockstep clients before the first step")) << run.err;
  EXPECT_TRUE(contains(run.err, "afhub run: still waiting after ")) << run.err;
  EXPECT_TRUE(contains(run.err, "0 of 1 lockstep clients joined; no client yet for ambf/env/ball"))
      << run.err;
  EXPECT_TRUE(contains(run.err, "afhub run: error: gave up after ")) << run.err;
  EXPECT_TRUE(contains(run.err,
                       "(--wait-timeout): 0 of 1 lockstep clients joined; no client for "
                       "ambf/env/ball"))
      << run.err;

  RunResult no_wait_for = run_afhub({"run", ball, "--offline", "--wait-timeout", "3"});
  EXPECT_EQ(no_wait_for.exit_code, 1);
  EXPECT_TRUE(contains(no_wait_for.err, "--wait-timeout needs --wait-for")) << no_wait_for.err;
}

}  // namespace
}  // namespace afhub::test
