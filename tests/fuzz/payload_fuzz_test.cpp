// Payloads come from other processes and are untrusted. Random and mutated bytes of
// every payload kind go into check_payload, and what it accepts into every consumer,
// as the real readers do: the CLI's renderings (echo, ls, status, top), command
// application (the physics' copy into its input, the body's check, the input
// applied and stepped), the hub's catalog merge, and world control. No hub runs.
// Under the sanitize build (ASan, UBSan) an out-of-bounds read or undefined
// behaviour ends the run. The bounded run is a ctest entry; AFHUB_FUZZ_CASES=N
// runs N cases, AFHUB_FUZZ_SEED picks the sequence.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "afhub/devices/force_safety.hpp"
#include "afhub/hub/bodies.hpp"
#include "afhub/hub/step_tape.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/layout_id.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "afhub/shm_layout/world_control.hpp"
#include "afhub/teleop/teleop_law.hpp"
#include "catalog_merge.hpp"
#include "command_input.hpp"
#include "format.hpp"
#include "listings.hpp"
#include "loop_table.hpp"
#include "model_files.hpp"

namespace afhub {
namespace {

constexpr std::array kKinds{
    PayloadKind::kBodyState,    PayloadKind::kBodyCommand,   PayloadKind::kWorldState,
    PayloadKind::kWorldCommand, PayloadKind::kBodyDirectory, PayloadKind::kCatalog,
    PayloadKind::kHealth,       PayloadKind::kLoopStats,     PayloadKind::kBenchSample,
    PayloadKind::kDeviceState,  PayloadKind::kDeviceCommand, PayloadKind::kBenchSlot,
    PayloadKind::kStepTape};

std::uint64_t env_number(const char* name, std::uint64_t fallback) {
  const char* text = std::getenv(name);
  return text && *text ? std::strtoull(text, nullptr, 10) : fallback;
}

// A valid payload of each kind, with its counts in use: the mutations' starting points.
struct Seed {
  std::vector<unsigned char> bytes;
  std::vector<std::size_t> count_offsets;   // where its counts are, to hit them often
  std::vector<std::size_t> number_offsets;  // doubles to set to NaN, infinities, extremes
};

// `bytes`: the payload's real size (states and commands are sent with their counted
// joints only).
template <class T>
Seed seed_of(const T& payload, std::vector<std::size_t> count_offsets,
             std::size_t bytes = sizeof(T)) {
  Seed seed;
  seed.bytes.resize(bytes);
  std::memcpy(seed.bytes.data(), &payload, bytes);
  seed.count_offsets = std::move(count_offsets);
  return seed;
}

template <class T>
T stamped() {
  T payload{};
  payload.header.layout_id = kLayoutId;
  payload.header.kind = T::kKind;
  payload.header.sequence = 1;
  return payload;
}

// Three bodies, the last with kMaxJointsPerBody joints; the first two share its
// first two joint names, listed once, as loan_body_list writes them.
Seed body_list_seed(PayloadKind kind) {
  constexpr std::uint32_t kBodies = 3;
  constexpr std::uint32_t kNames = kMaxJointsPerBody;
  constexpr std::uint32_t kRefs = 2 + 2 + kMaxJointsPerBody;
  // Filled as a whole BodyList, then cut to its real size.
  std::vector<unsigned char> bytes(
      std::max(sizeof(BodyList), body_list_bytes(kBodies, kNames, kRefs)));
  auto* list = reinterpret_cast<BodyList*>(bytes.data());
  list->header = PayloadHeader{kLayoutId, kind};
  list->body_count = kBodies;
  list->joint_name_count = kNames;
  list->joint_ref_count = kRefs;
  std::vector<std::size_t> counts{offsetof(BodyList, body_count),
                                  offsetof(BodyList, joint_name_count),
                                  offsetof(BodyList, joint_ref_count)};
  std::uint32_t first_ref = 0;
  for (std::uint32_t b = 0; b < kBodies; ++b) {
    BodyInfo& body = list->bodies[b];
    set_name(body.channel, "fuzz/body" + std::to_string(b));
    set_name(body.owner, "fuzz-owner");
    body.joint_count = b == 2 ? kMaxJointsPerBody : 2;
    body.first_joint_ref = first_ref;
    for (std::uint32_t j = 0; j < body.joint_count; ++j) joint_refs_in(*list)[first_ref + j] = j;
    first_ref += body.joint_count;
    const std::size_t at = offsetof(BodyList, bodies) + b * sizeof(BodyInfo);
    counts.push_back(at + offsetof(BodyInfo, joint_count));
    counts.push_back(at + offsetof(BodyInfo, first_joint_ref));
  }
  for (std::uint32_t n = 0; n < kNames; ++n)
    set_name(joint_names_in(*list)[n], "joint" + std::to_string(n));
  counts.push_back(body_list_bytes(kBodies, kNames));  // the first joint reference
  bytes.resize(body_list_bytes(kBodies, kNames, kRefs));
  return {std::move(bytes), std::move(counts), {}};
}

// A step tape of a command taken and two states packed (named as a physics names its
// bodies), at its used size.
Seed step_tape_seed(const BodyState& state, const BodyCommand& command) {
  static_assert(sizeof(BodyCommand) <= sizeof(BodyState));  // the consumer's copy holds either
  auto tape = std::make_unique<StepTape>(stamped<StepTape>());
  std::vector<std::size_t> counts = {offsetof(StepTape, entry_count),
                                     offsetof(StepTape, data_bytes)};
  const auto add = [&](PayloadKind kind, const std::string& name, const PackedPieces& pieces) {
    std::size_t bytes = 0;
    for (const auto& piece : pieces) bytes += piece.size();
    const StepTapeEntry entry{static_cast<std::uint32_t>(name.size()),
                              static_cast<std::uint32_t>(bytes), kind, 0};
    const std::size_t entry_at = offsetof(StepTape, data) + tape->data_bytes;
    const std::size_t payload_at = entry_at + step_tape_payload_offset(name.size());
    counts.insert(counts.end(), {entry_at, entry_at + 4, entry_at + 8});  // its sizes, kind
    if (kind == PayloadKind::kBodyState)
      counts.insert(counts.end(), {payload_at + offsetof(BodyState, joint_count),
                                   payload_at + offsetof(BodyState, sensor_ray_count)});
    std::uint8_t* at = tape->data.data() + tape->data_bytes;
    std::memcpy(at, &entry, sizeof entry);
    std::memcpy(at + sizeof entry, name.data(), name.size());
    std::uint8_t* to = at + step_tape_payload_offset(name.size());
    for (const auto& piece : pieces) {
      if (!piece.empty()) std::memcpy(to, piece.data(), piece.size());
      to += piece.size();
    }
    tape->data_bytes += static_cast<std::uint32_t>(step_tape_entry_bytes(name.size(), bytes));
    ++tape->entry_count;
  };
  add(PayloadKind::kBodyCommand, "arm/base",
      {std::span(reinterpret_cast<const std::uint8_t*>(&command),
                 body_command_bytes(command.joint_count))});
  add(PayloadKind::kBodyState, "arm/base", packed_pieces(state));
  BodyState refused = state;  // packed with its reason
  std::memcpy(refused.refusal_reason.data(), "NaN in position", 16);
  add(PayloadKind::kBodyState, "arm/link1", packed_pieces(refused));
  tape->last_part = 1;
  return seed_of(*tape, std::move(counts), offsetof(StepTape, data) + tape->data_bytes);
}

std::vector<Seed> make_seeds() {
  auto state = stamped<BodyState>();
  state.joint_count = 7;
  state.sensor_ray_count = 3;
  auto command = stamped<BodyCommand>();
  command.cartesian_type = CartesianCommandType::kPosition;
  command.joint_count = 3;
  command.joints[1].type = JointCommandType::kPosition;
  auto world = stamped<WorldState>();
  world.light_count = 2;
  world.camera_count = 1;
  set_name(world.lights[0].name, "light");
  auto world_command = stamped<WorldCommand>();
  world_command.action = WorldAction::kStep;
  auto health = stamped<Health>();
  health.process_count = 2;
  health.mempool_count = 3;
  set_name(health.processes[0].name, "afhub-hub");
  auto loop = stamped<LoopStats>();
  set_name(loop.name, "ctl sine");
  set_name(loop.body, "arm/base");
  auto bench = stamped<BenchSample>();
  auto bench_slot = bench;  // the same payload, through a slot
  bench_slot.header.kind = PayloadKind::kBenchSlot;
  auto device = stamped<DeviceState>();
  device.spec.max_force_n = 10.0;
  device.spec.max_stiffness_npm = 3000.0;
  device.spec.sensed = kDeviceTranslation | kDeviceGripper;
  device.spec.button_count = 4;
  set_name(device.spec.model, "virtual");
  device.pose.position_m = {0.01, -0.02, 0.03};
  device.gripper_angle_rad = 0.4;
  device.gate = ForceGate::kApplying;
  device.applied.force_n = {1.0, 0.0, -1.0};
  auto device_command = stamped<DeviceCommand>();
  device_command.wrench.force_n = {1.0, 2.0, 3.0};
  device_command.gripper_force_n = 0.5;
  device_command.enable = 1;
  Seed device_seed = seed_of(device, {offsetof(DeviceState, gate)});
  for (std::size_t at = offsetof(DeviceState, pose); at < offsetof(DeviceState, buttons);
       at += sizeof(double))
    device_seed.number_offsets.push_back(at);  // pose, velocity, gripper angle
  for (std::size_t at = offsetof(DeviceState, spec) + offsetof(DeviceSpec, max_force_n);
       at < offsetof(DeviceState, spec) + offsetof(DeviceSpec, sensed); at += sizeof(double))
    device_seed.number_offsets.push_back(at);  // the spec's maxima
  Seed command_seed = seed_of(device_command, {});
  for (std::size_t at = offsetof(DeviceCommand, wrench); at < offsetof(DeviceCommand, enable);
       at += sizeof(double))
    command_seed.number_offsets.push_back(at);  // force, torque, gripper force
  return {
      seed_of(state, {offsetof(BodyState, joint_count), offsetof(BodyState, sensor_ray_count)},
              body_state_bytes(state.joint_count)),
      seed_of(command, {offsetof(BodyCommand, joint_count), offsetof(BodyCommand, actuator_count)},
              body_command_bytes(command.joint_count)),
      seed_of(world, {offsetof(WorldState, light_count), offsetof(WorldState, camera_count),
                      offsetof(WorldState, body_count)}),
      seed_of(world_command, {offsetof(WorldCommand, action), offsetof(WorldCommand, step_count),
                              offsetof(WorldCommand, hold_ms), offsetof(WorldCommand, valid_ms)}),
      body_list_seed(PayloadKind::kBodyDirectory),
      body_list_seed(PayloadKind::kCatalog),
      seed_of(health, {offsetof(Health, process_count), offsetof(Health, mempool_count)}),
      seed_of(loop, {}),
      seed_of(bench, {}),
      device_seed,
      command_seed,
      seed_of(bench_slot, {}),
      step_tape_seed(state, command),
  };
}

// What the command consumers act on: the example arm, and a body with an actuator.
struct CommandTarget {
  CommandTarget() {
    const std::string gripper_file = folder.write(
        "gripper.yaml",
        "bodies: [BODY gripper, BODY ball]\nactuators: [ACTUATOR grip]\n"
        "BODY gripper:\n  name: gripper\n  mass: 0\n"
        "BODY ball:\n  name: ball\n  mass: 1\n  shape: sphere\n  geometry: {radius: 0.05}\n"
        "  location: {position: {x: 0, y: 0, z: -0.045}}\n"
        "ACTUATOR grip:\n  name: grip\n  type: Constraint\n  parent: BODY gripper\n"
        "  max impulse: 10\n  tau: 1\n");
    model =
        physics::load_adf_files({std::string(AFHUB_EXAMPLE_MODELS) + "/arm7.yaml", gripper_file});
    sim = std::make_unique<physics::Simulation>(model, 0.001);
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      if (model.descendant_joints[b].size() > model.descendant_joints[arm].size()) arm = b;
      if (model.bodies[b].name == "gripper") gripper = b;
    }
  }
  testing::ModelFolder folder;
  physics::Model model;
  std::unique_ptr<physics::Simulation> sim;
  std::size_t arm = 0;      // the body with the most joints below it
  std::size_t gripper = 0;  // the body with an actuator
};

struct Tally {
  std::uint64_t cases = 0, accepted = 0;
  std::array<std::uint64_t, 5> by_error{};
};

class Fuzzer {
 public:
  explicit Fuzzer(std::uint64_t seed) : random_(seed), seeds_(make_seeds()) {
    const Seed& catalog = seeds_[5];
    catalog_ = catalog.bytes;
    health_ = seeds_[6].bytes;
    world_ = seeds_[2].bytes;
    info_ = entry_of(*reinterpret_cast<const BodyList*>(catalog_.data()), 2);
  }

  void run_case(std::size_t kind_index) {
    const PayloadKind kind = kKinds[kind_index];
    const std::vector<unsigned char> bytes = next_bytes(kind_index);
    // Exactly as long as the chunk: ASan sees a read one byte past it.
    std::unique_ptr<unsigned char[]> exact(
        new unsigned char[std::max<std::size_t>(bytes.size(), 1)]);
    if (!bytes.empty()) std::memcpy(exact.get(), bytes.data(), bytes.size());
    const char* field = nullptr;
    const PayloadError error = check_payload(exact.get(), bytes.size(), kind, &field);
    Tally& tally = tallies_[kind_index];
    ++tally.cases;
    ++tally.by_error[static_cast<std::size_t>(error)];
    EXPECT_NE(field, nullptr);
    // Read as any other kind, it is refused (the kinds differ) or valid as that kind.
    const PayloadKind other =
        kKinds[(kind_index + 1 + random_() % (kKinds.size() - 1)) % kKinds.size()];
    if (check_payload(exact.get(), bytes.size(), other) == PayloadError::kNone)
      consume(other, exact.get());
    if (error != PayloadError::kNone) return;
    ++tally.accepted;
    consume(kind, exact.get());
  }

  const std::array<Tally, kKinds.size()>& tallies() const { return tallies_; }
  std::uint64_t applied_commands() const { return applied_; }
  std::uint64_t steps() const { return steps_; }

 private:
  std::vector<unsigned char> next_bytes(std::size_t kind_index) {
    const Seed& seed = seeds_[kind_index];
    std::vector<unsigned char> bytes;
    switch (random_() % 4) {
      case 0: {  // random bytes of a random length, the header sometimes valid
        bytes.resize(random_() % (seed.bytes.size() + 64));
        for (auto& byte : bytes) byte = static_cast<unsigned char>(random_());
        if (random_() % 2 && bytes.size() >= sizeof(PayloadHeader))
          std::memcpy(bytes.data(), seed.bytes.data(), sizeof(PayloadHeader));
        return bytes;
      }
      case 1:  // the seed cut short or grown
        bytes = seed.bytes;
        bytes.resize(random_() % (seed.bytes.size() + 64), static_cast<unsigned char>(random_()));
        return bytes;
      default: {  // the seed with a few bytes changed, and often a count
        bytes = seed.bytes;
        const int flips = 1 + static_cast<int>(random_() % 8);
        for (int i = 0; i < flips; ++i)
          bytes[random_() % bytes.size()] = static_cast<unsigned char>(random_());
        if (!seed.count_offsets.empty() && random_() % 4 != 0) {
          const std::size_t at = seed.count_offsets[random_() % seed.count_offsets.size()];
          const std::uint32_t value = interesting_count();
          std::memcpy(bytes.data() + at, &value, sizeof value);
        }
        if (!seed.number_offsets.empty() && random_() % 2 == 0) {
          const std::size_t at = seed.number_offsets[random_() % seed.number_offsets.size()];
          const double value = interesting_number();
          std::memcpy(bytes.data() + at, &value, sizeof value);
        }
        if (random_() % 8 == 0) bytes.resize(random_() % bytes.size());
        return bytes;
      }
    }
  }

  // Around the capacities, and anything at all.
  std::uint32_t interesting_count() {
    static constexpr std::uint32_t kEdges[] = {
        0,    1,    7,    8,    9,     31,    32,    33,         63,
        64,   65,   255,  256,  257,   499,   500,   501,        1023,
        1024, 1025, 1028, 1029, 65535, 65536, 65537, 0x7fffffff, 0xffffffff};
    return random_() % 3 ? kEdges[random_() % std::size(kEdges)]
                         : static_cast<std::uint32_t>(random_());
  }

  // Non-finite, extreme and ordinary doubles.
  double interesting_number() {
    static constexpr double kEdges[] = {std::numeric_limits<double>::quiet_NaN(),
                                        -std::numeric_limits<double>::quiet_NaN(),
                                        std::numeric_limits<double>::infinity(),
                                        -std::numeric_limits<double>::infinity(),
                                        std::numeric_limits<double>::max(),
                                        -std::numeric_limits<double>::max(),
                                        std::numeric_limits<double>::denorm_min(),
                                        1e154,
                                        -1e154,
                                        0.0,
                                        -0.0,
                                        1.0,
                                        -1.0,
                                        1e-9};
    return kEdges[random_() % std::size(kEdges)];
  }

  // A DeviceState check_payload accepted: its gate names one, its numbers are finite
  // (what the readers rely on); then as `afhub echo` renders it and as the teleop law
  // reads it, whose device force stays finite and within the max force.
  void consume_device_state(const DeviceState& state, std::size_t& sink) {
    EXPECT_LE(state.gate, ForceGate::kStopping) << "check_payload let a bad gate through";
    const Pose& p = state.pose;
    const Twist& v = state.velocity;
    for (double x :
         {p.position_m.x, p.position_m.y, p.position_m.z, p.orientation.x, p.orientation.y,
          p.orientation.z, p.orientation.w, v.linear_mps.x, v.linear_mps.y, v.linear_mps.z,
          v.angular_radps.x, v.angular_radps.y, v.angular_radps.z, state.gripper_angle_rad})
      EXPECT_TRUE(std::isfinite(x)) << "check_payload let a non-finite device pose through";
    if (::testing::Test::HasFailure()) return;
    sink += cli::device_state_json(info_, state).size();
    sink += cli::device_state_text(info_, state).size();
    teleop::TeleopOutput out;
    law_.step(state, {}, {}, 0.001, out);
    const Vec3& f = out.device_wrench.force_n;
    const double force = std::hypot(f.x, f.y, f.z);
    EXPECT_TRUE(std::isfinite(force));
    EXPECT_LE(force, kLawMaxForce * (1 + 1e-12));
  }

  // A DeviceCommand check_payload accepted: finite, and a driver's safety rules apply it
  // within the device's maxima.
  void consume_device_command(const DeviceCommand& command, std::size_t& sink) {
    const Wrench& w = command.wrench;
    for (double x : {w.force_n.x, w.force_n.y, w.force_n.z, w.torque_nm.x, w.torque_nm.y,
                     w.torque_nm.z, command.gripper_force_n})
      EXPECT_TRUE(std::isfinite(x)) << "check_payload let a non-finite force through";
    ForceGate gate{};
    const devices::DeviceOutput output =
        safety_.apply(&command, command.header.publish_stamp_ns, gate);
    const Vec3& f = output.wrench.force_n;
    EXPECT_LE(std::hypot(f.x, f.y, f.z), safety_spec().max_force_n * (1 + 1e-12));
    EXPECT_LE(std::abs(output.gripper_force_n), safety_spec().max_gripper_force_n);
    sink += gate == ForceGate::kApplying;
  }

  static DeviceSpec safety_spec() {
    DeviceSpec spec;
    spec.max_force_n = 8.0;
    spec.max_torque_nm = 1.0;
    spec.max_gripper_force_n = 2.0;
    return spec;
  }
  static constexpr double kLawMaxForce = 4.0;
  static teleop::TeleopParams law_params() {
    teleop::TeleopParams params;
    params.haptic_gain_linear = 50.0;
    params.haptic_gain_angular = 1.0;
    params.max_force_n = kLawMaxForce;
    params.deadband_n = 0.01;
    params.body_gains.linear = {200.0, 10.0};
    params.body_gains.angular = {1.0, 0.1};
    return params;
  }

  void consume(PayloadKind kind, const unsigned char* data) {
    const auto& health = *reinterpret_cast<const Health*>(health_.data());
    const auto& catalog = *reinterpret_cast<const BodyList*>(catalog_.data());
    const auto* world = reinterpret_cast<const WorldState*>(world_.data());
    std::size_t sink = 0;
    switch (kind) {
      case PayloadKind::kBodyState: {
        const auto& state = *reinterpret_cast<const BodyState*>(data);
        sink += cli::state_json(info_, state).size();
        sink += cli::state_text(info_, state, cli::StateFields{}).size();
        break;
      }
      case PayloadKind::kBodyCommand:
        apply_command(*reinterpret_cast<const BodyCommand*>(data));
        break;
      case PayloadKind::kWorldState:
        world = reinterpret_cast<const WorldState*>(data);
        sink += cli::status_text(health, catalog, world, {}).size();
        sink += cli::status_json(health, catalog, world, {}).size();
        break;
      case PayloadKind::kWorldCommand: {
        WorldControl control;
        control.paused = random_() % 2;
        control.apply(*reinterpret_cast<const WorldCommand*>(data), 0);
        sink += control.take_step() + control.lapse(random_()).pid;
        break;
      }
      case PayloadKind::kBodyDirectory: {
        std::vector<std::string> messages;
        const auto* listed = reinterpret_cast<const BodyList*>(catalog_.data());
        std::vector<BodyEntry> current;
        for (std::uint32_t b = 0; b < listed->body_count; ++b)
          current.push_back(entry_of(*listed, b));
        const auto merged = merge_directories(
            current, {{"fuzz", reinterpret_cast<const BodyList*>(data)}, {"seed", listed}},
            messages);
        sink += merged.size() + messages.size();
        break;
      }
      case PayloadKind::kCatalog: {
        const auto& list = *reinterpret_cast<const BodyList*>(data);
        sink += cli::ls_text(list).size() + cli::ls_json(list).size();
        sink += cli::status_text(health, list, world, {}).size();
        sink += cli::status_json(health, list, world, {}).size();
        // echo renders a state with the joint names of the body's catalog entry.
        if (list.body_count > 0) {
          const auto& state = *reinterpret_cast<const BodyState*>(seeds_[0].bytes.data());
          const BodyEntry entry =
              entry_of(list, static_cast<std::uint32_t>(random_() % list.body_count));
          sink += cli::state_json(entry, state).size();
          sink += entry.joint_names.size();
        }
        break;
      }
      case PayloadKind::kHealth: {
        const auto& checked = *reinterpret_cast<const Health*>(data);
        sink += cli::status_text(checked, catalog, world, {}).size();
        sink += cli::status_json(checked, catalog, world, {}).size();
        break;
      }
      case PayloadKind::kLoopStats: {
        const std::vector<LoopStats> loops{*reinterpret_cast<const LoopStats*>(data)};
        JsonWriter json;
        cli::loop_json(json, loops);
        sink += cli::loop_table(loops).size() + json.str().size();
        sink += cli::status_text(health, catalog, world, loops).size();
        break;
      }
      case PayloadKind::kBenchSample:
      case PayloadKind::kBenchSlot:
        break;  // its fields are stamps and a round number, read as numbers
      case PayloadKind::kDeviceState:
        consume_device_state(*reinterpret_cast<const DeviceState*>(data), sink);
        break;
      case PayloadKind::kDeviceCommand:
        consume_device_command(*reinterpret_cast<const DeviceCommand*>(data), sink);
        break;
      case PayloadKind::kStepTape:
        // As a recorder reads it: each entry copied out, checked as what it says it is,
        // then read by that kind's consumers.
        for_each_tape_entry(
            *reinterpret_cast<const StepTape*>(data),
            [&](PayloadKind entry_kind, std::string_view name, const void* bytes,
                std::uint32_t size) {
              sink += name.size();
              auto copy = std::make_unique<BodyState>();
              std::memcpy(static_cast<void*>(copy.get()), bytes, size);
              if (entry_kind == PayloadKind::kBodyState) {  // packed
                if (check_packed_body_state(copy.get(), size) != PayloadError::kNone) return;
                auto state = std::make_unique<BodyState>();
                unpack_body_state(
                    std::span(reinterpret_cast<const std::uint8_t*>(copy.get()), size), *state);
                sink += cli::state_json(info_, *state).size();
              } else if (check_payload(copy.get(), size, entry_kind) == PayloadError::kNone) {
                apply_command(*reinterpret_cast<const BodyCommand*>(copy.get()));
              }
            });
        break;
      case PayloadKind::kSceneDescription:
      case PayloadKind::kSoftBodyMesh:
      case PayloadKind::kScenePoses:
        break;  // not yet fuzzed: no seed
    }
    sink_ += sink;
  }

  // As SimChannels::apply_commands does: copied, checked against the body, applied.
  void apply_command(const BodyCommand& command) {
    physics::BodyInput input;
    physics::to_input(command, input);
    physics::Simulation& sim = *target_.sim;
    // Mostly a body the command may fit, so that commands get applied.
    const std::size_t body = input.actuator_count > 0 ? target_.gripper
                             : random_() % 4          ? target_.arm
                                                      : random_() % target_.model.bodies.size();
    if (sim.input_problem(body, input)) return;
    sim.set_input(body, input);
    ++applied_;
    // Stepping is what costs: every so often, and a fresh world when it blew up.
    if (applied_ % 64 == 0) {
      sim.step();
      ++steps_;
      if (steps_ % 256 == 0)
        target_.sim = std::make_unique<physics::Simulation>(target_.model, 0.001);
    }
  }

  std::mt19937_64 random_;
  std::vector<Seed> seeds_;
  std::vector<unsigned char> catalog_, health_, world_;
  BodyEntry info_{};
  CommandTarget target_;
  teleop::TeleopLaw law_{law_params()};
  // No ramp, a watchdog that never fires (commands are applied at their own stamp).
  devices::ForceSafety safety_{safety_spec(), {1'000'000'000, 0.0, 0}};
  std::array<Tally, kKinds.size()> tallies_{};
  std::uint64_t applied_ = 0, steps_ = 0;
  std::size_t sink_ = 0;
};

TEST(PayloadFuzz, EveryKindIntoCheckAndEveryConsumer) {
  const std::uint64_t cases = env_number("AFHUB_FUZZ_CASES", 200'000);
  const std::uint64_t seed = env_number("AFHUB_FUZZ_SEED", 13);
  Fuzzer fuzzer(seed);
  for (std::uint64_t i = 0; i < cases; ++i) {
    fuzzer.run_case(i % kKinds.size());
    if (::testing::Test::HasFailure()) break;
  }
  std::printf("payload fuzz: %llu cases (seed %llu); %llu commands applied, %llu steps\n",
              static_cast<unsigned long long>(cases), static_cast<unsigned long long>(seed),
              static_cast<unsigned long long>(fuzzer.applied_commands()),
              static_cast<unsigned long long>(fuzzer.steps()));
  for (std::size_t k = 0; k < kKinds.size(); ++k) {
    const Tally& tally = fuzzer.tallies()[k];
    std::printf(
        "  kind %u: %llu cases, %llu accepted; refused: %llu too small, %llu foreign, "
        "%llu wrong kind, %llu count too large\n",
        static_cast<unsigned>(kKinds[k]), static_cast<unsigned long long>(tally.cases),
        static_cast<unsigned long long>(tally.accepted),
        static_cast<unsigned long long>(tally.by_error[1]),
        static_cast<unsigned long long>(tally.by_error[2]),
        static_cast<unsigned long long>(tally.by_error[3]),
        static_cast<unsigned long long>(tally.by_error[4]));
    // Every kind reached its consumers, and was refused too: the fuzz covers both.
    if (cases >= 10'000) {
      EXPECT_GT(tally.accepted, tally.cases / 10) << "kind " << static_cast<unsigned>(kKinds[k]);
      EXPECT_GT(tally.cases - tally.accepted, tally.cases / 10)
          << "kind " << static_cast<unsigned>(kKinds[k]);
    }
  }
  if (cases >= 10'000) {
    EXPECT_GT(fuzzer.applied_commands(), 0u);
  }
}

}  // namespace
}  // namespace afhub
