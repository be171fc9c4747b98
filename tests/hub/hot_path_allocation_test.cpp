// The steady-state loop (publish state, read command; read state, write command;
// and the physics step between them) must not touch the heap. Every operator new and, outside
// sanitizer builds, every malloc of the loop's thread is counted while the loop runs
// (support/heap_counter.cpp, support/malloc_counter.cpp).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <thread>

#include "afhub/bench/arms_scene.hpp"
#include "afhub/controllers/joint_targets.hpp"
#include "afhub/devices/driver_loop.hpp"
#include "afhub/devices/virtual_device.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/device_tape.hpp"
#include "afhub/hub/loop_stats_publisher.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/sim_channels.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/teleop/teleop_process.hpp"
#include "afhub_process.hpp"
#include "heap_counter.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"
#include "threads.hpp"

namespace afhub {
namespace {

// This thread's heap allocations in the last count_allocations: iceoryx and sanitizer
// threads run beside it.
long g_allocations = 0;

// Runs `cycle` `count` times counting heap allocations; false if a cycle failed.
template <class Cycle>
bool count_allocations(int count, Cycle&& cycle) {
  const long before = test::thread_heap_allocations();
  bool all_ok = true;
  for (int i = 0; i < count; ++i) all_ok = cycle() && all_ok;
  g_allocations = test::thread_heap_allocations() - before;
  return all_ok;
}

using namespace std::chrono_literals;

TEST(HotPath, CountsAllocationsWhenThereAreSome) {
  // The counter itself must see an allocation, or a zero below would prove nothing.
  // (A direct call: the compiler may elide a new-expression, not this.)
  long before = test::thread_heap_allocations();
  void* probe = ::operator new(16);
  const long counted = test::thread_heap_allocations() - before;
  ::operator delete(probe);
  EXPECT_EQ(counted, 1);
#if !defined(AFHUB_SANITIZED)
  // And malloc, through a pointer the compiler cannot see through.
  void* (*volatile allocate)(std::size_t) = std::malloc;
  before = test::thread_heap_allocations();
  void* block = allocate(16);
  const long counted_malloc = test::thread_heap_allocations() - before;
  std::free(block);
  EXPECT_EQ(counted_malloc, 1);
#endif
}

TEST(HotPath, SteadyStateLoopDoesNotAllocate) {
  BodyPublisher physics("test/hot_path");
  BodyClient controller("test/hot_path");
  auto one_cycle = [&](std::uint64_t step) {
    BodyState* state = physics.loan_state(7);
    if (!state) return false;
    state->header.sim_step = step;
    state->joint_count = 7;
    state->joints[6].position = static_cast<double>(step);
    physics.publish_state(state);
    const BodyState* seen = controller.latest_state();
    BodyCommand* command = controller.loan_command(kMaxJointsPerBody);
    if (!seen || !command) return false;
    command->header.sim_step = seen->header.sim_step;
    command->joint_count = 7;
    command->joints[6].value = seen->joints[6].position;
    controller.publish_command(command);
    return physics.latest_command() != nullptr;
  };
  // Warm-up: subscriptions settle and first-use paths run.
  ASSERT_TRUE(test::wait_until([&] { return one_cycle(0); }, 2s));
  for (std::uint64_t step = 1; step < 100; ++step) ASSERT_TRUE(one_cycle(step));

  constexpr int kCycles = 10000;
  std::uint64_t step = 100;
  EXPECT_TRUE(count_allocations(kCycles, [&] { return one_cycle(step++); }));
  EXPECT_EQ(g_allocations, 0) << "heap allocations in " << kCycles << " steady-state cycles";
  EXPECT_EQ(physics.latest_command()->joints[6].value, static_cast<double>(100 + kCycles - 1));
}

// The physics loop of `afhub run`: commands in, Bullet step (joint PID, closed
// loops), states and world state out, and a controller reading `body`'s state and
// writing position commands. `helped`: the world's islands are solved by two threads,
// and unless `taped` (a recorder reads the step tape, written by one thread) the states
// are written by both. `reduced`: open chains in reduced coordinates.
void expect_physics_loop_allocation_free(const std::vector<std::string>& files,
                                         const std::string& body, bool helped = false,
                                         bool taped = true, bool reduced = false) {
  physics::Model model = physics::load_adf_files(files);
  model.world.reduced_coordinates = reduced;
  physics::Simulation sim(model, 0.001);
  if (reduced) {
    ASSERT_GT(sim.links_in_reduced_coordinates(), 0u);
  }
  physics::SimChannels channels(sim, 0.5);
  BodyClient controller(body);
  // A viewer reading the pose feed, which then goes out every ~17 cycles of 1 ms.
  LatestReader<ScenePoses> viewer(
      {std::string(kService), world_instance(), std::string(kScenePosesEvent)});
  // A recorder reading the step tape, which then goes out every step.
  std::optional<StepTapeReader> recorder;
  if (taped) recorder.emplace(world_instance());
  const auto tape = std::make_unique<StepTape>();
  int cycle = 0;
  std::uint64_t viewer_updates = 0, taped_steps = 0;
  auto one_cycle = [&]() {
    channels.apply_commands(monotonic_ns());
    sim.step();
    channels.publish({});
    channels.publish_view(std::int64_t{++cycle} * 1'000'000);
    channels.prepare_next_step();
    if (viewer.latest() && viewer.updated()) ++viewer_updates;
    while (recorder && recorder->next(*tape)) taped_steps += tape->last_part;
    const BodyState* state = controller.latest_state();
    BodyCommand* command = controller.loan_command(kMaxJointsPerBody);
    if (!state || !command) return false;
    command->joint_count = state->joint_count;
    for (std::uint32_t j = 0; j < state->joint_count; ++j) {
      command->joints[j].type = JointCommandType::kPosition;
      command->joints[j].value = 0.3 * std::sin(1e-3 * static_cast<double>(sim.step_count()) + j);
    }
    controller.publish_command(command);
    return true;
  };
  ASSERT_TRUE(test::wait_until([&] { return one_cycle(); }, 2s));
  // First contacts, first commands: one period of the commanded motion (2 pi s), so
  // that Bullet's contact and island arrays have grown to what the motion needs.
  for (int i = 0; i < 6300; ++i) ASSERT_TRUE(one_cycle());

  constexpr int kCycles = 5000;
  const std::uint64_t updates_before = viewer_updates, taped_before = taped_steps;
  const std::uint64_t helped_before = sim.islands_solved_by_helper();
  const std::uint64_t shared_before = sim.items_shared_with_helper();
  // The solve's helper thread (physics/src/parallel_islands.hpp) counts too.
  std::atomic<long> helper_allocations{0};
  if (helped) {
    const pid_t helper = afhub::testing::thread_named("afhub-islands");
    ASSERT_NE(helper, 0) << "no thread afhub-islands: the islands are solved by one thread";
    test::count_allocations_of_thread(helper, &helper_allocations);
  }
  EXPECT_TRUE(count_allocations(kCycles, one_cycle));
  test::count_allocations_of_thread(0, nullptr);
  EXPECT_EQ(g_allocations, 0) << "heap allocations in " << kCycles << " physics cycles";
  EXPECT_EQ(helper_allocations.load(), 0) << "by the helper, in " << kCycles << " physics cycles";
  if (helped) {
    EXPECT_GT(sim.islands_solved_by_helper(), helped_before) << "the helper solved no island";
    if (!taped) {
      EXPECT_GT(sim.items_shared_with_helper(), shared_before) << "the helper wrote no state";
    }
  }
  EXPECT_GE(viewer_updates - updates_before, 290u) << "the pose feed went out at 60 Hz";
  EXPECT_EQ(taped_steps - taped_before, recorder ? static_cast<std::uint64_t>(kCycles) : 0u)
      << "the step tape";
  EXPECT_TRUE(sim.all_finite());
  EXPECT_EQ(channels.rejected_commands(), 0u);
}

// The example arm, and the remote-centre-of-motion arm with its closed loops and
// prismatic insertion.
TEST(HotPath, PhysicsLoopDoesNotAllocate) {
  expect_physics_loop_allocation_free(
      {AFHUB_EXAMPLE_MODELS "/arm7.yaml", AFHUB_EXAMPLE_MODELS "/rcm.yaml"}, "afhub/arm/base");
}

// Sixteen arms of eight links, sixteen islands solved by two threads
// (physics/src/parallel_islands.hpp), with a recorder; then 32 arms without one, whose
// two threads also share the joints' readings and the states.
TEST(HotPath, PhysicsLoopOfManyArmsSolvedByTwoThreadsDoesNotAllocate) {
  if (!afhub::testing::may_run_on_two_cpus())
    GTEST_SKIP() << "this process may run on one CPU: no helper to test";
  const testing::ModelFolder folder;
  expect_physics_loop_allocation_free({folder.write("arms.yaml", bench::arms_scene(16, 8))},
                                      "arms/a0l0", true, true);
  // 256 states: enough blocks of them to be shared (ParallelIslands::kMinItems).
  expect_physics_loop_allocation_free({folder.write("arms32.yaml", bench::arms_scene(32, 8))},
                                      "arms/a0l0", true, false);
}

// The arms as chains in reduced coordinates (physics/src/sim_chains.cpp), with the
// example arm, its loops and its prismatic insertion beside them (in maximal
// coordinates: the islands of both kinds solved in one step).
TEST(HotPath, PhysicsLoopOfArmsInReducedCoordinatesDoesNotAllocate) {
  const testing::ModelFolder folder;
  expect_physics_loop_allocation_free(
      {folder.write("arms.yaml", bench::arms_scene(16, 8)), AFHUB_EXAMPLE_MODELS "/rcm.yaml"},
      "arms/a0l0", false, true, true);
}

// The example cloth dropped on the floor, a soft body's nodes stepped, collided and
// published, beside the arm, out of its reach: the arm coming near it would make new
// pairs of colliding objects (a first contact, not the steady state this tests).
TEST(HotPath, PhysicsLoopWithASoftBodyDoesNotAllocate) {
  const testing::ModelFolder folder;
  std::string cloth = test::read_file(AFHUB_EXAMPLE_MODELS "/cloth.yaml");
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"./cloth.obj", AFHUB_EXAMPLE_MODELS "/cloth.obj"},
        {"{x: 0.8, y: 0.6, z: 1.0}", "{x: -1.4, y: 1.4, z: 0.5}"}}) {
    const std::size_t at = cloth.find(from);
    ASSERT_NE(at, std::string::npos) << from << " not in cloth.yaml";
    cloth.replace(at, from.size(), to);
  }
  expect_physics_loop_allocation_free(
      {AFHUB_EXAMPLE_MODELS "/arm7.yaml", AFHUB_EXAMPLE_MODELS "/floor.yaml",
       folder.write("cloth.yaml", cloth)},
      "afhub/arm/base");
}

// The real AMBF models: mesh shapes, and the four-bar's loop.
TEST(HotPath, PhysicsLoopOnAmbfModelsDoesNotAllocate) {
  SKIP_WITHOUT_SHARED_MODELS();
  const std::string models = AFHUB_SHARED_MODELS "/descriptions/multi-bodies/";
  expect_physics_loop_allocation_free(
      {models + "robots/blender-kuka.yaml", models + "puzzles/parallel_structure.yaml"},
      "ambf/env/base");
}

// A body that goes NaN is put back from storage made at build time: the recovery,
// and the world state saying so, allocate nothing either. A NaN force (set_input
// takes it unchecked) makes the arm's link3 NaN every 100th cycle.
TEST(HotPath, NanRecoveryDoesNotAllocate) {
  const physics::Model model = physics::load_adf_files(
      {AFHUB_EXAMPLE_MODELS "/arm7.yaml", AFHUB_EXAMPLE_MODELS "/rcm.yaml"});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 0.5);
  LatestReader<WorldState> world(
      {std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)});
  std::size_t link = 0;
  while (model.bodies[link].channel != "afhub/arm/link3") ++link;
  physics::BodyInput poison;
  poison.wrench.force_n = {std::nan(""), 0, 0};
  int cycle = 0;
  auto one_cycle = [&]() {
    if (++cycle % 100 == 0) sim.set_input(link, poison);
    sim.step();
    channels.publish({});
    return sim.all_finite();
  };
  ASSERT_TRUE(test::wait_until([&] { return one_cycle() && world.latest(); }, 2s));
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(one_cycle());
  const std::uint64_t before = sim.nan_recoveries().count;
  ASSERT_GE(before, 1u);

  constexpr int kCycles = 5000;
  EXPECT_TRUE(count_allocations(kCycles, one_cycle));
  EXPECT_EQ(g_allocations, 0) << "heap allocations in " << kCycles << " cycles with NaNs";
  EXPECT_GE(sim.nan_recoveries().count, before + kCycles / 100);
  ASSERT_TRUE(test::wait_until(
      [&] {
        return world.latest() && world.latest()->nan_recoveries == sim.nan_recoveries().count;
      },
      2s));
  EXPECT_EQ(world.latest()->last_nan_step, sim.nan_recoveries().last.step);
  EXPECT_EQ(name_of(world.latest()->last_nan_body),
            model.bodies[sim.nan_recoveries().last.body].channel);
}

// Constraint actuators engaging and releasing, and a proximity sensor read every
// step: a gripper (fixed, weightless world) holds a ball that touches it and lets
// go, every 50 steps, while its ray measures the distance to the ball.
TEST(HotPath, ActuatorsAndSensorsDoNotAllocate) {
  testing::ModelFolder folder;
  const physics::Model model = physics::load_adf_files({folder.write(
      "gripper.yaml",
      "bodies: [BODY gripper, BODY ball]\nactuators: [ACTUATOR grip]\nsensors: [SENSOR range]\n"
      "namespace: /test/grip/\ngravity: {x: 0, y: 0, z: 0}\n"
      "BODY gripper:\n  name: gripper\n  mass: 0\n"
      "BODY ball:\n  name: ball\n  mass: 1\n  shape: sphere\n  geometry: {radius: 0.05}\n"
      "  location: {position: {x: 0, y: 0, z: -0.045}}\n"
      "ACTUATOR grip:\n  name: grip\n  type: Constraint\n  parent: BODY gripper\n"
      "  max impulse: 10\n  tau: 1\n"
      "SENSOR range:\n  name: range\n  type: Proximity\n  parent: BODY gripper\n  range: 1.0\n"
      "  array:\n  - {offset: {x: 0, y: 0, z: 0.2}, direction: {x: 0, y: 0, z: -1}}\n")});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 0.5);
  BodyClient controller(model.bodies[0].channel);
  int cycle = 0, changes = 0;
  bool engaged = false;
  double distance = 0.0;
  auto one_cycle = [&]() {
    channels.apply_commands(monotonic_ns());
    if (sim.actuator_engaged(0) != engaged) {
      engaged = !engaged;
      ++changes;
    }
    sim.step();
    channels.publish({});
    const BodyState* state = controller.latest_state();
    BodyCommand* command = controller.loan_command(0);
    if (!state || !command) return false;
    distance = state->sensor_distances_m[0];
    command->actuator_count = 1;
    command->actuate[0] = (++cycle / 50) % 2;
    controller.publish_command(command);
    return true;
  };
  ASSERT_TRUE(test::wait_until([&] { return one_cycle(); }, 2s));
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(one_cycle());
  ASSERT_GE(changes, 4);  // the ball is held and let go

  changes = 0;
  constexpr int kCycles = 5000;
  EXPECT_TRUE(count_allocations(kCycles, one_cycle));
  EXPECT_EQ(g_allocations, 0) << "heap allocations in " << kCycles
                              << " cycles engaging and releasing an actuator";
  EXPECT_GE(changes, kCycles / 50 - 2);
  EXPECT_NEAR(distance, 0.2 - (0.05 - 0.045), 0.002);  // the ray meets the ball's top
  EXPECT_EQ(channels.rejected_commands(), 0u);
}

// What the loop used to print as it happened (a refused command, a watchdog expiry,
// a lockstep client joining and dropped) is noted without allocating or writing, and
// said by report_events() outside the loop. stderr goes to a pipe while the loop runs.
TEST(HotPath, EventsAreSaidOutsideTheLoopOnly) {
  const physics::Model model = physics::load_adf_files({AFHUB_EXAMPLE_MODELS "/arm7.yaml"});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 0.5);
  physics::LockstepOptions lockstep;
  lockstep.client_timeout_ns = 100'000;  // a step waits 0.1 ms for a missing answer
  lockstep.max_misses = 1;               // and drops its client at once
  channels.enable_lockstep(lockstep);
  channels.set_watchdog("afhub/arm/link2", 0.002);
  BodyClient base("afhub/arm/base"), link2("afhub/arm/link2"), link7("afhub/arm/link7");
  int cycle = 0;
  std::int64_t link2_commanded_ns = 0;
  auto one_cycle = [&]() {
    channels.publish({});
    const BodyState* state = base.latest_state();
    if (!state) return false;
    if (++cycle % 2 == 0) {  // the lockstep client answers every other step: joins, drops
      if (BodyCommand* command = base.loan_command(0)) {
        command->header.sim_step = state->header.sim_step;
        command->lockstep = 1;
        base.publish_command(command);
      }
    }
    if (BodyCommand* bad = link7.loan_command(3)) link7.publish_command(bad);  // link7 has 1
    const std::int64_t now = monotonic_ns();
    if (now - link2_commanded_ns > 5'000'000) {  // every 5 ms, past its 2 ms watchdog
      if (BodyCommand* command = link2.loan_command(0)) link2.publish_command(command);
      link2_commanded_ns = now;
    }
    channels.await_lockstep();
    sim.step();
    return true;
  };
  ASSERT_TRUE(test::wait_until([&] { return one_cycle(); }, 2s));
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(one_cycle());
  channels.report_events(stdout);  // what the warm-up noted, said before the count

  int pipe_fds[2];
  ASSERT_EQ(pipe2(pipe_fds, O_NONBLOCK), 0);
  std::fflush(stderr);
  const int saved_stderr = dup(2);
  dup2(pipe_fds[1], 2);
  const std::uint64_t dropped = channels.dropped_clients(), expiries = channels.watchdog_expiries(),
                      rejected = channels.rejected_commands();
  constexpr int kCycles = 2000;
  const bool ok = count_allocations(kCycles, one_cycle);
  std::fflush(stderr);
  char buffer[4096];
  const ssize_t written_in_loop = read(pipe_fds[0], buffer, sizeof buffer);
  const int lines = channels.report_events(stderr);
  std::fflush(stderr);
  const ssize_t report_bytes = read(pipe_fds[0], buffer, sizeof buffer - 1);
  dup2(saved_stderr, 2);
  close(saved_stderr);
  close(pipe_fds[0]);
  close(pipe_fds[1]);

  EXPECT_TRUE(ok);
  EXPECT_EQ(g_allocations, 0) << "heap allocations in " << kCycles << " eventful cycles";
  EXPECT_LE(written_in_loop, 0) << "the loop wrote to stderr: "
                                << std::string(buffer, std::max<ssize_t>(written_in_loop, 0));
  EXPECT_GE(channels.dropped_clients(), dropped + kCycles / 4);
  EXPECT_GT(channels.watchdog_expiries(), expiries);
  EXPECT_GE(channels.rejected_commands(), rejected + kCycles / 2);
  // Outside the loop, the report says the events that repeat (joins and drops); the
  // said-once ones (the refusal, the expiry) were said after the warm-up already.
  ASSERT_GT(report_bytes, 0);
  const std::string said(buffer, static_cast<std::size_t>(report_bytes));
  EXPECT_GE(lines, 2);
  EXPECT_NE(said.find("joined the barrier for afhub/arm/base"), std::string::npos) << said;
  EXPECT_NE(said.find("dropped from the barrier"), std::string::npos) << said;
  EXPECT_EQ(said.find("refused a command"), std::string::npos) << said;
}

// The controller side too: the shipped sine controller answering each step in
// lockstep, its timing recorded and its stats published, against the arm's
// lockstep barrier, step and publish.
TEST(HotPath, LockstepControllerLoopDoesNotAllocate) {
  const physics::Model model = physics::load_adf_files({AFHUB_EXAMPLE_MODELS "/arm7.yaml"});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 0.5);
  channels.enable_lockstep(physics::LockstepOptions{});
  BodyClient client("afhub/arm/base");
  const ControllerCycle controller = joint_position_controller(sine_targets(0.3, 1.0, {}));
  LoopTiming timing;
  LoopStatsPublisher stats("test", "afhub/arm/base", 1'000'000, true, RealtimeGrant{});
  std::int64_t fake_clock_ns = 0;  // a second per cycle: stats are published every cycle
  auto one_cycle = [&]() {
    channels.publish({});
    const BodyState* state = client.latest_state();
    BodyCommand* command = client.loan_command(kMaxJointsPerBody);
    if (!state || !command) return false;
    const std::int64_t begin = monotonic_ns();
    controller(*state, *command);
    command->header.sim_step = state->header.sim_step;
    command->lockstep = 1;
    client.publish_command(command);
    timing.record(0, monotonic_ns() - begin);
    stats.maybe_publish(fake_clock_ns += 1'000'000'000, timing);
    channels.await_lockstep();
    sim.step();
    return true;
  };
  ASSERT_TRUE(test::wait_until([&] { return one_cycle(); }, 2s));
  for (int i = 0; i < 500; ++i) ASSERT_TRUE(one_cycle());
  ASSERT_EQ(channels.lockstep_clients(), 1u);

  constexpr int kCycles = 5000;
  EXPECT_TRUE(count_allocations(kCycles, one_cycle));
  EXPECT_EQ(g_allocations, 0) << "heap allocations in " << kCycles << " lockstep cycles";
  EXPECT_EQ(channels.late_answers(), 0u);
  EXPECT_EQ(timing.cycles(), static_cast<std::uint64_t>(kCycles + 501));
}

// The gripper's palm bound to a virtual device, as `afhub teleop` binds them from an
// input device file (cli/cmd_teleop.cpp).
teleop::TeleopBinding palm_binding(const std::string& device) {
  const physics::Model model = physics::load_adf_files({AFHUB_EXAMPLE_MODELS "/gripper.yaml"});
  std::vector<bool> is_child(model.bodies.size(), false);
  for (const physics::JointSpec& joint : model.joints)
    if (joint.child >= 0) is_child[static_cast<std::size_t>(joint.child)] = true;
  const std::size_t root = static_cast<std::size_t>(
      std::find(is_child.begin(), is_child.end(), false) - is_child.begin());
  teleop::TeleopBinding binding;
  binding.spec.identifier = "Test Hand";
  binding.spec.hardware_name = "Virtual";
  binding.spec.haptic_gain_linear = 20.0;
  binding.spec.controller_gain = teleop::CartesianGains{{200.0, 16.0}, {1.0, 0.04}};
  binding.spec.workspace_scale = 5.0;
  binding.spec.max_force_n = 3.0;
  binding.spec.location.position_m = {0.6, 0.8, 0.6};
  binding.spec.location_given = true;
  binding.device_name = device;
  binding.body = model.bodies[root].channel;
  for (int j : model.descendant_joints[root]) {
    const physics::JointSpec& joint = model.joints[static_cast<std::size_t>(j)];
    binding.gripper_joints.push_back(
        {joint.limit_low.value_or(0.0), joint.limit_high.value_or(0.0)});
    binding.subtree_bodies.push_back(model.bodies[static_cast<std::size_t>(joint.child)].channel);
  }
  // Proxy and contact feedback: the cycle reads the fingers' states too.
  binding.feedback = teleop::FeedbackSource::kBoth;
  // What the physics accepts (physics/src/sim_bounds.cpp), as cmd_teleop.cpp bounds it.
  double mass_kg = 0.0;
  for (const physics::BodySpec& body : model.bodies) mass_kg += body.mass_kg;
  binding.body_limit.force_n = 0.99 * std::max(1.0, mass_kg) * 100.0 * 9.81;
  binding.body_limit.torque_nm = binding.body_limit.force_n;
  return binding;
}

// The whole teleoperation cycle, as `afhub teleop` runs it (run_teleop, its stats and
// latency recording included): on its own thread, against the physics simulating the
// gripper on the floor and the virtual device's driver (each on a thread of its own),
// with the device's hand on a circle, so that the palm moves and force comes back.
// Once the loop is steady, 2000 of its cycles must not allocate, nor the driver's.
TEST(HotPath, TeleopLoopDoesNotAllocate) {
  const std::string device = "hot_path_hand";
  const physics::Model model = physics::load_adf_files(
      {AFHUB_EXAMPLE_MODELS "/gripper.yaml", AFHUB_EXAMPLE_MODELS "/floor.yaml"});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 0.5);
  std::atomic<bool> done{false};
  std::thread physics_thread([&] {
    for (std::int64_t next = monotonic_ns(); !done; next += 1'000'000) {
      channels.apply_commands(monotonic_ns());
      sim.step();
      channels.publish({});
      sleep_until_ns(next);
    }
  });

  // Each loop ends on its own: the teleop's after kTeleopCycles, the driver's well after.
  constexpr std::uint64_t kTeleopCycles = 6000, kMeasured = 2000;
  std::atomic<long> driver_allocations{0}, teleop_allocations{0};
  // A loop that throws ends its thread with the error kept for the test to say (an
  // exception leaving a thread would abort the test binary and leave its hub running).
  std::string driver_error, teleop_error;
  std::thread driver_thread([&] {
    test::count_thread_allocations_into(&driver_allocations);
    devices::DriverOptions options;
    options.name = device;
    options.survive_hub_loss = false;
    options.loop.max_cycles = kTeleopCycles + 3000;
    const DeviceSpec spec = devices::VirtualDevice::default_spec(3.0);
    try {
      devices::run_driver(
          [&] {
            return std::make_unique<devices::VirtualDevice>(devices::circle_trajectory(0.02, 2.0),
                                                            true, spec);
          },
          options);
    } catch (const std::exception& error) {
      driver_error = error.what();
    }
  });
  teleop::TeleopOptions options;
  options.bindings.push_back(palm_binding(device));
  options.loop.max_cycles = kTeleopCycles;
  options.survive_hub_loss = false;
  options.stale_ns = 1'000'000'000;  // a starved driver is not this test's case
  options.latency_samples = 2 * kTeleopCycles;
  options.wait_s = 60.0;  // for the palm: the physics starts slowly under the sanitizers
  teleop::TeleopLatency latency;
  std::thread teleop_thread([&] {
    test::count_thread_allocations_into(&teleop_allocations);
    try {
      teleop::run_teleop(options, &latency);
    } catch (const std::exception& error) {
      teleop_error = error.what();
    }
  });

  // Steady: the device applies the teleop's force, then a second more for first
  // contacts and the force's ramp. The cycles are counted by the teleop's commands.
  LatestReader<DeviceState> device_state(body_state_channel(device_channel_name(device)));
  LatestReader<DeviceCommand> teleop_commands(body_command_channel(device_channel_name(device)));
  DeviceTapeReader device_tape(device_channel_name(device));  // the driver tapes every cycle
  const auto sequence = [&] {
    const DeviceCommand* command = teleop_commands.latest();
    return command ? command->header.sequence : 0;
  };
  const bool applying = test::wait_until(
      [&] {
        const DeviceState* state = device_state.latest();
        return state && state->gate == ForceGate::kApplying && sequence() > 0;
      },
      70s);
  EXPECT_TRUE(applying) << "the device never applied the teleoperation's force";
  const std::uint64_t warm = sequence() + 1000;
  EXPECT_TRUE(test::wait_until([&] { return sequence() >= warm; }, 20s));
  const long driver_before = driver_allocations, teleop_before = teleop_allocations;
  const std::uint64_t first = sequence();
  const bool measured = test::wait_until([&] { return sequence() >= first + kMeasured; }, 30s);
  const long driver_counted = driver_allocations - driver_before;
  const long teleop_counted = teleop_allocations - teleop_before;
  const std::uint64_t last = sequence();
  const DeviceState* state = device_state.latest();
  const bool device_live = state && state->gate == ForceGate::kApplying &&
                           monotonic_ns() - state->header.publish_stamp_ns < 100'000'000;
  const auto taped = std::make_unique<DeviceTape>();
  std::uint64_t taped_cycles = 0;
  while (device_tape.next(*taped)) ++taped_cycles;

  teleop_thread.join();
  driver_thread.join();
  done = true;
  physics_thread.join();
  ASSERT_TRUE(applying && measured)
      << "the teleoperation did not run " << kMeasured << " cycles after its warm-up"
      << "; teleop: " << teleop_error << "; driver: " << driver_error;
  EXPECT_TRUE(device_live) << "the driver stopped applying force while the cycles were counted";
  EXPECT_EQ(teleop_counted, 0) << "heap allocations in " << last - first
                               << " steady-state teleoperation cycles";
  EXPECT_EQ(driver_counted, 0) << "heap allocations in the driver's loop over " << last - first
                               << " teleoperation cycles";
  EXPECT_GT(taped_cycles + device_tape.lost(), kMeasured) << "the driver taped its cycles";
  EXPECT_GT(latency.to_device_force.size(), static_cast<std::size_t>(kMeasured));
  EXPECT_EQ(channels.rejected_commands(), 0u);
}

}  // namespace
}  // namespace afhub
