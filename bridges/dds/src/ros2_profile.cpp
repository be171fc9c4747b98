// `--profile ros2` (see ros2_profile.hpp). Samples point into buffers made when a body
// appears (joint names, value arrays, frame ids), so publishing allocates nothing
// here; the command sample is reused, so Cyclone reallocates its sequences only when
// a longer command than any before arrives.
#include "ros2_profile.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "afhub/shm_layout/error.hpp"
#include "ros2_msgs.h"

namespace afhub::bridges {
namespace {

char kWorldFrame[] = "world";
char kNoFrame[] = "";  // joint_states: ROS leaves the frame empty

bool is_ros_name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

builtin_interfaces_msg_dds__Time_ ros_time(double seconds) noexcept {
  if (!(seconds >= 0.0)) seconds = 0.0;
  auto sec = static_cast<std::int64_t>(std::floor(seconds));
  auto nanosec =
      static_cast<std::int64_t>(std::llround((seconds - static_cast<double>(sec)) * 1e9));
  if (nanosec >= 1'000'000'000) {
    ++sec;
    nanosec -= 1'000'000'000;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nanosec)};
}

geometry_msgs_msg_dds__Vector3_ ros_vector(const Vec3& v) noexcept {
  return {v.x, v.y, v.z};
}

dds_entity_t must(dds_entity_t entity, const std::string& what) {
  return checked(entity, ("--profile ros2: " + what).c_str());
}

}  // namespace

std::string ros2_topic(const std::string& prefix, const std::string& channel, const char* suffix) {
  std::string name = "rt";
  for (const std::string& part : {prefix, channel, std::string(suffix)}) {
    bool part_start = true;
    for (const char c : part) {
      if (c == '/') {
        part_start = true;
        continue;
      }
      if (part_start) {
        name += '/';
        if (c >= '0' && c <= '9') name += '_';
        part_start = false;
      }
      name += is_ros_name_char(c) ? c : '_';
    }
  }
  return name;
}

std::string ros2_joint_command(const Ros2JointState& joint_state,
                               const std::vector<std::string>& joint_names, const double* hold,
                               BodyCommand* command) noexcept {
  static constexpr const char* kArrays[3] = {"position", "velocity", "effort"};
  static constexpr JointCommandType kTypes[3] = {
      JointCommandType::kPosition, JointCommandType::kVelocity, JointCommandType::kEffort};
  int chosen = 0;
  while (chosen < 3 && joint_state.value_counts[chosen] == 0) ++chosen;
  const auto index_of = [&](std::uint32_t n) {
    const char* name = joint_state.names[n] ? joint_state.names[n] : "";
    std::uint32_t index = 0;
    while (index < joint_names.size() && joint_names[index] != name) ++index;
    return index;
  };
  try {
    if (joint_state.name_count == 0)
      return "name is empty: name the joints commanded (this body's first joint: " +
             (joint_names.empty() ? std::string("none") : joint_names.front()) + ")";
    if (chosen == 3) return "position, velocity and effort are all empty: fill one";
    if (joint_state.value_counts[chosen] != joint_state.name_count)
      return std::string(kArrays[chosen]) + " has " +
             std::to_string(joint_state.value_counts[chosen]) + " values for " +
             std::to_string(joint_state.name_count) + " names: give one per name";
    if (joint_state.name_count < joint_names.size() && !hold)
      return "no state of the body yet, so the joints left unnamed cannot hold their "
             "positions: name all " +
             std::to_string(joint_names.size()) + " joints or wait for its state";
    for (std::uint32_t n = 0; n < joint_state.name_count; ++n) {
      if (index_of(n) == joint_names.size()) {
        std::string known;
        for (const std::string& joint : joint_names) known += (known.empty() ? "" : ", ") + joint;
        return "name[" + std::to_string(n) + "] '" +
               (joint_state.names[n] ? joint_state.names[n] : "") +
               "' is not a joint of this body (" +
               (known.empty() ? "it has none" : "its joints: " + known) + ")";
      }
      if (!std::isfinite(joint_state.values[chosen][n]))
        return std::string(kArrays[chosen]) + "[" + std::to_string(n) + "] is not finite";
    }
  } catch (...) {
    return "out of memory describing a bad command";
  }
  if (!command) return {};
  // Every joint holds where it is, then the named ones get their values.
  command->joint_count = static_cast<std::uint32_t>(joint_names.size());
  for (std::uint32_t i = 0; i < command->joint_count; ++i) {
    command->joints[i].type = JointCommandType::kPosition;
    command->joints[i].value = hold ? hold[i] : 0.0;
  }
  for (std::uint32_t n = 0; n < joint_state.name_count; ++n) {
    const std::uint32_t index = index_of(n);
    command->joints[index].type = kTypes[chosen];
    command->joints[index].value = joint_state.values[chosen][n];
  }
  return {};
}

struct Ros2Profile::Body {
  std::string channel;
  LatestReader<BodyState>* state;
  std::unique_ptr<Writer<BodyCommand>> command_writer;  // at the first good command
  std::string joint_states_topic, command_topic_name;
  std::vector<std::string> names;
  std::vector<char*> name_pointers;
  std::vector<double> positions, velocities, efforts;
  dds_entity_t topics[5] = {0, 0, 0, 0, 0};
  dds_entity_t joint_writer = 0, pose_writer = 0, twist_writer = 0, wrench_writer = 0;
  dds_entity_t command_reader = 0;
  sensor_msgs_msg_dds__JointState_ joints{};
  geometry_msgs_msg_dds__PoseStamped_ pose{};
  geometry_msgs_msg_dds__TwistStamped_ twist{};
  geometry_msgs_msg_dds__WrenchStamped_ wrench{};
  sensor_msgs_msg_dds__JointState_ command{};  // reused by dds_take
  // Where the joints a command leaves unnamed hold: the positions when commands
  // (re)started, then each position command's targets. Not the newest state, or a
  // joint sagging under gravity would ratchet down command by command.
  std::vector<double> hold;
  bool holding = false;
  std::int64_t last_command_ns = 0;

  ~Body() {
    for (const dds_entity_t entity :
         {joint_writer, pose_writer, twist_writer, wrench_writer, command_reader})
      if (entity > 0) dds_delete(entity);
    for (const dds_entity_t topic : topics)
      if (topic > 0) dds_delete(topic);
    // The command sample's contents were allocated by Cyclone's dds_take.
    dds_sample_free(&command, &sensor_msgs_msg_dds__JointState__desc, DDS_FREE_CONTENTS);
  }
};

Ros2Profile::Ros2Profile(dds_entity_t participant, std::string prefix, bool accept_commands,
                         double max_command_age_s)
    : participant_(participant),
      prefix_(std::move(prefix)),
      accept_commands_(accept_commands),
      max_command_age_ns_(static_cast<std::int64_t>(max_command_age_s * 1e9)) {
  set_stream_qos(writer_qos_.get(), true);
  set_stream_qos(reader_qos_.get(), false);
}

Ros2Profile::~Ros2Profile() {
  bodies_.clear();
}

void Ros2Profile::add_body(const std::string& channel, const std::vector<std::string>& joint_names,
                           LatestReader<BodyState>& state) {
  auto body = std::make_unique<Body>();
  body->channel = channel;
  body->state = &state;
  body->names = joint_names;
  for (std::string& name : body->names) body->name_pointers.push_back(name.data());
  const std::size_t joints = body->names.size();
  body->positions.assign(joints, 0.0);
  body->velocities.assign(joints, 0.0);
  body->efforts.assign(joints, 0.0);
  body->hold.assign(joints, 0.0);

  struct Endpoint {
    const dds_topic_descriptor_t* type;
    const char* suffix;
    dds_entity_t* writer;
  };
  const Endpoint endpoints[4] = {
      {&sensor_msgs_msg_dds__JointState__desc, "joint_states", &body->joint_writer},
      {&geometry_msgs_msg_dds__PoseStamped__desc, "pose", &body->pose_writer},
      {&geometry_msgs_msg_dds__TwistStamped__desc, "twist", &body->twist_writer},
      {&geometry_msgs_msg_dds__WrenchStamped__desc, "wrench", &body->wrench_writer}};
  for (int i = 0; i < 4; ++i) {
    const std::string topic = ros2_topic(prefix_, channel, endpoints[i].suffix);
    body->topics[i] =
        must(dds_create_topic(participant_, endpoints[i].type, topic.c_str(), nullptr, nullptr),
             "creating topic " + topic);
    *endpoints[i].writer =
        must(dds_create_writer(participant_, body->topics[i], writer_qos_.get(), nullptr),
             "creating a writer on " + topic);
  }
  body->joint_states_topic = ros2_topic(prefix_, channel, "joint_states");
  if (accept_commands_) {
    body->command_topic_name = ros2_topic(prefix_, channel, "joint_command");
    body->topics[4] = must(dds_create_topic(participant_, &sensor_msgs_msg_dds__JointState__desc,
                                            body->command_topic_name.c_str(), nullptr, nullptr),
                           "creating topic " + body->command_topic_name);
    body->command_reader =
        must(dds_create_reader(participant_, body->topics[4], reader_qos_.get(), nullptr),
             "creating a reader on " + body->command_topic_name);
  }

  // The samples point at the body's own buffers (never released by Cyclone).
  auto& js = body->joints;
  js.header.frame_id = kNoFrame;
  js.name = {static_cast<std::uint32_t>(joints), static_cast<std::uint32_t>(joints),
             body->name_pointers.data(), false};
  js.position = {static_cast<std::uint32_t>(joints), static_cast<std::uint32_t>(joints),
                 body->positions.data(), false};
  js.velocity = {static_cast<std::uint32_t>(joints), static_cast<std::uint32_t>(joints),
                 body->velocities.data(), false};
  js.effort = {static_cast<std::uint32_t>(joints), static_cast<std::uint32_t>(joints),
               body->efforts.data(), false};
  body->pose.header.frame_id = kWorldFrame;
  body->twist.header.frame_id = kWorldFrame;
  body->wrench.header.frame_id = kWorldFrame;
  std::fprintf(stderr, "afhub bridge dds: ros2 profile: %s/{joint_states,pose,twist,wrench}%s\n",
               body->joint_states_topic.substr(0, body->joint_states_topic.size() - 13).c_str(),
               accept_commands_ ? ", joint_command in" : "");
  bodies_.push_back(std::move(body));
}

void Ros2Profile::publish(std::size_t index, const BodyState& state) noexcept {
  Body& body = *bodies_[index];
  const builtin_interfaces_msg_dds__Time_ stamp = ros_time(state.header.sim_time_s);
  const std::uint32_t joints =
      std::min<std::uint32_t>(state.joint_count, static_cast<std::uint32_t>(body.names.size()));
  for (std::uint32_t j = 0; j < joints; ++j) {
    body.positions[j] = state.joints[j].position;
    body.velocities[j] = state.joints[j].velocity;
    body.efforts[j] = state.joints[j].effort;
  }
  auto& js = body.joints;
  js.header.stamp = stamp;
  js.name._length = js.position._length = js.velocity._length = js.effort._length = joints;
  body.pose.header.stamp = body.twist.header.stamp = body.wrench.header.stamp = stamp;
  const Pose& p = state.pose;
  body.pose.pose = {{p.position_m.x, p.position_m.y, p.position_m.z},
                    {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}};
  body.twist.twist = {ros_vector(state.twist.linear_mps), ros_vector(state.twist.angular_radps)};
  body.wrench.wrench = {ros_vector(state.wrench.force_n), ros_vector(state.wrench.torque_nm)};
  const bool written = dds_write(body.joint_writer, &js) >= 0 &&
                       dds_write(body.pose_writer, &body.pose) >= 0 &&
                       dds_write(body.twist_writer, &body.twist) >= 0 &&
                       dds_write(body.wrench_writer, &body.wrench) >= 0;
  if (written) ++states_out_;
}

void Ros2Profile::import_commands() noexcept {
  for (const auto& owned : bodies_) {
    Body& body = *owned;
    if (body.command_reader <= 0) continue;
    void* samples[1] = {&body.command};
    dds_sample_info_t info;
    while (dds_take(body.command_reader, samples, &info, 1, 1) > 0) {
      if (!info.valid_data) continue;
      if (dds_time() - info.source_timestamp > max_command_age_ns_) {
        ++stale_commands_;
        continue;
      }
      const auto& in = body.command;
      const Ros2JointState joint_state{
          in.name._buffer,
          in.name._length,
          {in.position._buffer, in.velocity._buffer, in.effort._buffer},
          {in.position._length, in.velocity._length, in.effort._length}};
      // After a second without commands the holds restart from where the joints are.
      const BodyState* state = body.state->latest();
      const std::int64_t now_ns = dds_time();
      if ((!body.holding || now_ns - body.last_command_ns > 1'000'000'000) && state &&
          state->joint_count >= body.hold.size()) {
        for (std::size_t j = 0; j < body.hold.size(); ++j) body.hold[j] = state->joints[j].position;
        body.holding = true;
      }
      const double* hold = body.holding ? body.hold.data() : nullptr;
      const std::string error = ros2_joint_command(joint_state, body.names, hold, nullptr);
      if (!error.empty()) {
        ++bad_commands_;
        if (errors_printed_ < 3) {  // then counted only: a bad sender repeats itself
          ++errors_printed_;
          std::fprintf(stderr, "afhub bridge dds: %s: command dropped: %s%s\n",
                       body.command_topic_name.c_str(), error.c_str(),
                       errors_printed_ == 3 ? " (further bad commands are only counted)" : "");
        }
        continue;
      }
      if (!body.command_writer) {
        try {
          body.command_writer =
              std::make_unique<Writer<BodyCommand>>(body_command_channel(body.channel));
        } catch (const Error& refused) {  // no iceoryx publisher port left
          ++bad_commands_;
          if (errors_printed_ < 3) {
            ++errors_printed_;
            std::fprintf(stderr, "afhub bridge dds: %s: command dropped: %s\n",
                         body.command_topic_name.c_str(), refused.what());
          }
          continue;
        }
      }
      const auto joints = static_cast<std::uint32_t>(body.names.size());
      BodyCommand* command = body.command_writer->loan(body_command_bytes(joints));
      if (!command) continue;
      command->joint_count = joints;
      ros2_joint_command(joint_state, body.names, hold, command);
      for (std::uint32_t j = 0; j < command->joint_count; ++j)
        body.hold[j] = command->joints[j].type == JointCommandType::kPosition
                           ? command->joints[j].value
                           : (state && j < state->joint_count ? state->joints[j].position : 0.0);
      body.last_command_ns = now_ns;
      body.command_writer->publish(command);
      ++commands_in_;
    }
  }
}

void Ros2Profile::report() const {
  std::fprintf(stderr,
               "afhub bridge dds: ros2 profile: states out %llu, joint commands in %llu, stale "
               "dropped %llu, bad %llu\n",
               static_cast<unsigned long long>(states_out_),
               static_cast<unsigned long long>(commands_in_),
               static_cast<unsigned long long>(stale_commands_),
               static_cast<unsigned long long>(bad_commands_));
}

}  // namespace afhub::bridges
