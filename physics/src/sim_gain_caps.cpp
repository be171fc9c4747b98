// The stability cap of a joint's gains taken for the inertia it drives (see
// raise_gain_caps()).
#include <Eigen/Dense>

#include <algorithm>
#include <vector>

#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// A body reached from the ground, with the joint it was reached through, that joint's
// coordinate (-1: a fixed joint) and the body before it (-1: the ground).
struct Reached {
  int body;
  std::size_t via;
  int coordinate, before;
};

constexpr std::size_t kMostBodies = 256;  // past these, a joint keeps its own bodies' cap
constexpr std::size_t kMostCoordinates = 32;

}  // namespace

// A joint's effort moves every body it can reach, not only the link it joins: the UR5's
// shoulder pan was capped for its own link's 0.0067 kg m^2 while it swings the arm, and
// rang, 62 % over its target, for 5 s. With the direct solve (its islands solved
// exactly) the effort reaches in the step every body jointed to it: through a fixed
// joint rigidly, through a hinge or a slider only as that joint's own free motion lets
// it (its PID acts at the next step). So the inertia a joint drives is the one its
// tree puts up, from the ground on, with every hinge and slider free, its own included:
// one over its diagonal entry of the inverse of the tree's joint-space mass matrix
// (a light link before a heavy one on a parallel hinge counts little of the heavy one).
// Taken at a quarter, for poses that bring the bodies nearer the axis. A joint in no
// such tree with one ground (floating, in a closed loop, past a ball or six-dof joint),
// in a chain (reduced coordinates), beside the iterative solver, or among more bodies or
// joints than the bounds above keeps its own bodies' cap.
void Simulation::Data::raise_gain_caps() {
  if (!model.world.direct_solve) return;
  constexpr double kPoseMargin = 4.0;
  std::vector<std::vector<std::size_t>> joints_of(bodies.size());
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    joints_of[model.joints[j].parent].push_back(j);
    joints_of[model.joints[j].child].push_back(j);
  }
  const auto free_or_fixed = [&](std::size_t k) {
    const JointType type = model.joints[k].type;
    return type == JointType::kFixed || type == JointType::kRevolute ||
           type == JointType::kContinuous || type == JointType::kPrismatic;
  };
  std::vector<int> seen(bodies.size(), -1);  // the last search that reached it
  int mark = 0;
  std::vector<Reached> reached;
  std::vector<std::size_t> coordinate_joints;
  std::vector<int> path;
  // The first static body found from `from` on (itself, or through fixed joints,
  // hinges and sliders but `via`), with the joint that reaches it; false when none is.
  std::vector<std::pair<int, std::size_t>> stack;
  const auto ground_of = [&](int from, std::size_t via, int& ground, std::size_t& ground_via) {
    ++mark;
    stack.assign(1, {from, via});
    seen[from] = mark;
    while (!stack.empty()) {
      const auto [b, came] = stack.back();
      stack.pop_back();
      if (!bodies[b].dynamic) {
        ground = b;
        ground_via = came;
        return true;
      }
      for (std::size_t k : joints_of[b]) {
        const int next =
            model.joints[k].parent == b ? model.joints[k].child : model.joints[k].parent;
        if (k == came || !free_or_fixed(k) || seen[next] == mark) continue;
        seen[next] = mark;
        stack.push_back({next, k});
      }
    }
    return false;
  };
  // From the ground `from` on, through `via` first, every body reached through fixed
  // joints, hinges and sliders. False when a body comes twice or a static one is reached
  // (a loop), past a joint of more freedoms, or past the bounds.
  const auto search = [&](int from, std::size_t via) {
    ++mark;
    reached.assign(1, {from, via, -1, -1});
    seen[from] = mark;
    coordinate_joints.clear();
    for (std::size_t r = 0; r < reached.size(); ++r) {
      const int b = reached[r].body;
      for (std::size_t k : joints_of[b]) {
        if (r == 0 ? k != via : k == reached[r].via) continue;
        if (!free_or_fixed(k)) return false;
        const int next =
            model.joints[k].parent == b ? model.joints[k].child : model.joints[k].parent;
        if (seen[next] == mark || !bodies[next].dynamic) return false;  // a loop
        seen[next] = mark;
        int coordinate = -1;
        if (model.joints[k].type != JointType::kFixed) {
          coordinate = static_cast<int>(coordinate_joints.size());
          coordinate_joints.push_back(k);
        }
        reached.push_back({next, k, coordinate, static_cast<int>(r)});
      }
      if (reached.size() > kMostBodies || coordinate_joints.size() > kMostCoordinates) return false;
    }
    return true;
  };
  for (std::size_t j = 0; j < joints.size(); ++j) {
    JointModel& joint = *joints[j];
    if (!joint.constraint() || !joint.has_axis() || !free_or_fixed(j)) continue;
    // Its ground, reached from either of its bodies (the UR5's `world`, fixed under its
    // base link; the Allegro's palm); every body reached from there.
    int ground = -1;
    std::size_t ground_via = j;
    if ((!ground_of(model.joints[j].parent, j, ground, ground_via) &&
         !ground_of(model.joints[j].child, j, ground, ground_via)) ||
        !search(ground, ground_via))
      continue;
    const auto found = std::find(coordinate_joints.begin(), coordinate_joints.end(), j);
    if (found == coordinate_joints.end()) continue;
    const auto driver = static_cast<Eigen::Index>(found - coordinate_joints.begin());
    const auto n = static_cast<Eigen::Index>(coordinate_joints.size());
    Eigen::MatrixXd mass_matrix = Eigen::MatrixXd::Zero(n, n);
    std::vector<btVector3> angular(coordinate_joints.size()), linear(coordinate_joints.size());
    for (const Reached& at : reached) {
      if (!bodies[at.body].dynamic) continue;  // the ground
      const btRigidBody& body = *bodies[at.body].body;
      const btVector3 centre = body.getCenterOfMassPosition();
      const btMatrix3x3& basis = body.getWorldTransform().getBasis();
      const btVector3 inverse = body.getInvInertiaDiagLocal();
      btMatrix3x3 local(0, 0, 0, 0, 0, 0, 0, 0, 0);
      for (int i = 0; i < 3; ++i) local[i][i] = inverse[i] > 0 ? 1.0 / inverse[i] : 0.0;
      const btMatrix3x3 inertia = basis * local * basis.transpose();
      const double mass = 1.0 / body.getInvMass();
      path.clear();
      for (const Reached* step = &at; step->before >= 0; step = &reached[step->before])
        if (step->coordinate >= 0) path.push_back(step->coordinate);
      for (int c : path) {
        const JointModel& moving = *joints[coordinate_joints[c]];
        const btVector3 direction = moving.world_axis();
        angular[c] = moving.rotational() ? direction : btVector3(0, 0, 0);
        linear[c] =
            moving.rotational() ? direction.cross(centre - moving.world_pivot()) : direction;
      }
      for (int a : path)
        for (int c : path)
          mass_matrix(a, c) +=
              angular[a].dot(inertia * angular[c]) + mass * linear[a].dot(linear[c]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> solved(mass_matrix);
    if (solved.info() != Eigen::Success || !solved.isPositive()) continue;
    const double inverse = solved.solve(Eigen::VectorXd::Unit(n, driver))(driver);
    if (inverse > 0.0 && std::isfinite(inverse)) joint.raise_gain_cap(1.0 / inverse / kPoseMargin);
  }
}

}  // namespace afhub::physics
