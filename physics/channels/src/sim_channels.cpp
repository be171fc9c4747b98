// The simulation's channels (see sim_channels.hpp).
#include "afhub/physics/sim_channels.hpp"

#include <sched.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "afhub/hub/stop_signal.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub::physics {
namespace {

// A light or camera looking along `direction` with `up` as its z axis.
Quaternion look_rotation(const Vec3& direction, const Vec3& up) {
  auto normalize = [](Vec3 v) {
    const double n = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return n > 1e-12 ? Vec3{v.x / n, v.y / n, v.z / n} : Vec3{1, 0, 0};
  };
  auto cross = [](const Vec3& a, const Vec3& b) {
    return Vec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
  };
  const Vec3 x = normalize(direction);
  Vec3 y = cross(up, x);
  if (y.x * y.x + y.y * y.y + y.z * y.z < 1e-12) y = cross(Vec3{0, 1, 0}, x);
  y = normalize(y);
  const Vec3 z = cross(x, y);
  // Rotation matrix with columns x, y, z to a quaternion.
  const double m[3][3] = {{x.x, y.x, z.x}, {x.y, y.y, z.y}, {x.z, y.z, z.z}};
  const double trace = m[0][0] + m[1][1] + m[2][2];
  Quaternion q;
  if (trace > 0) {
    const double s = std::sqrt(trace + 1.0) * 2;
    q = {(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4};
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const double s = std::sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2;
    q = {s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s};
  } else if (m[1][1] > m[2][2]) {
    const double s = std::sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2;
    q = {(m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s};
  } else {
    const double s = std::sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2;
    q = {(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4, (m[1][0] - m[0][1]) / s};
  }
  return q;
}

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {
      a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
      a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

Vec3 rotate(const Quaternion& q, const Vec3& v) {
  const Quaternion p = multiply(multiply(q, {v.x, v.y, v.z, 0}), {-q.x, -q.y, -q.z, q.w});
  return {p.x, p.y, p.z};
}

// "/ambf/env/BODY LightCone" names the body whose identifier is "BODY LightCone".
int find_parent(const Model& model, const std::string& parent) {
  if (parent.empty()) return -1;
  const std::string identifier = parent.substr(parent.find_last_of('/') + 1);
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].identifier == identifier) return static_cast<int>(b);
  return -1;
}

}  // namespace

SimChannels::SimChannels(Simulation& sim, double watchdog_s)
    : sim_(sim),
      watchdog_ns_(static_cast<std::int64_t>(watchdog_s * 1e9)),
      world_({std::string(kService), std::string(kWorldInstance), std::string(kStateEvent)}),
      world_command_(
          {std::string(kService), std::string(kWorldInstance), std::string(kCommandEvent)}) {
  const Model& model = sim.model();
  if (model.bodies.size() + model.soft_bodies.size() > kMaxBodies)
    throw Error("the model has more than " + std::to_string(kMaxBodies) + " bodies");
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodySpec& body = model.bodies[b];
    if (body.passive) continue;
    std::vector<std::string> joint_names;
    for (int j : model.descendant_joints[b]) joint_names.push_back(model.joints[j].name);
    if (joint_names.size() > kMaxJointsPerBody)
      throw Error(body.where.str() + ": error: '" + body.name + "' has " +
                  std::to_string(joint_names.size()) +
                  " joints below it; a state carries at most " + std::to_string(kMaxJointsPerBody));
    directory_.add(make_body_info(body.channel, joint_names));
    Channel channel;
    channel.index = b;
    channel.publisher = std::make_unique<BodyPublisher>(body.channel);
    channel.joint_count = static_cast<std::uint32_t>(joint_names.size());
    for (const ActuatorSpec& actuator : model.actuators)
      if (actuator.parent == static_cast<int>(b)) ++channel.actuator_count;
    channels_.push_back(std::move(channel));
  }
  for (std::size_t s = 0; s < model.soft_bodies.size(); ++s) {
    directory_.add(make_body_info(model.soft_bodies[s].channel, {}));
    Channel channel;
    channel.index = s;
    channel.soft = true;
    channel.publisher = std::make_unique<BodyPublisher>(model.soft_bodies[s].channel);
    channels_.push_back(std::move(channel));
  }
  directory_.publish();
  auto objects = [&](const std::vector<WorldObjectSpec>& specs, std::vector<WorldObject>& out) {
    for (std::size_t i = 0; i < specs.size() && i < kMaxWorldObjects; ++i) {
      WorldObject object;
      object.spec = &specs[i];
      object.parent = find_parent(model, specs[i].parent);
      object.local = {specs[i].position_m, look_rotation(specs[i].direction, specs[i].up)};
      out.push_back(object);
    }
  };
  objects(model.world.lights, lights_);
  objects(model.world.cameras, cameras_);
}

void SimChannels::apply_commands(std::int64_t now_ns) noexcept {
  for (Channel& channel : channels_) {
    if (channel.soft) continue;  // soft bodies take no commands
    const BodyCommand* command = channel.publisher->latest_command();
    if (command && channel.publisher->command_updated()) {
      if (const char* problem =
              command_problem(*command, channel.joint_count, channel.actuator_count)) {
        ++rejected_;
        if (!channel.told_rejected) {
          std::fprintf(stderr,
                       "afhub run: refused a command for %s: %s (counted in `afhub status`)\n",
                       channel.publisher->channel().c_str(), problem);
          channel.told_rejected = true;
        }
      } else {
        if (lockstep_ && command->lockstep) note_lockstep_answer(channel, *command);
        channel.applied_answer_step = command->header.sim_step;
        sim_.set_command(channel.index, *command);
        channel.last_command_ns = now_ns;
        channel.commanded = true;
      }
    }
    if (channel.commanded && now_ns - channel.last_command_ns > watchdog_ns_) {
      if (channel.hold_on_watchdog)
        sim_.hold_command(channel.index);
      else
        sim_.clear_command(channel.index);
      channel.commanded = false;
      ++expiries_;
      std::fprintf(stderr, "afhub run: no command for %s in %.3f s: %s until commands come again\n",
                   channel.publisher->channel().c_str(), static_cast<double>(watchdog_ns_) * 1e-9,
                   channel.hold_on_watchdog ? "its joints hold their positions"
                                            : "its wrench and joint efforts are zero");
    }
  }
}

void SimChannels::hold_on_watchdog(const std::string& body) {
  bool found = false;
  for (Channel& channel : channels_) {
    const std::string& name = channel.publisher->channel();
    const bool match =
        name == body || (name.size() > body.size() &&
                         name.compare(name.size() - body.size(), body.size(), body) == 0 &&
                         name[name.size() - body.size() - 1] == '/');
    if (match && !channel.soft) channel.hold_on_watchdog = found = true;
  }
  if (!found)
    throw Error("--watchdog-hold: no active body is named '" + body +
                "'; give a body's channel name or its last part (see `afhub check`)");
}

void SimChannels::enable_lockstep(const LockstepOptions& options) {
  lockstep_ = true;
  lockstep_options_ = options;
}

void SimChannels::note_lockstep_answer(Channel& channel, const BodyCommand& command) noexcept {
  channel.answered_step = command.header.sim_step;
  if (command.header.sim_step != sim_.step_count()) return;  // an old step: no (re)join
  if (channel.lockstep_pid != command.header.publisher_pid)
    std::fprintf(stderr,
                 "afhub run: lockstep client pid %u joined the barrier for %s at step %llu\n",
                 command.header.publisher_pid, channel.publisher->channel().c_str(),
                 static_cast<unsigned long long>(command.header.sim_step));
  channel.lockstep_pid = command.header.publisher_pid;
  channel.misses = 0;
}

std::uint32_t SimChannels::lockstep_clients() const noexcept {
  std::uint32_t clients = 0;
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    const std::uint32_t pid = channels_[i].lockstep_pid;
    if (pid == 0) continue;
    bool seen = false;
    for (std::size_t k = 0; k < i && !seen; ++k) seen = channels_[k].lockstep_pid == pid;
    if (!seen) ++clients;
  }
  return clients;
}

bool SimChannels::await_lockstep() noexcept {
  const std::uint64_t step = sim_.step_count();
  const std::int64_t start = monotonic_ns();
  std::int64_t republish_ns = start + kRepublishWhileWaitingNs;
  bool told_waiting = false;
  for (;;) {
    const std::int64_t now = monotonic_ns();
    apply_commands(now);
    if (stop_requested()) return false;
    // State channels keep no history: a client that subscribes while the step is
    // held sees it only if it is published again.
    if (now >= republish_ns) {
      publish(last_published_.wall_time_s, last_published_.achieved_rate_hz,
              last_published_.paused);
      republish_ns = now + kRepublishWhileWaitingNs;
    }
    if (step == 0 && lockstep_clients() < lockstep_options_.wait_for) {
      if (!told_waiting)
        std::fprintf(stderr, "afhub run: waiting for %u lockstep clients before the first step\n",
                     lockstep_options_.wait_for);
      told_waiting = true;
      sched_yield();
      continue;
    }
    bool pending = false;
    for (const Channel& channel : channels_)
      pending = pending || (channel.lockstep_pid != 0 && channel.answered_step != step);
    if (!pending) {
      for (Channel& channel : channels_) channel.misses = 0;
      return true;
    }
    if (now - start > lockstep_options_.client_timeout_ns) break;
    sched_yield();
  }
  // Timed out: the step goes ahead without the late answers.
  for (Channel& channel : channels_) {
    if (channel.lockstep_pid == 0 || channel.answered_step == step) continue;
    ++late_answers_;
    if (++channel.misses < lockstep_options_.max_misses) continue;
    std::fprintf(stderr,
                 "afhub run: lockstep client pid %u missed %d steps in a row for %s; dropped from "
                 "the barrier (it rejoins by answering a current step)\n",
                 channel.lockstep_pid, channel.misses, channel.publisher->channel().c_str());
    channel.lockstep_pid = 0;
    channel.misses = 0;
    ++dropped_;
  }
  return true;
}

void SimChannels::fill_objects(std::array<WorldObjectPose, kMaxWorldObjects>& out,
                               const std::vector<WorldObject>& objects) const noexcept {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    set_name(out[i].name, objects[i].spec->name);
    if (objects[i].parent < 0) {
      out[i].pose = objects[i].local;
      continue;
    }
    const Pose parent = sim_.body_pose(static_cast<std::size_t>(objects[i].parent));
    const Vec3 offset = rotate(parent.orientation, objects[i].local.position_m);
    out[i].pose = {{parent.position_m.x + offset.x, parent.position_m.y + offset.y,
                    parent.position_m.z + offset.z},
                   multiply(parent.orientation, objects[i].local.orientation)};
  }
}

void SimChannels::publish(double wall_time_s, double achieved_rate_hz, bool paused) noexcept {
  last_published_ = {wall_time_s, achieved_rate_hz, paused};
  const std::uint64_t step = sim_.step_count();
  const double time_s = sim_.time_s();
  if (step != timeliness_step_) {  // once per step taken, not per publish while paused
    timeliness_step_ = step;
    for (const Channel& channel : channels_) {
      if (!channel.commanded) continue;
      ++commanded_steps_;
      if (channel.applied_answer_step + 1 == step) ++answered_steps_;
    }
  }
  for (Channel& channel : channels_) {
    BodyState* state = channel.publisher->loan_state();
    if (!state) continue;  // shared memory exhausted: skip this step, never block
    state->header.sim_step = step;
    state->header.sim_time_s = time_s;
    if (channel.soft)
      sim_.fill_soft_body_state(channel.index, *state);
    else
      sim_.fill_state(channel.index, *state);
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
    world->lockstep = lockstep_;
    world->lockstep_clients = lockstep_clients();
    world->late_answers = late_answers_;
    world->dropped_clients = dropped_;
    world->commanded_steps = commanded_steps_;
    world->answered_steps = answered_steps_;
    world->light_count = static_cast<std::uint32_t>(lights_.size());
    world->camera_count = static_cast<std::uint32_t>(cameras_.size());
    fill_objects(world->lights, lights_);
    fill_objects(world->cameras, cameras_);
    world_.publish(world);
  }
}

const WorldCommand* SimChannels::new_world_command() noexcept {
  const WorldCommand* command = world_command_.latest();
  if (!command || command->header.sequence == last_world_sequence_) return nullptr;
  last_world_sequence_ = command->header.sequence;
  return command;
}

}  // namespace afhub::physics
