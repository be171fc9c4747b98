// ADF joints (JOINT blocks): parent and child (resolved across files later), pivots
// and axes, type and limits, springs, motor, feedback and the joint PID.
#include <algorithm>
#include <cmath>
#include <map>

#include "adf_blocks.hpp"
#include "afhub/shm_layout/channel_names.hpp"

namespace afhub::physics::adf {
namespace {

const std::set<std::string> kJointKeys = {"name",
                                          "namespace",
                                          "parent",
                                          "child",
                                          "parent pivot",
                                          "parent axis",
                                          "child pivot",
                                          "child axis",
                                          "type",
                                          "joint limits",
                                          "offset",
                                          "joint offset",
                                          "damping",
                                          "stiffness",
                                          "equilibrium point",
                                          "enable motor",
                                          "max motor impulse",
                                          "max velocity",
                                          "joint erp",
                                          "joint cfm",
                                          "ignore inter-collision",
                                          "enable feedback",
                                          "controller",
                                          "controller output type",
                                          "passive",
                                          "plugins"};

JointType parse_joint_type(const FileReader& file, const YAML::Node& node) {
  static const std::map<std::string, JointType> kTypes = {
      {"hinge", JointType::kRevolute},
      {"revolute", JointType::kRevolute},
      {"continuous", JointType::kContinuous},
      {"slider", JointType::kPrismatic},
      {"prismatic", JointType::kPrismatic},
      {"fixed", JointType::kFixed},
      {"p2p", JointType::kP2P},
      {"spring", JointType::kLinearSpring},
      {"linear spring", JointType::kLinearSpring},
      {"torsion spring", JointType::kTorsionSpring},
      {"torsional spring", JointType::kTorsionSpring},
      {"angular spring", JointType::kTorsionSpring},
      {"cone twist", JointType::kConeTwist},
      {"six dof", JointType::kSixDof},
      {"six dof spring", JointType::kSixDofSpring}};
  auto found = kTypes.find(lower(file.text(node, "type")));
  if (found == kTypes.end())
    fail(file.at(node),
         "unknown joint type '" + node.Scalar() +
             "'; use revolute, continuous, prismatic, fixed, p2p, linear spring, torsion "
             "spring, cone twist, six dof or six dof spring");
  return found->second;
}

void read_joint_limits(const FileReader& file, const YAML::Node& limits, JointSpec& joint) {
  file.require_map(limits, "joint limits", "{low: -1.57, high: 1.57}");
  if (joint.type == JointType::kConeTwist) {
    if (limits.size() == 0) return;
    SixDofLimits cone;
    cone.angular_high = file.vec3(limits, "joint limits");
    joint.multi_limits = cone;
    return;
  }
  if (joint.type == JointType::kSixDof || joint.type == JointType::kSixDofSpring) {
    if (limits.size() == 0) return;
    SixDofLimits six;
    auto pair = [&](const char* group, Vec3& low, Vec3& high) {
      YAML::Node node = limits[group];
      if (!node) return;
      file.require_map(node, std::string("joint limits.") + group,
                       "{low: {x, y, z}, high: {x, y, z}}");
      if (node["low"]) low = file.vec3(node["low"], std::string("joint limits.") + group + ".low");
      if (node["high"])
        high = file.vec3(node["high"], std::string("joint limits.") + group + ".high");
    };
    pair("linear", six.linear_low, six.linear_high);
    pair("angular", six.angular_low, six.angular_high);
    joint.multi_limits = six;
    return;
  }
  // 1-DOF limits apply only when both ends are given, as upstream.
  if (limits["low"] && limits["high"]) {
    joint.limit_low = file.number(limits["low"], "joint limits.low");
    joint.limit_high = file.number(limits["high"], "joint limits.high");
    if (*joint.limit_low > *joint.limit_high)
      fail(file.at(limits), "'joint limits' has low " + limits["low"].Scalar() + " above high " +
                                limits["high"].Scalar() + "; swap them");
    // Past a turn each way (give or take a file's rounding of 2 pi) a revolute limit is no
    // limit: likely degrees.
    if (joint.type == JointType::kRevolute &&
        std::max(std::abs(*joint.limit_low), std::abs(*joint.limit_high)) > 2.0 * M_PI * 1.01)
      file.warn(limits, "'joint limits' {low: " + limits["low"].Scalar() +
                            ", high: " + limits["high"].Scalar() +
                            "} reach past a full turn: ADF gives them in radians (90 degrees is "
                            "1.5708); check their unit");
  }
}

}  // namespace

PendingJoint read_joint(const FileReader& file, const YAML::Node& block,
                        const std::string& identifier, const FileContext& context) {
  PendingJoint pending;
  JointSpec& joint = pending.spec;
  read_block_head(file, block, identifier, kJointKeys, "joint", joint);
  const std::string name_space = block_namespace(file, block, context);
  std::erase(joint.name, ' ');  // as AMBF does: scripts name 'baselink-yawlink'
  joint.channel = body_channel_name(name_space, joint.name);
  pending.from = {context.file_index, name_space};
  YAML::Node parent = file.require(block, "parent", joint.where);
  YAML::Node child = file.require(block, "child", joint.where);
  pending.parent = file.text(parent, "parent");
  pending.child = file.text(child, "child");
  pending.parent_at = file.at(parent);
  pending.child_at = file.at(child);
  joint.parent_pivot_m =
      file.position(file.require(block, "parent pivot", joint.where), "parent pivot");
  joint.child_pivot_m =
      file.position(file.require(block, "child pivot", joint.where), "child pivot");
  joint.parent_axis = file.axis(file.require(block, "parent axis", joint.where), "parent axis");
  joint.child_axis = file.axis(file.require(block, "child axis", joint.where), "child axis");
  joint.type = parse_joint_type(file, file.require(block, "type", joint.where));
  if (YAML::Node limits = block["joint limits"]) read_joint_limits(file, limits, joint);
  if (YAML::Node offset = block["offset"]) joint.offset_rad = file.number(offset, "offset");
  if (YAML::Node offset = block["joint offset"])
    joint.joint_offset_rad = file.number(offset, "joint offset");
  file.optional_non_negative(block, "damping", joint.damping, "damping");
  file.optional_non_negative(block, "stiffness", joint.stiffness, "stiffness");
  if (YAML::Node equilibrium = block["equilibrium point"])
    joint.equilibrium = file.number(equilibrium, "equilibrium point");
  file.optional_non_negative(block, "max motor impulse", joint.max_motor_impulse,
                             "max motor impulse");
  if (YAML::Node velocity = block["max velocity"]) {
    joint.max_velocity = file.non_negative(velocity, "max velocity");
    if (*joint.max_velocity == 0.0) joint.max_velocity.reset();  // as URDF's 0: none given
  }
  if (YAML::Node erp = block["joint erp"]) joint.erp = file.non_negative(erp, "joint erp");
  if (YAML::Node cfm = block["joint cfm"]) joint.cfm = file.non_negative(cfm, "joint cfm");
  file.optional_flag(block, "ignore inter-collision", joint.ignore_inter_collision);
  file.optional_flag(block, "enable feedback", joint.enable_feedback);
  file.optional_flag(block, "passive", joint.passive);
  if (YAML::Node motor = block["enable motor"]) {
    file.flag(motor, "enable motor");  // checked; motors are enabled by velocity commands
  }
  if (YAML::Node controller = block["controller"]) {
    joint.controller = read_pid(file, controller, "controller");
    joint.gains_from = GainSource::kFile;
  }
  if (YAML::Node output = block["controller output type"])
    joint.controller_output = read_output_type(file, output);
  return pending;
}

}  // namespace afhub::physics::adf
