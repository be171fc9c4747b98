// Recovery: a step that leaves a body NaN or infinite (a gain too high for a light
// link, a degenerate inertia) does not end the world for every client. The body
// goes back to its pose after the last good step, at rest: restoring its last
// velocity too would often replay the blow-up. Its Cartesian input, and the inputs
// of every joint touching it or driven by it, are released, so a command that
// caused it stops, and an actuator holding it or carried by it lets go.
// A link of a chain in reduced coordinates takes its whole chain back to the chain's
// last good joint coordinates, at rest.
// Everything is kept in storage made when the world was built: no allocation.
#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// Bodies checked by one thread at a time (Simulation::share): each check reads the
// body and keeps its good pose, nothing else.
constexpr int kBodiesPerItem = 32;

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

void keep_good_coordinates(ChainData& chain) {
  for (int l = 0; l < chain.body->getNumLinks(); ++l)
    chain.good_q[l] = chain.body->getLink(l).m_dofCount ? chain.body->getJointPos(l) : 0;
}

}  // namespace

void Simulation::Data::keep_good_state() noexcept {
  for (BodyData& body : bodies) body.good_pose = body.body->getWorldTransform();
  for (ChainData& chain : chains) keep_good_coordinates(chain);
  for (SoftBodyData& soft : soft_bodies)
    for (int n = 0; n < soft.body->m_nodes.size(); ++n)
      soft.good_positions[static_cast<std::size_t>(n)] = soft.body->m_nodes[n].m_x;
}

void Simulation::Data::recover_non_finite() noexcept {
  // Bullet takes an object out of the simulation when its bounds overflow, and its
  // contacts may hold NaN impulses that would warm-start the next step.
  auto refresh = [&](btCollisionObject& object) {
    object.forceActivationState(DISABLE_DEACTIVATION);
    world.updateSingleAabb(&object);
    if (btBroadphaseProxy* proxy = object.getBroadphaseHandle())
      world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(proxy, &dispatcher);
  };
  auto count = [&](std::size_t index, bool soft) {
    const NanEvent event{steps, index, soft};
    if (nan_recoveries.count == 0) nan_recoveries.first = event;
    nan_recoveries.last = event;
    ++nan_recoveries.count;
  };
  // Every body checked, and its pose kept when finite, by both threads; then, in order,
  // those the step left non-finite are put back.
  share_each(world, static_cast<int>(bodies.size()), kBodiesPerItem, [this](int b, int) {
    BodyData& body = bodies[static_cast<std::size_t>(b)];
    body.left_finite = finite_body(*body.body);
    if (body.left_finite) body.good_pose = body.body->getWorldTransform();
  });
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    BodyData& body = bodies[b];
    if (body.left_finite) continue;
    btRigidBody& rb = *body.body;
    if (finite_body(rb)) {  // a link whose chain was put back for a link before it
      body.good_pose = rb.getWorldTransform();
      continue;
    }
    count(b, false);
    if (body.chain < 0) {
      rb.setWorldTransform(body.good_pose);
      rb.setInterpolationWorldTransform(body.good_pose);
      rb.setLinearVelocity(btVector3(0, 0, 0));
      rb.setAngularVelocity(btVector3(0, 0, 0));
      rb.setInterpolationLinearVelocity(btVector3(0, 0, 0));
      rb.setInterpolationAngularVelocity(btVector3(0, 0, 0));
      rb.clearForces();
      refresh(rb);
    } else if (ChainData& chain = chains[body.chain]; chain.restored_at != steps) {
      chain.restored_at = steps;
      place_chain(chain, chain.good_q);
      for (auto& collider : chain.colliders) refresh(*collider);
    }
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
  share_each(world, static_cast<int>(chains.size()), kChainsPerItem, [this](int c, int) {
    ChainData& chain = chains[static_cast<std::size_t>(c)];
    if (chain.restored_at != steps) keep_good_coordinates(chain);
  });
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
