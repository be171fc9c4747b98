// `afhub bridge dds --profile ros2`: exported bodies also appear as ROS 2 topics that
// a ROS 2 system on rmw_cyclonedds reads as its own (types in idl/ros2/ros2_msgs.idl).
// For a body channel C (e.g. afhub/arm/base) and an optional prefix P:
//   rt/P/C/joint_states   sensor_msgs/JointState     the body's descendant joints
//   rt/P/C/pose           geometry_msgs/PoseStamped  frame "world"
//   rt/P/C/twist          geometry_msgs/TwistStamped frame "world"
//   rt/P/C/wrench         geometry_msgs/WrenchStamped frame "world", applied last step
//   rt/P/C/joint_command  sensor_msgs/JointState in, with --accept-commands
// Stamps are simulation time. Writers are reliable, keep last 1 (they match ROS 2's
// default and sensor-data subscribers); the command reader is best effort, keep last 1.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "dds_entity.hpp"

namespace afhub::bridges {

// The ROS 2 topic name for a body channel: characters ROS names forbid become '_',
// and a name part starting with a digit gets a leading '_'.
std::string ros2_topic(const std::string& prefix, const std::string& channel, const char* suffix);

// A received JointState's arrays.
struct Ros2JointState {
  const char* const* names;
  std::uint32_t name_count;
  const double* values[3];  // position, velocity, effort
  std::uint32_t value_counts[3];
};
// Checks a JointState command for a body with `joint_names` and, when it is good and
// `command` (holding that many joints) is given, fills it: the values of position if
// given, else velocity, else effort, one per name; the joints left unnamed hold the
// positions `hold` (one per joint; nullptr when unknown, and then every joint must be
// named). Returns what is wrong (naming the field), or "" when good. Allocates only
// to describe an error.
std::string ros2_joint_command(const Ros2JointState& joint_state,
                               const std::vector<std::string>& joint_names, const double* hold,
                               BodyCommand* command) noexcept;

class Ros2Profile {
 public:
  Ros2Profile(dds_entity_t participant, std::string prefix, bool accept_commands,
              double max_command_age_s);
  ~Ros2Profile();
  Ros2Profile(const Ros2Profile&) = delete;
  Ros2Profile& operator=(const Ros2Profile&) = delete;

  // A new exported body (before the loop sees it): its topics, writers, reader.
  // `state` (the bridge's reader of the body's states) must outlive this profile; the
  // body's command writer is opened at its first good command.
  void add_body(const std::string& channel, const std::vector<std::string>& joint_names,
                LatestReader<BodyState>& state);
  // Body `index` (in add_body order) has a new state. Allocates nothing of its own.
  void publish(std::size_t index, const BodyState& state) noexcept;
  // Joint commands from the network into the bodies' command slots.
  void import_commands() noexcept;
  void report() const;

 private:
  struct Body;
  dds_entity_t participant_;
  std::string prefix_;
  bool accept_commands_;
  std::int64_t max_command_age_ns_;
  Qos writer_qos_, reader_qos_;
  std::vector<std::unique_ptr<Body>> bodies_;
  std::uint64_t states_out_ = 0, commands_in_ = 0, stale_commands_ = 0, bad_commands_ = 0;
  std::uint32_t errors_printed_ = 0;
};

}  // namespace afhub::bridges
