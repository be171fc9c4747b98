// State: the readings after a step. A body's mesh-frame pose, twist, applied and
// contact wrenches, inertia, its descendant joints and its sensor rays; a soft body's
// centre and mean velocity; the lights' and cameras' poses; joint positions and pivot
// gaps; whether everything is still finite.
#include "simulation_data.hpp"

namespace afhub::physics {

void Simulation::read_body(std::size_t index, BodyReading& reading) const noexcept {
  const Data& d = *data_;
  const BodyData& body = d.bodies[index];
  const btRigidBody& rb = *body.body;
  const btTransform mesh_frame = rb.getWorldTransform() * body.com_from_mesh;
  reading.pose = to_pose(mesh_frame);
  reading.twist = {from_bt(rb.getLinearVelocity()), from_bt(rb.getAngularVelocity())};
  reading.wrench = body.applied;
  // The contact moment about the world origin, moved to the mesh frame's origin.
  const btVector3 origin = mesh_frame.getOrigin();
  reading.contact_wrench = {from_bt(body.contact_force), from_bt(body.contact_moment_at_origin -
                                                                 origin.cross(body.contact_force))};
  reading.contact_count = body.contact_count;
  reading.mass_kg = d.model.bodies[index].mass_kg;
  reading.principal_inertia_kgm2 =
      rb.getInvMass() > 0 ? Vec3{1.0 / std::max(rb.getInvInertiaDiagLocal().x(), 1e-300),
                                 1.0 / std::max(rb.getInvInertiaDiagLocal().y(), 1e-300),
                                 1.0 / std::max(rb.getInvInertiaDiagLocal().z(), 1e-300)}
                          : Vec3{};
  const std::vector<int>& below = d.model.descendant_joints[index];
  const std::size_t count = std::min(below.size(), kBodyJointCapacity);
  reading.joint_count = static_cast<std::uint32_t>(count);
  for (std::size_t j = 0; j < count; ++j) {
    const JointModel& joint = *d.joints[below[j]];
    reading.joint_positions[j] = joint.position();
    reading.joint_velocities[j] = joint.velocity();
    reading.joint_efforts[j] = joint.effort();
  }
  const std::size_t rays = std::min(body.ray_count, kBodyRayCapacity);
  reading.ray_count = static_cast<std::uint32_t>(rays);
  for (std::size_t r = 0; r < rays; ++r) {
    reading.ray_distances_m[r] = d.rays[body.first_ray + r].distance_m;
    reading.ray_ranges_m[r] = d.rays[body.first_ray + r].range_m;
  }
}

std::size_t Simulation::soft_body_node_count(std::size_t soft) const noexcept {
  return static_cast<std::size_t>(data_->soft_bodies[soft].body->m_nodes.size());
}

std::vector<std::array<std::uint32_t, 3>> Simulation::soft_body_faces(std::size_t soft) const {
  const btSoftBody& body = *data_->soft_bodies[soft].body;
  std::vector<std::array<std::uint32_t, 3>> faces;
  if (body.m_faces.size() == 0) return faces;
  const btSoftBody::Node* first = &body.m_nodes[0];
  faces.reserve(static_cast<std::size_t>(body.m_faces.size()));
  for (int f = 0; f < body.m_faces.size(); ++f) {
    const btSoftBody::Face& face = body.m_faces[f];
    faces.push_back({static_cast<std::uint32_t>(face.m_n[0] - first),
                     static_cast<std::uint32_t>(face.m_n[1] - first),
                     static_cast<std::uint32_t>(face.m_n[2] - first)});
  }
  return faces;
}

void Simulation::read_soft_body_nodes(std::size_t soft, std::array<float, 3>* xyz) const noexcept {
  const btSoftBody& body = *data_->soft_bodies[soft].body;
  for (int n = 0; n < body.m_nodes.size(); ++n) {
    const btVector3& p = body.m_nodes[n].m_x;
    xyz[n] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
  }
}

void Simulation::read_soft_body(std::size_t index, BodyReading& reading) const noexcept {
  reading = BodyReading{};
  const btSoftBody& soft = *data_->soft_bodies[index].body;
  btVector3 centre(0, 0, 0), velocity(0, 0, 0);
  for (int n = 0; n < soft.m_nodes.size(); ++n) {
    centre += soft.m_nodes[n].m_x;
    velocity += soft.m_nodes[n].m_v;
  }
  const btScalar count = std::max(1, soft.m_nodes.size());
  reading.pose = {from_bt(centre / count), {}};
  reading.twist = {from_bt(velocity / count), {}};
  reading.mass_kg = data_->model.soft_bodies[index].mass_kg;
}

Pose Simulation::body_pose(std::size_t index) const noexcept {
  const BodyData& body = data_->bodies[index];
  return to_pose(body.body->getWorldTransform() * body.com_from_mesh);
}

Pose Simulation::light_pose(std::size_t light) const noexcept {
  return data_->world_object_pose(data_->lights[light]);
}
Pose Simulation::camera_pose(std::size_t camera) const noexcept {
  return data_->world_object_pose(data_->cameras[camera]);
}

Pose Simulation::Data::world_object_pose(const WorldObjectData& object) const noexcept {
  if (object.parent < 0) return to_pose(object.local);
  const BodyData& parent = bodies[object.parent];
  return to_pose(parent.body->getWorldTransform() * parent.com_from_mesh * object.local);
}

double Simulation::joint_position(std::size_t joint) const noexcept {
  return data_->joints[joint]->position();
}
double Simulation::joint_velocity(std::size_t joint) const noexcept {
  return data_->joints[joint]->velocity();
}
double Simulation::joint_pivot_gap_m(std::size_t joint) const noexcept {
  return data_->joints[joint]->pivot_gap_m();
}
bool Simulation::joint_position_target(std::size_t joint, double& target) const noexcept {
  return data_->joints[joint]->position_target(target);
}

bool Simulation::all_finite() const noexcept {
  for (const BodyData& body : data_->bodies) {
    const btRigidBody& rb = *body.body;
    if (!finite(rb.getWorldTransform().getOrigin()) || !finite(rb.getLinearVelocity()) ||
        !finite(rb.getAngularVelocity()) || !std::isfinite(rb.getOrientation().w()))
      return false;
  }
  for (const SoftBodyData& soft : data_->soft_bodies)
    for (int n = 0; n < soft.body->m_nodes.size(); ++n)
      if (!finite(soft.body->m_nodes[n].m_x)) return false;
  return true;
}

}  // namespace afhub::physics
