// A body command into the core's input (see command_input.hpp).
#include "command_input.hpp"

#include <algorithm>

namespace afhub::physics {

// The wire and the core agree on capacities, so a copy never truncates what fits.
static_assert(kBodyJointCapacity == kMaxJointsPerBody);
static_assert(kBodyActuatorCapacity == kMaxActuatorsPerBody);
static_assert(static_cast<int>(CartesianMode::kPosition) ==
              static_cast<int>(CartesianCommandType::kPosition));
static_assert(static_cast<int>(JointMode::kVelocity) ==
              static_cast<int>(JointCommandType::kVelocity));

void to_input(const BodyCommand& command, BodyInput& input) noexcept {
  input.cartesian = static_cast<CartesianMode>(command.cartesian_type);
  input.target_pose = command.pose;
  input.wrench = command.wrench;
  input.twist = command.twist;
  input.joint_count = command.joint_count;
  const std::size_t joints = std::min<std::size_t>(command.joint_count, kBodyJointCapacity);
  for (std::size_t j = 0; j < joints; ++j) {
    input.joint_modes[j] = static_cast<JointMode>(command.joints[j].type);
    input.joint_values[j] = command.joints[j].value;
  }
  input.actuator_count = command.actuator_count;
  const std::size_t actuators =
      std::min<std::size_t>(command.actuator_count, kBodyActuatorCapacity);
  for (std::size_t a = 0; a < actuators; ++a) input.engage[a] = command.actuate[a] != 0;
}

}  // namespace afhub::physics
