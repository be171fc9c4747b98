// The simulation's channels (see sim_channels.hpp): construction, claiming the bodies,
// publishing their states and the world, and the world's commands.
#include "afhub/physics/sim_channels.hpp"

#include <algorithm>
#include <cstdio>
#include <map>

#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/hub_health.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/hub/world_command_queue.hpp"
#include "afhub/rt/clock.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/slot_block.hpp"
#include "scene_description.hpp"

namespace afhub::physics {
namespace {

// The wire and the core agree on capacities, so a copy never truncates what fits.
static_assert(kBodyRayCapacity == kMaxSensorRaysPerBody);

// A new step's states, untaped, are written a block of channels at a time by the
// stepping thread and the islands' helper at once (Simulation::share): each channel's
// slot and publisher are its own, and each thread has a reading buffer. A thousand
// bodies: publishing 0.58 to 0.70x (docs/performance.md).
constexpr int kChannelsPerItem = 16;

// A reading into a loaned state (its header is the caller's), within the joints
// it was loaned for.
void to_state(const BodyReading& reading, BodyState& state) noexcept {
  state.pose = reading.pose;
  state.twist = reading.twist;
  state.wrench = reading.wrench;
  state.contact_wrench = reading.contact_wrench;
  state.contact_count = reading.contact_count;
  state.mass_kg = reading.mass_kg;
  state.principal_inertia_kgm2 = reading.principal_inertia_kgm2;
  state.joint_count = std::min(state.joint_count, reading.joint_count);
  for (std::uint32_t j = 0; j < state.joint_count; ++j)
    state.joints[j] = {reading.joint_positions[j], reading.joint_velocities[j],
                       reading.joint_efforts[j]};
  state.sensor_ray_count = reading.ray_count;
  for (std::uint32_t r = 0; r < reading.ray_count; ++r) {
    state.sensor_distances_m[r] = reading.ray_distances_m[r];
    // A range stays as the model set it: rewritten, its line would leave the readers'
    // caches every step (BodyPublisher::prefetch_state_update).
    if (state.sensor_ranges_m[r] != reading.ray_ranges_m[r])
      state.sensor_ranges_m[r] = reading.ray_ranges_m[r];
  }
}

// Body b's catalog entry: its joints, and by name its sensors' rays and actuators in
// state and command order (the order Simulation builds them in), the bodies jointed
// below it and its parent (the first joint's in file order, for a body in a loop).
BodyEntry body_entry(const Model& model, std::size_t b, const std::vector<std::string>& joints) {
  BodyEntry entry = make_body_entry(model.bodies[b].channel, joints);
  std::vector<std::string> rays, actuators, children;
  std::string parent;
  const int body = static_cast<int>(b);
  for (const SensorSpec& sensor : model.sensors)
    if (sensor.parent == body) rays.insert(rays.end(), sensor.rays.size(), sensor.name);
  for (const ActuatorSpec& actuator : model.actuators)
    if (actuator.parent == body) actuators.push_back(actuator.name);
  for (const JointSpec& joint : model.joints) {
    if (joint.parent == body && joint.child >= 0)
      children.push_back(model.bodies[joint.child].name);
    if (joint.child == body && joint.parent >= 0 && parent.empty())
      parent = model.bodies[joint.parent].name;
  }
  set_body_parts(entry, std::move(rays), std::move(actuators), std::move(children),
                 std::move(parent));
  return entry;
}

// The bodies the model publishes (passive ones publish nothing), checked with the hub
// before this process opens a publisher: one publisher per body, room for them, and
// no other live simulation of this world. The blocks of their state slots (by size: a body's state
// carries the joints below it), and the world state's, the scene's, the pose feed's, the step
// tape's, the directory's and the loop stats' publishers.
std::vector<std::string> claim_bodies(const Model& model, const std::string& world) {
  std::vector<std::string> claimed;
  std::map<std::uint32_t, std::size_t> states_by_size;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    if (model.bodies[b].passive) continue;
    claimed.push_back(model.bodies[b].channel);
    ++states_by_size[slot_payload_capacity(
        static_cast<std::uint32_t>(body_state_bytes(model.descendant_joints[b].size())))];
  }
  for (const SoftBodySpec& soft : model.soft_bodies) {
    claimed.push_back(soft.channel);
    ++states_by_size[slot_payload_capacity(static_cast<std::uint32_t>(body_state_bytes(0)))];
  }
  if (claimed.size() > kMaxBodies)
    throw Error("the model publishes " + std::to_string(claimed.size()) +
                " bodies; the hub holds " + std::to_string(kMaxBodies));
  std::size_t publishers = 6;
  for (const auto& [capacity, count] : states_by_size)
    publishers += slot_blocks_for(count, capacity);
  if (check_room_for_bodies(claimed, publishers) > 0) check_world_free(world);
  return claimed;
}

}  // namespace

SimChannels::SimChannels(Simulation& sim, double watchdog_s, std::string_view name_space)
    : sim_(sim),
      claimed_(claim_bodies(sim.model(), world_instance(name_space))),
      world_({std::string(kService), world_instance(name_space), std::string(kStateEvent)}),
      scene_({std::string(kService), world_instance(name_space), std::string(kSceneEvent)}),
      scene_poses_(
          {std::string(kService), world_instance(name_space), std::string(kScenePosesEvent)}),
      world_instance_(world_instance(name_space)),
      tape_(world_instance_),
      world_commands_(std::make_unique<WorldCommandQueue>(world_instance(name_space))) {
  if (!(watchdog_s >= kMinWatchdogS && watchdog_s <= kMaxWatchdogS))
    throw Error("the watchdog period must be 0.002 to 3600 s, got " + std::to_string(watchdog_s));
  const auto watchdog_ns = static_cast<std::int64_t>(watchdog_s * 1e9);
  const Model& model = sim.model();
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodySpec& body = model.bodies[b];
    if (body.passive) continue;
    std::vector<std::string> joint_names;
    for (int j : model.descendant_joints[b]) joint_names.push_back(model.joints[j].name);
    if (joint_names.size() > kMaxJointsPerBody)
      throw Error(body.where.str() + ": error: '" + body.name + "' has " +
                  std::to_string(joint_names.size()) +
                  " joints below it; a state carries at most " + std::to_string(kMaxJointsPerBody));
    directory_.add(body_entry(model, b, joint_names));
    Channel channel;
    channel.index = b;
    channel.publisher = std::make_unique<BodyPublisher>(body.channel);
    channel.joint_count = static_cast<std::uint32_t>(joint_names.size());
    channel.watchdog_ns = watchdog_ns;
    for (const ActuatorSpec& actuator : model.actuators)
      if (actuator.parent == static_cast<int>(b)) ++channel.actuator_count;
    for (const SensorSpec& sensor : model.sensors)
      if (sensor.parent == static_cast<int>(b))
        channel.ray_count += static_cast<std::uint32_t>(sensor.rays.size());
    channels_.push_back(std::move(channel));
  }
  for (std::size_t s = 0; s < model.soft_bodies.size(); ++s) {
    directory_.add(make_body_entry(model.soft_bodies[s].channel, {}));
    Channel channel;
    channel.index = s;
    channel.soft = true;
    channel.publisher = std::make_unique<BodyPublisher>(model.soft_bodies[s].channel);
    channels_.push_back(std::move(channel));
    if (s >= kMaxSceneSoftBodies) continue;  // not in the scene: fill_scene says so
    const std::string& name = model.soft_bodies[s].channel;
    SoftSurface surface;
    surface.index = s;
    surface.faces = std::make_unique<Writer<SoftBodyMesh>>(
        ChannelId{std::string(kService), name, std::string(kSoftFacesEvent)});
    surface.nodes = std::make_unique<Writer<SoftBodyMesh>>(
        ChannelId{std::string(kService), name, std::string(kSoftNodesEvent)});
    soft_surfaces_.push_back(std::move(surface));
  }
  // Before the first loan.
  std::vector<SlotWritten> slots{{PayloadKind::kWorldState, sizeof(WorldState)}};
  for (const Channel& channel : channels_)
    slots.push_back({PayloadKind::kBodyState, body_state_bytes(channel.joint_count)});
  require_chunks(written_as_slots(slots),
                 "this physics (" + std::to_string(channels_.size()) + " bodies)");
  std::size_t joint_values = 0;
  for (std::size_t b = 0; b < scene_body_count(model); ++b)
    if (!model.bodies[b].passive)
      joint_values += std::min(model.descendant_joints[b].size(), kBodyJointCapacity);
  if (joint_values > kMaxSceneJointValues)
    std::fprintf(stderr,
                 "afhub run: a viewer's pose feed holds %zu joint positions and this model's "
                 "bodies have %zu below them: a viewer shows no joints for the bodies past it\n",
                 kMaxSceneJointValues, joint_values);
  scene_joint_values_ = static_cast<std::uint32_t>(std::min(joint_values, kMaxSceneJointValues));
  lockstep_pids_.reserve(channels_.size());
  attach_command_waiter();  // past its capacity, the waits for commands poll
  publish_scene();
  publish_soft_faces();
  directory_.publish();
  confirm_body_claims(claimed_, kClaimConfirmTimeout);
}

SimChannels::~SimChannels() = default;

void SimChannels::fill_objects(std::array<WorldObjectPose, kMaxWorldObjects>& out,
                               const std::vector<WorldObjectSpec>& specs,
                               Pose (Simulation::*pose)(std::size_t)
                                   const noexcept) const noexcept {
  for (std::size_t i = 0; i < specs.size() && i < kMaxWorldObjects; ++i) {
    set_name(out[i].name, specs[i].name);
    out[i].pose = (sim_.*pose)(i);
  }
}

void SimChannels::publish(const WorldClock& clock) noexcept {
  last_published_ = clock;
  const std::uint64_t step = sim_.step_count();
  const double time_s = sim_.time_s();
  if (step != timeliness_step_) {  // once per step taken, not per publish while paused
    timeliness_step_ = step;
    for (Channel& channel : channels_) {
      // Fixed when the step is taken: a step published again while the physics waits
      // may meet a command already taken for the next one.
      channel.state_command_step =
          channel.commanded ? static_cast<std::int64_t>(channel.applied_answer_step) : -1;
      if (!channel.commanded) continue;
      ++commanded_steps_;
      ++channel.commanded_steps;
      if (channel.applied_answer_step + 1 == step) {
        ++answered_steps_;
        ++channel.answered_steps;
        channel.in_phase = true;
        channel.phase_misses = 0;
      }
    }
  }
  // A step is taped once: a paused or held step published again is not, and the commands
  // taken meanwhile wait for the next step's tape.
  const bool new_step = step != taped_step_;
  const bool taping = new_step && tape_.begin(step, time_s);
  taped_step_ = step;
  // The step's states share one stamp, read before the first is filled: a clock read
  // per state was a quarter of publishing a thousand (28 ns each on the project's VM).
  const StateStamp stamp{step, time_s, clock.step_due_ns, monotonic_ns()};
  if (new_step) step_published_ns_ = stamp.stamp_ns;
  const int count = static_cast<int>(channels_.size());
  if (new_step && !taping) {
    share_each(sim_, count, kChannelsPerItem, [&](int c, int thread) {
      // The state slots were last read by other cores (controllers, viewers): their
      // lines are asked for a few bodies ahead, within this thread's block (share_each
      // hands a thread whole blocks of kChannelsPerItem from a multiple of it; another
      // block's writer may be in loan() on the other thread).
      const int block_end = std::min(count, (c / kChannelsPerItem + 1) * kChannelsPerItem);
      const int ahead = c + static_cast<int>(kBodyPrefetchAhead);
      for (int k = c % kChannelsPerItem == 0 ? c + 1 : ahead; k <= ahead && k < block_end; ++k)
        channels_[static_cast<std::size_t>(k)].prefetch_state_update();
      Channel& channel = channels_[static_cast<std::size_t>(c)];
      publish_state(channel, readings_[static_cast<std::size_t>(thread)], stamp);
      channel.taken_command = nullptr;
    });
  } else {  // the tape is written in channel order; a step published again is not shared
    for (std::size_t c = 0; c < channels_.size(); ++c) {
      if (c + kBodyPrefetchAhead < channels_.size())
        channels_[c + kBodyPrefetchAhead].prefetch_state_update();
      Channel& channel = channels_[c];
      const BodyState* state = publish_state(channel, readings_[0], stamp);
      // Only the bodies someone reads: a recorder holds the state slots of those it
      // records (taping all of a thousand bodies for a recorder of one cost about 60 us
      // of a 1.1 ms step); a body of no one's is not worth a copy.
      if (taping && state && channel.publisher->has_state_readers()) {
        const std::string& name = channel.soft ? sim_.model().soft_bodies[channel.index].channel
                                               : sim_.model().bodies[channel.index].channel;
        if (channel.taken_command)  // what this step answered, as it was taken
          tape_.add(PayloadKind::kBodyCommand, name, channel.taken_command,
                    channel.publisher->command_bytes());
        // This process's own entry: read back as it was just published.
        tape_.add(PayloadKind::kBodyState, name, state,
                  static_cast<std::uint32_t>(body_state_bytes(channel.joint_count)));
      }
      if (new_step) channel.taken_command = nullptr;
    }
  }
  if (WorldState* world = world_.loan()) {
    world->header.sim_step = step;
    world->header.sim_time_s = time_s;
    world->wall_time_s = clock.wall_time_s;
    world->achieved_rate_hz = clock.achieved_rate_hz;
    world->step_due_ns = clock.step_due_ns;
    world->step_period_ns = clock.step_period_ns;
    world->body_count = static_cast<std::uint32_t>(channels_.size());
    clock.control.describe_pause(*world);
    world->rejected_commands = rejected_;
    world->watchdog_expiries = expiries_;
    world->stale_commands = stale_;
    world->lockstep = lockstep_;
    world->lockstep_clients = lockstep_clients();
    world->late_answers = late_answers_;
    world->dropped_clients = dropped_;
    world->commanded_steps = commanded_steps_;
    world->answered_steps = answered_steps_;
    const NanRecoveries& nan = sim_.nan_recoveries();
    world->nan_recoveries = nan.count;
    world->last_nan_step = nan.count > 0 ? nan.last.step : 0;
    const Model& model = sim_.model();
    set_name(world->last_nan_body, nan.count == 0 ? std::string_view()
                                   : nan.last.soft
                                       ? std::string_view(model.soft_bodies[nan.last.body].channel)
                                       : std::string_view(model.bodies[nan.last.body].channel));
    const WorldSpec& spec = sim_.model().world;
    world->light_count = static_cast<std::uint32_t>(std::min(spec.lights.size(), kMaxWorldObjects));
    world->camera_count =
        static_cast<std::uint32_t>(std::min(spec.cameras.size(), kMaxWorldObjects));
    fill_objects(world->lights, spec.lights, &Simulation::light_pose);
    fill_objects(world->cameras, spec.cameras, &Simulation::camera_pose);
    world_.publish(world);
    if (taping) tape_.add(PayloadKind::kWorldState, world_instance_, world, sizeof *world);
  }
  if (taping) tape_.finish();
}

const BodyState* SimChannels::publish_state(Channel& channel, BodyReading& reading,
                                            const StateStamp& stamp) noexcept {
  // Every field is set below: the slot's last update needs no defaults first.
  BodyState* state = channel.publisher->rewrite_state(channel.joint_count);
  if (!state) return nullptr;  // shared memory exhausted: skip this step, never block
  state->header.sim_step = stamp.step;
  state->header.sim_time_s = stamp.time_s;
  if (channel.soft)
    sim_.read_soft_body(channel.index, reading);
  else
    sim_.read_body(channel.index, reading);
  to_state(reading, *state);
  state->step_due_ns = stamp.step_due_ns;
  state->commanded_steps = static_cast<std::uint32_t>(channel.commanded_steps);
  state->answered_steps = static_cast<std::uint32_t>(channel.answered_steps);
  state->command_answered_step = channel.state_command_step;
  state->refused_commands = channel.refused;
  // Written when they change only: a line written is taken from every reader's cache.
  if (state->refused_command_pid != channel.refused_pid)
    state->refused_command_pid = channel.refused_pid;
  if (state->refusal_reason != channel.refusal_reason)
    state->refusal_reason = channel.refusal_reason;
  channel.publisher->publish_state(state, stamp.stamp_ns);
  return state;
}

bool SimChannels::next_world_command(WorldCommand& out) noexcept {
  return world_commands_->next(out);
}

}  // namespace afhub::physics
