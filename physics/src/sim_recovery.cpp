// Recovery: a step that leaves a body NaN or infinite (a gain too high for a light
// link, a degenerate inertia) does not end the world for every client. The body
// goes back to its pose after the last good step, at rest: restoring its last
// velocity too would often replay the blow-up. Its Cartesian input, and the inputs
// of every joint touching it or driven by it, are released, so a command that
// caused it stops, and an actuator holding it or carried by it lets go.
// Everything is kept in storage made when the world was built: no allocation.
#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

bool finite_body(const btRigidBody& rb) {
  const btTransform& t = rb.getWorldTransform();
  const btMatrix3x3& basis = t.getBasis();
  return finite(t.getOrigin()) && finite(basis[0]) && finite(basis[1]) && finite(basis[2]) &&
         finite(rb.getLinearVelocity()) && finite(rb.getAngularVelocity());
}

bool finite_soft_body(const btSoftBody& soft) {
  for (int n = 0; n < soft.m_nodes.size(); ++n)
    if (!finite(soft.m_nodes[n].m_x) || !finite(soft.m_nodes[n].m_v)) return false;
  return true;
}

}  // namespace

void Simulation::Data::keep_good_state() noexcept {
  for (BodyData& body : bodies) body.good_pose = body.body->getWorldTransform();
  for (SoftBodyData& soft : soft_bodies)
    for (int n = 0; n < soft.body->m_nodes.size(); ++n)
      soft.good_positions[static_cast<std::size_t>(n)] = soft.body->m_nodes[n].m_x;
}

void Simulation::Data::recover_non_finite() noexcept {
  auto count = [&](std::size_t index, bool soft) {
    const NanEvent event{steps, index, soft};
    if (nan_recoveries.count == 0) nan_recoveries.first = event;
    nan_recoveries.last = event;
    ++nan_recoveries.count;
  };
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    BodyData& body = bodies[b];
    btRigidBody& rb = *body.body;
    if (finite_body(rb)) {
      body.good_pose = rb.getWorldTransform();
      continue;
    }
    count(b, false);
    rb.setWorldTransform(body.good_pose);
    rb.setInterpolationWorldTransform(body.good_pose);
    rb.setLinearVelocity(btVector3(0, 0, 0));
    rb.setAngularVelocity(btVector3(0, 0, 0));
    rb.setInterpolationLinearVelocity(btVector3(0, 0, 0));
    rb.setInterpolationAngularVelocity(btVector3(0, 0, 0));
    rb.clearForces();
    // Bullet takes a body out of the simulation when its bounds overflow, and its
    // contacts may hold NaN impulses that would warm-start the next step.
    rb.forceActivationState(DISABLE_DEACTIVATION);
    world.updateSingleAabb(&rb);
    if (btBroadphaseProxy* proxy = rb.getBroadphaseHandle())
      world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(proxy, &dispatcher);
    // Its commands (Cartesian, and the joints it drives), and those of the joints
    // touching it, fall to zero.
    body.commanded = false;
    const int index = static_cast<int>(b);
    for (std::size_t j = 0; j < joints.size(); ++j) {
      const JointSpec& spec = model.joints[j];
      if (spec.parent != index && spec.child != index && joint_driver[j] != index) continue;
      joints[j]->release();
      joint_driver[j] = -1;
    }
    // An actuator on it or holding it lets go (releasing allocates nothing).
    for (ActuatorData& actuator : actuators)
      if (actuator.parent == index || actuator.held == index) actuate(actuator, false);
  }
  for (std::size_t s = 0; s < soft_bodies.size(); ++s) {
    SoftBodyData& data = soft_bodies[s];
    btSoftBody& soft = *data.body;
    if (finite_soft_body(soft)) {
      for (int n = 0; n < soft.m_nodes.size(); ++n)
        data.good_positions[static_cast<std::size_t>(n)] = soft.m_nodes[n].m_x;
      continue;
    }
    count(s, true);
    for (int n = 0; n < soft.m_nodes.size(); ++n) {
      btSoftBody::Node& node = soft.m_nodes[n];
      node.m_x = node.m_q = data.good_positions[static_cast<std::size_t>(n)];
      node.m_v = node.m_f = btVector3(0, 0, 0);
    }
    soft.updateBounds();
  }
}

const NanRecoveries& Simulation::nan_recoveries() const noexcept {
  return data_->nan_recoveries;
}

}  // namespace afhub::physics
