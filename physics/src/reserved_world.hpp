// The Bullet world the simulation steps: room for every constraint it may hold at
// once, and islands handed to the solver one at a time without Bullet's search for
// each island's constraints.
#pragma once

#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <vector>

namespace afhub::physics {

class ReservedWorld : public btSoftRigidDynamicsWorld {
 public:
  using btSoftRigidDynamicsWorld::btSoftRigidDynamicsWorld;
  void reserve_constraints(int count);

 protected:
  // With islands solved one at a time (a minimum solver batch of 1: the direct
  // solve, constraint_solver.hpp), Bullet finds each island's constraints by
  // walking the sorted list from the island's first to its very end, which for 125
  // arms took 9 % of the step. Here each island's range is found by binary search;
  // within an island the constraints keep the order they were added in (the
  // model's joints, then actuators' holds), which is the direct solve's row order.
  // A larger batch is left to Bullet.
  void solveConstraints(btContactSolverInfo& info) override;

 private:
  struct Keyed {
    int island, index;  // the island the constraint is in; its place in m_constraints
  };
  std::vector<Keyed> keyed_;
  std::vector<btTypedConstraint*> sorted_;
};

}  // namespace afhub::physics
