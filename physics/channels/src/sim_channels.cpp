// The simulation's channels (see sim_channels.hpp).
#include "afhub/physics/sim_channels.hpp"

#include <sched.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "afhub/hub/body_claims.hpp"
#include "afhub/hub/sample_waiter.hpp"
#include "afhub/hub/world_command_queue.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "command_input.hpp"
#include "scene_description.hpp"

namespace afhub::physics {
namespace {

std::string format_seconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", seconds);
  return text;
}

// The wire and the core agree on capacities, so a copy never truncates what fits.
static_assert(kBodyRayCapacity == kMaxSensorRaysPerBody);

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
  for (std::uint32_t r = 0; r < reading.ray_count; ++r)
    state.sensor_distances_m[r] = reading.ray_distances_m[r];
}

// The bodies the model publishes (passive ones publish nothing), checked with the hub
// before this process opens a publisher: one publisher per body, and room for them.
// A state publisher per body, the world's, the scene's, the directory's and the loop
// stats'.
std::vector<std::string> claim_bodies(const Model& model) {
  std::vector<std::string> claimed;
  for (const BodySpec& body : model.bodies)
    if (!body.passive) claimed.push_back(body.channel);
  for (const SoftBodySpec& soft : model.soft_bodies) claimed.push_back(soft.channel);
  if (claimed.size() > kMaxBodies)
    throw Error("the model publishes " + std::to_string(claimed.size()) +
                " bodies; the hub holds " + std::to_string(kMaxBodies));
  check_room_for_bodies(claimed, claimed.size() + 4);
  return claimed;
}

}  // namespace

SimChannels::SimChannels(Simulation& sim, double watchdog_s, std::string_view name_space)
    : sim_(sim),
      claimed_(claim_bodies(sim.model())),
      world_({std::string(kService), world_instance(name_space), std::string(kStateEvent)}),
      scene_({std::string(kService), world_instance(name_space), std::string(kSceneEvent)}),
      scene_poses_(
          {std::string(kService), world_instance(name_space), std::string(kScenePosesEvent)}),
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
    directory_.add(make_body_entry(body.channel, joint_names));
    Channel channel;
    channel.index = b;
    channel.publisher = std::make_unique<BodyPublisher>(body.channel);
    channel.joint_count = static_cast<std::uint32_t>(joint_names.size());
    channel.watchdog_ns = watchdog_ns;
    for (const ActuatorSpec& actuator : model.actuators)
      if (actuator.parent == static_cast<int>(b)) ++channel.actuator_count;
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
  publish_scene();
  publish_soft_faces();
  directory_.publish();
  confirm_body_claims(claimed_, std::chrono::seconds(2));
}

SimChannels::~SimChannels() = default;

void SimChannels::publish_scene() {
  const std::size_t count = scene_body_count(sim_.model());
  SceneDescription* scene = scene_.loan(scene_description_bytes(count));
  if (!scene)
    throw Error("no shared memory for the scene description of " + std::to_string(count) +
                " bodies; see `afhub status` for the mempools");
  std::vector<std::string> warnings;
  fill_scene(sim_, *scene, warnings);
  for (const std::string& warning : warnings)
    std::fprintf(stderr, "afhub run: %s\n", warning.c_str());
  scene_.publish(scene);
}

void SimChannels::apply_commands(std::int64_t now_ns) noexcept {
  for (Channel& channel : channels_) {
    if (channel.soft) continue;  // soft bodies take no commands
    const BodyCommand* command = channel.publisher->latest_command();
    if (command && channel.publisher->command_updated()) {
      // Copied out of shared memory once, then checked, then applied.
      to_input(*command, input_);
      const Answer answer{command->header.sim_step, command->header.publisher_pid,
                          command->lockstep != 0};
      // Its age by its publish stamp (the same monotonic clock in every process),
      // not by when this process first saw it. A stamp from the future (a forged or
      // broken writer) is no fresher than an old one: past a small allowance it is
      // ignored too, or it would hold the watchdog off for as long as it is ahead.
      const std::int64_t stamp_ns = command->header.publish_stamp_ns;
      const std::int64_t age_ns = now_ns - stamp_ns;
      if (age_ns > channel.watchdog_ns || age_ns < -kFutureStampAllowanceNs) {
        ++stale_;
        if (Notice* notice = note(channel, kStale, answer.pid))
          notice->seconds = static_cast<double>(age_ns) * 1e-9;
      } else if (const char* problem = sim_.input_problem(channel.index, input_)) {
        ++rejected_;
        ++channel.refused;
        channel.refused_pid = answer.pid;
        set_name(channel.refusal_reason, problem);
        if (Notice* notice = note(channel, kRejected, answer.pid)) set_name(notice->why, problem);
      } else {
        // Entries for joints without an axis are refused and counted; the rest applies.
        if (const char* entry = sim_.axisless_entry(channel.index, input_)) {
          ++rejected_;
          if (Notice* notice = note(channel, kAxisless, answer.pid)) set_name(notice->why, entry);
        }
        if (lockstep_ && answer.lockstep) note_lockstep_answer(channel, answer);
        channel.applied_answer_step = answer.step;
        sim_.set_input(channel.index, input_);
        channel.last_command_ns = std::min(stamp_ns, now_ns);
        channel.commanded = true;
      }
    }
    if (channel.commanded && now_ns - channel.last_command_ns > channel.watchdog_ns) {
      if (channel.hold_on_watchdog)
        sim_.hold_joints(channel.index);
      else
        sim_.clear_input(channel.index);
      channel.commanded = false;
      ++expiries_;
      note(channel, kExpired, 0);
    }
  }
}

SimChannels::Notice* SimChannels::note(Channel& channel, Event event, std::uint32_t pid) noexcept {
  Notice& notice = channel.notices[event];
  // Said once: the first occurrence's details stay until reported, later ones are counts.
  if (said_once(event) && (notice.said || notice.pending)) return nullptr;
  notice.pending = true;
  notice.pid = pid;
  return &notice;
}

int SimChannels::report_events(std::FILE* out) {
  int lines = 0;
  for (Channel& channel : channels_) {
    const char* body = channel.publisher->channel().c_str();
    for (int event = 0; event < kEventKinds; ++event) {
      Notice& n = channel.notices[event];
      if (!n.pending) continue;
      n.pending = false;
      n.said = said_once(static_cast<Event>(event));
      ++lines;
      switch (event) {
        case kStale:
          if (n.seconds < 0.0)
            std::fprintf(out,
                         "afhub run: ignored a command for %s from pid %u: stamped %.3f s in the "
                         "future (a forged stamp, or a writer on another clock; counted in "
                         "`afhub status`)\n",
                         body, n.pid, -n.seconds);
          else
            std::fprintf(out,
                         "afhub run: ignored a command for %s from pid %u: published %.3f s ago, "
                         "older than the body's watchdog of %.3f s (counted in `afhub status`)\n",
                         body, n.pid, n.seconds, static_cast<double>(channel.watchdog_ns) * 1e-9);
          break;
        case kRejected:
          std::fprintf(out,
                       "afhub run: refused a command for %s: %s (from pid %u; counted in `afhub "
                       "status`; said once per body)\n",
                       body, n.why.data(), n.pid);
          break;
        case kAxisless:
          std::fprintf(out,
                       "afhub run: refused part of a command for %s: %s (from pid %u; counted "
                       "in `afhub status`; said once per body)\n",
                       body, n.why.data(), n.pid);
          break;
        case kExpired:
          std::fprintf(out,
                       "afhub run: no command for %s in %.3f s: %s until commands come again "
                       "(said once; `afhub status` counts every expiry)\n",
                       body, static_cast<double>(channel.watchdog_ns) * 1e-9,
                       channel.hold_on_watchdog ? "its joints hold their positions"
                                                : "its wrench and the efforts it drove are zero");
          break;
        case kJoined:
          std::fprintf(out,
                       "afhub run: lockstep client pid %u joined the barrier for %s at step %llu\n",
                       n.pid, body, static_cast<unsigned long long>(n.step));
          break;
        case kDropped:
          std::fprintf(out,
                       "afhub run: lockstep client pid %u missed %d steps in a row for %s; dropped "
                       "from the barrier (it rejoins by answering a current step)\n",
                       n.pid, n.misses, body);
          break;
        default:
          break;
      }
    }
  }
  return lines;
}

void SimChannels::forget_commands() noexcept {
  for (Channel& channel : channels_) {
    channel.commanded = false;
    channel.answered_step = 0;
    channel.applied_answer_step = 0;
    channel.misses = 0;
  }
  timeliness_step_ = 0;
}

SimChannels::Channel& SimChannels::active_channel(const std::string& body, const char* option) {
  std::vector<std::string> active;
  for (const Channel& channel : channels_)
    if (!channel.soft) active.push_back(channel.publisher->channel());
  std::string name;
  try {
    name = resolve_body(body, active);
  } catch (const Error& error) {
    throw Error(std::string(option) + ": " + error.what());
  }
  for (Channel& channel : channels_)
    if (!channel.soft && channel.publisher->channel() == name) return channel;
  throw Error(std::string(option) + ": no active body " + name);
}

void SimChannels::hold_on_watchdog(const std::string& body) {
  active_channel(body, "--watchdog-hold").hold_on_watchdog = true;
}

void SimChannels::set_watchdog(const std::string& body, double seconds) {
  if (!(seconds >= kMinWatchdogS && seconds <= kMaxWatchdogS))
    throw Error("--watchdog-body: the watchdog of '" + body + "' must be 0.002 to 3600 s, got " +
                std::to_string(seconds));
  active_channel(body, "--watchdog-body").watchdog_ns = static_cast<std::int64_t>(seconds * 1e9);
}

void SimChannels::enable_lockstep(const LockstepOptions& options) {
  lockstep_ = true;
  lockstep_options_ = options;
  waiter_.reset();
  if (options.spin) return;
  waiter_ = std::make_unique<SampleWaiter>();
  for (Channel& channel : channels_) {
    if (channel.soft || waiter_->attach(channel.publisher->command_reader())) continue;
    std::fprintf(stderr,
                 "afhub run: the lockstep wait can sleep on at most %zu bodies' commands; this "
                 "model has more, so it polls instead (as with --spin)\n",
                 SampleWaiter::kCapacity);
    waiter_.reset();
    return;
  }
}

void SimChannels::wait_for_commands(std::int64_t until_ns) noexcept {
  if (waiter_)
    waiter_->wait(until_ns - monotonic_ns());
  else
    sched_yield();
}

void SimChannels::note_lockstep_answer(Channel& channel, const Answer& answer) noexcept {
  channel.answered_step = answer.step;
  if (answer.step != sim_.step_count()) return;  // an old step: no (re)join
  if (channel.lockstep_pid != answer.pid) {
    note(channel, kJoined, answer.pid)->step = answer.step;
    set_lockstep_pid(channel, answer.pid);
  }
  channel.misses = 0;
}

// Runs only when a body joins or leaves the barrier: the count is then read in O(1).
void SimChannels::set_lockstep_pid(Channel& channel, std::uint32_t pid) noexcept {
  auto find = [&](std::uint32_t wanted) {
    return std::find_if(lockstep_pids_.begin(), lockstep_pids_.end(),
                        [&](const auto& entry) { return entry.first == wanted; });
  };
  if (channel.lockstep_pid != 0) {
    const auto old = find(channel.lockstep_pid);
    if (old != lockstep_pids_.end() && --old->second == 0) {
      *old = lockstep_pids_.back();
      lockstep_pids_.pop_back();
    }
  }
  channel.lockstep_pid = pid;
  if (pid != 0) {
    const auto entry = find(pid);
    if (entry != lockstep_pids_.end())
      ++entry->second;
    else
      lockstep_pids_.emplace_back(pid, 1u);  // within the capacity reserved: no allocation
  }
  lockstep_client_count_ = static_cast<std::uint32_t>(lockstep_pids_.size());
}

bool SimChannels::hold_step_turn(std::int64_t now_ns, std::int64_t& republish_ns) noexcept {
  apply_commands(now_ns);
  if (stop_requested()) return false;
  // State channels keep no history: a client that subscribes while the step is held
  // sees it only if it is published again.
  if (now_ns >= republish_ns) {
    publish(last_published_.wall_time_s, last_published_.achieved_rate_hz, last_published_.paused);
    republish_ns = now_ns + kRepublishWhileWaitingNs;
  }
  return true;
}

std::string SimChannels::bodies_without_client() const {
  constexpr int kListed = 8;
  std::string names;
  int count = 0;
  for (const Channel& channel : channels_) {
    if (channel.soft || channel.lockstep_pid != 0) continue;
    if (++count <= kListed) names += (names.empty() ? "" : ", ") + channel.publisher->channel();
  }
  if (count > kListed) names += " and " + std::to_string(count - kListed) + " more";
  return names;
}

bool SimChannels::wait_for_clients() {
  const std::uint32_t wanted = lockstep_options_.wait_for;
  if (lockstep_clients() >= wanted) return true;
  std::fprintf(stderr, "afhub run: waiting for %u lockstep clients before the first step\n",
               wanted);
  const std::int64_t start = monotonic_ns();
  std::int64_t republish_ns = start + kRepublishWhileWaitingNs;
  std::int64_t report_ns = start + lockstep_options_.wait_report_ns;
  while (lockstep_clients() < wanted) {
    const std::int64_t now = monotonic_ns();
    if (!hold_step_turn(now, republish_ns)) return false;
    report_events(stderr);  // setup, before the first step: joins are said as they come
    const double waited_s = static_cast<double>(now - start) * 1e-9;
    // The report first: even a process stalled past the timeout says it once.
    if (now >= report_ns) {
      std::fprintf(stderr,
                   "afhub run: still waiting after %.0f s: %u of %u lockstep clients joined; no "
                   "client yet for %s\n",
                   waited_s, lockstep_clients(), wanted, bodies_without_client().c_str());
      report_ns = now + lockstep_options_.wait_report_ns;
    }
    if (lockstep_options_.wait_timeout_ns > 0 && now - start >= lockstep_options_.wait_timeout_ns)
      throw Error("gave up after " + format_seconds(waited_s) + " s (--wait-timeout): " +
                  std::to_string(lockstep_clients()) + " of " + std::to_string(wanted) +
                  " lockstep clients joined; no client for " + bodies_without_client() +
                  ". Start them with `afhub ctl ... --lockstep`, or lower --wait-for");
    std::int64_t until = std::min(republish_ns, report_ns);
    if (lockstep_options_.wait_timeout_ns > 0)
      until = std::min(until, start + lockstep_options_.wait_timeout_ns);
    wait_for_commands(until);
  }
  return true;
}

bool SimChannels::await_lockstep() noexcept {
  const std::uint64_t step = sim_.step_count();
  const std::int64_t start = monotonic_ns();
  std::int64_t republish_ns = start + kRepublishWhileWaitingNs;
  for (;;) {
    const std::int64_t now = monotonic_ns();
    if (!hold_step_turn(now, republish_ns)) return false;
    bool pending = false;
    for (const Channel& channel : channels_)
      pending = pending || (channel.lockstep_pid != 0 && channel.answered_step != step);
    if (!pending) {
      for (Channel& channel : channels_) channel.misses = 0;
      return true;
    }
    if (now - start > lockstep_options_.client_timeout_ns) break;
    wait_for_commands(std::min(republish_ns, start + lockstep_options_.client_timeout_ns + 1));
  }
  // Timed out: the step goes ahead without the late answers.
  for (Channel& channel : channels_) {
    if (channel.lockstep_pid == 0 || channel.answered_step == step) continue;
    ++late_answers_;
    if (++channel.misses < lockstep_options_.max_misses) continue;
    note(channel, kDropped, channel.lockstep_pid)->misses = channel.misses;
    set_lockstep_pid(channel, 0);
    channel.misses = 0;
    ++dropped_;
  }
  return true;
}

void SimChannels::fill_objects(std::array<WorldObjectPose, kMaxWorldObjects>& out,
                               const std::vector<WorldObjectSpec>& specs,
                               Pose (Simulation::*pose)(std::size_t)
                                   const noexcept) const noexcept {
  for (std::size_t i = 0; i < specs.size() && i < kMaxWorldObjects; ++i) {
    set_name(out[i].name, specs[i].name);
    out[i].pose = (sim_.*pose)(i);
  }
}

void SimChannels::publish_soft_faces() {
  for (SoftSurface& surface : soft_surfaces_) {
    const auto faces = sim_.soft_body_faces(surface.index);  // within bounds: checked at load
    SoftBodyMesh* mesh = surface.faces->loan(soft_body_mesh_bytes(faces.size()));
    if (!mesh)
      throw Error("no shared memory for the faces of soft body '" +
                  sim_.model().soft_bodies[surface.index].channel +
                  "'; see `afhub status` for the mempools");
    mesh->node_count = static_cast<std::uint32_t>(sim_.soft_body_node_count(surface.index));
    mesh->face_count = static_cast<std::uint32_t>(faces.size());
    sim_.read_soft_body_nodes(surface.index, mesh->nodes.data());
    std::copy(faces.begin(), faces.end(), mesh->faces.begin());
    surface.faces->publish(mesh);
  }
}

void SimChannels::publish_view(std::int64_t now_ns) noexcept {
  if (now_ns < view_next_ns_) return;
  view_next_ns_ = now_ns + static_cast<std::int64_t>(1e9 / kViewerRateHz);
  publish_scene_poses();
  publish_soft_nodes();
}

void SimChannels::publish_soft_nodes() noexcept {
  for (SoftSurface& surface : soft_surfaces_) {
    // Kept for a viewer that joins later: published once without readers, then for them.
    if (surface.nodes_published && !surface.nodes->raw().has_readers()) continue;
    SoftBodyMesh* mesh = surface.nodes->loan(soft_body_mesh_bytes(0));
    if (!mesh) continue;  // shared memory exhausted: skip, never block
    mesh->header.sim_step = sim_.step_count();
    mesh->header.sim_time_s = sim_.time_s();
    mesh->node_count = static_cast<std::uint32_t>(sim_.soft_body_node_count(surface.index));
    sim_.read_soft_body_nodes(surface.index, mesh->nodes.data());
    surface.nodes->publish(mesh);
    surface.nodes_published = true;
  }
}

void SimChannels::publish_scene_poses() noexcept {
  if (scene_poses_published_ && !scene_poses_.raw().has_readers()) return;
  const Model& model = sim_.model();
  const auto bodies = static_cast<std::uint32_t>(scene_body_count(model));
  auto* poses = static_cast<ScenePoses*>(
      scene_poses_.raw().loan(scene_poses_bytes(bodies, scene_joint_values_)));
  if (!poses) return;  // shared memory exhausted: skip, never block
  poses->header = PayloadHeader{};
  poses->header.sim_step = sim_.step_count();
  poses->header.sim_time_s = sim_.time_s();
  poses->body_count = bodies;
  float* joint_positions = joint_positions_in(*poses);
  std::uint32_t values = 0;
  for (std::uint32_t b = 0; b < poses->body_count; ++b) {
    const Pose pose = sim_.body_pose(b);
    ScenePose& out = poses->bodies[b];
    out.first_joint = out.joint_count = 0;
    out.position_m = {static_cast<float>(pose.position_m.x), static_cast<float>(pose.position_m.y),
                      static_cast<float>(pose.position_m.z)};
    out.orientation_xyzw = {
        static_cast<float>(pose.orientation.x), static_cast<float>(pose.orientation.y),
        static_cast<float>(pose.orientation.z), static_cast<float>(pose.orientation.w)};
    if (model.bodies[b].passive) continue;  // no state: no joints to show
    const std::vector<int>& below = model.descendant_joints[b];
    const auto count = static_cast<std::uint32_t>(std::min(below.size(), kBodyJointCapacity));
    if (values + count > scene_joint_values_) continue;  // past the feed's capacity: said once
    out.first_joint = values;
    out.joint_count = count;
    for (std::uint32_t j = 0; j < count; ++j)
      joint_positions[values++] = static_cast<float>(sim_.joint_position(below[j]));
  }
  poses->joint_value_count = values;
  scene_poses_.publish(poses);
  scene_poses_published_ = true;
}

void SimChannels::publish(double wall_time_s, double achieved_rate_hz, bool paused) noexcept {
  last_published_ = {wall_time_s, achieved_rate_hz, paused};
  const std::uint64_t step = sim_.step_count();
  const double time_s = sim_.time_s();
  if (step != timeliness_step_) {  // once per step taken, not per publish while paused
    timeliness_step_ = step;
    for (Channel& channel : channels_) {
      if (!channel.commanded) continue;
      ++commanded_steps_;
      ++channel.commanded_steps;
      if (channel.applied_answer_step + 1 == step) {
        ++answered_steps_;
        ++channel.answered_steps;
      }
    }
  }
  for (Channel& channel : channels_) {
    BodyState* state = channel.publisher->loan_state(channel.joint_count);
    if (!state) continue;  // shared memory exhausted: skip this step, never block
    state->header.sim_step = step;
    state->header.sim_time_s = time_s;
    if (channel.soft)
      sim_.read_soft_body(channel.index, reading_);
    else
      sim_.read_body(channel.index, reading_);
    to_state(reading_, *state);
    state->commanded_steps = static_cast<std::uint32_t>(channel.commanded_steps);
    state->answered_steps = static_cast<std::uint32_t>(channel.answered_steps);
    state->refused_commands = channel.refused;
    state->refused_command_pid = channel.refused_pid;
    state->refusal_reason = channel.refusal_reason;
    channel.publisher->publish_state(state);
  }
  if (WorldState* world = world_.loan()) {
    world->header.sim_step = step;
    world->header.sim_time_s = time_s;
    world->wall_time_s = wall_time_s;
    world->achieved_rate_hz = achieved_rate_hz;
    world->body_count = static_cast<std::uint32_t>(channels_.size());
    world->paused = paused;
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
  }
}

bool SimChannels::next_world_command(WorldCommand& out) noexcept {
  return world_commands_->next(out);
}

}  // namespace afhub::physics
