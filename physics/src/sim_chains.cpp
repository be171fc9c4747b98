// Chains: the open chains of chains.hpp as Bullet multibodies. Built from the bodies
// and joints as the rigid world would hold them (each link's mass, inertia and shape
// are its body's; each joint's zero is its frames meeting), placed at the joint
// coordinates the bodies' poses give, then stepped by the world; after each step
// every link's body mirrors the link (ChainData).
#include <cmath>

#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// Bullet's multibody caps each joint's speed at 100 (rad or m per second) and its
// constraints' impulses at 1000 N s, which the rigid world does not: a joint's speed
// is left unbounded (a blow-up then shows as a NaN, and is recovered), the impulses
// bounded far away.
constexpr btScalar kLargeImpulse = BT_LARGE_FLOAT;

btScalar damping_rate(btScalar damping) {
  return damping <= 0 ? 0 : -std::log(std::max<btScalar>(1 - damping, 1e-6));
}

}  // namespace

void Simulation::Data::build_chains() {
  const btVector3 world_gravity = to_bt(model.world.gravity_mps2);
  chains.reserve(chain_plans.size());
  for (const ChainPlan& plan : chain_plans) {
    ChainData& chain = chains.emplace_back();
    chain.base = plan.base;
    const int links = static_cast<int>(plan.joints.size());
    chain.body = std::make_unique<btMultiBody>(links, 0.0, btVector3(0, 0, 0), true, false);
    btMultiBody& mb = *chain.body;
    mb.setBaseWorldTransform(bodies[plan.base].body->getWorldTransform());
    for (int l = 0; l < links; ++l) {
      const int j = plan.joints[l];
      const JointModel& joint = *joints[j];
      const int b = model.joints[j].child;
      const btRigidBody& rb = *bodies[b].body;
      ChainData::Link& link = chain.links.emplace_back();
      link.body = b;
      link.mass = 1 / rb.getInvMass();
      for (int i = 0; i < 3; ++i)
        if (rb.getInvInertiaDiagLocal()[i] > 0)
          link.inertia[i] = 1 / rb.getInvInertiaDiagLocal()[i];
      // At q = 0 the joint frames meet: the child's frame, in the parent's, is a c^-1.
      const btTransform& a = joint.frame_in_parent();
      const btTransform& c = joint.frame_in_child();
      const btQuaternion parent_to_child = (a * c.inverse()).getRotation().inverse();
      const bool apart = model.joints[j].ignore_inter_collision;
      switch (model.joints[j].type) {
        case JointType::kPrismatic:
          mb.setupPrismatic(l, link.mass, link.inertia, plan.parent[l], parent_to_child,
                            joint.axis_in_child(), a.getOrigin(), -c.getOrigin(), apart);
          break;
        case JointType::kFixed:
          mb.setupFixed(l, link.mass, link.inertia, plan.parent[l], parent_to_child, a.getOrigin(),
                        -c.getOrigin(), apart);
          break;
        default:  // revolute, continuous
          mb.setupRevolute(l, link.mass, link.inertia, plan.parent[l], parent_to_child,
                           joint.axis_in_child(), a.getOrigin(), -c.getOrigin(), apart);
          break;
      }
      const BodySpec& spec = model.bodies[b];
      link.linear_rate = damping_rate(rb.getLinearDamping());
      link.angular_rate = damping_rate(rb.getAngularDamping());
      if (spec.gravity_mps2)
        link.gravity_correction = link.mass * (to_bt(*spec.gravity_mps2) - world_gravity);
    }
    mb.finalizeMultiDof();
    mb.setHasSelfCollision(true);  // as rigid bodies: all but the joints' own pairs
    mb.setLinearDamping(0);        // applied as forces (ChainData)
    mb.setAngularDamping(0);
    mb.setMaxCoordinateVelocity(SIMD_INFINITY);
    mb.setMaxAppliedImpulse(kLargeImpulse);
    world.addMultiBody(&mb, btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter);
    for (int l = 0; l < links; ++l) {
      const btRigidBody& rb = *bodies[chain.links[l].body].body;
      auto& collider =
          chain.colliders.emplace_back(std::make_unique<btMultiBodyLinkCollider>(&mb, l));
      collider->setCollisionShape(const_cast<btCollisionShape*>(rb.getCollisionShape()));
      collider->setUserIndex(chain.links[l].body);
      collider->setFriction(rb.getFriction());
      collider->setRollingFriction(rb.getRollingFriction());
      collider->setRestitution(rb.getRestitution());
      collider->setActivationState(DISABLE_DEACTIVATION);
      mb.getLink(l).m_collider = collider.get();
      world.addCollisionObject(collider.get(), btBroadphaseProxy::DefaultFilter,
                               btBroadphaseProxy::AllFilter);
      JointModel& joint = *joints[plan.joints[l]];
      chain.initial_q.push_back(static_cast<btScalar>(joint.coordinate_as_placed()));
      joint.attach(mb, l);
      for (btMultiBodyConstraint* constraint : {joint.motor(), joint.limit()})
        if (constraint) world.addMultiBodyConstraint(constraint);
    }
    if (model.joints[plan.joints[0]].ignore_inter_collision)
      filter.ignore_base(chain.links[0].body, plan.base);
    chain.omega.resize(static_cast<std::size_t>(links) + 1);
    chain.velocity.resize(static_cast<std::size_t>(links) + 1);
    chain.world_to_local.resize(links + 1);
    chain.local_origin.resize(links + 1);
    chain.good_q = chain.initial_q;
    place_chain(chain, chain.initial_q);
  }
  // Islands one at a time, each with its own rows as ReservedWorld finds them: Bullet's
  // batches look for each island's multibody rows through all of them (125 arms: 37 %
  // of the step).
  if (!chains.empty()) world.getSolverInfo().m_minimumSolverBatchSize = 1;
}

std::size_t Simulation::links_in_reduced_coordinates() const noexcept {
  std::size_t links = 0;
  for (const ChainData& chain : data_->chains) links += chain.links.size();
  return links;
}

// Joint coordinates `q`, at rest; every link's collider and body follow.
void Simulation::Data::place_chain(ChainData& chain, const std::vector<btScalar>& q) noexcept {
  btMultiBody& mb = *chain.body;
  for (int l = 0; l < mb.getNumLinks(); ++l) {
    if (mb.getLink(l).m_dofCount > 0) {
      mb.setJointPos(l, q[static_cast<std::size_t>(l)]);
      mb.setJointVel(l, 0);
    }
  }
  mb.clearForcesAndTorques();
  mb.forwardKinematics(chain.world_to_local, chain.local_origin);
  mb.updateCollisionObjectWorldTransforms(chain.world_to_local, chain.local_origin);
  mirror_chain(chain);
}

// Each link's body takes the link's pose, and its velocities turned into the world;
// then the forces of the coming step are added.
void Simulation::Data::mirror_chain(ChainData& chain) noexcept {
  chain.body->compTreeLinkVelocities(chain.omega.data(), chain.velocity.data());
  for (std::size_t l = 0; l < chain.links.size(); ++l) {
    btRigidBody& rb = *bodies[chain.links[l].body].body;
    const btTransform& pose = chain.colliders[l]->getWorldTransform();
    rb.setWorldTransform(pose);
    rb.setLinearVelocity(pose.getBasis() * chain.velocity[l + 1]);
    rb.setAngularVelocity(pose.getBasis() * chain.omega[l + 1]);
  }
  drive_chain(chain);
}

// Each link's gravity correction and damping for the coming step, from the velocities
// the last one left (mirror_chain: Bullet has cleared the last step's forces).
void Simulation::Data::drive_chain(ChainData& chain) noexcept {
  for (std::size_t l = 0; l < chain.links.size(); ++l) {
    const ChainData::Link& link = chain.links[l];
    const btRigidBody& rb = *bodies[link.body].body;
    const btMatrix3x3& turn = rb.getWorldTransform().getBasis();
    const btVector3 momentum = link.inertia * (turn.transpose() * rb.getAngularVelocity());
    const int index = static_cast<int>(l);
    chain.body->addLinkForce(
        index, link.gravity_correction - link.linear_rate * link.mass * rb.getLinearVelocity());
    chain.body->addLinkTorque(index, -link.angular_rate * (turn * momentum));
  }
}

void Simulation::Data::mirror_chains() noexcept {
  share_each(world, static_cast<int>(chains.size()), kChainsPerItem,
             [this](int c, int) { mirror_chain(chains[c]); });
}

}  // namespace afhub::physics
