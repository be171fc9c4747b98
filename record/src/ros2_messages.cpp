#include "ros2_messages.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "afhub/shm_layout/body_command.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/world.hpp"

namespace afhub::mcap {

namespace {

// A dependency's definition, after the message's own: a line of 80 '=', its name, its
// fields, as ROS 2 bags hold them.
std::string dependency(const char* name, const char* fields) {
  return std::string(80, '=') + "\nMSG: " + name + "\n" + fields;
}

std::vector<Ros2Schema> make_schemas() {
  const std::string header =
      dependency("std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n") +
      dependency("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n");
  const std::string vector3 =
      dependency("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n");
  return {
      {"sensor_msgs/msg/JointState",
       "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
       "float64[] effort\n" +
           header},
      {"geometry_msgs/msg/PoseStamped",
       "std_msgs/Header header\ngeometry_msgs/Pose pose\n" + header +
           dependency("geometry_msgs/Pose", "Point position\nQuaternion orientation\n") +
           dependency("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n") +
           dependency("geometry_msgs/Quaternion",
                      "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n")},
      {"geometry_msgs/msg/TwistStamped",
       "std_msgs/Header header\ngeometry_msgs/Twist twist\n" + header +
           dependency("geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n") + vector3},
      {"geometry_msgs/msg/WrenchStamped",
       "std_msgs/Header header\ngeometry_msgs/Wrench wrench\n" + header +
           dependency("geometry_msgs/Wrench", "Vector3 force\nVector3 torque\n") + vector3},
      {"rosgraph_msgs/msg/Clock",
       "builtin_interfaces/Time clock\n" +
           dependency("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n")},
  };
}
enum SchemaIndex : std::size_t { kJointState, kPoseStamped, kTwistStamped, kWrenchStamped, kClock };

// Plain CDR, little-endian (the encapsulation rmw writes): each primitive aligned to its
// size, counted from after the 4-byte encapsulation header.
class Cdr {
 public:
  explicit Cdr(std::vector<std::uint8_t>& out) : out_(out) {
    out_.assign({0x00, 0x01, 0x00, 0x00});  // CDR_LE
  }
  template <class T>
  Cdr& put(T value) {
    while ((out_.size() - 4) % sizeof(T) != 0) out_.push_back(0);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
    out_.insert(out_.end(), bytes, bytes + sizeof value);
    return *this;
  }
  Cdr& string(const std::string& text) {
    put(static_cast<std::uint32_t>(text.size() + 1));
    out_.insert(out_.end(), text.begin(), text.end());
    out_.push_back(0);
    return *this;
  }
  // builtin_interfaces/Time, then the frame: a std_msgs/Header.
  Cdr& header(double sim_time_s, const std::string& frame_id) {
    time(sim_time_s);
    return string(frame_id);
  }
  Cdr& time(double seconds) {
    const long long ns = std::llround(seconds * 1e9);
    const long long sec = ns >= 0 ? ns / 1'000'000'000 : (ns - 999'999'999) / 1'000'000'000;
    put(static_cast<std::int32_t>(sec));
    return put(static_cast<std::uint32_t>(ns - sec * 1'000'000'000));
  }
  Cdr& vec(const Vec3& v) { return put(v.x).put(v.y).put(v.z); }

 private:
  std::vector<std::uint8_t>& out_;
};

const BodyState& state_of(std::span<const std::uint8_t> payload, BodyState& copy) {
  std::memcpy(&copy, payload.data(), std::min(payload.size(), sizeof copy));
  return copy;
}

const char* const kWorldFrame = "world";

}  // namespace

std::span<const Ros2Schema> ros2_schemas() {
  static const std::vector<Ros2Schema> schemas = make_schemas();
  return schemas;
}

std::string ros2_topic_name(const std::string& channel, const std::string& suffix) {
  std::string name;
  for (const std::string& part : {channel, suffix}) {
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
      const bool allowed =
          (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
      name += allowed ? c : '_';
    }
  }
  return name;
}

std::vector<Ros2Output> ros2_outputs(PayloadKind kind, const std::string& channel,
                                     const std::vector<std::string>& joint_names) {
  // A state is copied out of the buffer once per message: a BodyState is a few
  // kilobytes, and the writing thread has the time.
  auto state = std::make_shared<BodyState>();
  switch (kind) {
    case PayloadKind::kBodyState:
      return {
          {ros2_topic_name(channel, "joint_states"), kJointState,
           [state, joint_names](auto payload, auto& out) {
             const BodyState& s = state_of(payload, *state);
             const std::size_t n = std::min<std::size_t>(s.joint_count, joint_names.size());
             Cdr cdr(out);
             cdr.header(s.header.sim_time_s, "").put(static_cast<std::uint32_t>(n));
             for (std::size_t j = 0; j < n; ++j) cdr.string(joint_names[j]);
             for (double JointSample::*field :
                  {&JointSample::position, &JointSample::velocity, &JointSample::effort}) {
               cdr.put(static_cast<std::uint32_t>(n));
               for (std::size_t j = 0; j < n; ++j) cdr.put(s.joints[j].*field);
             }
           }},
          {ros2_topic_name(channel, "pose"), kPoseStamped,
           [state](auto payload, auto& out) {
             const BodyState& s = state_of(payload, *state);
             const Quaternion& q = s.pose.orientation;
             Cdr(out)
                 .header(s.header.sim_time_s, kWorldFrame)
                 .vec(s.pose.position_m)
                 .put(q.x)
                 .put(q.y)
                 .put(q.z)
                 .put(q.w);
           }},
          {ros2_topic_name(channel, "twist"), kTwistStamped,
           [state](auto payload, auto& out) {
             const BodyState& s = state_of(payload, *state);
             Cdr(out)
                 .header(s.header.sim_time_s, kWorldFrame)
                 .vec(s.twist.linear_mps)
                 .vec(s.twist.angular_radps);
           }},
          {ros2_topic_name(channel, "wrench"), kWrenchStamped,
           [state](auto payload, auto& out) {
             const BodyState& s = state_of(payload, *state);
             Cdr(out)
                 .header(s.header.sim_time_s, kWorldFrame)
                 .vec(s.wrench.force_n)
                 .vec(s.wrench.torque_nm);
           }},
      };
    case PayloadKind::kBodyCommand: {
      // As the bridge takes a command in (its joint_command topic): the joints by name,
      // and an array for each command type used, a joint of another type NaN in it.
      auto command = std::make_shared<BodyCommand>();
      return {{ros2_topic_name(channel, "joint_command"), kJointState,
               [command, joint_names](auto payload, auto& out) {
                 std::memcpy(static_cast<void*>(command.get()), payload.data(),
                             std::min(payload.size(), sizeof *command));
                 const BodyCommand& c = *command;
                 const std::size_t n = std::min<std::size_t>(c.joint_count, joint_names.size());
                 Cdr cdr(out);
                 cdr.header(c.header.sim_time_s, "").put(static_cast<std::uint32_t>(n));
                 for (std::size_t j = 0; j < n; ++j) cdr.string(joint_names[j]);
                 for (JointCommandType type :
                      {JointCommandType::kPosition, JointCommandType::kVelocity,
                       JointCommandType::kEffort}) {
                   bool used = false;
                   for (std::size_t j = 0; j < n; ++j) used = used || c.joints[j].type == type;
                   cdr.put(static_cast<std::uint32_t>(used ? n : 0));
                   for (std::size_t j = 0; used && j < n; ++j)
                     cdr.put(c.joints[j].type == type ? c.joints[j].value
                                                      : std::numeric_limits<double>::quiet_NaN());
                 }
               }}};
    }
    case PayloadKind::kWorldState:
      return {{"/clock", kClock, [](auto payload, auto& out) {
                 PayloadHeader header;
                 std::memcpy(&header, payload.data(), sizeof header);
                 Cdr(out).time(header.sim_time_s);
               }}};
    default:
      return {};
  }
}

}  // namespace afhub::mcap
