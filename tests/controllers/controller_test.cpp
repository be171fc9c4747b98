// Controllers as processes against the real simulation: lockstep runs that are
// bit-identical, a killed lockstep client dropped from the barrier and a restarted
// one rejoining, a killed free-running controller tripping the watchdog (hold
// policy) and a restarted one taking over, `afhub top` and `afhub status`.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <fstream>
#include <optional>
#include <thread>

#include "afhub/hub/bodies.hpp"
#include "afhub/rt/cpu_wake_latency.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "strict_json.hpp"
#include "world_reader.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

// The project's own 7-DOF arm: these tests need no AMBF corpus.
const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

// One lockstep run of the arm driven by `afhub ctl sine`; returns the report, the
// physics' log in run<run>.log. With `second_after`, a second arm beside it
// (afhub/arm/base1), held by a second client (`ctl hold`) that joins that long after the
// first. With `stopped_for`, the sine client (or with `physics_stopped` the physics, once
// it holds a step for the client) is stopped (SIGSTOP) that long at step 1000 or later.
std::string lockstep_sine_run(const afhub::testing::ModelFolder& folder, int run,
                              std::optional<std::chrono::milliseconds> second_after = {},
                              std::optional<std::chrono::milliseconds> stopped_for = {},
                              bool physics_stopped = false) {
  const std::string report = (folder.dir() / ("report" + std::to_string(run) + ".json")).string();
  const std::string log = (folder.dir() / ("run" + std::to_string(run) + ".log")).string();
  // A client that misses a step's deadline is dropped for that step (100 ms by default):
  // on a loaded machine that would make the runs differ for a reason that is not the
  // physics', so the deadline here is a minute.
  std::vector<std::string> args = {"run",
                                   kArm,
                                   "--no-autostart",
                                   "--lockstep",
                                   "--wait-for",
                                   second_after ? "2" : "1",
                                   "--client-timeout",
                                   "60000",
                                   "--fast",
                                   "--steps",
                                   "3000",
                                   "--report",
                                   report};
  if (second_after)
    args.insert(args.end(), {kArm, "--at", kArm + "=0,0,0", "--at", kArm + "=1,0,0"});
  ScopedProcess physics(spawn_afhub(args, log));
  BodyClient base("afhub/arm/base");
  EXPECT_TRUE(wait_until([&] { return base.latest_state() != nullptr; }, 10s)) << read_file(log);
  ScopedProcess controller(spawn_afhub(
      {"ctl", "sine", "arm/base", "--lockstep", "--period", "1", "--amplitude", "0.4"}));
  std::optional<ScopedProcess> second;
  if (second_after) {
    std::this_thread::sleep_for(*second_after);
    second.emplace(spawn_afhub({"ctl", "hold", "arm/base1", "--lockstep"}));
  }
  if (stopped_for) {
    EXPECT_TRUE(wait_until(
        [&] {
          const BodyState* state = base.latest_state();
          return state && state->header.sim_step >= 1000;
        },
        30s))
        << read_file(log);
    kill(controller.pid, SIGSTOP);
    if (physics_stopped) {
      // The physics stopped while it holds a step for the client, which answers then:
      // the answer is `stopped_for` old when the physics reads it.
      std::this_thread::sleep_for(100ms);
      kill(physics.pid, SIGSTOP);
      kill(controller.pid, SIGCONT);
    }
    std::this_thread::sleep_for(*stopped_for);
    EXPECT_LT(base.latest_state()->header.sim_step, 3000u) << "the run ended before the stop";
    kill(physics_stopped ? physics.pid : controller.pid, SIGCONT);
  }
  EXPECT_EQ(wait_for_exit(physics, 30s), 0) << read_file(log);
  return read_file(report);
}

// Poses and joints are written in full (shortest round-trip) precision: equal text is
// equal bits. Times differ from run to run and are left out.
std::string trajectory(const std::string& report) {
  return report.substr(0, report.find("\"max_joint_error_m\""));
}

TEST(Lockstep, SameModelSameControllerGivesBitIdenticalRuns) {
  afhub::testing::ModelFolder folder;
  const std::string first = lockstep_sine_run(folder, 1);
  const std::string second = lockstep_sine_run(folder, 2);
  ASSERT_TRUE(contains(first, "\"steps\":3000")) << first;
  EXPECT_EQ(trajectory(first), trajectory(second));
  // And the controller did drive the arm: joint 2 is 0.4 sin(2 pi 3 + pi/7 * ...) away
  // from where it started, which is far from zero.
  const double q1 =
      parse_json(first).at("joints").at("afhub/arm/link1-link2").at("position").get<double>();
  EXPECT_GT(std::abs(q1), 0.05) << first;
}

// Step 0 held for a second client that came 1.5 s after the first: the first one's
// command to step 0 was expired by its body's watchdog (0.5 s) meanwhile, so step 0 ran
// without it, and the run depended on when the second came. And a client stalled for
// longer than the watchdog while the physics holds a step for it (a loaded CI machine
// once; here stopped for a second): the simulation waits, so its command does not age.
// Nor does an answer that came while the physics itself was stopped (it was ignored as
// older than its body's watchdog, and the step went on without it).
TEST(Lockstep, AClientIsNotTimedOutWhileThePhysicsHoldsAStepForItOrOthers) {
  afhub::testing::ModelFolder folder;
  const std::string together = lockstep_sine_run(folder, 1, 0ms);
  const std::string later = lockstep_sine_run(folder, 2, 1500ms);
  const std::string stalled = lockstep_sine_run(folder, 3, 0ms, 1000ms);
  const std::string physics_stalled = lockstep_sine_run(folder, 4, 0ms, 1000ms, true);
  for (const std::string* report : {&later, &stalled, &physics_stalled})
    ASSERT_TRUE(contains(*report, "\"steps\":3000")) << *report;
  for (int run : {1, 2, 3, 4}) {
    const std::string log =
        read_file((folder.dir() / ("run" + std::to_string(run) + ".log")).string());
    EXPECT_TRUE(contains(log, "joined the barrier for afhub/arm/base1 at step 0")) << log;
    EXPECT_FALSE(contains(log, "no command for")) << "run " << run << ":\n" << log;
    EXPECT_FALSE(contains(log, "ignored a command")) << "run " << run << ":\n" << log;
  }
  EXPECT_EQ(trajectory(together), trajectory(later));
  EXPECT_EQ(trajectory(together), trajectory(stalled));
  EXPECT_EQ(trajectory(together), trajectory(physics_stalled));
}

// Steps taken while the world is paused (`afhub world step`) do not wait for the barrier:
// the command of a lockstep client that died meanwhile is expired by its body's watchdog,
// as any writer's (a rule that spared every lockstep client in the barrier kept it on
// for good).
TEST(Lockstep, StepsTakenWhilePausedExpireADeadClientsCommand) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub(
      {"run", kArm, "--no-autostart", "--lockstep", "--wait-for", "1", "--client-timeout", "60000"},
      log));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s)) << read_file(log);
  ScopedProcess client(spawn_afhub({"ctl", "hold", "base", "--lockstep"}));
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sim_step > 300; }, 10s))
      << read_file(log);
  const RunResult pause = run_afhub({"world", "pause"});
  ASSERT_EQ(pause.exit_code, 0) << pause.err;
  kill(client.pid, SIGKILL);
  waitpid(client.pid, nullptr, 0);
  client.pid = -1;
  const RunResult steps = run_afhub({"world", "step", "1000", "--timeout", "30"});
  ASSERT_EQ(steps.exit_code, 0) << steps.err;  // 1 s of steps at 1 kHz: past the 0.5 s watchdog
  EXPECT_TRUE(wait_until([&] { return world.latest()->watchdog_expiries >= 1; }, 5s))
      << read_file(log);
  EXPECT_EQ(physics.stop(), 0);
}

// A lockstep client says whether its physics waits for it: it read "in lockstep" even
// against a physics run without --lockstep, which never waits.
TEST(Lockstep, AClientSaysWhetherItsPhysicsWaitsForIt) {
  for (const bool lockstep : {false, true}) {
    std::vector<std::string> args = {"run", kArm, "--no-autostart"};
    if (lockstep) args.push_back("--lockstep");
    ScopedProcess physics(spawn_afhub(args));
    BodyClient base("afhub/arm/base");
    ASSERT_TRUE(wait_until([&] { return base.latest_state() != nullptr; }, 10s));
    const RunResult client =
        run_afhub({"ctl", "hold", "base", "--lockstep", "--cycles", "100"}, 30s);
    EXPECT_EQ(client.exit_code, 0) << client.err;
    EXPECT_EQ(contains(client.err, "commanding afhub/arm/base in lockstep with the physics"),
              lockstep)
        << client.err;
    EXPECT_EQ(contains(client.err, "its physics steps on its own clock, not in lockstep"),
              !lockstep)
        << client.err;
    EXPECT_EQ(physics.stop(), 0);
  }
}

TEST(Lockstep, KilledClientIsDroppedTheWorldGoesOnAndARestartedClientRejoins) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub(
      {"run", kArm, "--no-autostart", "--lockstep", "--wait-for", "1", "--client-timeout", "50"},
      log));
  BodyClient base("afhub/arm/base");
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return base.latest_state() && world.latest(); }, 10s))
      << read_file(log);
  EXPECT_EQ(world.latest()->header.sim_step, 0u) << "step 0 must wait for the client";

  ScopedProcess first(spawn_afhub({"ctl", "hold", "base", "--lockstep"}));
  ASSERT_TRUE(wait_until(
      [&] {
        return world.latest()->lockstep_clients == 1 && world.latest()->header.sim_step > 300;
      },
      10s))
      << read_file(log);
  EXPECT_EQ(world.latest()->dropped_clients, 0u);

  LatestReader<BodyCommand> commands(body_command_channel("afhub/arm/base"));
  ASSERT_TRUE(wait_until([&] { return commands.latest() != nullptr; }, 5s));
  kill(first.pid, SIGKILL);
  waitpid(first.pid, nullptr, 0);
  first.pid = -1;
  const std::int64_t last_command_ns = commands.latest()->header.publish_stamp_ns;
  ASSERT_TRUE(wait_until([&] { return world.latest()->dropped_clients == 1; }, 3s))
      << read_file(log);
  EXPECT_EQ(world.latest()->lockstep_clients, 0u);
  EXPECT_GE(world.latest()->late_answers, 3u);
  // The world goes on without it, and the body's watchdog engages.
  const std::uint64_t step = world.latest()->header.sim_step;
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sim_step > step + 200; }, 3s));
  ASSERT_TRUE(wait_until([&] { return world.latest()->watchdog_expiries == 1; }, 3s));
  // The physics' own stamps, not this test's wall clock: the watchdog fired no earlier
  // than its 0.5 s after the last command (the waits bound how much later).
  EXPECT_GE(world.latest()->header.publish_stamp_ns - last_command_ns, 500'000'000)
      << "the watchdog fired before its 0.5 s";

  ScopedProcess second(spawn_afhub({"ctl", "hold", "base", "--lockstep"}));
  ASSERT_TRUE(wait_until([&] { return world.latest()->lockstep_clients == 1; }, 5s))
      << read_file(log);
  const std::uint64_t rejoined = world.latest()->header.sim_step;
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sim_step > rejoined + 300; }, 5s));
  EXPECT_EQ(world.latest()->lockstep_clients, 1u);
  EXPECT_EQ(world.latest()->dropped_clients, 1u);

  EXPECT_EQ(physics.stop(), 0);
  const std::string output = read_file(log);
  EXPECT_TRUE(contains(output, "waiting for 1 lockstep clients")) << output;
  EXPECT_TRUE(contains(output, "dropped from the barrier")) << output;
  EXPECT_TRUE(contains(output, "lockstep client pid " + std::to_string(second.pid) + " joined"))
      << output;
}

// A client killed and another started before the first is dropped (a minute's timeout):
// the second answers after a dead one, never with it, and is not said to be a second.
TEST(Lockstep, AClientRestartedBeforeTheDeadOneIsDroppedIsNotASecondOne) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub(
      {"run", kArm, "--no-autostart", "--lockstep", "--wait-for", "1", "--client-timeout", "60000"},
      log));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s)) << read_file(log);
  ScopedProcess first(spawn_afhub({"ctl", "hold", "base", "--lockstep"}));
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sim_step > 300; }, 10s))
      << read_file(log);
  kill(first.pid, SIGKILL);
  waitpid(first.pid, nullptr, 0);
  first.pid = -1;
  ScopedProcess second(spawn_afhub({"ctl", "hold", "base", "--lockstep"}));
  const std::uint64_t step = world.latest()->header.sim_step;
  ASSERT_TRUE(wait_until([&] { return world.latest()->header.sim_step > step + 300; }, 10s))
      << read_file(log);
  EXPECT_EQ(world.latest()->dropped_clients, 0u) << "the dead client was not dropped first";
  EXPECT_EQ(physics.stop(), 0);
  const std::string output = read_file(log);
  EXPECT_TRUE(contains(output, "lockstep client pid " + std::to_string(second.pid) + " joined"))
      << output;
  EXPECT_FALSE(contains(output, "two lockstep clients")) << output;
}

// Two lockstep clients on one body: the physics takes whichever command came last, so
// the run depends on their timing. It said nothing; now it says so, once.
TEST(Lockstep, TwoClientsOnOneBodyAreSaid) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart", "--lockstep", "--paused",
                                     "--client-timeout", "60000", "--fast", "--steps", "3000"},
                                    log));
  // Both in their loops before the world runs: a fast run would end before a late one.
  const std::string hold_log = (folder.dir() / "hold.log").string(),
                    sine_log = (folder.dir() / "sine.log").string();
  ScopedProcess hold(spawn_afhub({"ctl", "hold", "base", "--lockstep"}, hold_log));
  ScopedProcess sine(spawn_afhub({"ctl", "sine", "base", "--lockstep"}, sine_log));
  ASSERT_TRUE(wait_until(
      [&] {
        return contains(read_file(hold_log), "in lockstep with the physics") &&
               contains(read_file(sine_log), "in lockstep with the physics");
      },
      20s))
      << read_file(hold_log) << read_file(sine_log);
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  EXPECT_EQ(wait_for_exit(physics, 60s), 0) << read_file(log);
  const std::string output = read_file(log);
  EXPECT_EQ(occurrences(output, "two lockstep clients command afhub/arm/base"), 1) << output;
}

// `afhub cmd` (100 Hz) on a body a lockstep client answers for: each step takes
// whichever command came last, said once. The client's answers are taken before the
// newer command: hidden, each held the step for the client timeout (a fault-injection
// run counted 44 late answers in 5 s).
TEST(Lockstep, ACommandBesideALockstepClientIsSaidAndHidesNoAnswer) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart", "--lockstep"}, log));
  const std::string hold_log = (folder.dir() / "hold.log").string();
  ScopedProcess hold(spawn_afhub({"ctl", "hold", "base", "--lockstep"}, hold_log));
  ASSERT_TRUE(wait_until([&] { return contains(read_file(log), "joined the barrier"); }, 20s))
      << read_file(log) << read_file(hold_log);
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s));
  const std::uint64_t late_before = world.latest()->late_answers;
  const std::uint64_t step_before = world.latest()->header.sim_step;
  ScopedProcess cmd(spawn_afhub({"cmd", "base", "--joint", "0=0.1"}));
  const std::string said = "commands afhub/arm/base outside the lockstep";
  EXPECT_TRUE(wait_until([&] { return contains(read_file(log), said); }, 20s)) << read_file(log);
  std::this_thread::sleep_for(3s);
  const WorldState* now = world.latest();
  ASSERT_NE(now, nullptr);
  std::printf("afhub cmd beside a lockstep client: %llu steps in 3 s, %llu late answers\n",
              static_cast<unsigned long long>(now->header.sim_step - step_before),
              static_cast<unsigned long long>(now->late_answers - late_before));
  EXPECT_EQ(now->late_answers, late_before) << read_file(log);
  EXPECT_EQ(occurrences(read_file(log), said), 1) << read_file(log);
}

TEST(Controllers, KilledControllerTripsTheHoldWatchdogAndARestartTakesOver) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(
      spawn_afhub({"run", kArm, "--no-autostart", "--watchdog-hold", "base"}, log));
  BodyClient base("afhub/arm/base");
  LatestReader<WorldState> world = world_reader();
  LatestReader<BodyCommand> commands(body_command_channel("afhub/arm/base"));
  ASSERT_TRUE(wait_until([&] { return base.latest_state() && world.latest(); }, 10s))
      << read_file(log);

  ScopedProcess sine(spawn_afhub({"ctl", "sine", "base", "--amplitude", "0.4", "--period", "1"}));
  ASSERT_TRUE(wait_until(
      [&] {
        const BodyCommand* command = commands.latest();
        return command && command->header.publisher_pid == static_cast<std::uint32_t>(sine.pid);
      },
      5s));
  std::this_thread::sleep_for(1500ms);  // mid-swing
  kill(sine.pid, SIGKILL);
  waitpid(sine.pid, nullptr, 0);
  sine.pid = -1;
  const std::int64_t last_command_ns = commands.latest()->header.publish_stamp_ns;
  ASSERT_TRUE(wait_until([&] { return world.latest()->watchdog_expiries == 1; }, 10s));
  // The physics' own stamps, not this test's wall clock: the watchdog fired no earlier
  // than its period after the last command, and at once after (the next world state).
  const std::int64_t expired_ns = world.latest()->header.publish_stamp_ns;
  EXPECT_GE(expired_ns - last_command_ns, 500'000'000);

  // Held: the joints stay where the watchdog found them, mid-swing, while the physics
  // runs on (after a moment to absorb the swing's speed).
  std::this_thread::sleep_for(300ms);
  // A state holds its body's joints only (body_state_bytes): copied as far as they go.
  BodyState held, later;
  copy_body_state(*base.latest_state(), held);
  // 500 steps on, counted in steps, not timed (the wait only bounds a hang).
  EXPECT_TRUE(wait_until(
      [&] { return base.latest_state()->header.sim_step > held.header.sim_step + 500; }, 10s))
      << "the physics stopped stepping";
  copy_body_state(*base.latest_state(), later);
  for (int j = 0; j < 7; ++j)
    EXPECT_NEAR(later.joints[j].position, held.joints[j].position, 0.005) << "joint " << j;

  // A restarted controller takes over: its commands arrive and none is refused. It
  // holds the machine's CPU wake-up latency limit at 0 while it runs (needs root).
  const bool can_hold_limit = geteuid() == 0 && access(kCpuWakeLatencyDevice, W_OK) == 0;
  ScopedProcess hold(spawn_afhub({"ctl", "hold", "base", "--cpu-wake-latency", "0"}));
  ASSERT_TRUE(wait_until(
      [&] {
        const BodyCommand* command = commands.latest();
        return command && command->header.publisher_pid == static_cast<std::uint32_t>(hold.pid);
      },
      5s));
  EXPECT_EQ(world.latest()->rejected_commands, 0u);

  // Its loop shows in `afhub top` and `afhub status` as soon as it runs: top waits for the
  // first stats of every loop it finds (a loop publishes them a second into its run).
  RunResult top = run_afhub({"top", "--json"});
  // Hung once in a fresh CI run (no output in 20 s): what the hub was doing then says why.
  ASSERT_EQ(top.exit_code, 0) << top.err << (top.exit_code == -1 ? stack_traces("afhub hub") : "");
  const nlohmann::json loops = parse_json(top.out).at("loops");
  // The controller's own entry, never the physics' loop (also 1 kHz, also on the arm).
  const nlohmann::json* loop = find_element(loops, "name", "ctl hold");
  ASSERT_NE(loop, nullptr) << "no loop named \"ctl hold\" in\n" << top.out;
  EXPECT_EQ(loop->at("pid"), hold.pid) << top.out;
  EXPECT_EQ(loop->at("body"), "afhub/arm/base") << top.out;
  EXPECT_NE(find_element(loops, "name", "run"), nullptr) << "the physics loop is listed too\n"
                                                         << top.out;
  // Its period, and that it ran (its measured rate depends on this machine's load).
  EXPECT_EQ(loop->at("period_s").get<double>(), 0.001) << top.out;
  EXPECT_GT(loop->at("rate_hz").get<double>(), 0.0) << top.out;
  EXPECT_GT(loop->at("cycles").get<double>(), 500.0) << top.out;
  RunResult status = run_afhub({"status"});
  EXPECT_TRUE(contains(status.out, "loops:")) << status.out;
  EXPECT_TRUE(contains(status.out, "ctl hold")) << status.out;
  if (can_hold_limit) {
    EXPECT_EQ(loop->at("cpu_wake_latency_us"), 0) << top.out;  // the physics: -1
    EXPECT_TRUE(contains(status.out, "wake<=0us")) << status.out;
    std::int32_t limit = -1;
    std::ifstream(kCpuWakeLatencyDevice, std::ios::binary)
        .read(reinterpret_cast<char*>(&limit), sizeof limit);
    EXPECT_EQ(limit, 0) << "the kernel's limit while `ctl hold --cpu-wake-latency 0` runs";
  }

  EXPECT_EQ(physics.stop(), 0);
  EXPECT_TRUE(contains(read_file(log), "its joints hold their positions")) << read_file(log);
}

TEST(Controllers, AFreeRunningControllerWakesInPhaseSoEachCommandAnswersTheNewestState) {
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}, log));
  LatestReader<WorldState> world = world_reader();
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s)) << read_file(log);
  EXPECT_EQ(world.latest()->commanded_steps, 0u);  // nothing commands the arm yet

  // Woken half a period after each step is due (the default), the controller's
  // command is in place before the next one: the physics counts the steps whose
  // command answered the state it had just published.
  ScopedProcess hold(spawn_afhub({"ctl", "hold", "base", "--cycles", "3000"}));
  ASSERT_EQ(wait_for_exit(hold, 15s), 0);
  ASSERT_TRUE(wait_until([&] { return world.latest()->commanded_steps >= 2900; }, 2s));
  const WorldState& counts = *world.latest();
  EXPECT_LE(counts.answered_steps, counts.commanded_steps);
  // Misses come only from this machine's stalls: about 1 % when quiet, 16 % seen with
  // a load average of 8 on its 2 cores.
  EXPECT_GT(static_cast<double>(counts.answered_steps) / counts.commanded_steps, 0.75)
      << counts.answered_steps << " of " << counts.commanded_steps;
  EXPECT_EQ(physics.stop(), 0);
}

TEST(Controllers, BadArgumentsGetClearErrors) {
  afhub::testing::ModelFolder folder;
  ScopedProcess physics(spawn_afhub({"run", kArm, "--no-autostart"}));
  BodyClient base("afhub/arm/base");
  ASSERT_TRUE(wait_until([&] { return base.latest_state() != nullptr; }, 10s));
  RunResult missing_body = run_afhub({"ctl", "sine", "nosuchbody", "--wait", "0.5"});
  EXPECT_EQ(missing_body.exit_code, 1);
  EXPECT_TRUE(contains(missing_body.err, "no body 'nosuchbody' is live yet; waiting up to"))
      << missing_body.err;
  EXPECT_TRUE(contains(missing_body.err, "no live body is named 'nosuchbody'")) << missing_body.err;
  EXPECT_TRUE(contains(missing_body.err, "wait longer with --wait")) << missing_body.err;
  RunResult missing_file = run_afhub({"ctl", "track", "base", folder.dir().string() + "/x.csv"});
  EXPECT_EQ(missing_file.exit_code, 1);
  EXPECT_TRUE(contains(missing_file.err, "x.csv: error: no such file; expected a trajectory (CSV)"))
      << missing_file.err;
  RunResult bad_rate = run_afhub({"ctl", "hold", "base", "--rate", "0"});
  EXPECT_EQ(bad_rate.exit_code, 1);
  EXPECT_TRUE(contains(bad_rate.err, "--rate")) << bad_rate.err;
  // NaN and negative offsets were taken (as "not given", or rounded to garbage).
  for (const char* phase : {"1000", "nan", "-5"}) {
    RunResult bad_phase = run_afhub({"ctl", "hold", "base", "--after-step", phase});
    EXPECT_EQ(bad_phase.exit_code, 1) << phase;
    EXPECT_TRUE(contains(bad_phase.err, "--after-step takes 0 up to the loop's period (1000 us)"))
        << bad_phase.err;
  }
  // No name is no late body: refused at once (it waited the whole --wait).
  for (const char* name : {"", "/", " "}) {
    RunResult no_name = run_afhub({"ctl", "hold", name, "--wait", "600"}, 10s);
    EXPECT_EQ(no_name.exit_code, 1) << no_name.err;
    EXPECT_TRUE(contains(no_name.err, "no body name given")) << no_name.err;
  }
  RunResult both = run_afhub({"ctl", "hold", "base", "--after-step", "100", "--unaligned"});
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_TRUE(contains(both.err, "--after-step and --unaligned exclude each other")) << both.err;
  RunResult bad_fifo = run_afhub({"run", kArm, "--offline", "--steps", "1", "--fifo", "120"});
  EXPECT_EQ(bad_fifo.exit_code, 1);
  EXPECT_TRUE(contains(bad_fifo.err, "--fifo takes a SCHED_FIFO priority")) << bad_fifo.err;
  RunResult bad_wake =
      run_afhub({"run", kArm, "--offline", "--steps", "1", "--cpu-wake-latency", "5000"});
  EXPECT_EQ(bad_wake.exit_code, 1);
  EXPECT_TRUE(contains(bad_wake.err, "--cpu-wake-latency must be 0 to 1000 microseconds"))
      << bad_wake.err;
  RunResult bad_hold =
      run_afhub({"run", kArm, "--offline", "--steps", "1", "--watchdog-hold", "x"});
  EXPECT_EQ(bad_hold.exit_code, 1);
  EXPECT_TRUE(contains(bad_hold.err, "drop --offline")) << bad_hold.err;
}

}  // namespace
}  // namespace afhub::test
