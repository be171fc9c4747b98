// `afhub run` end to end against a hub: the KUKA on its channels, commands that
// move it, refused NaN commands counted in the world state, the watchdog, the
// launch file with -l, the report, and real-time pacing.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "afhub/bench/arms_scene.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/run_loop.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"
#include "strict_json.hpp"
#include "threads.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const std::string kDescriptions = AFHUB_SHARED_MODELS "/descriptions/";
const std::string kKuka = kDescriptions + "multi-bodies/robots/blender-kuka.yaml";

// The physics' pacing on a clock the test drives: every step takes no time, and one
// sleep (the 100th) returns `stall_ns` late, as after a SIGSTOP or a long preemption.
// Counts the steps that then ran back to back (their deadline already past).
class StallingClock final : public LoopClock {
 public:
  explicit StallingClock(std::int64_t stall_ns) : stall_ns_(stall_ns) {}
  std::int64_t now_ns() noexcept override { return now_; }
  void sleep_until_ns(std::int64_t deadline_ns) noexcept override {
    if (deadline_ns <= now_) ++back_to_back;
    now_ = std::max(now_, deadline_ns) + (++sleeps_ == 100 ? stall_ns_ : 0);
  }
  int back_to_back = 0;

 private:
  std::int64_t now_ = 1'000'000'000'000;
  std::int64_t stall_ns_;
  int sleeps_ = 0;
};

int steps_in_a_burst_after_a_stall(OverrunPolicy policy, std::int64_t max_catch_up_ns,
                                   std::int64_t stall_ns) {
  afhub::testing::ModelFolder folder;
  const physics::Model model = physics::load_adf_files(
      {folder.write("ball.yaml", "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1\n")});
  physics::Simulation sim(model, 0.001);
  StallingClock clock(stall_ns);
  physics::RunOptions options;
  options.steps = 1000;
  options.overrun = policy;
  options.max_catch_up_ns = max_catch_up_ns;
  options.clock = &clock;
  physics::RunReport report;
  physics::run_loop(sim, nullptr, options, report);
  EXPECT_EQ(report.steps, 1000u);
  return clock.back_to_back;
}

// After a stall, the physics catches up at most --max-catch-up of steps back to back
// (beyond, it skips them), or with --overrun skip none: no burst a haptic user feels.
TEST(Run, AfterAStallThePhysicsCatchesUpBoundedOrSkips) {
  // 50 ms behind: caught up step by step, within the default 100 ms bound.
  EXPECT_EQ(steps_in_a_burst_after_a_stall(OverrunPolicy::kCatchUp, 100'000'000, 50'000'000), 50);
  // 5 s behind: beyond the bound, skipped rather than 5000 steps in a burst.
  EXPECT_EQ(steps_in_a_burst_after_a_stall(OverrunPolicy::kCatchUp, 100'000'000, 5'000'000'000), 0);
  // A tighter bound, or skipping, for haptics.
  EXPECT_EQ(steps_in_a_burst_after_a_stall(OverrunPolicy::kCatchUp, 10'000'000, 50'000'000), 0);
  EXPECT_EQ(steps_in_a_burst_after_a_stall(OverrunPolicy::kSkip, 100'000'000, 50'000'000), 0);
  EXPECT_EQ(steps_in_a_burst_after_a_stall(OverrunPolicy::kSkip, 100'000'000, 2'000'000), 0);
}

// The CPU time this thread used while `wait` ran, in ms, and the times it slept
// (voluntary context switches: a block on a futex; a yield or a preemption is none).
struct ThreadUse {
  double cpu_ms = 0.0;
  long sleeps = 0;
};
template <class Wait>
ThreadUse thread_use(Wait&& wait) {
  auto cpu_ns = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) * 1e9 + static_cast<double>(t.tv_nsec);
  };
  auto sleeps = [] {
    rusage usage{};
    getrusage(RUSAGE_THREAD, &usage);
    return usage.ru_nvcsw;
  };
  const double before = cpu_ns();
  const long slept_before = sleeps();
  wait();
  return {(cpu_ns() - before) * 1e-6, sleeps() - slept_before};
}

// A lockstep step waiting for an answer that does not come sleeps on the command
// channels (a futex) instead of spinning: over a 300 ms wait it uses almost no CPU,
// where --spin polls all along (under SCHED_FIFO, starving the client it waits for).
// An answer wakes it: the step goes ahead with no answer counted late.
// A step's body states carry one publish stamp (one clock read a step, not one a body),
// which grows from step to step.
TEST(Run, AStepsStatesShareOnePublishStampThatGrowsByStep) {
  afhub::testing::ModelFolder folder;
  const physics::Model model = physics::load_adf_files(
      {folder.write("balls.yaml",
                    "bodies: [BODY a, BODY b]\nnamespace: /test/stamp/\n"
                    "BODY a:\n  name: a\n  mass: 1\nBODY b:\n  name: b\n  mass: 1\n")});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 5.0);
  BodyClient a(model.bodies[0].channel), b(model.bodies[1].channel);
  auto step_stamps = [&](std::uint64_t step) -> std::pair<std::int64_t, std::int64_t> {
    std::pair<std::int64_t, std::int64_t> stamps{0, -1};
    wait_until(
        [&] {
          channels.publish({});
          const BodyState* of_a = a.latest_state();
          const BodyState* of_b = b.latest_state();
          if (!of_a || !of_b || of_a->header.sim_step != step || of_b->header.sim_step != step)
            return false;
          stamps = {of_a->header.publish_stamp_ns, of_b->header.publish_stamp_ns};
          return true;
        },
        5s);
    return stamps;
  };
  sim.step();
  const auto first = step_stamps(1);
  EXPECT_GT(first.first, 0);
  EXPECT_EQ(first.first, first.second);
  sim.step();
  const auto second = step_stamps(2);
  EXPECT_EQ(second.first, second.second);
  EXPECT_GT(second.first, first.first);
}

// `count` eight-link arms stepped and on their channels; two solver threads.
struct ArmsOnChannels {
  explicit ArmsOnChannels(int count)
      : model(physics::load_adf_files(
            {folder.write("arms.yaml", afhub::bench::arms_scene(count, 8))})),
        sim(model, 0.001),
        channels(sim, 5.0) {}
  afhub::testing::ModelFolder folder;
  const physics::Model model;
  physics::Simulation sim;
  physics::SimChannels channels;
};

// A thousand bodies' states are written by two threads at once, the stepping thread and
// the islands' helper (SimChannels::publish, Simulation::share): each body's state holds
// its own readings of the newest step, under the step's one stamp.
TEST(Run, AThousandStatesWrittenByTwoThreadsAreEachTheirBodysReadings) {
  if (!afhub::testing::may_run_on_two_cpus())
    GTEST_SKIP() << "this process may run on one CPU: no helper to test";
  ArmsOnChannels arms(125);
  const physics::Model& model = arms.model;
  physics::Simulation& sim = arms.sim;
  physics::SimChannels& channels = arms.channels;
  std::vector<std::unique_ptr<BodyClient>> clients;
  for (const physics::BodySpec& body : model.bodies)
    clients.push_back(std::make_unique<BodyClient>(body.channel));
  for (int step = 0; step < 50; ++step) {  // falling under gravity: every reading moves
    sim.step();
    channels.publish({});
  }
  // Until every reader has found its body's slot, in which it then reads each update.
  ASSERT_TRUE(wait_until(
      [&] {
        channels.publish({});
        return std::all_of(clients.begin(), clients.end(),
                           [&](auto& client) { return client->latest_state() != nullptr; });
      },
      10s));
  const auto reading = std::make_unique<physics::BodyReading>();
  std::uint64_t by_helper = 0;  // of the states' blocks
  // Each step published once; more than 5 if a loaded machine kept the helper away.
  for (int step = 0; step < 5 || (by_helper == 0 && step < 100); ++step) {
    sim.step();
    const std::uint64_t before = sim.items_shared_with_helper();
    channels.publish({});
    by_helper += sim.items_shared_with_helper() - before;
    const std::int64_t stamp = clients[0]->latest_state()->header.publish_stamp_ns;
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      const BodyState& state = *clients[b]->latest_state();
      sim.read_body(b, *reading);
      SCOPED_TRACE(model.bodies[b].channel);
      ASSERT_EQ(state.header.sim_step, sim.step_count());
      EXPECT_EQ(state.header.publish_stamp_ns, stamp);
      EXPECT_EQ(std::memcmp(&state.pose, &reading->pose, sizeof state.pose), 0);
      EXPECT_EQ(std::memcmp(&state.twist, &reading->twist, sizeof state.twist), 0);
      ASSERT_EQ(state.joint_count, reading->joint_count);
      for (std::uint32_t j = 0; j < state.joint_count; ++j) {
        EXPECT_EQ(state.joints[j].position, reading->joint_positions[j]) << "joint " << j;
        EXPECT_EQ(state.joints[j].velocity, reading->joint_velocities[j]) << "joint " << j;
      }
    }
  }
  EXPECT_GT(by_helper, 0u) << "the helper wrote no state in 100 steps: nothing was compared";
}

// A paused world publishes its held step again every period without stepping; those
// states are written by the stepping thread alone, so the islands' helper, given no
// work, stops napping after 20 ms and sleeps until the next step (on a futex).
TEST(Run, WhileTheWorldIsPausedTheIslandsHelperSleeps) {
  if (!afhub::testing::may_run_on_two_cpus())
    GTEST_SKIP() << "this process may run on one CPU: no helper to test";
  ArmsOnChannels arms(32);  // 256 states: 16 blocks, enough to be shared
  physics::Simulation& sim = arms.sim;
  physics::SimChannels& channels = arms.channels;
  for (int step = 0; step < 20; ++step) {
    sim.step();
    channels.publish({});
  }
  ASSERT_GT(sim.islands_solved_by_helper(), 0u) << "no helper";
  const pid_t helper = afhub::testing::thread_named("afhub-islands");
  ASSERT_NE(helper, 0);
  // Its system call as /proc shows it: the first field is the call's number.
  auto in_futex = [&] {
    std::ifstream file("/proc/self/task/" + std::to_string(helper) + "/syscall");
    long call = -1;
    file >> call;
    return call == SYS_futex;
  };
  // Paused: published every 1 ms. Asleep after 20 ms; a loaded machine may take longer.
  const auto start = std::chrono::steady_clock::now();
  bool slept = false;
  while (!slept && std::chrono::steady_clock::now() - start < 2s) {
    channels.publish({});
    std::this_thread::sleep_for(1ms);
    slept = std::chrono::steady_clock::now() - start > 30ms && in_futex();
  }
  EXPECT_TRUE(slept) << "the helper was not asleep in 2 s of a paused world's publishing";
}

TEST(Run, LockstepWaitsAsleepUnlessSpinning) {
  afhub::testing::ModelFolder folder;
  const physics::Model model =
      physics::load_adf_files({folder.write("ball.yaml",
                                            "bodies: [BODY ball]\nnamespace: /test/sleep/\n"
                                            "BODY ball:\n  name: ball\n  mass: 1\n")});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 5.0);
  BodyClient client(model.bodies[0].channel);
  auto answer = [&] {
    channels.publish({});
    const BodyState* state = client.latest_state();
    BodyCommand* command = client.loan_command(0);
    if (!state || !command) return false;
    command->header.sim_step = state->header.sim_step;
    command->lockstep = 1;
    client.publish_command(command);
    return true;
  };
  for (bool spin : {false, true}) {
    physics::LockstepOptions options;
    options.client_timeout_ns = 300'000'000;
    options.max_misses = 1000;
    options.spin = spin;
    channels.enable_lockstep(options);
    ASSERT_TRUE(wait_until([&] { return answer() && channels.await_lockstep(); }, 5s));
    ASSERT_EQ(channels.lockstep_clients(), 1u);
    sim.step();
    channels.publish({});
    const std::uint64_t late = channels.late_answers();
    const ThreadUse use = thread_use([&] { channels.await_lockstep(); });  // no answer: 300 ms
    EXPECT_EQ(channels.late_answers(), late + 1);
    // Counted, not timed: how much CPU a spin gets depends on the machine's load, but
    // a spin never sleeps and a sleeping wait does.
    std::printf("a 300 ms wait, %s: %.1f ms of CPU, %ld sleeps\n", spin ? "spinning" : "asleep",
                use.cpu_ms, use.sleeps);
    if (spin) {
      EXPECT_EQ(use.sleeps, 0) << "spinning";
    } else {
      EXPECT_GE(use.sleeps, 1) << "asleep";
      // A tenth of the wait: each wake-up costs more CPU on a loaded machine (a CI run
      // beside the sanitizers' build took 16.5 ms over 253 wake-ups), a spin all it gets
      // (51 ms in that run).
      EXPECT_LT(use.cpu_ms, 30.0) << "asleep";
    }
    // An answer from another thread ends the wait before the timeout.
    sim.step();
    std::thread answering([&] {
      std::this_thread::sleep_for(20ms);
      if (BodyCommand* command = client.loan_command(0)) {
        command->header.sim_step = sim.step_count();
        command->lockstep = 1;
        client.publish_command(command);
      }
    });
    channels.publish({});
    channels.await_lockstep();
    answering.join();
    EXPECT_EQ(channels.late_answers(), late + 1) << (spin ? "spinning" : "asleep");
  }
}

TEST(Run, AStepHandsOffOnlyBehindItsGridAndWithTimeToSpare) {
  constexpr std::int64_t kDue = 5'000'000'000, kPeriod = 1'000'000;
  const physics::PreviousStep on_time{kDue - kPeriod + 30'000, 25'000};
  EXPECT_FALSE(physics::hands_off(kDue, kDue + 60'000, on_time, kPeriod)) << "on its grid";
  EXPECT_TRUE(physics::hands_off(kDue, kDue + 3'000'000, on_time, kPeriod)) << "woke 3 ms late";
  EXPECT_FALSE(physics::hands_off(kDue, kDue + 200'000, on_time, kPeriod)) << "0.2 ms: in bounds";
  const physics::PreviousStep catching_up{kDue + 10'000, 25'000};
  EXPECT_TRUE(physics::hands_off(kDue, kDue + 12'000, catching_up, kPeriod))
      << "the step before ended after this one was due";
  const physics::PreviousStep overloaded{kDue + 60'000, 1'050'000};
  EXPECT_FALSE(physics::hands_off(kDue, kDue + 62'000, overloaded, kPeriod))
      << "its own steps fill the period";
  EXPECT_FALSE(physics::hands_off(kDue, kDue + 5'000'000, {kDue - 400'000, 201'000}, kPeriod))
      << "a step longer than the hand-off";
}

// Catching up, a step waits for the answer of a controller in phase (its commands in
// time) to the state before it; a controller that misses that wait kPhaseMisses times
// in a row is not waited for again until a command of its is in time again. Judged by
// the physics' own count of commands in time: a step taken without waiting misses an
// answer sent 20 ms later.
TEST(Run, CatchingUpAStepWaitsForTheControllersInPhaseUntilOneMissesAFewTimesInARow) {
  afhub::testing::ModelFolder folder;
  const physics::Model model =
      physics::load_adf_files({folder.write("ball.yaml",
                                            "bodies: [BODY ball]\nnamespace: /test/phase/\n"
                                            "BODY ball:\n  name: ball\n  mass: 1\n")});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 5.0);
  BodyClient client(model.bodies[0].channel);
  auto send = [&](std::uint64_t step) {
    BodyCommand* command = client.loan_command(0);
    ASSERT_NE(command, nullptr);
    command->header.sim_step = step;
    client.publish_command(command);
  };
  // The next step, its command applied after `wait`: whether it was in time.
  auto step_in_time = [&](const std::function<void()>& wait) {
    wait();
    channels.apply_commands(monotonic_ns());
    sim.step();
    const std::uint64_t answered = channels.answered_steps();
    channels.publish({});
    return channels.answered_steps() == answered + 1;
  };
  auto answer_later = [&](std::uint64_t step) {
    return std::thread([&, step] {
      std::this_thread::sleep_for(20ms);
      send(step);
    });
  };
  // In phase: a command in time (once the physics has found the command's writer).
  auto in_time_once_found = [&] {
    return wait_until(
        [&] {
          send(sim.step_count());
          return step_in_time([] {});
        },
        5s);
  };
  channels.publish({});
  ASSERT_TRUE(in_time_once_found());

  std::thread answering = answer_later(sim.step_count());
  EXPECT_TRUE(step_in_time([&] { channels.await_answers_in_phase(5'000'000'000); }))
      << "the step waited for the answer";
  answering.join();
  // No answer: the wait ends at its timeout, and the step is late.
  EXPECT_FALSE(step_in_time([&] { channels.await_answers_in_phase(30'000'000); }));
  // One miss (a controller woken by the same stall, a moment after the physics): still
  // waited for, and its answer in time clears the miss.
  answering = answer_later(sim.step_count());
  EXPECT_TRUE(step_in_time([&] { channels.await_answers_in_phase(5'000'000'000); }))
      << "waited for after one miss";
  answering.join();
  for (int miss = 0; miss < physics::SimChannels::kPhaseMisses; ++miss)
    EXPECT_FALSE(step_in_time([&] { channels.await_answers_in_phase(30'000'000); }));
  // Out of phase now: not waited for.
  answering = answer_later(sim.step_count());
  EXPECT_FALSE(step_in_time([&] { channels.await_answers_in_phase(5'000'000'000); }));
  answering.join();
  // A command in time puts it back in phase.
  ASSERT_TRUE(in_time_once_found());
  answering = answer_later(sim.step_count());
  EXPECT_TRUE(step_in_time([&] { channels.await_answers_in_phase(5'000'000'000); }));
  answering.join();
}

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
  EXPECT_EQ(parse_json(status.out).at("world").at("rejected_commands"), 1) << status.out;

  // Position commands every 5 ms for 2 s of simulated time bring every joint to its
  // target (counted in the world's steps: a loaded machine may run it behind real time).
  const double targets[7] = {0.4, -0.3, 0.2, 0.5, -0.4, 0.3, 0.6};
  const std::uint64_t until = world.latest()->header.sim_step + 2000;
  const auto give_up = std::chrono::steady_clock::now() + 60s;
  while (world.latest()->header.sim_step < until) {
    ASSERT_LT(std::chrono::steady_clock::now(), give_up) << "the world stopped stepping";
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
    EXPECT_TRUE(parse_json(physics::report_json(report, sim)).at("nan_recoveries").is_number())
        << stop;
  }
}

// The project's own launch file: check takes it as run does, and neither loads the world
// alone when no model is picked.
// Two pendulums swinging from a fixed base under gravity: a long, heavy, slow one and
// a short, light one that swings fast, whose pivots drift apart most: the report names
// it, and when.
std::string two_pendulums(const afhub::testing::ModelFolder& folder) {
  std::string text =
      "bodies: [BODY base, BODY long, BODY short]\n"
      "joints: [JOINT base-long, JOINT base-short]\n"
      "ignore inter-collision: true\n"
      "BODY base:\n  name: base\n  mass: 0\n";
  auto pendulum = [&](const std::string& name, double x, double length, double mass) {
    const std::string half = std::to_string(length / 2);
    text += "BODY " + name + ":\n  name: " + name + "\n  mass: " + std::to_string(mass) +
            "\n  location: {position: {x: " + std::to_string(x) + ", y: " + half +
            ", z: 0}}\n  shape: box\n  geometry: {x: 0.02, y: " + std::to_string(length) +
            ", z: 0.02}\n";
    text += "JOINT base-" + name + ":\n  name: base-" + name +
            "\n  parent: BODY base\n  child: BODY " + name +
            "\n  parent pivot: {x: " + std::to_string(x) +
            ", y: 0, z: 0}\n  parent axis: {x: 1, y: 0, z: 0}\n" + "  child pivot: {x: 0, y: -" +
            half + ", z: 0}\n  child axis: {x: 1, y: 0, z: 0}\n" + "  type: revolute\n";
  };
  pendulum("long", 0.0, 1.0, 5.0);
  pendulum("short", 1.0, 0.1, 0.1);
  return folder.write("pendulums.yaml", text);
}

TEST(Run, TheReportAndTheEndLineNameTheWorstJointItsErrorAndStep) {
  afhub::testing::ModelFolder folder;
  const std::string pendulums = two_pendulums(folder);
  const physics::Model model = physics::load_adf_files({pendulums});
  physics::Simulation sim(model, 0.001);
  physics::RunOptions options;
  options.fast = true;
  options.steps = 400;
  physics::RunReport report;
  physics::run_loop(sim, nullptr, options, report);

  const std::optional<std::size_t> worst = physics::worst_joint(report);
  ASSERT_TRUE(worst.has_value());
  const physics::JointError& error = report.joint_errors.at(*worst);
  EXPECT_EQ(model.joints[*worst].channel, "ambf/env/base-short");
  EXPECT_EQ(error.max_m, report.max_joint_error_m);
  EXPECT_GT(error.max_m, report.joint_errors.at(1 - *worst).max_m);
  EXPECT_GT(error.step, 0u);
  // The same world stepped to that step again has that joint's pivots that far apart.
  physics::Simulation replay(model, 0.001);
  for (std::uint64_t step = 0; step < error.step; ++step) replay.step();
  EXPECT_EQ(replay.joint_pivot_gap_m(*worst), error.max_m);

  const nlohmann::json json = parse_json(physics::report_json(report, sim));
  const nlohmann::json& named = json.at("worst_joint");
  EXPECT_EQ(named.at("name"), "ambf/env/base-short");
  EXPECT_EQ(named.at("max_pivot_gap_m").get<double>(), error.max_m);
  EXPECT_EQ(named.at("step"), error.step);
  for (const std::string joint : {"ambf/env/base-long", "ambf/env/base-short"}) {
    const nlohmann::json& entry = json.at("joints").at(joint);
    EXPECT_GT(entry.at("max_pivot_gap_m").get<double>(), 0.0) << joint;
    EXPECT_LE(entry.at("max_pivot_gap_m").get<double>(), error.max_m) << joint;
    EXPECT_LE(entry.at("max_pivot_gap_step").get<std::uint64_t>(), 400u) << joint;
  }

  // `afhub run` says the same at its end.
  RunResult run = run_afhub({"run", pendulums, "--offline", "--fast", "--steps", "400"}, 60s);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(contains(run.err, "afhub run: 400 steps; largest joint error ")) << run.err;
  EXPECT_TRUE(contains(run.err, ", at ambf/env/base-short at step " + std::to_string(error.step)))
      << run.err;
}

TEST(Run, AtPlacesAFileAndRefusesBadValues) {
  afhub::testing::ModelFolder folder;
  const std::string pendulums = two_pendulums(folder);
  const std::string report = (folder.dir() / "report.json").string();
  RunResult placed = run_afhub({"run", pendulums, "--at", pendulums + "=0,2,5", "--offline",
                                "--fast", "--steps", "1", "--report", report},
                               60s);
  ASSERT_EQ(placed.exit_code, 0) << placed.err;
  const nlohmann::json base = parse_json(read_file(report)).at("bodies").at("ambf/env/base");
  EXPECT_EQ(base.at("position"), nlohmann::json::array({0.0, 2.0, 5.0}));
  for (const auto& [at, error] : std::vector<std::pair<std::string, std::string>>{
           {pendulums + "=0,2", "--at takes FILE=x,y,z or FILE=x,y,z,r,p,y"},
           {folder.dir().string() + "/other.yaml=0,2,5", "--at names '"}}) {
    RunResult bad = run_afhub({"run", pendulums, "--at", at, "--offline", "--steps", "1"}, 60s);
    EXPECT_EQ(bad.exit_code, 1) << at;
    EXPECT_TRUE(contains(bad.err, error)) << bad.err;
  }
}

// --reduced-coordinates: the arm's chain on its static mount becomes a multibody, the
// remote-centre-of-motion arm's loops stay as they were, and `run` says which.
TEST(Run, ReducedCoordinatesTakeTheOpenChainsAndSaySo) {
  afhub::testing::ModelFolder folder;
  const std::string report = (folder.dir() / "report.json").string();
  RunResult run = run_afhub(
      {"run", AFHUB_EXAMPLE_MODELS "/arm7.yaml", AFHUB_EXAMPLE_MODELS "/rcm.yaml",
       "--reduced-coordinates", "--offline", "--fast", "--steps", "300", "--report", report},
      60s);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(contains(run.err, "afhub run: 8 of 17 bodies in reduced coordinates")) << run.err;
  const nlohmann::json joints = parse_json(read_file(report)).at("joints");
  // A joint coordinate cannot open; the loops' joints can, a little.
  EXPECT_EQ(joints.at("afhub/arm/link3-link4").at("max_pivot_gap_m").get<double>(), 0.0);
  double loops = 0;
  for (const auto& [name, joint] : joints.items())
    if (name.rfind("afhub/rcm/", 0) == 0)
      loops = std::max(loops, joint.at("max_pivot_gap_m").get<double>());
  EXPECT_GT(loops, 0.0);
}

TEST(Run, CheckAndRunTakeALaunchFileAndRefuseItWithNoModelPicked) {
  const std::string launch = AFHUB_EXAMPLE_MODELS "/launch.yaml";
  RunResult picked = run_afhub({"check", "--launch", launch, "-l", "0,2"}, 60s);
  EXPECT_EQ(picked.exit_code, 0) << picked.err;
  EXPECT_TRUE(contains(picked.out + picked.err, "arm")) << picked.out;
  // -l repeated, or with spaces, picks the same (both were refused); check takes -a as
  // run does (it was refused).
  for (const std::vector<std::string>& same :
       {std::vector<std::string>{"check", "--launch", launch, "-l", "0", "-l", "2"},
        std::vector<std::string>{"check", "--launch", launch, "-l", "0, 2"}}) {
    RunResult again = run_afhub(same, 60s);
    EXPECT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(again.out, picked.out) << again.err;
  }
  const std::string arm = AFHUB_EXAMPLE_MODELS "/arm7.yaml",
                    gripper = AFHUB_EXAMPLE_MODELS "/gripper.yaml";
  RunResult listed = run_afhub({"check", "-a", arm + "," + gripper}, 60s);
  RunResult given = run_afhub({"check", arm, gripper}, 60s);
  EXPECT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_EQ(listed.out, given.out) << listed.err;
  EXPECT_TRUE(contains(listed.out, "afhub/gripper/palm")) << listed.out;
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"check", "--launch", launch},
        std::vector<std::string>{"run", "--launch", launch, "--offline"}}) {
    RunResult unpicked = run_afhub(args, 60s);
    EXPECT_EQ(unpicked.exit_code, 1) << args[0];
    EXPECT_TRUE(contains(unpicked.err, "no model picked from 'multibody configs': give -l"))
        << unpicked.err;
    EXPECT_TRUE(contains(unpicked.err, "  2: ./gripper.yaml")) << unpicked.err;
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
  const std::string text = read_file(report);
  const nlohmann::json json = parse_json(text);
  EXPECT_EQ(json.at("steps"), 2000) << text;  // the run's, not a joint tracking's "steps"
  EXPECT_NEAR(json.at("sim_time_s").get<double>(), 2.0, 1e-9);
  // Absolute deadlines: never faster than real time. (How much slower depends on this
  // shared machine's load, so it is not asserted; the pacing itself is tested on an
  // injected clock in tests/rt/periodic_loop_test.cpp.)
  EXPECT_GE(json.at("wall_time_s").get<double>(), 1.999);
  EXPECT_LT(json.at("max_joint_error_m").get<double>(), 0.002);
  EXPECT_EQ(json.at("nan_detected"), false) << text;
  const nlohmann::json& l1 = json.at("bodies").at("ambf/env/l1");
  EXPECT_EQ(l1.at("position").size(), 3u) << text;
  EXPECT_EQ(l1.at("quaternion").size(), 4u) << text;
  EXPECT_TRUE(json.at("bodies").contains("ambf/env/Plane")) << text;
  EXPECT_TRUE(json.at("joints").at("ambf/env/l1-l4").at("position").is_number()) << text;
  for (const char* key : {"max", "p50", "p99"})
    EXPECT_TRUE(json.at("step_time_us").at(key).is_number()) << key << " in " << text;
}

TEST(Run, MissingModelOfALaunchFileIsReportedWhereItIsListed) {
  SKIP_WITHOUT_SHARED_MODELS();
  RunResult run =
      run_afhub({"run", "--launch", kDescriptions + "launch.yaml", "-l", "3", "--offline"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.err,
                       "launch.yaml:10:5: error: multibody config #3 "
                       "'./multi-bodies/robots/blender-raven2.yaml': "))
      << run.err;
  EXPECT_TRUE(contains(run.err, "blender-raven2.yaml does not exist")) << run.err;
  RunResult beyond =
      run_afhub({"run", "--launch", kDescriptions + "launch.yaml", "-l", "40", "--offline"});
  EXPECT_EQ(beyond.exit_code, 1);
  EXPECT_TRUE(contains(beyond.err, "model index 40 (-l) is beyond 'multibody configs'"))
      << beyond.err;
  // A launch file with no -l would load its world alone: refused, listing what to pick.
  RunResult unpicked = run_afhub({"run", "--launch", kDescriptions + "launch.yaml", "--offline"});
  EXPECT_EQ(unpicked.exit_code, 1);
  EXPECT_TRUE(contains(unpicked.err, "no model picked from 'multibody configs': give -l"))
      << unpicked.err;
  EXPECT_TRUE(contains(unpicked.err, "\n  3: ./multi-bodies/robots/blender-raven2.yaml"))
      << unpicked.err;
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

// The same model twice (issue 18): the copy gets its own channels, named as AMBF
// names copies (an index after each body's name), both move, and `afhub ls` lists them.
TEST(Run, TheSameModelTwiceRunsAsTwoSetsOfChannelsThatLsShows) {
  const std::string arm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";
  afhub::testing::ModelFolder folder;
  const std::string log = (folder.dir() / "run.log").string();
  ScopedProcess physics(spawn_afhub({"run", arm, arm, "--no-autostart"}, log));
  BodyClient first("afhub/arm/base"), copy("afhub/arm/base1");
  // A bound on a hang only: on a machine loaded to 30 runnable threads (a fresh run
  // without the corpus, beside builds), the two arms took more than 10 s to publish.
  ASSERT_TRUE(wait_until([&] { return first.latest_state() && copy.latest_state(); }, 60s))
      << read_file(log);
  EXPECT_EQ(copy.latest_state()->joint_count, first.latest_state()->joint_count);
  RunResult ls;  // the hub's catalog follows the physics' directory within its period
  wait_until([&] { return contains((ls = run_afhub({"ls"})).out, "afhub/arm/link71 "); }, 10s);
  ASSERT_EQ(ls.exit_code, 0) << ls.err;
  for (const char* channel : {"afhub/arm/base ", "afhub/arm/base1 ", "afhub/arm/link71 "})
    EXPECT_TRUE(contains(ls.out, channel)) << channel << " in " << ls.out;
  EXPECT_EQ(physics.stop(), 0);
  EXPECT_TRUE(contains(read_file(log), "arm7.yaml:1:1: warning: ")) << read_file(log);
}

// The PR2 grippers name their sensor's and actuator's parent qualified
// ("/ambf/env/BODY r_gripper_palm_link"), and the two share block names.
TEST(Run, CheckAcceptsThePr2GrippersAloneAndTogether) {
  SKIP_WITHOUT_SHARED_MODELS();
  const std::string grippers = kDescriptions + "multi-bodies/grippers/";
  RunResult small = run_afhub({"check", grippers + "pr2 gripper small.yaml"}, 60s);
  EXPECT_EQ(small.exit_code, 0) << small.err;
  RunResult both = run_afhub(
      {"check", grippers + "pr2 gripper small.yaml", grippers + "pr2 gripper small red.yaml"}, 60s);
  EXPECT_EQ(both.exit_code, 0) << both.err;
}

}  // namespace
}  // namespace afhub::test
