// Commands are bounded, arrive, and are never stale (issue 12), against `afhub run`
// of the example arm on a test hub: finite extreme commands refused and counted
// while the world runs on; world commands from several writers acted on once each,
// in order; a restarted physics ignoring a live writer's old command; a per-body
// watchdog of 2 ms; one count of late commands in `status`, `top` and the world; and a
// --once command to a stopped physics said to be lost.
// Assertions are on counters, states and messages, never on tight wall-clock times.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <optional>
#include <thread>

#include <signal.h>
#include <unistd.h>

#include "afhub/hub/bodies.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "latest_slot.hpp"
#include "model_files.hpp"
#include "strict_json.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

ChannelId world_channel(std::string_view event) {
  return {std::string(kService), std::string(kWorldInstance), std::string(event)};
}

// The arm on the hub; the world state read as it comes.
struct ArmRun {
  // `args`: how afhub runs the world, the arm's physics by default.
  explicit ArmRun(const std::vector<std::string>& args = {"run", kArm, "--no-autostart"})
      : log((folder.dir() / "run.log").string()) {
    physics = std::make_unique<ScopedProcess>(spawn_afhub(args, log));
  }
  bool ready() {
    return wait_until([&] { return world.latest() != nullptr; }, 10s);
  }
  const WorldState& now() { return *world.latest(); }
  // A world state published after this call began. now() may hand back an old copy: a
  // read that meets the physics mid-update keeps the last one, seconds old in a test
  // that slept, when the physics stays in its update longer than a reader waits (2 ms).
  // The physics publishes every cycle, paused too.
  WorldState fresh() {
    world.latest();  // what came before this call
    EXPECT_TRUE(wait_until(
        [&] {
          world.latest();
          return world.updated();
        },
        5s))
        << "no world state came";
    return now();
  }
  afhub::testing::ModelFolder folder;
  std::string log;
  std::unique_ptr<ScopedProcess> physics;
  LatestReader<WorldState> world{world_channel(kStateEvent)};
};

TEST(FaultsCommands, FiniteExtremeCommandsAreRefusedAndCountedWhileTheWorldRunsOn) {
  ArmRun run;
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  const std::vector<std::vector<std::string>> extremes = {
      {"--joint-effort", "1e308"},
      {"--force", "1e308,0,0"},
      {"--torque", "0,0,1e308"},
      {"--pose", "1e308,0,0,0,0,0"},
  };
  std::uint64_t expected = 0;
  for (const auto& extreme : extremes) {
    std::vector<std::string> args = {"cmd", "arm/base", "--once"};
    args.insert(args.end(), extreme.begin(), extreme.end());
    // cmd reads the refusal back from the body's state and says it, exit 1.
    RunResult sent = run_afhub(args);
    EXPECT_EQ(sent.exit_code, 1) << sent.err;
    EXPECT_TRUE(contains(sent.err, "the physics refused the command for afhub/arm/base: "))
        << sent.err;
    EXPECT_FALSE(contains(sent.err, " inf ")) << "the value as sent, not its overflow\n"
                                              << sent.err;
    ++expected;
    ASSERT_TRUE(wait_until([&] { return run.now().rejected_commands >= expected; }, 5s))
        << extreme[0] << ": " << run.now().rejected_commands << " refused\n"
        << read_file(run.log);
  }
  // The world runs on: it keeps stepping, and the physics is alive.
  const std::uint64_t step = run.now().header.sim_step;
  EXPECT_TRUE(wait_until([&] { return run.now().header.sim_step > step + 100; }, 5s));
  EXPECT_EQ(wait_for_exit(*run.physics, 0ms), -1) << read_file(run.log);
  RunResult status = run_afhub({"status", "--json"});
  EXPECT_EQ(parse_json(status.out).at("world").at("rejected_commands"), 4) << status.out;
  EXPECT_EQ(run.physics->stop(), 0);
  const std::string output = read_file(run.log);
  // Said once for the body, naming the field, the value and the bound.
  EXPECT_TRUE(contains(output, "refused a command for afhub/arm/base: joint 0 (base-link1) effort"))
      << output;
  EXPECT_TRUE(contains(output, "joint 0 (base-link1) effort 1e+308 N m is beyond its bound"))
      << output;
  EXPECT_FALSE(contains(output, "NaN")) << output;
}

// A --once command lives in its writer's slot until the writer exits: to a physics that
// does not take it up (stopped here, as by a debugger), `afhub cmd --once` says after a
// bounded wait that nothing was applied, exit 1, and the physics carries on once resumed.
TEST(FaultsCommands, OnceToAStoppedPhysicsSaysNothingWasApplied) {
  ArmRun run;
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  ASSERT_EQ(kill(run.physics->pid, SIGSTOP), 0);
  const RunResult sent = run_afhub({"cmd", "arm/base", "--once", "--force", "1,0,0"});
  ASSERT_EQ(kill(run.physics->pid, SIGCONT), 0);
  EXPECT_EQ(sent.exit_code, 1) << sent.err;
  EXPECT_TRUE(contains(sent.err,
                       "no physics took the command for afhub/arm/base within 5 s, "
                       "so nothing of it was applied"))
      << sent.err;
  const std::uint64_t step = run.now().header.sim_step;
  EXPECT_TRUE(wait_until([&] { return run.now().header.sim_step > step + 100; }, 10s))
      << read_file(run.log);
  // Running again, it takes the next one.
  const RunResult again = run_afhub({"cmd", "arm/base", "--once", "--force", "1,0,0"});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(run.physics->stop(), 0);
}

// A world command that its sender reported failed (the physics stopped, as by a
// debugger) does not act once the physics runs again: a reset and a pause that failed
// after 1 s reset the world and paused it for good when it was resumed.
TEST(FaultsCommands, AWorldCommandReportedFailedDoesNotActLater) {
  ArmRun run;
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  ASSERT_TRUE(wait_until([&] { return run.now().header.sim_step > 200; }, 10s));
  ASSERT_EQ(kill(run.physics->pid, SIGSTOP), 0);
  const std::uint64_t stopped_at = run.now().header.sim_step;
  const RunResult reset = run_afhub({"world", "reset", "--timeout", "1"});
  const RunResult pause = run_afhub({"world", "pause", "--timeout", "1"});
  ASSERT_EQ(kill(run.physics->pid, SIGCONT), 0);
  for (const RunResult* failed : {&reset, &pause}) {
    EXPECT_EQ(failed->exit_code, 1) << failed->err;
    EXPECT_TRUE(contains(failed->err, "did not act on it within 1 s, and it will not later"))
        << failed->err;
  }
  EXPECT_GE(run.fresh().header.sim_step, stopped_at) << "reset after it failed";
  EXPECT_TRUE(wait_until([&] { return run.fresh().header.sim_step > stopped_at + 100; }, 10s))
      << "paused after it failed: " << read_file(run.log);
  EXPECT_FALSE(run.now().paused);
  EXPECT_EQ(run.physics->stop(), 0);
  const std::string output = read_file(run.log);
  EXPECT_TRUE(contains(output, "ignored a world command (reset) from pid")) << output;
  EXPECT_TRUE(contains(output, "ignored a world command (pause) from pid")) << output;
  EXPECT_TRUE(contains(output, "past the 1.000 s its sender waited for it")) << output;
}

// A command entry for a joint without an axis (here a fixed one) is refused and
// counted, said once; a 0, what a full-length command carries for it, is not.
TEST(FaultsCommands, EntriesForJointsWithoutAnAxisAreRefusedAndCounted) {
  afhub::testing::ModelFolder folder;
  const std::string model = folder.write(
      "fixed.yaml",
      "bodies: [BODY base, BODY a, BODY b]\njoints: [JOINT weld, JOINT hinge]\n"
      "gravity: {x: 0, y: 0, z: 0}\nBODY base:\n  name: base\n  mass: 0\n"
      "BODY a:\n  name: a\n  mass: 1\n  location: {position: {x: 0.1, y: 0, z: 0}}\n"
      "BODY b:\n  name: b\n  mass: 1\n  location: {position: {x: 0.3, y: 0, z: 0}}\n"
      "JOINT weld:\n  name: weld\n  parent: BODY base\n  child: BODY a\n"
      "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 0, z: 1}\n"
      "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 0, z: 1}\n  type: fixed\n"
      "JOINT hinge:\n  name: hinge\n  parent: BODY a\n  child: BODY b\n"
      "  parent pivot: {x: 0.1, y: 0, z: 0}\n  parent axis: {x: 0, y: 0, z: 1}\n"
      "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 0, z: 1}\n"
      "  type: revolute\n");
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", model, "--no-autostart"}, log));
  LatestReader<WorldState> world{world_channel(kStateEvent)};
  ASSERT_TRUE(wait_until([&] { return world.latest() != nullptr; }, 10s)) << read_file(log);
  RunResult zero = run_afhub({"cmd", "env/base", "--once", "--joint-effort", "0,0.5"});
  ASSERT_EQ(zero.exit_code, 0) << zero.err;
  RunResult asks = run_afhub({"cmd", "env/base", "--once", "--joint-pos", "0.3,0.5"});
  ASSERT_EQ(asks.exit_code, 0) << asks.err;
  ASSERT_TRUE(wait_until([&] { return world.latest()->rejected_commands >= 1; }, 5s))
      << read_file(log);
  const std::uint64_t step = world.latest()->header.sim_step;
  EXPECT_TRUE(wait_until([&] { return world.latest()->header.sim_step > step + 100; }, 5s));
  EXPECT_EQ(world.latest()->rejected_commands, 1u) << "a 0 for the fixed joint is no command";
  EXPECT_EQ(physics.stop(), 0);
  const std::string output = read_file(log);
  EXPECT_TRUE(contains(output,
                       "refused part of a command for ambf/env/base: joint 0 (weld) is "
                       "fixed: it has no single axis to command"))
      << output;
}

// Every process that runs a world (the physics, `afhub synth`) reads world commands
// the same way: a queue, each command once, in order.
class WorldCommands : public ::testing::TestWithParam<const char*> {};

TEST_P(WorldCommands, FromEveryWriterActOnceEachInOrder) {
  ArmRun run(std::string(GetParam()) == "synth"
                 ? std::vector<std::string>{"synth", "--bodies", "2", "--no-autostart"}
                 : std::vector<std::string>{"run", kArm, "--no-autostart"});
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  // Writers whose sequences all start at 1, as every process's do.
  auto send = [](Writer<WorldCommand>& writer, WorldAction action, std::uint32_t steps = 1) {
    WorldCommand* command = writer.loan();
    ASSERT_NE(command, nullptr);
    command->action = action;
    command->step_count = steps;
    writer.publish(command);
  };
  Writer<WorldCommand> a(world_channel(kCommandEvent)), b(world_channel(kCommandEvent)),
      c(world_channel(kCommandEvent)), d(world_channel(kCommandEvent));
  // Pause from one writer, resume from another: both act.
  send(a, WorldAction::kPause);
  ASSERT_TRUE(wait_until([&] { return run.now().paused == 1; }, 5s));
  send(b, WorldAction::kResume);
  ASSERT_TRUE(wait_until([&] { return run.now().paused == 0; }, 5s)) << "resume from b was lost";
  // A step asked for while running is ignored, not kept for the next pause.
  send(c, WorldAction::kStep, 500);
  std::this_thread::sleep_for(20ms);
  send(a, WorldAction::kPause);
  ASSERT_TRUE(wait_until([&] { return run.now().paused == 1; }, 5s));
  std::this_thread::sleep_for(50ms);
  const std::uint64_t paused_at = run.fresh().header.sim_step;
  std::this_thread::sleep_for(700ms);
  EXPECT_EQ(run.fresh().header.sim_step, paused_at) << "steps asked for while running ran later";
  // Two writers' steps published back to back, within one physics cycle: both run.
  send(c, WorldAction::kStep, 5);
  send(d, WorldAction::kStep, 7);
  EXPECT_TRUE(wait_until([&] { return run.now().header.sim_step == paused_at + 12; }, 5s))
      << "stepped " << run.now().header.sim_step - paused_at << " of 12";
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(run.fresh().header.sim_step, paused_at + 12);
  // `resume resume` from a third writer: each acts once (the world runs), then a
  // pause from the first stops it again.
  send(d, WorldAction::kResume);
  send(d, WorldAction::kResume);
  ASSERT_TRUE(wait_until([&] { return run.now().paused == 0; }, 5s));
  send(b, WorldAction::kPause);
  EXPECT_TRUE(wait_until([&] { return run.now().paused == 1; }, 5s));
  EXPECT_EQ(run.physics->stop(), 0);
}

INSTANTIATE_TEST_SUITE_P(FaultsCommands, WorldCommands, ::testing::Values("run", "synth"));

TEST(FaultsCommands, ARestartedPhysicsIgnoresALiveWritersOldCommand) {
  BodyClient* base = nullptr;
  std::unique_ptr<BodyClient> client;
  {
    ArmRun first;
    ASSERT_TRUE(first.ready()) << read_file(first.log);
    client = std::make_unique<BodyClient>("afhub/arm/base");
    base = client.get();
    ASSERT_TRUE(wait_until([&] { return base->latest_state() != nullptr; }, 5s));
    // One command, kept by the writer's history: joint 0 to 1 rad.
    BodyCommand* command = base->loan_command(kMaxJointsPerBody);
    ASSERT_NE(command, nullptr);
    command->joint_count = 1;
    command->joints[0].type = JointCommandType::kPosition;
    command->joints[0].value = 1.0;
    base->publish_command(command);
    ASSERT_TRUE(wait_until([&] { return base->latest_state()->joints[0].position > 0.5; }, 5s));
    EXPECT_EQ(first.physics->stop(), 0);
  }
  // Longer than the watchdog (0.5 s): the command is stale when the new physics reads it.
  std::this_thread::sleep_for(1s);
  ArmRun second;
  ASSERT_TRUE(second.ready()) << read_file(second.log);
  ASSERT_TRUE(wait_until([&] { return second.now().stale_commands == 1; }, 5s))
      << read_file(second.log);
  std::this_thread::sleep_for(1s);
  ASSERT_NE(base->latest_state(), nullptr);
  EXPECT_LT(std::abs(base->latest_state()->joints[0].position), 0.05)
      << "the old command moved the new physics' arm";
  EXPECT_EQ(second.now().rejected_commands, 0u);
  RunResult status = run_afhub({"status", "--json"});
  EXPECT_EQ(parse_json(status.out).at("world").at("stale_commands"), 1) << status.out;
  EXPECT_EQ(second.physics->stop(), 0);
  const std::string output = read_file(second.log);
  EXPECT_TRUE(contains(output, "ignored a command for afhub/arm/base from pid")) << output;
}

// A free-running controller goes on answering the states it read before a world reset
// for a step or two: those commands, for the old pose, kicked the KUKA's joints at 19 to
// 34 rad/s. A command answering a step this run has not reached is ignored, counted
// and said once; one answering a current state is taken.
TEST(FaultsCommands, CommandsAnsweringAStepFromBeforeAResetAreIgnored) {
  ArmRun run;
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  BodyClient link("afhub/arm/link2");
  ASSERT_TRUE(wait_until(
      [&] { return link.latest_state() && link.latest_state()->header.sim_step > 1500; }, 20s));
  // Paused, then reset: the world waits at step 0 while the old commands come (running,
  // a loaded machine stepped past the old step before they were all sent).
  ASSERT_EQ(run_afhub({"world", "pause"}).exit_code, 0);
  const std::uint64_t before_reset = link.latest_state()->header.sim_step;
  ASSERT_EQ(run_afhub({"world", "reset"}).exit_code, 0);
  const auto send = [&](std::uint64_t answers) {
    BodyCommand* command = link.loan_command(1);
    ASSERT_NE(command, nullptr);
    command->header.sim_step = answers;
    command->joint_count = 1;
    command->joints[0].type = JointCommandType::kPosition;
    command->joints[0].value = 1.0;
    link.publish_command(command);
  };
  for (int i = 0; i < 20; ++i) {
    send(before_reset);
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_EQ(run_afhub({"world", "step", "200"}).exit_code, 0);
  ASSERT_LT(link.latest_state()->header.sim_step, before_reset) << "the world was not reset";
  EXPECT_GE(run.fresh().stale_commands, 1u);
  EXPECT_LT(std::abs(link.latest_state()->joints[0].position), 0.05)
      << "a command from before the reset moved the arm";
  ASSERT_EQ(run_afhub({"world", "resume"}).exit_code, 0);
  ASSERT_TRUE(wait_until(
      [&] {
        send(link.latest_state()->header.sim_step);
        return link.latest_state()->joints[0].position > 0.5;
      },
      5s))
      << "a command answering a current state was not taken";
  EXPECT_EQ(run.physics->stop(), 0);
  const std::string output = read_file(run.log);
  EXPECT_EQ(occurrences(output, "which this run has not reached"), 1) << output;
  EXPECT_TRUE(contains(output, "answering step " + std::to_string(before_reset))) << output;
}

// A command stamped an hour ahead (forged in its slot, as a forger or a writer on
// another clock would: afhub's own writers stamp at publish) is ignored and counted as
// stale, said once; it does not move the arm.
TEST(FaultsCommands, ACommandStampedInTheFutureIsIgnored) {
  ArmRun run;
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  // Not the base: the previous test's old command to it, still held for a late
  // subscriber until the hub drops its writer, would be the one stale notice said.
  BodyClient link("afhub/arm/link1");
  ASSERT_TRUE(wait_until([&] { return link.latest_state() != nullptr; }, 5s));
  RawWriter forger(body_command_channel("afhub/arm/link1"), PayloadKind::kBodyCommand);
  auto* command = static_cast<BodyCommand*>(forger.loan(body_command_bytes(1)));
  ASSERT_NE(command, nullptr);
  // Sized for one joint: only that much is written.
  std::memset(static_cast<void*>(command), 0, body_command_bytes(1));
  command->joint_count = 1;
  forger.publish(command);  // a command holding nothing, in a slot the physics takes
  // The slot's control block heads its entry in the block (shm_layout/slot_block.hpp).
  SlotControl* slot = &reinterpret_cast<SlotEntryHeader*>(
                           reinterpret_cast<unsigned char*>(command) - kSlotEntryHeaderBytes)
                           ->control;
  for (std::uint64_t sequence = 2; sequence <= 50; ++sequence) {
    slot::begin_update(*slot, static_cast<std::uint32_t>(body_command_bytes(1)));
    command->header.sequence = sequence;
    command->header.publish_stamp_ns = monotonic_ns() + 3'600'000'000'000LL;
    command->joints[0].type = JointCommandType::kPosition;
    command->joints[0].value = 1.0;
    slot::end_update(*slot, command->header.publish_stamp_ns);
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(wait_until([&] { return run.now().stale_commands >= 1; }, 5s)) << read_file(run.log);
  EXPECT_LT(std::abs(link.latest_state()->joints[0].position), 0.05)
      << "the command from the future moved the arm";
  EXPECT_EQ(run.physics->stop(), 0);
  const std::string output = read_file(run.log);
  EXPECT_EQ(occurrences(output, "s in the future"), 1) << output;
  // An hour ahead, less the moments between the stamp and the read.
  EXPECT_TRUE(contains(output, "stamped 3599.9") || contains(output, "stamped 3600.0")) << output;
}

TEST(FaultsCommands, APerBodyWatchdogOfTwoMillisecondsFiresForThatBodyAlone) {
  ArmRun run({"run", kArm, "--no-autostart", "--watchdog-body", "arm/link3=0.002"});
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  BodyClient base("afhub/arm/base"), link3("afhub/arm/link3");
  ASSERT_TRUE(wait_until([&] { return link3.latest_state() && base.latest_state(); }, 5s));
  auto hold = [](BodyClient& body, std::uint32_t joints) {
    BodyCommand* command = body.loan_command(kMaxJointsPerBody);
    if (!command) return;
    command->joint_count = joints;
    for (std::uint32_t j = 0; j < joints; ++j)
      command->joints[j].type = JointCommandType::kPosition;
    body.publish_command(command);
  };
  // Both commanded for 0.3 s (link3 at about 1 kHz), then link3 stops while the base
  // goes on at 100 Hz, well within its 0.5 s.
  for (int i = 0; i < 300; ++i) {
    hold(link3, 4);
    if (i % 10 == 0) hold(base, 7);
    std::this_thread::sleep_for(1ms);
  }
  for (int i = 0; i < 100; ++i) {
    hold(base, 7);
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_GE(run.fresh().watchdog_expiries, 1u);
  EXPECT_EQ(run.physics->stop(), 0);
  const std::string output = read_file(run.log);
  EXPECT_TRUE(contains(output, "no command for afhub/arm/link3 in 0.002 s")) << output;
  EXPECT_FALSE(contains(output, "no command for afhub/arm/base")) << output;
  // Out of range: refused with a message.
  RunResult bad = run_afhub(
      {"run", kArm, "--no-autostart", "--steps", "1", "--watchdog-body", "arm/link3=0.0001"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(contains(bad.err, "0.002 to 3600")) << bad.err;
  // Decimal only: strtod read it as 1 s.
  RunResult hex = run_afhub(
      {"run", kArm, "--no-autostart", "--steps", "1", "--watchdog-body", "arm/link3=0x1"});
  EXPECT_NE(hex.exit_code, 0);
  EXPECT_TRUE(contains(hex.err, "--watchdog-body takes BODY=SECONDS")) << hex.err;
}

TEST(FaultsCommands, LateCommandsAreOneCountInTheWorldStatusAndTop) {
  ArmRun run;
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  // A 500 Hz controller of a 1 kHz physics: every other step runs on a command that
  // answered the state before the last.
  ScopedProcess controller(spawn_afhub({"ctl", "hold", "arm/base", "--rate", "500"}));
  ASSERT_TRUE(wait_until([&] { return run.now().commanded_steps > 500; }, 10s));
  const WorldState before = run.fresh();
  const std::uint64_t late_before = before.commanded_steps - before.answered_steps;
  EXPECT_GT(late_before, before.commanded_steps / 4);
  std::this_thread::sleep_for(1500ms);  // the controller publishes its stats every second
  RunResult top = run_afhub({"top", "--json"});
  const WorldState after = run.fresh();
  const std::uint64_t late_after = after.commanded_steps - after.answered_steps;
  ASSERT_EQ(top.exit_code, 0) << top.err;
  const nlohmann::json loops = parse_json(top.out).at("loops");
  const nlohmann::json* loop = find_element(loops, "name", "ctl hold");
  ASSERT_NE(loop, nullptr) << "no loop named \"ctl hold\" in\n" << top.out;
  EXPECT_EQ(loop->at("pid"), controller.pid) << top.out;
  // The controller's late count is the physics' count for its body, as of its last
  // stats: between the world's counts before and after.
  const double controller_late = loop->at("late_commands").get<double>();
  EXPECT_GE(controller_late, static_cast<double>(late_before)) << top.out;
  EXPECT_LE(controller_late, static_cast<double>(late_after)) << top.out;
  RunResult status = run_afhub({"status", "--json"});
  const nlohmann::json world = parse_json(status.out).at("world");
  EXPECT_TRUE(world.at("late_steps").is_number()) << status.out;
  EXPECT_TRUE(world.at("commanded_steps").is_number()) << status.out;
  controller.stop();
  EXPECT_EQ(run.physics->stop(), 0);
}

// The rate the physics reports is the rate it steps at, with --fast too (it once said
// 562 steps/s while the world ran at about 35 000). Checked against the steps and the
// publish stamps of the world states around one rate window, not against the clock:
// a loaded machine moves the rate, never that.
TEST(FaultsCommands, TheReportedStepRateIsTheRateTheWorldSteps) {
  ArmRun run({"run", kArm, "--no-autostart", "--fast"});
  ASSERT_TRUE(run.ready()) << read_file(run.log);
  // A window closes between the last state that carries the old rate (published
  // before the window's end) and the first that carries the new one (after it). Two
  // such changes in a row enclose one whole window: its steps and its length lie
  // between what those four states say. A window lasts at least a second, so a
  // change seen within less than a second holds one window's end, not two (the
  // test's poll may stall; then it waits for the next window).
  struct Change {
    WorldState before, after;  // the last state with the old rate, the first with the new
  };
  std::optional<Change> opened, closed;
  WorldState previous = run.now();
  const auto give_up = std::chrono::steady_clock::now() + 30s;
  while (!closed && std::chrono::steady_clock::now() < give_up) {
    const WorldState state = run.now();
    if (state.achieved_rate_hz != previous.achieved_rate_hz) {
      const Change change{previous, state};
      if (opened &&
          state.header.publish_stamp_ns - previous.header.publish_stamp_ns < 1'000'000'000)
        closed = change;
      else
        opened = change;
    }
    previous = state;
    std::this_thread::sleep_for(100us);
  }
  ASSERT_TRUE(closed) << "no whole rate window seen in 30 s\n" << read_file(run.log);
  const double rate = closed->after.achieved_rate_hz;
  const auto steps = [](const WorldState& later, const WorldState& earlier) {
    return static_cast<double>(later.header.sim_step) -
           static_cast<double>(earlier.header.sim_step);
  };
  const auto seconds = [](const WorldState& later, const WorldState& earlier) {
    return static_cast<double>(later.header.publish_stamp_ns - earlier.header.publish_stamp_ns) *
           1e-9;
  };
  const double fewest = steps(closed->before, opened->after);
  const double most = steps(closed->after, opened->before);
  const double shortest_s = seconds(closed->before, opened->after);
  const double longest_s = seconds(closed->after, opened->before);
  std::printf("reported %.0f steps/s; the window: %.0f to %.0f steps in %.4f to %.4f s\n", rate,
              fewest, most, shortest_s, longest_s);
  EXPECT_GT(fewest, 0.0) << "the world did not step in a rate window";
  EXPECT_GE(rate * longest_s, fewest) << "reported " << rate << " steps/s";
  EXPECT_LE(rate * shortest_s, most) << "reported " << rate << " steps/s";
}

}  // namespace
}  // namespace afhub::test
