// Load and step times of the real AMBF models, with and without publishing, and
// what publishing ten bodies costs; load and convert times of the real URDF robots
// beside them. Run: build/release/bin/physics_benchmark
// (it starts a hub when none runs, and stops it at the end).
#include <benchmark/benchmark.h>

#include <linux/futex.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <new>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <btBulletDynamicsCommon.h>

#include "afhub/bench/arms_scene.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/adf_writer.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/physics/sim_channels.hpp"
#include "afhub/rt/latency_histogram.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub_process.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

const std::string kModels = AFHUB_SHARED_MODELS "/descriptions/multi-bodies/";
const std::string kKuka = kModels + "robots/blender-kuka.yaml";
const std::string kFourBar = kModels + "puzzles/parallel_structure.yaml";
const std::string kEcm = kModels + "robots/blender-ecm.yaml";

// False, with the benchmark skipped naming the directory, when the corpus is missing.
bool have_shared_models(benchmark::State& state) {
  if (afhub::testing::shared_models_present()) return true;
  state.SkipWithError(afhub::testing::shared_models_missing().c_str());
  return false;
}

// The channels of `sim`, once the hub's pool has room: the previous benchmark's ports
// give their chunks back when the hub's discovery loop next runs, which on a loaded
// machine came after the next 1000-body physics asked ("needs 3 chunks ... and 4 are
// free"). Other refusals, or that one past 20 s, are thrown.
std::unique_ptr<SimChannels> channels_for(Simulation& sim) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  for (;;) {
    try {
      return std::make_unique<SimChannels>(sim, 0.5);
    } catch (const afhub::Error& error) {
      if (std::string(error.what()).find("chunks") == std::string::npos ||
          std::chrono::steady_clock::now() > give_up)
        throw;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

// Loading is parsing the files, reading the meshes and building the Bullet world.
void BM_Load(benchmark::State& state, const std::string& file) {
  if (!have_shared_models(state)) return;
  for (auto _ : state) {
    Model model = load_adf_files({file});
    Simulation sim(model, 0.001);
    benchmark::DoNotOptimize(sim.step_count());
  }
}
BENCHMARK_CAPTURE(BM_Load, kuka, kKuka)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Load, four_bar, kFourBar)->Unit(benchmark::kMillisecond);

// The real URDF robots in ../shared/urdf_models, their meshes through --package-path:
// the UR5 (11 links, 6 collision meshes) is the size of the Kuka above (8 bodies).
const std::string kUrdfModels = AFHUB_SHARED_URDF_MODELS;
const std::string kUr5 =
    kUrdfModels + "/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf";
const std::string kAllegro =
    kUrdfModels +
    "/example-robot-data/robots/allegro_hand_description/urdf/allegro_right_hand.urdf";

bool have_urdf_models(benchmark::State& state) {
  if (std::filesystem::is_directory(kUrdfModels)) return true;
  state.SkipWithError(("needs the URDF robots, and " + kUrdfModels + " does not exist").c_str());
  return false;
}

// As BM_Load: the URDF parsed, its meshes read and the Bullet world built.
void BM_LoadUrdf(benchmark::State& state, const std::string& file) {
  if (!have_urdf_models(state)) return;
  for (auto _ : state) {
    Model model;
    load_adf_files_into({file}, model, {{kUrdfModels}, false});
    Simulation sim(model, 0.001);
    benchmark::DoNotOptimize(sim.step_count());
  }
}
BENCHMARK_CAPTURE(BM_LoadUrdf, ur5, kUr5)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadUrdf, allegro_hand, kAllegro)->Unit(benchmark::kMillisecond);

// `afhub convert`'s work: the URDF parsed and written as ADF text.
void BM_ConvertUrdf(benchmark::State& state, const std::string& file) {
  if (!have_urdf_models(state)) return;
  for (auto _ : state) {
    Model model;
    load_adf_files_into({file}, model, {{kUrdfModels}, false});
    std::vector<std::string> lost;
    benchmark::DoNotOptimize(adf_text(model, lost).size());
  }
}
BENCHMARK_CAPTURE(BM_ConvertUrdf, ur5, kUr5)->Unit(benchmark::kMillisecond);

// One iteration of `afhub run`'s loop as it times it (commands in, step, states out),
// its phases' times kept in `times` while there is room.
struct StepTimes {
  explicit StepTimes(std::size_t room) {
    for (auto* phase : {&total, &commands, &physics, &publish}) phase->reserve(room);
  }
  std::vector<float> total, commands, physics, publish;  // us
};

void timed_step(Simulation& sim, SimChannels* channels, StepTimes& times) {
  const std::int64_t begin_ns = monotonic_ns();
  if (channels) channels->apply_commands(begin_ns);
  const std::int64_t commanded_ns = monotonic_ns();
  sim.step();
  const std::int64_t stepped_ns = monotonic_ns();
  if (channels) channels->publish({});
  const std::int64_t end_ns = monotonic_ns();
  if (times.total.size() == times.total.capacity()) return;
  times.total.push_back(static_cast<float>(end_ns - begin_ns) * 1e-3F);
  times.commands.push_back(static_cast<float>(commanded_ns - begin_ns) * 1e-3F);
  times.physics.push_back(static_cast<float>(stepped_ns - commanded_ns) * 1e-3F);
  times.publish.push_back(static_cast<float>(end_ns - stepped_ns) * 1e-3F);
}

// The steps' p50 and p99, and each phase's p50 (commands read and applied, the
// physics' step, the states published): the publishing share is measured, not
// inferred from two runs.
void report_step_times(benchmark::State& state, StepTimes& times) {
  if (times.total.empty()) return;
  const auto percentile = [](std::vector<float>& values, std::size_t percent) {
    std::sort(values.begin(), values.end());
    return values[values.size() * percent / 100];
  };
  state.counters["step_p50_us"] = percentile(times.total, 50);
  state.counters["step_p99_us"] = percentile(times.total, 99);
  state.counters["commands_p50_us"] = percentile(times.commands, 50);
  state.counters["physics_p50_us"] = percentile(times.physics, 50);
  state.counters["publish_p50_us"] = percentile(times.publish, 50);
}

// A recorder of `bodies` in the benchmark's process: the step tape's reader, drained
// between steps (untimed), and a reader holding each body's state slot, as `afhub
// record` holds those it records. The physics then copies those bodies' states, their
// commands and the world state into the tape, which is what a recorder costs the step.
struct TapeDrain {
  StepTapeReader reader{world_instance()};
  std::unique_ptr<StepTape> sample = std::make_unique<StepTape>();
  std::vector<std::unique_ptr<LatestReader<BodyState>>> held;

  explicit TapeDrain(const std::vector<BodySpec>& bodies) {
    for (const BodySpec& body : bodies)
      held.push_back(std::make_unique<LatestReader<BodyState>>(body_state_channel(body.channel)));
  }

  // Steps until a step's tape comes (after RouDi's discovery pass); false if none in 5 s.
  bool connect(Simulation& sim, SimChannels& channels) {
    return afhub::test::wait_until(
        [&] {
          sim.step();
          channels.publish({});
          for (auto& body : held) body->latest();  // holds its slot
          return drain();
        },
        std::chrono::seconds(5));
  }
  bool drain() {
    bool any = false;
    while (reader.next(*sample)) any = true;
    return any;
  }
};

// A recorder of `bodies` on the physics' tape, which only a publishing physics writes;
// nothing (the benchmark skipped) when its tape did not come.
std::unique_ptr<TapeDrain> connect_tape(benchmark::State& state, Simulation& sim,
                                        SimChannels* channels, std::vector<BodySpec> bodies) {
  auto tape = std::make_unique<TapeDrain>(bodies);
  if (channels && tape->connect(sim, *channels)) return tape;
  state.SkipWithError("the step tape reader did not connect");
  return nullptr;
}

// One step of the physics alone, or the whole loop iteration of `afhub run`:
// commands read, step, every body's state and the world state published, and the
// display-rate chores after them, at 1 ms per step; `viewed`: with a viewer reading
// the pose feed (which then goes out at 60 Hz, every ~17th step); `taped`: with a
// recorder's step tape reader (TapeDrain).
void BM_Step(benchmark::State& state, const std::string& file, bool publish, bool viewed,
             bool taped = false) {
  if (!have_shared_models(state)) return;
  const Model model = load_adf_files({file});
  Simulation sim(model, 0.001);
  std::unique_ptr<SimChannels> channels;
  if (publish) channels = channels_for(sim);
  std::unique_ptr<LatestReader<ScenePoses>> viewer;
  if (viewed) {
    viewer = std::make_unique<LatestReader<ScenePoses>>(
        ChannelId{std::string(kService), world_instance(), std::string(kScenePosesEvent)});
    if (!afhub::test::wait_until([&] { return viewer->raw().subscribed(); },
                                 std::chrono::seconds(5)))
      state.SkipWithError("the viewer's reader did not connect");
  }
  std::unique_ptr<TapeDrain> tape;
  if (taped) tape = connect_tape(state, sim, channels.get(), model.bodies);
  std::int64_t clock_ns = 0;
  // Each step's time as `afhub run` times it (commands in, step, states out; not the
  // display-rate chores after), for its tail: the mean hides a cost paid every 17th step.
  StepTimes times(1 << 22);
  for (auto _ : state) {
    timed_step(sim, channels.get(), times);
    if (channels) {
      channels->publish_view(clock_ns += 1'000'000);
      channels->prepare_next_step();
    }
    if (tape) tape->drain();
  }
  state.counters["bodies"] = static_cast<double>(model.bodies.size());
  report_step_times(state, times);
}
BENCHMARK_CAPTURE(BM_Step, kuka_physics, kKuka, false, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Step, kuka_published, kKuka, true, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Step, kuka_published_viewed, kKuka, true, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Step, kuka_published_taped, kKuka, true, false, true)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Step, four_bar_physics, kFourBar, false, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Step, four_bar_published, kFourBar, true, false)
    ->Unit(benchmark::kMicrosecond);

// A robot with closed loops, stepped with its loop islands solved directly and with
// them iterated like the rest (the world's 20 iterations), in one run: what the
// direct solve costs (physics/src/constraint_solver.hpp).
void BM_LoopStep(benchmark::State& state, const std::string& file, bool direct) {
  if (!have_shared_models(state)) return;
  Model model = load_adf_files({file});
  model.world.direct_solve = direct;
  Simulation sim(model, 0.001);
  StepTimes times(1 << 22);
  for (auto _ : state) timed_step(sim, nullptr, times);
  report_step_times(state, times);
}

// How a recorder reads the scene's step tape: not at all; drained by the stepping thread
// between steps; or from the other CPU every millisecond, as `afhub record` reads it
// from another process, with or without the tape's next part readied between steps
// (SimChannels::prepare_next_step, as `afhub run` does).
enum class Tape { kNone, kSameThread, kOtherCpu, kOtherCpuUnprepared };

// The first `count` CPUs the calling thread may run on (fewer if it may run on fewer).
std::vector<int> allowed_cpus(std::size_t count) {
  cpu_set_t allowed;
  std::vector<int> cpus;
  if (pthread_getaffinity_np(pthread_self(), sizeof allowed, &allowed) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE && cpus.size() < count; ++cpu)
    if (CPU_ISSET(cpu, &allowed)) cpus.push_back(cpu);
  return cpus;
}

// The calling thread on `cpu` alone; false if refused.
bool pin_this_thread(int cpu) {
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  CPU_SET(cpu, &cpus);
  return pthread_setaffinity_np(pthread_self(), sizeof cpus, &cpus) == 0;
}

// The stepping thread on the first CPU it may run on and a reader draining the tape on
// the second until destroyed (then the stepping thread may run where it ran before).
// `pinned`: both are where they should be (false with fewer than two CPUs allowed).
struct OtherCpuDrain {
  explicit OtherCpuDrain(TapeDrain& tape) {
    pthread_getaffinity_np(pthread_self(), sizeof before, &before);
    const std::vector<int> allowed = allowed_cpus(2);
    if (allowed.size() < 2 || !pin_this_thread(allowed[0])) return;
    std::promise<bool> reader_pinned;
    std::future<bool> reader_pinned_result = reader_pinned.get_future();
    reader = std::thread([this, &tape, &reader_pinned, cpu = allowed[1]] {
      reader_pinned.set_value(pin_this_thread(cpu));
      while (!stop.load()) {
        tape.drain();
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
    pinned = reader_pinned_result.get();
  }
  ~OtherCpuDrain() {
    stop.store(true);
    if (reader.joinable()) reader.join();
    pthread_setaffinity_np(pthread_self(), sizeof before, &before);
  }
  cpu_set_t before{};
  bool pinned = false;
  std::atomic<bool> stop{false};
  std::thread reader;
};

// The example scene (`afhub run --launch examples/models/launch.yaml -l 0,1,2`: a
// 7-joint arm, the remote-centre-of-motion arm's loops, a gripper, the floor) stepped
// with its islands of joints solved directly and iterated, in one run.
void BM_ExampleSceneStep(benchmark::State& state, bool direct, bool publish = false,
                         Tape taped = Tape::kNone) {
  SceneRequest request;
  request.launch_file = AFHUB_EXAMPLE_MODELS "/launch.yaml";
  request.launch_indices = {0, 1, 2};
  Model model = load_scene(request);
  model.world.direct_solve = direct;
  Simulation sim(model, 0.001);
  std::unique_ptr<SimChannels> channels;
  if (publish) channels = channels_for(sim);
  std::unique_ptr<TapeDrain> tape;
  if (taped != Tape::kNone) tape = connect_tape(state, sim, channels.get(), model.bodies);
  std::unique_ptr<OtherCpuDrain> other;
  if (tape && taped != Tape::kSameThread) {
    other = std::make_unique<OtherCpuDrain>(*tape);
    if (!other->pinned) state.SkipWithError("needs two CPUs to run on");
  }
  StepTimes times(1 << 22);
  for (auto _ : state) {
    timed_step(sim, channels.get(), times);
    if (channels && taped != Tape::kOtherCpuUnprepared) channels->prepare_next_step();
    if (taped == Tape::kSameThread) tape->drain();
  }
  report_step_times(state, times);
}
BENCHMARK_CAPTURE(BM_ExampleSceneStep, direct, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ExampleSceneStep, iterated, false)->Unit(benchmark::kMicrosecond);
// What `bench/record_bench.sh` measures across processes, in one: the scene's states
// published, and taped for a recorder of all its bodies.
BENCHMARK_CAPTURE(BM_ExampleSceneStep, published, true, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ExampleSceneStep, published_taped, true, true, Tape::kSameThread)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ExampleSceneStep, published_taped_other_cpu, true, true, Tape::kOtherCpu)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ExampleSceneStep, published_taped_other_cpu_unprepared, true, true,
                  Tape::kOtherCpuUnprepared)
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_CAPTURE(BM_LoopStep, ecm_direct, kEcm, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LoopStep, ecm_iterated, kEcm, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LoopStep, four_bar_direct, kFourBar, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LoopStep, four_bar_iterated, kFourBar, false)->Unit(benchmark::kMicrosecond);

// A controller on another CPU: after each step a thread there reads every body's state
// and, with `commands`, writes every body's command (its joints held where they are),
// as a controller process of them all would: what each line a step writes, and each
// line of a command, then costs to take across. The reader runs on the second CPU this
// process may use. It spins there, the stepping thread on the first (with the islands
// solved by the stepping thread alone, nothing else needs it); or, `asleep`, it sleeps
// between steps, as a controller process does, and the stepping thread and the
// islands' helper run on either CPU.
class ControllerElsewhere {
 public:
  // False when this process may use fewer than two CPUs.
  static bool possible() { return allowed_cpus(2).size() == 2; }

  ControllerElsewhere(const std::vector<BodySpec>& bodies, bool commands, bool asleep) {
    answer_us_.reserve(1 << 20);
    for (const BodySpec& body : bodies)
      bodies_.push_back(std::make_unique<BodyClient>(body.channel));
    for (auto& reader : bodies_)
      afhub::test::wait_until([&] { return reader->subscribed(); }, std::chrono::seconds(5));
    const std::vector<int> cpus = allowed_cpus(2);
    sched_getaffinity(0, sizeof saved_, &saved_);
    if (!asleep) pin_this_thread(cpus[0]);
    thread_ = std::thread([this, reading = cpus[1], commands, asleep] {
      pin_this_thread(reading);
      for (std::uint64_t seen = 0; !stop_.load(std::memory_order_relaxed);) {
        const std::uint64_t step = published_.load(std::memory_order_acquire);
        if (step == seen) {
          if (asleep) published_.wait(seen, std::memory_order_acquire);
          continue;
        }
        const std::int64_t begin_ns = monotonic_ns();
        for (std::size_t b = 0; b < bodies_.size(); ++b) {
          // A few bodies ahead, as a controller process does (bench/src/bodies_bench.cpp).
          if (b + kBodyPrefetchAhead < bodies_.size()) {
            bodies_[b + kBodyPrefetchAhead]->prefetch_state();
            if (commands) bodies_[b + kBodyPrefetchAhead]->prefetch_command_update();
          }
          BodyClient* body = bodies_[b].get();
          const BodyState* read = body->latest_state();
          if (!read || !commands) continue;
          BodyCommand* command = body->loan_command(read->joint_count);
          if (!command) continue;
          for (std::uint32_t j = 0; j < read->joint_count; ++j)
            command->joints[j] = {read->joints[j].position, JointCommandType::kPosition};
          command->header.sim_step = read->header.sim_step;
          body->publish_command(command);
        }
        if (answer_us_.size() < answer_us_.capacity())
          answer_us_.push_back(static_cast<float>(monotonic_ns() - begin_ns) * 1e-3F);
        seen = step;
        read_.store(step, std::memory_order_release);
      }
    });
  }
  ~ControllerElsewhere() {
    stop_ = true;
    published_.fetch_add(1, std::memory_order_release);
    published_.notify_one();
    thread_.join();
    sched_setaffinity(0, sizeof saved_, &saved_);
  }
  // After a step is published (untimed): the controller answers it all.
  void answer_step(std::uint64_t step) {
    published_.store(step, std::memory_order_release);
    published_.notify_one();
    while (read_.load(std::memory_order_acquire) != step) {
    }
  }
  // The median time the controller took to read (and answer) a step's states, us;
  // after answer_step, whose wait orders the controller's records before it.
  float answer_p50_us() {
    if (answer_us_.empty()) return 0.0F;
    std::sort(answer_us_.begin(), answer_us_.end());
    return answer_us_[answer_us_.size() / 2];
  }

 private:
  std::vector<std::unique_ptr<BodyClient>> bodies_;
  cpu_set_t saved_;
  std::vector<float> answer_us_;  // written by thread_ alone until the last answer_step
  std::thread thread_;
  std::atomic<std::uint64_t> published_{0}, read_{0};
  std::atomic<bool> stop_{false};
};

// Who reads the states and writes the commands on another CPU (ControllerElsewhere):
// spinning there, or asleep between steps.
enum class Elsewhere { kNone, kReads, kCommands, kCommandsAsleep };

// The thousand bodies at 1 kHz: one step of 125 eight-link arms, as the physics alone,
// with every state and the world state published, and with every body commanded each
// step by one controller in this process (its 1000 command slots in a few blocks).
// Issue 30's goal: step p99 under 1 ms, publishing under 10 % of the step (the
// published case's p50 against the physics alone's, in one run). The islands are
// solved by two threads (physics/src/parallel_islands.hpp), or by the stepping thread
// alone (`one_thread`): "helped" is the share of islands the helper solved. `taped`:
// with a recorder of that many bodies (TapeDrain), the first ones. `elsewhere`: the
// states read, or read and answered, by a controller on another CPU (spinning there, the
// islands solved by the stepping thread alone; or asleep between steps, as a controller
// process is, with the helper beside it). `reduced`: each
// arm a chain in reduced coordinates (`afhub run --reduced-coordinates`).
void BM_StepThousandBodies(benchmark::State& state, bool publish, bool commanded,
                           int solver_threads, std::size_t taped = 0,
                           Elsewhere elsewhere = Elsewhere::kNone, bool reduced = false) {
  afhub::testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("arms.yaml", afhub::bench::arms_scene(125, 8))});
  model.world.solver_threads = solver_threads;
  model.world.reduced_coordinates = reduced;
  Simulation sim(model, 0.001);
  const std::uint64_t helped_before = sim.islands_solved_by_helper();
  std::unique_ptr<SimChannels> channels;
  if (publish) channels = channels_for(sim);
  std::vector<std::unique_ptr<BodyClient>> controller;
  if (commanded)
    for (const BodySpec& body : model.bodies)
      controller.push_back(std::make_unique<BodyClient>(body.channel));
  std::unique_ptr<TapeDrain> tape;
  if (taped > 0)
    tape = connect_tape(
        state, sim, channels.get(),
        {model.bodies.begin(), model.bodies.begin() + std::min(taped, model.bodies.size())});
  std::unique_ptr<ControllerElsewhere> other_cpu;
  if (elsewhere != Elsewhere::kNone && !ControllerElsewhere::possible()) {
    state.SkipWithError("needs two CPUs");
    return;
  }
  if (elsewhere != Elsewhere::kNone)
    other_cpu = std::make_unique<ControllerElsewhere>(model.bodies, elsewhere != Elsewhere::kReads,
                                                      elsewhere == Elsewhere::kCommandsAsleep);
  StepTimes times(1 << 20);
  std::uint64_t step = 0;
  for (auto _ : state) {
    for (auto& body : controller)
      if (BodyCommand* command = body->loan_command(0)) {
        command->header.sim_step = step;
        body->publish_command(command);
      }
    timed_step(sim, channels.get(), times);
    if (channels) channels->prepare_next_step();
    if (tape) tape->drain();
    ++step;
    if (other_cpu) other_cpu->answer_step(step);
  }
  state.counters["bodies"] = static_cast<double>(model.bodies.size());
  state.counters["helped"] =
      static_cast<double>(sim.islands_solved_by_helper() - helped_before) / (125.0 * step);
  if (channels) state.counters["published"] = static_cast<double>(channels->channel_count());
  if (other_cpu) state.counters["controller_p50_us"] = other_cpu->answer_p50_us();
  report_step_times(state, times);
}
BENCHMARK_CAPTURE(BM_StepThousandBodies, physics, false, false, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, physics_one_thread, false, false, 1)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, physics_reduced, false, false, 2, 0, Elsewhere::kNone,
                  true)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published, true, false, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_taped, true, false, 2, 1000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_taped_one, true, false, 2, 1)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_read_elsewhere, true, false, 1, 0,
                  Elsewhere::kReads)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_commanded_elsewhere, true, false, 1, 0,
                  Elsewhere::kCommands)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_commanded_asleep_elsewhere, true, false, 2, 0,
                  Elsewhere::kCommandsAsleep)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_commanded_asleep_elsewhere_reduced, true, false,
                  2, 0, Elsewhere::kCommandsAsleep, true)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_commanded, true, true, 2)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_commanded_one_thread, true, true, 1)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodies, published_commanded_reduced, true, true, 2, 0,
                  Elsewhere::kNone, true)
    ->Unit(benchmark::kMicrosecond);

// What reading the thousand bodies' states costs a controller on another CPU, without
// the physics' step between: every state published, then all of them read there (and,
// with `commands`, answered), each publish. controller_p50_us is the reader's time for
// one publish's states: the read path alone, steadier than beside the step.
void BM_ReadThousandStates(benchmark::State& state, bool commands) {
  if (!ControllerElsewhere::possible()) {
    state.SkipWithError("needs two CPUs");
    return;
  }
  afhub::testing::ModelFolder folder;
  Model model = load_adf_files({folder.write("arms.yaml", afhub::bench::arms_scene(125, 8))});
  Simulation sim(model, 0.001);
  const std::unique_ptr<SimChannels> channels = channels_for(sim);
  ControllerElsewhere other_cpu(model.bodies, commands, false);
  std::uint64_t published = 0;
  for (auto _ : state) {
    channels->publish({});
    other_cpu.answer_step(++published);
  }
  state.counters["controller_p50_us"] = other_cpu.answer_p50_us();
}
BENCHMARK_CAPTURE(BM_ReadThousandStates, read, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ReadThousandStates, answered, true)->Unit(benchmark::kMicrosecond);

// The same 125 arms as Featherstone multibodies (Bullet's btMultiBody, reduced
// coordinates: 7 revolute links on a fixed base each, their PD as joint torques, one
// collider per link colliding with nothing, as the arms ignore each other): what the
// thousand bodies' physics would cost with the arms' joints as coordinates instead of
// constraints, built with Bullet alone: the floor for `afhub run --reduced-coordinates`
// (`ThousandBodies/physics_reduced`), which adds what afhub does around a body (its
// readings, damping, gravity, contacts) (docs/performance.md).
class MultibodyArms {
 public:
  static constexpr int kLinks = 8;
  // Arms [first, first + count) of the 125, placed as arms_scene places them.
  MultibodyArms(int first, int count) {
    world_.setGravity(btVector3(0, 0, -9.81));
    for (int a = first; a < first + count; ++a) {
      auto arm = std::make_unique<btMultiBody>(kLinks - 1, 0.0, btVector3(0, 0, 0), true, false);
      arm->setBasePos(btVector3(a % 12, a / 12, 0));
      arm->setWorldToBaseRot(btQuaternion::getIdentity());
      for (int l = 1; l < kLinks; ++l)  // axes alternating between y and z, as arms_scene's
        arm->setupRevolute(l - 1, 1.0, btVector3(0.01, 0.01, 0.01), l - 2,
                           btQuaternion::getIdentity(),
                           l % 2 ? btVector3(0, 1, 0) : btVector3(0, 0, 1), btVector3(0, 0, 0.05),
                           btVector3(0, 0, 0.05), true);
      arm->finalizeMultiDof();
      arm->setLinearDamping(0);
      arm->setAngularDamping(0);
      world_.addMultiBody(arm.get());
      for (int l = -1; l < kLinks - 1; ++l) {
        auto& collider =
            colliders_.emplace_back(std::make_unique<btMultiBodyLinkCollider>(arm.get(), l));
        collider->setCollisionShape(&box_);
        btTransform pose = btTransform::getIdentity();
        pose.setOrigin(btVector3(a % 12, a / 12, 0.1 * (l + 1)));
        collider->setWorldTransform(pose);
        world_.addCollisionObject(collider.get(), 1, 0);
        if (l < 0)
          arm->setBaseCollider(collider.get());
        else
          arm->getLink(l).m_collider = collider.get();
      }
      arms_.push_back(std::move(arm));
    }
  }
  void step() {
    for (auto& arm : arms_)
      for (int l = 0; l < kLinks - 1; ++l)
        arm->addJointTorque(l, -50.0 * arm->getJointPos(l) - 2.0 * arm->getJointVel(l));
    world_.stepSimulation(0.001, 0, 0.001);
  }

 private:
  btDefaultCollisionConfiguration configuration_;
  btCollisionDispatcher dispatcher_{&configuration_};
  btDbvtBroadphase broadphase_;
  btMultiBodyConstraintSolver solver_;
  // Declared before the world, which meets its colliders again when it goes.
  btBoxShape box_{btVector3(0.025, 0.025, 0.05)};
  std::vector<std::unique_ptr<btMultiBody>> arms_;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders_;
  btMultiBodyDynamicsWorld world_{&dispatcher_, &broadphase_, &solver_, &configuration_};
};

// `threads` 2: the arms split between two worlds, the second stepped by a helper
// spinning on another CPU (the islands' helper sleeps between steps): the most that
// stepping the multibodies on both threads could give (the broadphase and the
// colliders' bounds, serial in one world, are shared too).
void BM_StepThousandBodiesAsMultibodies(benchmark::State& state, int threads) {
  constexpr int kArms = 125;
  const int helped = threads == 2 ? kArms / 2 : 0;
  MultibodyArms own(0, kArms - helped);
  std::unique_ptr<MultibodyArms> other;
  std::atomic<std::uint64_t> asked{0}, done{0};
  std::atomic<bool> stop{false};
  std::jthread helper;
  if (helped > 0) {
    other = std::make_unique<MultibodyArms>(kArms - helped, helped);
    helper = std::jthread([&] {
      for (std::uint64_t stepped = 0; !stop.load(std::memory_order_relaxed);) {
        if (asked.load(std::memory_order_acquire) == stepped) continue;
        other->step();
        done.store(++stepped, std::memory_order_release);
      }
    });
  }
  StepTimes times(1 << 20);
  std::uint64_t step = 0;
  for (auto _ : state) {
    const std::int64_t begin_ns = monotonic_ns();
    ++step;
    if (other) asked.store(step, std::memory_order_release);
    own.step();
    while (other && done.load(std::memory_order_acquire) != step) {
    }
    const auto took = static_cast<float>(monotonic_ns() - begin_ns) * 1e-3F;
    if (times.total.size() == times.total.capacity()) continue;
    for (auto* phase : {&times.total, &times.physics}) phase->push_back(took);
    for (auto* phase : {&times.commands, &times.publish}) phase->push_back(0.0F);
  }
  stop = true;
  state.counters["bodies"] = kArms * MultibodyArms::kLinks;
  report_step_times(state, times);
}
BENCHMARK_CAPTURE(BM_StepThousandBodiesAsMultibodies, one_thread, 1)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_StepThousandBodiesAsMultibodies, two_threads, 2)
    ->Unit(benchmark::kMicrosecond);

// Publishing alone: one step's ten body states (a ten-link chain, so each body
// carries its descendant joints) and the world state. Argument: readers per body.
// With none this is the physics' own cost; each subscribed reader adds iceoryx's
// push into its queue (a chunk swap) to every publish.
void BM_PublishTenBodies(benchmark::State& state) {
  afhub::testing::ModelFolder folder;
  std::string text = "bodies: [";
  for (int b = 0; b < 10; ++b) text += (b ? ", " : "") + std::string("BODY b") + std::to_string(b);
  text += "]\njoints: [";
  for (int j = 1; j < 10; ++j)
    text += (j > 1 ? ", " : "") + std::string("JOINT j") + std::to_string(j);
  text += "]\n";
  for (int b = 0; b < 10; ++b)
    text += "BODY b" + std::to_string(b) + ":\n  name: link" + std::to_string(b) +
            "\n  mass: " + (b ? "1" : "0") + "\n  shape: sphere\n  geometry: {radius: 0.01}\n";
  for (int j = 1; j < 10; ++j)
    text += "JOINT j" + std::to_string(j) + ":\n  name: j" + std::to_string(j) +
            "\n  parent: BODY b" + std::to_string(j - 1) + "\n  child: BODY b" + std::to_string(j) +
            "\n  parent pivot: {x: 0, y: 0, z: 0.1}\n  parent axis: {x: 0, y: 1, z: 0}\n"
            "  child pivot: {x: 0, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n"
            "  type: revolute\n";
  const Model model = load_adf_files({folder.write("chain.yaml", text)});
  Simulation sim(model, 0.001);
  SimChannels channels(sim, 0.5);
  std::vector<std::unique_ptr<BodyClient>> readers;
  for (int r = 0; r < state.range(0); ++r)
    for (const BodySpec& body : model.bodies)
      readers.push_back(std::make_unique<BodyClient>(body.channel));
  for (auto& reader : readers)
    if (!afhub::test::wait_until([&] { return reader->subscribed(); }, std::chrono::seconds(5)))
      state.SkipWithError("a reader did not connect");
  for (auto _ : state) channels.publish({});
  state.counters["bodies"] = static_cast<double>(channels.channel_count());
}
BENCHMARK(BM_PublishTenBodies)->ArgName("readers")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// One body state slot alone, the physics' fill left out: what an update costs with 0,
// 1 or 4 readers holding the slot (the same: a reader costs the writer nothing).
// Argument: readers.
void BM_PublishOneChannel(benchmark::State& state) {
  static int instance = 0;  // a fresh channel per run: no reader left from the last
  const ChannelId channel = body_state_channel("bench/one" + std::to_string(instance++));
  Writer<BodyState> writer(channel);
  std::vector<std::unique_ptr<LatestReader<BodyState>>> readers;
  for (int r = 0; r < state.range(0); ++r) {
    auto& reader = readers.emplace_back(std::make_unique<LatestReader<BodyState>>(channel));
    if (!afhub::test::wait_until([&] { return reader->raw().subscribed(); },
                                 std::chrono::seconds(5)))
      state.SkipWithError("a reader did not connect");
  }
  // At the KUKA base's size (7 joints below it), as the physics loans it.
  for (auto _ : state)
    if (BodyState* sample = writer.loan(body_state_bytes(7))) {
      sample->joint_count = 7;
      writer.publish(sample);
    }
}
BENCHMARK(BM_PublishOneChannel)
    ->ArgName("readers")
    ->Arg(0)
    ->Arg(1)
    ->Arg(4)
    ->Unit(benchmark::kNanosecond);

// Where the two sides of a round trip run. On two CPUs, each wake-up is of a halted
// vCPU (the floor the lockstep goal is set against); on one, each is a context switch.
// Left to the scheduler they mix the two, differently for a forked floor and an exec'd
// controller (a bare floor's median was 5.6 us in one run and 34 us in the next).
enum class Placement { kFree, kApart, kTogether };

// The calling thread on the first allowed CPU, and the CPU for the other side, until
// destroyed. `problem` says why it could not place them, or is null.
class ScopedPlacement {
 public:
  explicit ScopedPlacement(Placement placement) {
    pthread_getaffinity_np(pthread_self(), sizeof before_, &before_);
    if (placement == Placement::kFree) return;
    const std::vector<int> cpus = allowed_cpus(2);
    if (cpus.size() < (placement == Placement::kApart ? 2U : 1U) || !pin_this_thread(cpus[0])) {
      problem = "could not pin to the CPUs the placement needs";
      return;
    }
    peer_cpu = placement == Placement::kApart ? cpus[1] : cpus[0];
  }
  ScopedPlacement(const ScopedPlacement&) = delete;
  ScopedPlacement& operator=(const ScopedPlacement&) = delete;
  ~ScopedPlacement() { pthread_setaffinity_np(pthread_self(), sizeof before_, &before_); }
  const char* problem = nullptr;
  int peer_cpu = -1;  // -1: where the scheduler puts it

 private:
  cpu_set_t before_{};
};

// The floor under a lockstep round trip asleep: a forked process ping-ponging with
// this one on a bare futex in shared memory, each asleep until the other's turn ends
// (two futex wake-ups per round trip, as in lockstep). A `timed` round trip's waits
// have afhub's timeout on slots (10 ms, sample_waiter.cpp) and the peer the timer slack
// of afhub's loops (1 ns), as every wait of afhub's has one (a lockstep drops a dead
// client, a controller notices a dead physics): it arms a kernel timer.
class FutexPingPong {
 public:
  // Forks the peer, pinned to `peer_cpu` unless it is -1; `problem` says why not.
  explicit FutexPingPong(int peer_cpu) {
    void* memory =
        mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (memory == MAP_FAILED) {
      problem = "mmap for the futex floor failed";
      return;
    }
    shared_ = new (memory) Shared;
    const pid_t parent = getpid();
    // The child only touches the shared words and makes system calls: safe after a
    // fork of this multi-threaded process.
    child_ = fork();
    if (child_ < 0) {
      problem = "fork for the futex floor failed";
      return;
    }
    if (child_ > 0) {
      round_trip_ns(false);  // the peer has placed itself
      if (!shared_->placed.load()) problem = "could not pin the floor's peer";
      return;
    }
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // never left behind asleep
    if (getppid() != parent) _exit(0);
    prctl(PR_SET_TIMERSLACK, 1UL);
    shared_->placed.store(peer_cpu < 0 || pin_this_thread(peer_cpu));
    for (std::uint32_t seen = 0;;) {
      wait_while(seen, shared_->timed.load(std::memory_order_relaxed) != 0);
      const std::uint32_t now = shared_->turn.load(std::memory_order_acquire);
      if (now == kStop) _exit(0);
      seen = now + 1;
      pass(seen);  // odd in, even out
    }
  }
  FutexPingPong(const FutexPingPong&) = delete;
  FutexPingPong& operator=(const FutexPingPong&) = delete;
  ~FutexPingPong() {
    if (!shared_) return;
    if (child_ > 0) {
      pass(kStop);
      waitpid(child_, nullptr, 0);
    }
    munmap(shared_, sizeof(Shared));
  }
  // After `pause_ns` of work here, as a physics steps before it publishes: the peer
  // sleeps that much longer.
  std::int64_t round_trip_ns(bool timed, std::int64_t pause_ns = 0) {
    shared_->timed.store(timed ? 1 : 0, std::memory_order_relaxed);
    for (const std::int64_t until = monotonic_ns() + pause_ns; monotonic_ns() < until;) {
    }
    const std::int64_t sent = monotonic_ns();
    pass(++value_);
    wait_while(value_, timed);
    value_ = shared_->turn.load(std::memory_order_acquire);
    return monotonic_ns() - sent;
  }
  const char* problem = nullptr;

 private:
  struct Shared {
    std::atomic<std::uint32_t> turn{0};
    std::atomic<std::uint32_t> timed{0};  // the peer's waits too, from its next one
    std::atomic<bool> placed{false};
  };
  static constexpr std::uint32_t kStop = ~0U;
  std::uint32_t* word() { return reinterpret_cast<std::uint32_t*>(&shared_->turn); }
  // Sleeps while the turn is `value`.
  void wait_while(std::uint32_t value, bool timed) {
    const timespec timeout{0, 10'000'000};
    while (shared_->turn.load(std::memory_order_acquire) == value)
      syscall(SYS_futex, word(), FUTEX_WAIT, value, timed ? &timeout : nullptr, nullptr, 0);
  }
  void pass(std::uint32_t value) {
    shared_->turn.store(value, std::memory_order_release);
    syscall(SYS_futex, word(), FUTEX_WAKE, 1, nullptr, nullptr, 0);
  }
  Shared* shared_ = nullptr;
  pid_t child_ = -1;
  std::uint32_t value_ = 0;
};

// Whether the main thread of process `pid` may run on `cpu` alone.
bool on_cpu_alone(pid_t pid, int cpu) {
  cpu_set_t cpus;
  return sched_getaffinity(pid, sizeof cpus, &cpus) == 0 && CPU_COUNT(&cpus) == 1 &&
         CPU_ISSET(cpu, &cpus);
}

// Lockstep: the physics publishes a step, an `afhub ctl hold --lockstep` process
// answers it, the physics resumes. One body (a ball) isolates the protocol; the KUKA
// (8 bodies published per step) is the realistic case. Both sides wait asleep on the
// slots' futexes, or with `spin` poll with sched_yield (--spin). Asleep and placed,
// the futex floor is measured in the same run, in turns of 200 round trips with the
// lockstep's (the floor moves from minute to minute on a VM: 33 to 45 us within a
// quarter of an hour), its peer where the controller is. Counters, p50 and p99 in us: the
// round trip (publish start to the answer applied), the bare and timed floors, the
// round trip's p50 over the bare floor's (over_floor), and simulated seconds per wall
// second with the physics step included.
void BM_LockstepRoundTrip(benchmark::State& state, bool kuka, bool spin, Placement placement) {
  if (kuka && !have_shared_models(state)) return;
  const ScopedPlacement placed(placement);
  if (placed.problem) {
    state.SkipWithError(placed.problem);
    return;
  }
  // Not when free: the scheduler places a forked floor and an exec'd controller apart.
  std::optional<FutexPingPong> floor;
  if (!spin && placement != Placement::kFree) {
    floor.emplace(placed.peer_cpu);
    if (floor->problem) {
      state.SkipWithError(floor->problem);
      return;
    }
  }
  afhub::testing::ModelFolder folder;
  const std::string file =
      kuka ? kKuka
           : folder.write("ball.yaml",
                          "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1\n"
                          "  shape: sphere\n  geometry: {radius: 0.05}\n");
  const Model model = load_adf_files({file});
  Simulation sim(model, 0.001);
  SimChannels channels(sim, 0.5);
  LockstepOptions options;
  options.wait_for = 1;
  options.spin = spin;
  channels.enable_lockstep(options);
  channels.publish({});
  std::vector<std::string> client_args{"ctl", "hold", kuka ? "base" : "ball", "--lockstep"};
  if (spin) client_args.push_back("--spin");
  if (placed.peer_cpu >= 0) {
    client_args.push_back("--cpu");
    client_args.push_back(std::to_string(placed.peer_cpu));
  }
  afhub::test::ScopedProcess client(afhub::test::spawn_afhub(client_args));
  channels.wait_for_clients();  // step 0 waits for the client to join
  channels.await_lockstep();
  if (placed.peer_cpu >= 0 && !on_cpu_alone(client.pid, placed.peer_cpu)) {
    state.SkipWithError("the controller could not be pinned");
    return;
  }
  // The paused floor: the bare one after as long as the physics' mean step, which the
  // controller sleeps through too (the longer a vCPU halts, the slower it wakes).
  enum Turn : std::uint64_t { kLockstep, kBareFloor, kTimedFloor, kPausedFloor, kTurns };
  LatencyHistogram round_trip, bare_floor, timed_floor, paused_floor;
  std::int64_t lockstep_ns = 0, stepping_ns = 0, steps = 0;
  std::uint64_t turn = 0;
  for (auto _ : state) {
    const std::uint64_t kind = floor ? (turn++ / 200) % kTurns : kLockstep;
    if (kind == kBareFloor) bare_floor.record(floor->round_trip_ns(false));
    if (kind == kTimedFloor) timed_floor.record(floor->round_trip_ns(true));
    if (kind == kPausedFloor)
      paused_floor.record(floor->round_trip_ns(false, steps ? stepping_ns / steps : 0));
    if (kind != kLockstep) continue;
    const std::int64_t begin = monotonic_ns();
    sim.step();
    const std::int64_t published = monotonic_ns();
    channels.publish({});
    channels.await_lockstep();
    const std::int64_t answered = monotonic_ns();
    round_trip.record(answered - published);
    lockstep_ns += answered - begin;
    stepping_ns += published - begin;
    ++steps;
  }
  state.counters["round_trip_p50_us"] = round_trip.percentile_us(0.50);
  state.counters["round_trip_p99_us"] = round_trip.percentile_us(0.99);
  if (floor) {
    state.counters["floor_p50_us"] = bare_floor.percentile_us(0.50);
    state.counters["floor_p99_us"] = bare_floor.percentile_us(0.99);
    state.counters["timed_floor_p50_us"] = timed_floor.percentile_us(0.50);
    state.counters["paused_floor_p50_us"] = paused_floor.percentile_us(0.50);
    state.counters["step_us"] =
        static_cast<double>(stepping_ns) * 1e-3 / static_cast<double>(steps);
    state.counters["over_floor"] = round_trip.percentile_us(0.50) / bare_floor.percentile_us(0.50);
    state.counters["over_paused_floor"] =
        round_trip.percentile_us(0.50) / paused_floor.percentile_us(0.50);
  }
  state.counters["x_real_time"] = static_cast<double>(round_trip.count()) * sim.dt_s() /
                                  (static_cast<double>(lockstep_ns) * 1e-9);
  state.counters["late"] = static_cast<double>(channels.late_answers());
}
// Fixed iterations: one run per case, so the client process starts once (a second
// SimChannels in this process would briefly publish beside the first). With the floors,
// a quarter of them are the lockstep's, a quarter each floor's (so Google Benchmark's
// own time per iteration mixes the four: read the counters).
void LockstepCases(benchmark::internal::Benchmark* cases) {
  cases->Unit(benchmark::kMicrosecond)->Iterations(30000);
}
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, one_body, false, false, Placement::kFree)
    ->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, one_body_apart, false, false, Placement::kApart)
    ->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, one_body_together, false, false, Placement::kTogether)
    ->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, one_body_spin, false, true, Placement::kFree)
    ->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, kuka, true, false, Placement::kFree)->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, kuka_apart, true, false, Placement::kApart)
    ->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, kuka_together, true, false, Placement::kTogether)
    ->Apply(LockstepCases);
BENCHMARK_CAPTURE(BM_LockstepRoundTrip, kuka_spin, true, true, Placement::kFree)
    ->Apply(LockstepCases);

}  // namespace
}  // namespace afhub::physics

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  // A hub of our own when none runs, stopped at the end.
  pid_t hub = -1;
  if (afhub::probe_roudi() != afhub::RoudiPresence::kRunning) {
    hub = afhub::test::spawn_afhub({"hub"});
    if (!afhub::test::wait_until(
            [] { return afhub::probe_roudi() == afhub::RoudiPresence::kRunning; },
            std::chrono::seconds(10))) {
      std::fprintf(stderr, "physics_benchmark: the hub did not start\n");
      return 1;
    }
  }
  afhub::connect_to_hub("physics-benchmark", afhub::HubPolicy::kRequire);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (hub > 0) afhub::test::stop_process(hub, SIGTERM);
  return 0;
}
