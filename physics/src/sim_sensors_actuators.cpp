// Sensors and actuators: proximity rays cast after each step (the closest hit
// within range, ignoring the body the sensor sits on), and constraint actuators
// that pin whatever body touches them when engaged and let go when released.
// Neither allocates: the loop may engage and release at any step.
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// Whether `shape` at `transform` comes within the sphere `probe` around `point`.
// GJK (with EPA for overlaps) on the stack: no allocation, unlike contactTest.
bool touches(const btSphereShape& probe, const btVector3& point, const btCollisionShape& shape,
             const btTransform& transform) noexcept {
  if (shape.isCompound()) {
    const auto& compound = static_cast<const btCompoundShape&>(shape);
    for (int c = 0; c < compound.getNumChildShapes(); ++c)
      if (touches(probe, point, *compound.getChildShape(c),
                  transform * compound.getChildTransform(c)))
        return true;
    return false;
  }
  if (!shape.isConvex()) return false;  // dynamic bodies have convex shapes only
  btVoronoiSimplexSolver simplex;
  btGjkEpaPenetrationDepthSolver depth;
  btGjkPairDetector gjk(&probe, static_cast<const btConvexShape*>(&shape), &simplex, &depth);
  btGjkPairDetector::ClosestPointInput input;
  input.m_transformA = btTransform(btQuaternion::getIdentity(), point);
  input.m_transformB = transform;
  btPointCollector closest;
  gjk.getClosestPoints(input, closest, nullptr);
  return closest.m_hasResult && closest.m_distance <= 0;
}

// Closest hit, ignoring the body the sensor sits on.
struct SensorRayCallback : btCollisionWorld::ClosestRayResultCallback {
  SensorRayCallback(const btVector3& from, const btVector3& to, const btCollisionObject* ignore)
      : ClosestRayResultCallback(from, to), ignore_(ignore) {}
  bool needsCollision(btBroadphaseProxy* proxy) const override {
    return proxy->m_clientObject != ignore_ && ClosestRayResultCallback::needsCollision(proxy);
  }
  const btCollisionObject* ignore_;
};

}  // namespace

void Simulation::Data::read_sensors() noexcept {
  for (Ray& ray : rays) {
    const btRigidBody& parent = *bodies[ray.parent].body;
    const btTransform mesh = parent.getWorldTransform() * bodies[ray.parent].com_from_mesh;
    const btVector3 from = mesh * ray.from_in_mesh;
    const btVector3 to = mesh * ray.to_in_mesh;
    SensorRayCallback callback(from, to, &parent);
    world.rayTest(from, to, callback);
    ray.distance_m = callback.hasHit() ? callback.m_closestHitFraction * ray.range_m : -1.0;
  }
}

// The first dynamic rigid body, other than `parent`, touching the probe at `point`;
// -1 when none does. Bodies are few and engaging is rare: a scan of their bounds.
int Simulation::Data::touching_body(int parent, const btVector3& point) const noexcept {
  const btVector3 reach(probe.getRadius(), probe.getRadius(), probe.getRadius());
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const btRigidBody& body = *bodies[b].body;
    // A link of a chain in reduced coordinates is no rigid body to hold.
    if (static_cast<int>(b) == parent || !(body.getInvMass() > 0) || bodies[b].chain >= 0) continue;
    btVector3 low, high;
    body.getAabb(low, high);
    if (!TestAabbAgainstAabb2(low, high, point - reach, point + reach)) continue;
    if (touches(probe, point, *body.getCollisionShape(), body.getWorldTransform()))
      return static_cast<int>(b);
  }
  return -1;
}

// The constraint is made in storage reserved at build, in a world and on bodies
// with room reserved for it: engaging and releasing allocate nothing.
void Simulation::Data::actuate(ActuatorData& actuator, bool engage) noexcept {
  if (engage == (actuator.hold != nullptr)) return;
  if (!engage) {
    world.removeConstraint(actuator.hold);
    actuator.storage->reset();
    actuator.hold = nullptr;
    actuator.held = -1;
    return;
  }
  BodyData& parent = bodies[actuator.parent];
  const btTransform mesh = parent.body->getWorldTransform() * parent.com_from_mesh;
  const btVector3 point = mesh * actuator.point_in_mesh;
  const int held = touching_body(actuator.parent, point);
  if (held < 0) return;  // nothing to hold: stays released
  btRigidBody& other = *bodies[held].body;
  const ActuatorSpec& spec = model.actuators[&actuator - actuators.data()];
  btPoint2PointConstraint& hold = actuator.storage->emplace(
      *parent.body, other, parent.body->getWorldTransform().invXform(point),
      other.getWorldTransform().invXform(point));
  hold.m_setting.m_impulseClamp = spec.max_impulse;
  hold.m_setting.m_tau = spec.tau;
  world.addConstraint(&hold, true);
  actuator.hold = &hold;
  actuator.held = held;
}

bool Simulation::actuator_engaged(std::size_t actuator) const noexcept {
  return data_->actuators[actuator].hold != nullptr;
}

}  // namespace afhub::physics
