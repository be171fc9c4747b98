// What a loaded model must satisfy as a whole, checked once every file is read:
// channels used once and not reserved, and every per-body capacity of the hub's
// payloads (shm_layout/limits.hpp) respected. Each problem is located.
#include <string>
#include <unordered_map>

#include "adf_blocks.hpp"
#include "afhub/physics/body_input.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub::physics::adf {
namespace {

static_assert(kBodyJointCapacity == kMaxJointsPerBody);
static_assert(kBodyRayCapacity == kMaxSensorRaysPerBody);
static_assert(kBodyActuatorCapacity == kMaxActuatorsPerBody);

// Each channel once: two bodies on one channel would both publish on it.
void check_unique(std::unordered_map<std::string, SourceLocation>& seen, const std::string& channel,
                  const SourceLocation& where, const std::string& kind) {
  auto [first, added] = seen.try_emplace(channel, where);
  if (!added)
    fail(where, kind + " channel '" + channel + "' is already used by the " + kind + " at " +
                    first->second.str() + "; give one of them another name or namespace");
}

void check_not_reserved(const std::string& channel, const SourceLocation& where) {
  for (std::string_view reserved : {kWorldInstance, kHubInstance})
    if (channel == reserved)
      fail(where, "a body on channel '" + channel + "' would collide with the hub's '" +
                      std::string(reserved) + "' channel; rename the body or give it a namespace");
}

}  // namespace

void check_model(const Model& model) {
  std::unordered_map<std::string, SourceLocation> bodies, joints;
  for (const BodySpec& body : model.bodies) {
    check_not_reserved(body.channel, body.where);
    check_unique(bodies, body.channel, body.where, "body");
  }
  for (const SoftBodySpec& soft : model.soft_bodies) {
    check_not_reserved(soft.channel, soft.where);
    check_unique(bodies, soft.channel, soft.where, "body");
  }
  for (const JointSpec& joint : model.joints) {
    check_unique(joints, joint.channel, joint.where, "joint");
    if (joint.name.size() > kMaxJointNameLength)
      fail(joint.where, "joint name '" + joint.name + "' has " + std::to_string(joint.name.size()) +
                            " characters; the hub's catalog holds at most " +
                            std::to_string(kMaxJointNameLength));
  }
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodySpec& body = model.bodies[b];
    if (!body.passive && model.descendant_joints[b].size() > kMaxJointsPerBody)
      fail(body.where, "body '" + body.identifier + "' has " +
                           std::to_string(model.descendant_joints[b].size()) +
                           " joints below it; its state carries at most " +
                           std::to_string(kMaxJointsPerBody) +
                           " (kMaxJointsPerBody): split the model or mark the body passive");
  }
  std::vector<std::size_t> rays(model.bodies.size(), 0), actuators(model.bodies.size(), 0);
  for (const SensorSpec& sensor : model.sensors) {
    rays[sensor.parent] += sensor.rays.size();
    if (rays[sensor.parent] > kMaxSensorRaysPerBody)
      fail(sensor.where, "the sensors on body '" + model.bodies[sensor.parent].identifier +
                             "' have " + std::to_string(rays[sensor.parent]) +
                             " rays with this one; a body's state carries at most " +
                             std::to_string(kMaxSensorRaysPerBody) + " (kMaxSensorRaysPerBody)");
  }
  for (const ActuatorSpec& actuator : model.actuators)
    if (++actuators[actuator.parent] > kMaxActuatorsPerBody)
      fail(actuator.where, "body '" + model.bodies[actuator.parent].identifier +
                               "' has more than " + std::to_string(kMaxActuatorsPerBody) +
                               " actuators with this one; a body command drives at most " +
                               std::to_string(kMaxActuatorsPerBody) + " (kMaxActuatorsPerBody)");
}

void count_model_bodies(std::size_t count, const SourceLocation& where) {
  if (count > kMaxModelBodies)
    fail(where, "the model lists " + std::to_string(count) + " bodies with this list; afhub " +
                    "simulates at most " + std::to_string(kMaxModelBodies) +
                    " (kMaxModelBodies): split the scene into several runs");
}

void count_published_body(const std::string& identifier, const SourceLocation& where,
                          std::size_t& published) {
  if (++published > kMaxBodies)
    fail(where, "'" + identifier + "' is published body number " + std::to_string(published) +
                    "; the hub holds at most " + std::to_string(kMaxBodies) +
                    " (kMaxBodies): mark bodies that need no channel 'passive: true', or split "
                    "the model into several runs");
}

}  // namespace afhub::physics::adf
