// Sensors and actuators: proximity rays cast after each step (the closest hit
// within range, ignoring the body the sensor sits on), and constraint actuators
// that pin whatever body touches them when engaged and let go when released.
#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// The first dynamic rigid body, other than `parent`, touching the probe sphere.
struct TouchingBody : btCollisionWorld::ContactResultCallback {
  explicit TouchingBody(const btCollisionObject* parent) : parent_(parent) {}
  btScalar addSingleResult(btManifoldPoint&, const btCollisionObjectWrapper* a, int, int,
                           const btCollisionObjectWrapper* b, int, int) override {
    for (const btCollisionObjectWrapper* side : {a, b}) {
      const btCollisionObject* object = side->getCollisionObject();
      const btRigidBody* body = btRigidBody::upcast(object);
      if (!found && body && object != parent_ && object->getUserIndex() >= 0 &&
          body->getInvMass() > 0)
        found = const_cast<btRigidBody*>(body);
    }
    return 0;
  }
  const btCollisionObject* parent_;
  btRigidBody* found = nullptr;
};

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

void Simulation::Data::actuate(ActuatorData& actuator, bool engage) noexcept {
  if (engage == static_cast<bool>(actuator.hold)) return;
  if (!engage) {
    world.removeConstraint(actuator.hold.get());
    actuator.hold.reset();
    return;
  }
  BodyData& parent = bodies[actuator.parent];
  const btTransform mesh = parent.body->getWorldTransform() * parent.com_from_mesh;
  const btVector3 point = mesh * actuator.point_in_mesh;
  probe.setWorldTransform(btTransform(btQuaternion::getIdentity(), point));
  TouchingBody touching(parent.body.get());
  world.contactTest(&probe, touching);
  if (!touching.found) return;  // nothing to hold: stays released
  const ActuatorSpec& spec = model.actuators[&actuator - actuators.data()];
  actuator.hold = std::make_unique<btPoint2PointConstraint>(
      *parent.body, *touching.found, parent.body->getWorldTransform().invXform(point),
      touching.found->getWorldTransform().invXform(point));
  actuator.hold->m_setting.m_impulseClamp = spec.max_impulse;
  actuator.hold->m_setting.m_tau = spec.tau;
  world.addConstraint(actuator.hold.get(), true);
}

bool Simulation::actuator_engaged(std::size_t actuator) const noexcept {
  return static_cast<bool>(data_->actuators[actuator].hold);
}

}  // namespace afhub::physics
