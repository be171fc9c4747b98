#include "chains.hpp"

#include "afhub/physics/lineage.hpp"
#include "body_groups.hpp"

namespace afhub::physics {
namespace {

bool reducible(const JointSpec& joint) {
  const bool kind = joint.type == JointType::kRevolute || joint.type == JointType::kContinuous ||
                    joint.type == JointType::kPrismatic || joint.type == JointType::kFixed;
  return kind && !joint.erp && !joint.cfm;
}

}  // namespace

std::vector<ChainPlan> plan_chains(const Model& model) {
  const std::size_t bodies = model.bodies.size();
  auto moves = [&](int b) { return model.bodies[b].mass_kg > 0.0; };
  // Moving bodies joined by joints, as groups.
  BodyGroups joined(bodies);
  for (const JointSpec& joint : model.joints)
    if (moves(joint.parent) && moves(joint.child)) joined.join(joint.parent, joint.child);
  struct Group {
    int bodies = 0, inner_joints = 0, base_joints = 0, base_joint = -1;
    bool reducible = true;
  };
  std::vector<Group> groups(bodies);
  for (std::size_t b = 0; b < bodies; ++b)
    if (moves(static_cast<int>(b))) ++groups[joined.root(static_cast<int>(b))].bodies;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const JointSpec& joint = model.joints[j];
    if (!moves(joint.parent) && !moves(joint.child)) continue;
    Group& g = groups[joined.root(moves(joint.child) ? joint.child : joint.parent)];
    g.reducible &= reducible(joint);
    if (moves(joint.parent) && moves(joint.child)) {
      ++g.inner_joints;
    } else {
      ++g.base_joints;
      g.base_joint = static_cast<int>(j);
      g.reducible &= moves(joint.child);  // from the static body outwards
    }
  }
  for (const ActuatorSpec& actuator : model.actuators)
    if (moves(actuator.parent)) groups[joined.root(actuator.parent)].reducible = false;

  // Each qualifying tree's links, breadth first from its base joint: a joint whose
  // parent is not yet a link points inwards, and the tree does not qualify.
  const std::vector<std::vector<int>> joints_from = joints_by_parent(model);
  std::vector<ChainPlan> chains;
  for (std::size_t b = 0; b < bodies; ++b) {
    const Group& g = groups[b];
    if (joined.root(static_cast<int>(b)) != static_cast<int>(b) || !moves(static_cast<int>(b)) ||
        !g.reducible || g.base_joints != 1 || g.inner_joints != g.bodies - 1)
      continue;
    ChainPlan chain;
    chain.base = model.joints[g.base_joint].parent;
    chain.joints.push_back(g.base_joint);
    chain.parent.push_back(-1);
    for (std::size_t next = 0; next < chain.joints.size(); ++next) {
      const int body = model.joints[chain.joints[next]].child;
      for (int j : joints_from[body]) {
        chain.joints.push_back(j);
        chain.parent.push_back(static_cast<int>(next));
      }
    }
    if (static_cast<int>(chain.joints.size()) == g.bodies) chains.push_back(std::move(chain));
  }
  return chains;
}

}  // namespace afhub::physics
