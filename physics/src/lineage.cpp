// Lineage (see lineage.hpp). A joint is below a body when the body reaches the
// joint's parent going from parent to child. Sorting by joint index keeps the
// file's order, and a set keeps each joint once inside closed loops (upstream
// AMBF dropped loop joints and scrambled the order: issues 38, 107, 204).
// Passive joints are left out of the lists, as AMBF leaves them out of a body's
// joint names and joint commands.
#include "afhub/physics/lineage.hpp"

#include <algorithm>

#include "body_groups.hpp"

namespace afhub::physics {

std::vector<std::vector<int>> joints_by_parent(const Model& model) {
  std::vector<std::vector<int>> joints(model.bodies.size());
  for (int j = 0; j < static_cast<int>(model.joints.size()); ++j)
    joints[model.joints[j].parent].push_back(j);
  return joints;
}

void compute_lineage(Model& model) {
  const int body_count = static_cast<int>(model.bodies.size());
  const std::vector<std::vector<int>> joints_from = joints_by_parent(model);

  model.descendant_joints.assign(body_count, {});
  // Marks stamped with the body being walked, so that each walk costs what it
  // visits, not a fresh array per body (which made loading quadratic in the bodies).
  std::vector<int> body_seen(body_count, -1), joint_seen(model.joints.size(), -1);
  std::vector<int> stack;
  for (int body = 0; body < body_count; ++body) {
    if (joints_from[body].empty()) continue;
    stack.assign(1, body);
    body_seen[body] = body;
    while (!stack.empty()) {
      int current = stack.back();
      stack.pop_back();
      for (int j : joints_from[current]) {
        if (joint_seen[j] == body) continue;
        joint_seen[j] = body;
        // A passive joint is walked through but not listed (AMBF's active list).
        if (!model.joints[j].passive) model.descendant_joints[body].push_back(j);
        int child = model.joints[j].child;
        if (body_seen[child] != body) {
          body_seen[child] = body;
          stack.push_back(child);
        }
      }
    }
    std::sort(model.descendant_joints[body].begin(), model.descendant_joints[body].end());
  }

  // Loops = edges - vertices + components, over bodies connected by joints.
  BodyGroups groups(model.bodies.size());
  int loops = 0;
  for (const JointSpec& joint : model.joints)
    if (!groups.join(joint.parent, joint.child)) ++loops;
  model.closed_loop_count = loops;
}

}  // namespace afhub::physics
