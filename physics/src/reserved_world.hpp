// The Bullet world the simulation steps: room for every constraint it may hold at
// once, and islands handed to the solver one at a time without Bullet's search for
// each island's constraints. A multibody world: open chains in reduced coordinates
// (Bullet's btMultiBody, sim_chains.cpp) are stepped with the rigid bodies; a world
// without one steps bit for bit as the rigid world did.
#pragma once

#include <BulletSoftBody/btSoftBodySolvers.h>
#include <BulletSoftBody/btSoftMultiBodyDynamicsWorld.h>

#include <memory>
#include <vector>

#include "parallel_islands.hpp"

namespace afhub::physics {

// btRigidBody::applyDamping (v *= (1 - damping)^dt, linear and angular), less its
// "additional damping", which afhub never sets; each power computed once per distinct
// damping and step rather than twice per body per step, to the same bits.
class BodyDamping {
 public:
  void apply(btRigidBody& body, btScalar dt) noexcept;

 private:
  // (1 - damping)^dt for the last damping and dt asked: bodies mostly share theirs.
  struct Factor {
    btScalar damping = -1, dt = 0, factor = 1;
    btScalar of(btScalar new_damping, btScalar new_dt) noexcept;
  };
  Factor linear_, angular_;
};

class ReservedWorld : public btSoftMultiBodyDynamicsWorld, private ParallelIslands::AroundIsland {
 public:
  // `soft_solver` must outlive the world.
  ReservedWorld(btDispatcher* dispatcher, btBroadphaseInterface* broadphase,
                btMultiBodyConstraintSolver* solver, btCollisionConfiguration* collision_config,
                btSoftBodySolver& soft_solver);
  void reserve_constraints(int count);
  // Numbers each multibody (its user index) for the step's bookkeeping.
  void addMultiBody(btMultiBody* body, int group, int mask) override;
  // Islands solved one at a time are solved by two threads at once when there are
  // many (parallel_islands.hpp), the world's solver being a ConstraintSolver(bodies,
  // joints) with the direct solve; `objects`: the collision objects it will hold. Not
  // with a kinematic body, which Bullet writes to from every island it touches.
  void solve_islands_in_parallel(int bodies, int joints, int objects);
  std::uint64_t islands_solved_by_helper() const noexcept {
    return parallel_ ? parallel_->helped() : 0;
  }
  std::uint64_t items_shared_with_helper() const noexcept {
    return parallel_ ? parallel_->shared() : 0;
  }
  // `work` shared with the islands' helper, or run by this thread without one.
  void share(int count, SharedWork& work) noexcept {
    if (parallel_)
      parallel_->share(count, work);
    else
      run_alone(count, work);
  }

 protected:
  // With islands solved one at a time (a minimum solver batch of 1: the direct
  // solve, constraint_solver.hpp), Bullet finds each island's constraints by
  // walking the sorted list from the island's first to its very end, which for 125
  // arms took 9 % of the step. Here each island's range is found by binary search;
  // within an island the constraints keep the order they were added in (the
  // model's joints, then actuators' holds), which is the direct solve's row order.
  // A larger batch is left to Bullet.
  void solveConstraints(btContactSolverInfo& info) override;
  // With a helper, each island's bodies are moved to their new poses (Bullet's
  // integration) by the thread that solved the island, straight after, while they
  // are in its cache (0.94x the step of 1000 bodies); integrateTransforms() does the
  // rest, and all of it with speculative contact restitution on. A multibody is
  // readied for its island's solve and advanced after it so, with or without a helper
  // (ready(), advance()).
  void integrateTransforms(btScalar dt) override;
  // Bullet damps each body's velocities and predicts its next pose, which only
  // continuous collision detection reads (the body's bounds swept to reach it, and
  // its predictive contacts). With continuous collision off, only the damping is done,
  // and no predictive contact is looked for (a thousand bodies: about 40 us a step).
  // The damping is Bullet's, by BodyDamping (its powers were 2 % of a thousand bodies'
  // step).
  void predictUnconstraintMotion(btScalar dt) override;
  void createPredictiveContacts(btScalar dt) override;
  // Each collision object's bounds, as Bullet's updateSingleAabb makes them, made by
  // both threads at once with a helper, then handed to the broadphase in the objects'
  // order by this one (the broadphase's tree is one structure): the same bits. Bullet
  // does it all on one thread: for a thousand colliders, 8 % of the step in a profile.
  void updateAabbs() override;

 private:
  struct Keyed {
    int island, index;  // the island the constraint is in; its place in m_constraints
  };
  std::vector<Keyed> keyed_, multibody_keyed_;
  std::vector<btTypedConstraint*> sorted_;
  std::vector<btMultiBodyConstraint*> multibody_sorted_;
  btSoftBodySolver& soft_solver_;  // the base class's, which it keeps to itself
  // With a helper: the step's islands, gathered before they are solved, and their
  // bodies (Bullet's list of an island's bodies lasts only for its callback).
  std::unique_ptr<ParallelIslands> parallel_;
  std::vector<ParallelIslands::Island> islands_;
  std::vector<btCollisionObject*> island_bodies_;
  // Per collision object (its world array index): the step it was integrated in with
  // its island; the bodies left over for integrateTransforms().
  std::vector<std::uint64_t> integrated_;
  std::uint64_t stamp_ = 0;
  std::vector<btRigidBody*> unintegrated_;
  // Per collision object: its bounds for updateAabbs(), and whether they are updated.
  struct Bounds {
    btVector3 min, max;
    bool update = false;
  };
  std::vector<Bounds> bounds_;

  void island_to_solve(btCollisionObject** bodies, int count, int thread) noexcept override;
  void island_solved(btCollisionObject** bodies, int count, int thread) noexcept override;
  void ready(btMultiBody& body, int thread) noexcept;
  void advance(btMultiBody& body, int thread) noexcept;
  BodyDamping damping_;
  // Per thread (0 the stepping thread, 1 the islands' helper): scratch for a
  // multibody's kinematics and dynamics, of which Bullet's world keeps one.
  struct MultibodyScratch {
    btAlignedObjectArray<btQuaternion> world_to_local;
    btAlignedObjectArray<btVector3> local_origin;
    btAlignedObjectArray<btScalar> r;
    btAlignedObjectArray<btVector3> v;
    btAlignedObjectArray<btMatrix3x3> m;
  };
  MultibodyScratch scratch_[2];
  // Per multibody: the step it was readied for, and advanced in.
  std::vector<std::uint64_t> readied_, advanced_;
};

}  // namespace afhub::physics
