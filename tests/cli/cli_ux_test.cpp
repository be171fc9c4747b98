// The command line a user expects, end to end against one hub: `afhub world`
// against the real simulation, `afhub cmd` keeping a command alive with joints by
// name (and the C++ client's joint_index), `afhub echo --fields/--rate`, and
// `afhub ls` before a rate is measured.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "strict_json.hpp"
#include "world_reader.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

TEST(World, HelpOnEverySubcommand) {
  for (std::vector<std::string> args : {std::vector<std::string>{"world", "--help"},
                                        {"world", "pause", "--help"},
                                        {"world", "resume", "--help"},
                                        {"world", "step", "--help"},
                                        {"world", "reset", "--help"}}) {
    RunResult help = run_afhub(args);
    EXPECT_EQ(help.exit_code, 0) << args[1];
    EXPECT_TRUE(contains(help.out, "Usage")) << help.out;
  }
  EXPECT_TRUE(contains(run_afhub({"world", "step", "--help"}).out, "While paused"));
}

TEST(Cli, AnUnknownOrMissingSubcommandNamesTheChoices) {
  RunResult bogus = run_afhub({"world", "bogus"});
  EXPECT_EQ(bogus.exit_code, 2);
  EXPECT_TRUE(contains(bogus.err,
                       "afhub world: unknown subcommand 'bogus'; choose one of: "
                       "pause, resume, step, reset"))
      << bogus.err;
  RunResult none = run_afhub({"device"});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_TRUE(contains(none.err, "afhub device: a subcommand is required; choose one of: list"))
      << none.err;
  // Every other mistake of the command line: its command named, exit code 2 (CLI11's
  // codes were 105 to 109, its line named no command).
  for (const auto& [args, said] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"echo"}, "afhub echo: body is required (see `afhub echo --help`)"},
           {{"ls", "--bogus"}, "afhub ls: The following argument was not expected: --bogus"},
           {{"ctl", "sine", "base", "--rate", "abc"}, "afhub ctl sine: Could not convert"},
           {{"run", "--steps", "-1", "x.yaml"}, "afhub run: --steps: takes a whole number"}}) {
    RunResult wrong = run_afhub(args);
    EXPECT_EQ(wrong.exit_code, 2) << args[0] << ": " << wrong.err;
    EXPECT_TRUE(contains(wrong.err, said)) << wrong.err;
  }
  RunResult version = run_afhub({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_TRUE(contains(version.out, "afhub 0.")) << version.out;
}

// Mistakes a script makes are loud: a device no driver serves, a body that is not
// there yet (echo --wait waits for it), and top into a pipe writes no terminal codes.
TEST(Cli, ScriptsGetErrorsWaitsAndPlainText) {
  RunResult device = run_afhub({"device", "force", "nosuch", "--force", "0,0,1", "--cycles", "5"});
  EXPECT_EQ(device.exit_code, 1);
  EXPECT_TRUE(contains(device.err, "device/nosuch")) << device.err;

  ScopedProcess echo(spawn_afhub({"echo", "synth/body0", "-n", "1", "--wait", "20"},
                                 "/tmp/afhub-test-echo-wait.log"));
  ScopedProcess synth(spawn_afhub({"synth", "--bodies", "1", "--no-autostart"}));
  EXPECT_EQ(wait_for_exit(echo, 20s), 0) << read_file("/tmp/afhub-test-echo-wait.log");
  EXPECT_TRUE(contains(read_file("/tmp/afhub-test-echo-wait.log"), "synth/body0 step "));

  RunResult top = run_afhub({"top", "--once"});
  EXPECT_EQ(top.exit_code, 0) << top.err;
  ScopedProcess live_top(spawn_afhub({"top"}, "/tmp/afhub-test-top.log"));
  ASSERT_TRUE(
      wait_until([] { return contains(read_file("/tmp/afhub-test-top.log"), "loops"); }, 10s));
  EXPECT_FALSE(contains(read_file("/tmp/afhub-test-top.log"), "\x1b["))
      << "terminal codes written into a file";
  EXPECT_EQ(synth.stop(), 0);
}

// Two processes, one only pausing and one only resuming: the world can act on a pause
// and a resume between two of its states, and then none shows the pause. That is no
// failure (1 call in 60 exited 1, "did not act ... is it stalled"): it is said, exit
// 0. A world that is stopped (SIGSTOP) still fails the command.
TEST(World, PausingAndResumingFromTwoProcessesAlwaysSucceeds) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}, log));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s)) << read_file(log);
  constexpr int kCalls = 100;  // each
  const auto hammer = [&](const std::string& action) {
    const std::string out = (folder.dir() / (action + ".txt")).string();
    return std::pair{std::make_unique<ScopedProcess>(spawn_command(
                         {"bash", "-c",
                          "for i in $(seq " + std::to_string(kCalls) + "); do \"$0\" world " +
                              action + " --timeout 3 || echo \"EXIT $?\"; done > " + out + " 2>&1",
                          afhub_executable()})),
                     out};
  };
  auto [pausing, pausing_out] = hammer("pause");
  auto [resuming, resuming_out] = hammer("resume");
  EXPECT_EQ(wait_for_exit(*pausing, 600s), 0);
  EXPECT_EQ(wait_for_exit(*resuming, 600s), 0);
  const std::string said = read_file(pausing_out) + read_file(resuming_out);
  int lines = 0, undone = 0;
  std::istringstream in(said);
  for (std::string line; std::getline(in, line);) {
    ++lines;
    if (contains(line, "undone since by another process")) ++undone;
  }
  EXPECT_FALSE(contains(said, "EXIT ")) << said;
  EXPECT_EQ(lines, 2 * kCalls) << said;
  std::printf("%d calls, %d of them undone by the other process\n", lines, undone);

  kill(physics.pid, SIGSTOP);
  // In two loaded runs of every test it had not ended after 20 s and 60 s, having said
  // nothing; the cause is not known yet. Hung, its stacks and the hub's are printed.
  const std::string stalled_log = "/tmp/afhub-cli-ux-stalled.log";
  ScopedProcess stalled(spawn_afhub({"world", "pause", "--timeout", "1"}, stalled_log));
  const auto asked = std::chrono::steady_clock::now();
  int stalled_exit = wait_for_exit(stalled, 20s);
  if (stalled_exit == -1)
    std::printf("world pause hung on a stopped simulation:\n%s%s",
                stack_traces("afhub world pause").c_str(), stack_traces("afhub hub").c_str());
  kill(physics.pid, SIGCONT);
  if (stalled_exit == -1) stalled_exit = wait_for_exit(stalled, 40s);
  std::printf("world pause on a stopped simulation: exit %d in %.1f s\n", stalled_exit,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count());
  EXPECT_EQ(stalled_exit, 1) << read_file(stalled_log);
  EXPECT_TRUE(contains(read_file(stalled_log), "stalled")) << read_file(stalled_log);
  EXPECT_EQ(physics.stop(), 0) << read_file(log);
}

TEST(World, WithoutASimulationItSaysSo) {
  RunResult pause = run_afhub({"world", "pause"});
  EXPECT_EQ(pause.exit_code, 1);
  EXPECT_TRUE(contains(pause.err, "no simulation is running")) << pause.err;
  EXPECT_TRUE(contains(pause.err, "afhub run")) << pause.err;
}

TEST(World, PauseStepResumeAndResetTheSimulation) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}, log));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(
      wait_until([&] { return world.latest() && world.latest()->header.sim_step > 50; }, 10s))
      << read_file(log);

  RunResult refused = run_afhub({"world", "step", "5"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_TRUE(contains(refused.err, "pause it first")) << refused.err;

  RunResult pause = run_afhub({"world", "pause"});
  ASSERT_EQ(pause.exit_code, 0) << pause.err;
  EXPECT_TRUE(contains(pause.out, "paused at step ")) << pause.out;
  ASSERT_TRUE(wait_until([&] { return world.latest()->paused == 1; }, 2s));
  const std::uint64_t paused_at = world.latest()->header.sim_step;
  EXPECT_EQ(std::strtoull(pause.out.c_str() + pause.out.find("step ") + 5, nullptr, 10), paused_at)
      << pause.out;

  // Each `afhub world` is a new process: its command must not be taken for an old one.
  RunResult step = run_afhub({"world", "step", "10"});
  ASSERT_EQ(step.exit_code, 0) << step.err;
  EXPECT_TRUE(
      contains(step.out, "stepped 10 steps: now paused at step " + std::to_string(paused_at + 10)))
      << step.out;
  RunResult step_again = run_afhub({"world", "step"});
  ASSERT_EQ(step_again.exit_code, 0) << step_again.err;
  EXPECT_TRUE(contains(step_again.out,
                       "stepped 1 step: now paused at step " + std::to_string(paused_at + 11)))
      << step_again.out;
  std::this_thread::sleep_for(100ms);
  world.latest();
  EXPECT_EQ(world.latest()->header.sim_step, paused_at + 11) << "paused: no step of its own";
  EXPECT_TRUE(contains(run_afhub({"world", "pause"}).out, "already paused"));

  RunResult reset = run_afhub({"world", "reset"});
  ASSERT_EQ(reset.exit_code, 0) << reset.err;
  EXPECT_TRUE(contains(reset.out, "reset from step " + std::to_string(paused_at + 11) +
                                      ": now at step 0 (t = 0.000 s), paused"))
      << reset.out;
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sim_step == 0; }, 2s));

  RunResult resume = run_afhub({"world", "resume"});
  ASSERT_EQ(resume.exit_code, 0) << resume.err;
  EXPECT_TRUE(contains(resume.out, "resumed at step ")) << resume.out;
  EXPECT_TRUE(wait_until(
      [&] { return world.latest()->paused == 0 && world.latest()->header.sim_step > 100; }, 5s));
  EXPECT_EQ(physics.stop(), 0);
}

// A step count beyond the bound is refused; a long step runs with the world saying it
// is not paused, and `world pause` stops it where it is.
TEST(World, ALongStepSaysItRunsAndPauseStopsIt) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}, log));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s)) << read_file(log);
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);

  RunResult absurd = run_afhub({"world", "step", "4294967295"});
  EXPECT_EQ(absurd.exit_code, 1);
  EXPECT_TRUE(contains(absurd.err, "from 1 to 1000000")) << absurd.err;

  // Longer than --timeout: it waits while the world steps (it failed, saying the world
  // had not acted).
  const RunResult long_step = run_afhub({"world", "step", "1500", "--timeout", "0.5"}, 30s);
  EXPECT_EQ(long_step.exit_code, 0) << long_step.err;
  EXPECT_TRUE(contains(long_step.out, "stepped 1500 steps: now paused")) << long_step.out;
  // Ctrl-C while it steps: said, exit 0, the steps run on (it said the world had not acted
  // within its timeout, exit 1).
  const std::string interrupted_log = (folder.dir() / "interrupted.log").string();
  ScopedProcess interrupted(spawn_afhub({"world", "step", "100000"}, interrupted_log));
  const std::uint64_t before_interrupted = world.latest()->header.sim_step;
  ASSERT_TRUE(
      wait_until([&] { return world.latest()->header.sim_step > before_interrupted + 50; }, 10s));
  EXPECT_EQ(interrupted.stop(SIGINT), 0) << read_file(interrupted_log);
  EXPECT_TRUE(contains(read_file(interrupted_log), "stopped waiting at step"))
      << read_file(interrupted_log);
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);

  const std::uint64_t paused_at = world.latest()->header.sim_step;
  const std::string stepping_log = (folder.dir() / "stepping.log").string();
  ScopedProcess stepping(spawn_afhub({"world", "step", "1000000"}, stepping_log));
  ASSERT_TRUE(wait_until(
      [&] {
        const WorldState* w = world.latest();
        return w->header.sim_step > paused_at + 20 && w->paused == 0;
      },
      10s))
      << "the world did not step, or said it was paused while it stepped";
  // More steps asked while they run: added (it was refused, the world said running).
  RunResult more = run_afhub({"world", "step", "5"});
  EXPECT_EQ(more.exit_code, 0) << more.err;
  // Said so: the world runs on (it said "now paused").
  EXPECT_TRUE(contains(more.out, "stepped 5 steps, and steps asked by another run on: now at step"))
      << more.out;
  RunResult pause = run_afhub({"world", "pause"});
  ASSERT_EQ(pause.exit_code, 0) << pause.err;
  EXPECT_TRUE(contains(pause.out, "paused at step")) << pause.out;
  // The long step says its steps were ended by that pause (it waited out its timeout and
  // said the world had not acted).
  EXPECT_EQ(wait_for_exit(stepping, 5s), 0) << read_file(stepping_log);
  EXPECT_TRUE(contains(read_file(stepping_log), "and undone since by another process (pid "))
      << read_file(stepping_log);
  EXPECT_TRUE(contains(read_file(stepping_log), ": paused): now paused at step"))
      << read_file(stepping_log);
  ASSERT_TRUE(wait_until([&] { return world.latest()->paused == 1; }, 2s));
  const std::uint64_t stopped_at = world.latest()->header.sim_step;
  // Still for as many of the world's own publishes as 100 steps would take.
  std::uint64_t seen = world.latest()->header.sequence;
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sequence > seen + 100; }, 5s));
  EXPECT_EQ(world.latest()->header.sim_step, stopped_at) << "the pause did not stop the steps";
  EXPECT_EQ(physics.stop(), 0);
}

// Synthetic bodies: synth/body0 and synth/body1, joints "bodyN-jointJ". Uncommanded,
// their joints follow a sinusoid; a position target pulls a joint to it.
class WithSynth : public ::testing::Test {
 protected:
  void SetUp() override {
    synth_.pid = spawn_afhub({"synth", "--bodies", "2", "--joints", "3", "--no-autostart"},
                             "/tmp/afhub-test-synth.log");
    ASSERT_TRUE(wait_until([&] { return body0_.latest_state() && body1_.latest_state(); }, 10s));
    // The hub lists a new process's bodies a moment after their states flow.
    CatalogReader catalog;
    catalog.wait(1s);
    ASSERT_TRUE(wait_until(
        [&] {
          const BodyList& list = catalog.latest();
          return list.body_count == 2 &&
                 list.bodies[0].owner_pid == static_cast<std::uint32_t>(synth_.pid);
        },
        5s));
  }
  void TearDown() override { EXPECT_EQ(synth_.stop(), 0); }
  // The joint positions of a fresh state of body0.
  std::array<double, 3> joints_now() {
    const std::uint64_t seen = body0_.latest_state()->header.sequence;
    EXPECT_TRUE(wait_until([&] { return body0_.latest_state()->header.sequence > seen; }, 2s));
    const BodyState& state = *body0_.latest_state();
    return {state.joints[0].position, state.joints[1].position, state.joints[2].position};
  }
  ScopedProcess synth_{-1};
  BodyClient body0_{"synth/body0"};
  BodyClient body1_{"synth/body1"};
};

TEST_F(WithSynth, CmdKeepsSendingPastTheWatchdogAndUnnamedJointsHold) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "cmd.log").string();
  ScopedProcess commander(
      spawn_afhub({"cmd", "body0", "--joint", "body0-joint0=0.3", "-j", "2=-0.1"}, log));
  ASSERT_TRUE(wait_until(
      [&] {
        auto q = joints_now();
        return std::abs(q[0] - 0.3) < 1e-3 && std::abs(q[2] + 0.1) < 1e-3;
      },
      5s))
      << read_file(log);
  const std::array<double, 3> first = joints_now();
  // Well past synth's 0.5 s watchdog: still commanded, and the unnamed joint 1 holds
  // where it was (uncommanded, it would follow its sinusoid).
  std::this_thread::sleep_for(1500ms);
  const std::array<double, 3> later = joints_now();
  EXPECT_NEAR(later[0], 0.3, 1e-3);
  EXPECT_NEAR(later[2], -0.1, 1e-3);
  // (Its 0.5 rad sinusoid would move it by tenths of a radian; held, it moved 1.02e-6 once.)
  EXPECT_NEAR(later[1], first[1], 1e-4) << "the unnamed joint moved";
  EXPECT_EQ(wait_for_exit(commander, 0ms), -1) << "cmd stopped by itself: " << read_file(log);
  EXPECT_EQ(commander.stop(SIGINT), 0);
  const std::string said = read_file(log);
  EXPECT_TRUE(contains(said, "commanding synth/body0 at 100 Hz until Ctrl-C")) << said;
  EXPECT_TRUE(contains(said, "body0-joint0 -> 0.3, body0-joint2 -> -0.1")) << said;
  EXPECT_TRUE(contains(said, "the joint left unnamed holds its current position")) << said;
  EXPECT_TRUE(contains(said, "watchdog")) << said;
}

TEST_F(WithSynth, CmdOnceWarnsAboutTheWatchdog) {
  RunResult once = run_afhub({"cmd", "body0", "--joint", "0=0.2", "--once"});
  EXPECT_EQ(once.exit_code, 0) << once.err;
  EXPECT_TRUE(contains(once.err, "sent one command to synth/body0")) << once.err;
  EXPECT_TRUE(contains(once.err, "warning: the physics' watchdog releases it")) << once.err;
  RunResult help = run_afhub({"cmd", "--help"});
  EXPECT_TRUE(contains(help.out, "until Ctrl-C")) << help.out;
  EXPECT_TRUE(contains(help.out, "--once")) << help.out;
  EXPECT_TRUE(contains(help.out, "left unnamed hold")) << help.out;
}

TEST_F(WithSynth, CmdExplainsBadJoints) {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  for (const Case& bad : std::vector<Case>{
           {{"cmd", "body0", "--joint", "elbow=0.3"},
            "no joint named 'elbow'; its joints are (index name): 0 body0-joint0, 1 body0-joint1"},
           {{"cmd", "body0", "--joint", "3=0.3"}, "indices 0 to 2"},
           {{"cmd", "body0", "--joint", "99999999999999999999=0.3"}, "indices 0 to 2"},
           {{"cmd", "body0", "--joint", "0.3"}, "--joint takes NAME=VALUE"},
           {{"cmd", "body0", "--joint", "0=x"}, "'x' is not a finite number; e.g. --joint 0=0.3"},
           // strtod read these as 16 and 0.
           {{"cmd", "body0", "--joint", "0=0x10"}, "'0x10' is not a finite number"},
           {{"cmd", "body0", "--joint", "0=1e-400"}, "'1e-400' is not a finite number"},
           {{"cmd", "body0", "--joint", "body0-joint1=abc"},
            "--joint body0-joint1=abc: 'abc' is not a finite number; e.g. --joint "
            "body0-joint1=0.3"},
           {{"cmd", "body0", "--joint", "0=1", "--joint", "body0-joint0=2"}, "twice"},
           {{"cmd", "body0", "--joint", "0=1", "--joint-pos", "1"}, "give one"},
           {{"cmd", "body0", "--joint", "0=1", "--others", "drop"}, "--others takes hold"},
           {{"cmd", "body0", "--joint", "0=1", "--once", "--repeat", "5"}, "excludes"},
       }) {
    RunResult result = run_afhub(bad.args);
    EXPECT_NE(result.exit_code, 0) << bad.args[3];
    EXPECT_TRUE(contains(result.err, bad.message))
        << "expected '" << bad.message << "' in: " << result.err;
  }
  // Blanks around a number and a sign '+' are taken.
  const RunResult spaced =
      run_afhub({"cmd", "body0", "--joint-pos", " 0.1, +0.2,-3e-1 ", "--once"});
  EXPECT_EQ(spaced.exit_code, 0) << spaced.err;
}

TEST_F(WithSynth, ClientAddressesJointsByName) {
  CatalogReader catalog;
  catalog.wait(1s);
  BodyClient from_catalog(catalog.resolve("body1"));
  EXPECT_EQ(from_catalog.joint_index("body1-joint2"), 2u);
  EXPECT_EQ(from_catalog.joint_names().size(), 3u);
  // From a channel name alone, the names are looked up in the catalog.
  BodyClient from_channel("synth/body0");
  EXPECT_EQ(from_channel.joint_index("body0-joint1"), 1u);
  try {
    from_channel.joint_index("elbow");
    ADD_FAILURE() << "an unknown joint name was accepted";
  } catch (const Error& error) {
    EXPECT_TRUE(contains(error.what(), "no joint named 'elbow'")) << error.what();
    EXPECT_TRUE(contains(error.what(), "0 body0-joint0, 1 body0-joint1, 2 body0-joint2"))
        << error.what();
  }
}

TEST_F(WithSynth, EchoShowsOrientationAndTwistAndPicksFields) {
  RunResult text = run_afhub({"echo", "body1", "-n", "2"});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(occurrences(text.out, "synth/body1 step "), 2) << text.out;
  for (const char* part : {" pos [", " quat_xyzw [", " lin_vel [", " ang_vel [", " joints ["})
    EXPECT_TRUE(contains(text.out, part)) << part << " in " << text.out;
  // synth turns body1 about z at 0.2 Hz: the angular velocity is 2 pi 0.2 rad/s.
  EXPECT_NEAR(numbers_after(text.out, "ang_vel [")[2], 2 * M_PI * 0.2, 1e-3) << text.out;

  RunResult twist = run_afhub({"echo", "body1", "-n", "1", "--fields", "twist"});
  ASSERT_EQ(twist.exit_code, 0) << twist.err;
  EXPECT_TRUE(contains(twist.out, "lin_vel [")) << twist.out;
  EXPECT_FALSE(contains(twist.out, " pos [")) << twist.out;
  EXPECT_FALSE(contains(twist.out, "joints [")) << twist.out;

  RunResult json = run_afhub({"echo", "body1", "-n", "1", "--json", "--fields", "joints,wrench"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json state = parse_json(json.out);
  EXPECT_TRUE(state.at("joint_positions").is_array()) << json.out;
  EXPECT_EQ(state.at("force_n").size(), 3u) << json.out;
  EXPECT_FALSE(state.contains("position_m")) << json.out;
  EXPECT_FALSE(state.contains("joint_velocities")) << json.out;

  RunResult bad = run_afhub({"echo", "body1", "--fields", "pose,colour"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(contains(bad.err, "no field 'colour'; the fields are pose, twist")) << bad.err;
}

TEST_F(WithSynth, EchoRateLimitsByThePublishStamps) {
  RunResult limited = run_afhub({"echo", "body0", "-n", "3", "--json", "--rate", "5"});
  ASSERT_EQ(limited.exit_code, 0) << limited.err;
  std::vector<double> stamps;  // one JSON document a line
  std::istringstream lines(limited.out);
  for (std::string line; std::getline(lines, line);) {
    const nlohmann::json state = parse_json(line);
    stamps.push_back(state.at("publish_stamp_ns").get<double>());
    EXPECT_EQ(state.at("command_answered_step"), -1) << "synth's bodies take no command";
  }
  ASSERT_EQ(stamps.size(), 3u) << limited.out;
  // At most 5 a second: the states printed were published at least 0.2 s apart
  // (at 1 kHz, every state would be about 1 ms after the last).
  EXPECT_GE(stamps[1] - stamps[0], 0.2e9);
  EXPECT_GE(stamps[2] - stamps[1], 0.2e9);
}

TEST(Ls, ARateNotMeasuredYetShowsAsADash) {
  // A body that never publishes a state: the hub has no rate to measure.
  DirectoryPublisher directory;
  directory.add(make_body_entry("test/silent", {"a"}));
  directory.publish();
  RunResult ls;
  ASSERT_TRUE(wait_until(
      [&] {
        ls = run_afhub({"ls"});
        return contains(ls.out, "test/silent");
      },
      5s))
      << ls.out;
  const std::string row = ls.out.substr(ls.out.find("test/silent"));
  EXPECT_TRUE(contains(row.substr(0, row.find('\n')), " - ")) << ls.out;
  EXPECT_FALSE(contains(row.substr(0, row.find('\n')), "0.0")) << ls.out;
  RunResult json = run_afhub({"ls", "--json"});
  const nlohmann::json bodies = parse_json(json.out);
  const nlohmann::json* silent = find_element(bodies, "body", "test/silent");
  ASSERT_NE(silent, nullptr) << json.out;
  EXPECT_TRUE(silent->at("rate_hz").is_null()) << json.out;
  RunResult help = run_afhub({"ls", "--help"});
  EXPECT_TRUE(contains(help.out, "'-' until")) << help.out;
}

}  // namespace
}  // namespace afhub::test
