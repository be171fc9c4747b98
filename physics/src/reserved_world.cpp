#include "reserved_world.hpp"

#include <BulletCollision/CollisionDispatch/btSimulationIslandManager.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include <algorithm>

namespace afhub::physics {
namespace {

// Collision objects whose bounds one thread makes at a time (updateAabbs): fewer than
// 16 items (ParallelIslands::kMinItems) are made by the stepping thread alone.
constexpr int kObjectsPerItem = 32;

// As Bullet tells a constraint's island: its first body's, unless that is static.
int island_of(const btTypedConstraint& constraint) {
  const int a = constraint.getRigidBodyA().getIslandTag();
  return a >= 0 ? a : constraint.getRigidBodyB().getIslandTag();
}

}  // namespace

ReservedWorld::ReservedWorld(btDispatcher* dispatcher, btBroadphaseInterface* broadphase,
                             btMultiBodyConstraintSolver* solver,
                             btCollisionConfiguration* collision_config,
                             btSoftBodySolver& soft_solver)
    : btSoftMultiBodyDynamicsWorld(dispatcher, broadphase, solver, collision_config, &soft_solver),
      soft_solver_(soft_solver) {
  // Bullet's multibody world asks for two friction directions per contact; the rigid
  // world, which afhub's contacts were tuned in and tested with, for one.
  getSolverInfo().m_solverMode &= ~SOLVER_USE_2_FRICTION_DIRECTIONS;
}

void ReservedWorld::reserve_constraints(int count) {
  m_constraints.reserve(count);
  m_sortedConstraints.reserve(count);
  keyed_.reserve(count);
  sorted_.reserve(count);
  // A joint of a chain in reduced coordinates has a motor and limits (JointModel::attach).
  m_sortedMultiBodyConstraints.reserve(2 * count);
  multibody_keyed_.reserve(2 * count);
  multibody_sorted_.reserve(2 * count);
}

void ReservedWorld::addMultiBody(btMultiBody* body, int group, int mask) {
  body->setUserIndex(m_multiBodies.size());
  readied_.push_back(0);
  advanced_.push_back(0);
  btSoftMultiBodyDynamicsWorld::addMultiBody(body, group, mask);
}

void ReservedWorld::solve_islands_in_parallel(int bodies, int joints, int objects) {
  for (int i = 0; i < getNumCollisionObjects(); ++i)
    if (getCollisionObjectArray()[i]->isKinematicObject()) return;
  parallel_ = std::make_unique<ParallelIslands>(bodies, joints);
  islands_.reserve(objects);
  island_bodies_.reserve(objects);
  integrated_.assign(objects, 0);
  unintegrated_.reserve(objects);
  bounds_.resize(objects);
}

void ReservedWorld::island_to_solve(btCollisionObject** bodies, int count, int thread) noexcept {
  for (int i = 0; i < count; ++i)
    if (const btMultiBodyLinkCollider* link = btMultiBodyLinkCollider::upcast(bodies[i]))
      if (readied_[link->m_multiBody->getUserIndex()] != stamp_) ready(*link->m_multiBody, thread);
}

// As Bullet's integrateTransformsInternal does for one body, unless the body is to be
// swept for continuous collision (which reads the broadphase: left to the stepping
// thread), or speculative contact restitution is on (integrateTransforms() does it);
// a multibody's links advance it, once.
void ReservedWorld::island_solved(btCollisionObject** bodies, int count, int thread) noexcept {
  const btScalar dt = getSolverInfo().m_timeStep;
  for (int i = 0; i < count; ++i) {
    if (const btMultiBodyLinkCollider* link = btMultiBodyLinkCollider::upcast(bodies[i])) {
      btMultiBody& multibody = *link->m_multiBody;
      if (advanced_[multibody.getUserIndex()] != stamp_) advance(multibody, thread);
      continue;
    }
    if (m_applySpeculativeContactRestitution) continue;
    btRigidBody* body = btRigidBody::upcast(bodies[i]);
    const auto index = static_cast<std::size_t>(bodies[i]->getWorldArrayIndex());
    if (!body || index >= integrated_.size() || !body->isActive() ||
        body->isStaticOrKinematicObject())
      continue;
    btTransform next;
    body->predictIntegratedTransform(dt, next);
    const btScalar threshold = body->getCcdSquareMotionThreshold();
    if (getDispatchInfo().m_useContinuous && threshold != 0 &&
        threshold < (next.getOrigin() - body->getWorldTransform().getOrigin()).length2())
      continue;
    body->setHitFraction(1);
    body->proceedToTransform(next);
    integrated_[index] = stamp_;
  }
}

// What Bullet's multibody world does before its solve (solveExternalForces), for one
// multibody, before its island's solve: its links' frames, and its velocities under
// the forces on it. (Less Bullet's sort of every multibody constraint by island,
// comparing through two virtual calls, 10 % of 125 arms' step: each island's are found
// by solveConstraints() instead.) Debian's Bullet is built with
// BT_USE_VIRTUAL_CLEARFORCES_AND_GRAVITY: gravity is added by applyGravity() and the
// forces cleared by clearForces(), both in stepSimulation (the pendulum tests of
// tests/physics/reduced_coordinates_test.cpp would see it otherwise).
void ReservedWorld::ready(btMultiBody& body, int thread) noexcept {
  readied_[body.getUserIndex()] = stamp_;
  MultibodyScratch& scratch = scratch_[thread];
  const btContactSolverInfo& info = getSolverInfo();
  body.clearConstraintForces();
  body.forwardKinematics(scratch.world_to_local, scratch.local_origin);
  body.computeAccelerationsArticulatedBodyAlgorithmMultiDof(
      info.m_timeStep, scratch.r, scratch.v, scratch.m, false, info.m_jointFeedbackInWorldSpace,
      info.m_jointFeedbackInJointFrame);
}

// After its island's solve: the velocity changes the solve gave it applied, then its
// joints moved by its velocities and its links' colliders placed (what Bullet's
// multibody world does for every multibody after the solve and in its integration).
void ReservedWorld::advance(btMultiBody& body, int thread) noexcept {
  advanced_[body.getUserIndex()] = stamp_;
  MultibodyScratch& scratch = scratch_[thread];
  body.processDeltaVeeMultiDof2();
  body.stepPositionsMultiDof(getSolverInfo().m_timeStep);
  body.updateCollisionObjectWorldTransforms(scratch.world_to_local, scratch.local_origin);
}

void ReservedWorld::predictUnconstraintMotion(btScalar dt) {
  if (getDispatchInfo().m_useContinuous) {
    btSoftMultiBodyDynamicsWorld::predictUnconstraintMotion(dt);
    return;
  }
  for (int i = 0; i < m_nonStaticRigidBodies.size(); ++i)
    if (!m_nonStaticRigidBodies[i]->isStaticOrKinematicObject())
      damping_.apply(*m_nonStaticRigidBodies[i], dt);
  soft_solver_.predictMotion(static_cast<float>(dt));  // as Bullet's soft world does
}

void BodyDamping::apply(btRigidBody& body, btScalar dt) noexcept {
  body.setLinearVelocity(body.getLinearVelocity() * linear_.of(body.getLinearDamping(), dt));
  body.setAngularVelocity(body.getAngularVelocity() * angular_.of(body.getAngularDamping(), dt));
}

btScalar BodyDamping::Factor::of(btScalar new_damping, btScalar new_dt) noexcept {
  if (new_damping != damping || new_dt != dt) {
    damping = new_damping;
    dt = new_dt;
    factor = btPow(btScalar(1) - damping, dt);
  }
  return factor;
}

void ReservedWorld::updateAabbs() {
  const int count = m_collisionObjects.size();
  if (!parallel_ || count > static_cast<int>(bounds_.size())) {
    btSoftMultiBodyDynamicsWorld::updateAabbs();
    return;
  }
  // Bullet's updateSingleAabb, in two parts. A shape's bounds read only the shape.
  const btVector3 margin(gContactBreakingThreshold, gContactBreakingThreshold,
                         gContactBreakingThreshold);
  share_each(*this, count, kObjectsPerItem, [this, &margin](int i, int) {
    const btCollisionObject& object = *m_collisionObjects[i];
    Bounds& bounds = bounds_[static_cast<std::size_t>(i)];
    bounds.update = m_forceUpdateAllAabbs || object.isActive();
    if (!bounds.update) return;
    object.getCollisionShape()->getAabb(object.getWorldTransform(), bounds.min, bounds.max);
    bounds.min -= margin;
    bounds.max += margin;
    if (getDispatchInfo().m_useContinuous &&
        object.getInternalType() == btCollisionObject::CO_RIGID_BODY &&
        !object.isStaticOrKinematicObject()) {
      btVector3 min, max;
      object.getCollisionShape()->getAabb(object.getInterpolationWorldTransform(), min, max);
      bounds.min.setMin(min - margin);
      bounds.max.setMax(max + margin);
    }
  });
  for (int i = 0; i < count; ++i) {
    const Bounds& bounds = bounds_[static_cast<std::size_t>(i)];
    if (!bounds.update) continue;
    btCollisionObject& object = *m_collisionObjects[i];
    // As Bullet: a moving object whose bounds overflow leaves the simulation.
    if (object.isStaticObject() || (bounds.max - bounds.min).length2() < btScalar(1e12))
      m_broadphasePairCache->setAabb(object.getBroadphaseHandle(), bounds.min, bounds.max,
                                     m_dispatcher1);
    else
      object.setActivationState(DISABLE_SIMULATION);
  }
}

void ReservedWorld::createPredictiveContacts(btScalar dt) {
  if (getDispatchInfo().m_useContinuous)
    btSoftMultiBodyDynamicsWorld::createPredictiveContacts(dt);
  else
    releasePredictiveContacts();  // none are made; as Bullet, clear the last step's
}

void ReservedWorld::integrateTransforms(btScalar dt) {
  for (int i = 0; i < m_multiBodies.size(); ++i)  // any no island held
    if (advanced_[i] != stamp_) {
      if (readied_[i] != stamp_) ready(*m_multiBodies[i], 0);
      advance(*m_multiBodies[i], 0);
    }
  if (!parallel_ || m_applySpeculativeContactRestitution) {
    btDiscreteDynamicsWorld::integrateTransforms(dt);  // the rigid bodies
    return;
  }
  unintegrated_.clear();
  for (int i = 0; i < m_nonStaticRigidBodies.size(); ++i) {
    btRigidBody* body = m_nonStaticRigidBodies[i];
    const auto index = static_cast<std::size_t>(body->getWorldArrayIndex());
    if (index >= integrated_.size() || integrated_[index] != stamp_) unintegrated_.push_back(body);
  }
  if (!unintegrated_.empty())
    integrateTransformsInternal(unintegrated_.data(), static_cast<int>(unintegrated_.size()), dt);
}

void ReservedWorld::solveConstraints(btContactSolverInfo& info) {
  ++stamp_;  // from 1: 0 is never integrated
  if (info.m_minimumSolverBatchSize > 1) {
    btSoftMultiBodyDynamicsWorld::solveConstraints(info);  // its multibodies readied too
    std::fill(readied_.begin(), readied_.end(), stamp_);
    return;
  }
  const auto by_island = [](const Keyed& x, const Keyed& y) {
    return x.island != y.island ? x.island < y.island : x.index < y.index;
  };
  keyed_.clear();
  for (int i = 0; i < m_constraints.size(); ++i)
    keyed_.push_back({island_of(*m_constraints[i]), i});
  std::sort(keyed_.begin(), keyed_.end(), by_island);
  sorted_.clear();
  for (const Keyed& k : keyed_) sorted_.push_back(m_constraints[k.index]);
  multibody_keyed_.clear();
  for (int i = 0; i < m_multiBodyConstraints.size(); ++i) {
    const btMultiBodyConstraint& c = *m_multiBodyConstraints[i];
    multibody_keyed_.push_back({c.getIslandIdA() >= 0 ? c.getIslandIdA() : c.getIslandIdB(), i});
  }
  std::sort(multibody_keyed_.begin(), multibody_keyed_.end(), by_island);
  multibody_sorted_.clear();
  for (const Keyed& k : multibody_keyed_)
    multibody_sorted_.push_back(m_multiBodyConstraints[k.index]);

  struct Islands : btSimulationIslandManager::IslandCallback {
    ReservedWorld& world;
    btContactSolverInfo& info;
    Islands(ReservedWorld& w, btContactSolverInfo& i) : world(w), info(i) {}
    void processIsland(btCollisionObject** bodies, int body_count, btPersistentManifold** manifolds,
                       int manifold_count, int island) override {
      const auto& keyed = world.keyed_;
      if (island < 0) {  // islands not split: everything at once
        world.island_to_solve(bodies, body_count, 0);
        world.m_multiBodyConstraintSolver->solveMultiBodyGroup(
            bodies, body_count, manifolds, manifold_count, world.sorted_.data(),
            static_cast<int>(keyed.size()), world.multibody_sorted_.data(),
            static_cast<int>(world.multibody_sorted_.size()), info, world.m_debugDrawer,
            world.getDispatcher());
        return;
      }
      const auto [first, count] = range(keyed, island);
      const auto [multibody_first, multibody_count] = range(world.multibody_keyed_, island);
      if (world.parallel_) {
        world.islands_.push_back({static_cast<int>(world.island_bodies_.size()), body_count,
                                  manifolds, manifold_count, first, count, multibody_first,
                                  multibody_count});
        world.island_bodies_.insert(world.island_bodies_.end(), bodies, bodies + body_count);
        return;
      }
      world.island_to_solve(bodies, body_count, 0);
      world.m_multiBodyConstraintSolver->solveMultiBodyGroup(
          bodies, body_count, manifolds, manifold_count, count ? &world.sorted_[first] : nullptr,
          count, multibody_count ? &world.multibody_sorted_[multibody_first] : nullptr,
          multibody_count, info, world.m_debugDrawer, world.getDispatcher());
    }
    // The first of `island`'s entries in `keyed` (sorted by island), and their count.
    static std::pair<int, int> range(const std::vector<Keyed>& keyed, int island) {
      const auto in =
          std::equal_range(keyed.begin(), keyed.end(), Keyed{island, 0},
                           [](const Keyed& x, const Keyed& y) { return x.island < y.island; });
      return {static_cast<int>(in.first - keyed.begin()), static_cast<int>(in.second - in.first)};
    }
  } islands(*this, info);
  m_constraintSolver->prepareSolve(getNumCollisionObjects(), getDispatcher()->getNumManifolds());
  islands_.clear();
  island_bodies_.clear();
  m_islandManager->buildAndProcessIslands(getDispatcher(), this, &islands);
  if (parallel_)
    parallel_->solve(static_cast<ConstraintSolver&>(*m_constraintSolver), islands_,
                     island_bodies_.data(), sorted_.data(), multibody_sorted_.data(), info, *this);
  m_constraintSolver->allSolved(info, m_debugDrawer);
}

}  // namespace afhub::physics
