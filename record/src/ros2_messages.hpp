// `afhub record --profile ros2`: body states, commands and the world's clock as the ROS 2
// messages the DDS bridge's ROS 2 profile publishes and takes (sensor_msgs/JointState,
// geometry_msgs/PoseStamped, TwistStamped, WrenchStamped, rosgraph_msgs/Clock; a command
// as the JointState of its joint_command topic), CDR-encoded as
// ROS 2's rmw writes them, with their .msg definitions as schemas: a ROS 2 bag that ROS 2
// tools and Foxglove Studio open. Stamps are simulation time.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "afhub/shm_layout/header.hpp"

namespace afhub::mcap {

struct Ros2Schema {
  std::string name;        // "sensor_msgs/msg/JointState"
  std::string definition;  // the .msg text with its dependencies, as ROS 2 bags hold it
};
std::span<const Ros2Schema> ros2_schemas();

using Encode =
    std::function<void(std::span<const std::uint8_t> payload, std::vector<std::uint8_t>& out)>;

// One ROS 2 message made from each payload of an afhub channel.
struct Ros2Output {
  std::string topic;
  std::size_t schema;  // index into ros2_schemas()
  Encode encode;       // from a checked payload
};

// The messages of a channel of `kind` ("afhub/arm/base" for a body, with its joints'
// names): four for a body state, its joint_command for a body command, /clock for the
// world's state, none for the rest.
std::vector<Ros2Output> ros2_outputs(PayloadKind kind, const std::string& channel,
                                     const std::vector<std::string>& joint_names);

// ROS 2's name of `channel`'s `suffix` topic: characters ROS names forbid become '_',
// and a part that starts with a digit gets one in front.
std::string ros2_topic_name(const std::string& channel, const std::string& suffix);

}  // namespace afhub::mcap
