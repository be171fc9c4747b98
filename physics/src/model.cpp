// Small helpers of the model (see model.hpp).
#include "afhub/physics/model.hpp"

#include <algorithm>
#include <filesystem>

#include "afhub/shm_layout/channel_names.hpp"
#include "frames.hpp"

namespace afhub::physics {

Quaternion rpy_to_quaternion(const Vec3& rpy_rad) {
  const btQuaternion q = rpy_rotation(rpy_rad);
  return {q.x(), q.y(), q.z(), q.w()};
}

std::string SourceLocation::str() const {
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

const char* joint_type_name(JointType type) {
  switch (type) {
    case JointType::kRevolute:
      return "revolute";
    case JointType::kContinuous:
      return "continuous";
    case JointType::kPrismatic:
      return "prismatic";
    case JointType::kFixed:
      return "fixed";
    case JointType::kP2P:
      return "p2p";
    case JointType::kLinearSpring:
      return "linear spring";
    case JointType::kTorsionSpring:
      return "torsion spring";
    case JointType::kConeTwist:
      return "cone twist";
    case JointType::kSixDof:
      return "six dof";
    case JointType::kSixDofSpring:
      return "six dof spring";
  }
  return "unknown";
}

bool is_rotational(JointType type) {
  switch (type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
    case JointType::kTorsionSpring:
    case JointType::kConeTwist:
      return true;
    default:
      return false;
  }
}

bool has_joint_axis(JointType type) {
  switch (type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
    case JointType::kPrismatic:
    case JointType::kLinearSpring:
    case JointType::kTorsionSpring:
      return true;
    default:
      return false;
  }
}

Vec3 effective_gravity(const Model& model, std::size_t body) {
  return model.bodies[body].gravity_mps2.value_or(model.world.gravity_mps2);
}

bool possible_principal_inertias(const Vec3& inertia_kgm2) {
  const Vec3& i = inertia_kgm2;
  const double most = std::max({i.x, i.y, i.z});
  return most <= 1.01 * (i.x + i.y + i.z - most);
}

int world_object_parent(const Model& model, const WorldObjectSpec& object) {
  if (object.parent.empty()) return -1;
  const std::string identifier = object.parent.substr(object.parent.find_last_of('/') + 1);
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].identifier == identifier) return static_cast<int>(b);
  return -1;
}

std::vector<std::string> model_files(const Model& model) {
  std::vector<std::string> files;
  const auto add = [&](const std::string& file) {
    std::error_code ignored;
    if (!file.empty())
      files.push_back(std::filesystem::absolute(file, ignored).lexically_normal().string());
  };
  for (const BodySpec& body : model.bodies) add(body.where.file);
  for (const JointSpec& joint : model.joints) add(joint.where.file);
  for (const SoftBodySpec& soft : model.soft_bodies) add(soft.where.file);
  for (const SensorSpec& sensor : model.sensors) add(sensor.where.file);
  for (const ActuatorSpec& actuator : model.actuators) add(actuator.where.file);
  add(model.world.file);
  for (const std::string& file : model.other_files) add(file);
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
  return files;
}

void override_gravity(Model& model, const Vec3& gravity_mps2) {
  model.world.gravity_mps2 = gravity_mps2;
  for (BodySpec& body : model.bodies) body.gravity_mps2.reset();
}

void prefix_channels(Model& model, std::string_view prefix) {
  const auto prefixed = [&](std::string& channel) {
    channel = body_channel_name(prefix, channel);
    require_valid_channel_name(channel);
  };
  for (BodySpec& body : model.bodies) prefixed(body.channel);
  for (SoftBodySpec& soft : model.soft_bodies) prefixed(soft.channel);
  for (JointSpec& joint : model.joints) prefixed(joint.channel);
}

}  // namespace afhub::physics
