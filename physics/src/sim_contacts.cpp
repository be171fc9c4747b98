// Contacts: after a step, each rigid body's net contact wrench, from Bullet's
// contact manifolds. A point's normal and friction impulses over the step's dt are
// the force it carried in the step; the manifold's body0 gets it, body1 the
// opposite. The moment is summed about the world's origin (read_body moves it to
// the body's mesh frame). Soft-body contacts are not in the rigid manifolds and are
// not counted. No allocation: the manifolds are read in place into each body's sums.
#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// The index of the rigid body `object` is (its user index), or -1.
int rigid_body_index(const btCollisionObject* object, std::size_t body_count) {
  if (object->getInternalType() != btCollisionObject::CO_RIGID_BODY) return -1;
  const int index = object->getUserIndex();
  return index >= 0 && static_cast<std::size_t>(index) < body_count ? index : -1;
}

void add_contact(BodyData& body, const btVector3& force, const btVector3& at) {
  body.contact_force += force;
  body.contact_moment_at_origin += at.cross(force);
}

}  // namespace

void Simulation::Data::sum_contacts() noexcept {
  for (BodyData& body : bodies) {
    body.contact_force.setZero();
    body.contact_moment_at_origin.setZero();
    body.contact_count = 0;
  }
  const btScalar per_second = btScalar(1) / dt_s;
  const int manifolds = dispatcher.getNumManifolds();
  for (int m = 0; m < manifolds; ++m) {
    const btPersistentManifold& manifold = *dispatcher.getManifoldByIndexInternal(m);
    const int a = rigid_body_index(manifold.getBody0(), bodies.size());
    const int b = rigid_body_index(manifold.getBody1(), bodies.size());
    if (a < 0 && b < 0) continue;
    for (int p = 0; p < manifold.getNumContacts(); ++p) {
      const btManifoldPoint& point = manifold.getContactPoint(p);
      // Friction is bounded by the normal impulse: a point that did not push carried nothing.
      if (!(point.getAppliedImpulse() > 0)) continue;
      // Bullet's normal points from body1 to body0; friction rows push body0 along their
      // direction (Lateral2 stays 0 unless two friction directions are solved).
      const btVector3 on_a = (point.m_normalWorldOnB * point.getAppliedImpulse() +
                              point.m_lateralFrictionDir1 * point.m_appliedImpulseLateral1 +
                              point.m_lateralFrictionDir2 * point.m_appliedImpulseLateral2) *
                             per_second;
      if (a >= 0) {
        add_contact(bodies[a], on_a, point.getPositionWorldOnA());
        ++bodies[a].contact_count;
      }
      if (b >= 0) {
        add_contact(bodies[b], -on_a, point.getPositionWorldOnB());
        ++bodies[b].contact_count;
      }
    }
  }
}

}  // namespace afhub::physics
