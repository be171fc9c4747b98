// The simulation (see simulation.hpp): built once (sim_build.cpp), then each step
// applies the inputs (sim_control.cpp), steps Bullet at the fixed dt, and updates
// the contacts', joints' and sensors' readings (sim_contacts.cpp, sim_state.cpp,
// sim_sensors_actuators.cpp).
#include "afhub/physics/simulation.hpp"

#include "bullet_allocator.hpp"
#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// Bullet's broadphase grows its pair table the first time more bodies' boxes
// overlap than ever before: a heap allocation in the middle of a run (a swinging
// linkage meeting a new neighbour). Growing it once here, by adding and removing
// pairs of placeholder proxies, keeps the step allocation-free for any scene with
// fewer overlapping pairs. Before the collision filter is set: it reads real bodies.
void reserve_overlapping_pairs(btOverlappingPairCache& cache, btDispatcher& dispatcher, int pairs) {
  std::vector<btBroadphaseProxy> proxies(static_cast<std::size_t>(pairs) + 1);
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    proxies[i].m_uniqueId = -1 - static_cast<int>(i);  // no real proxy's id
    proxies[i].m_collisionFilterGroup = proxies[i].m_collisionFilterMask = -1;
  }
  for (std::size_t i = 1; i < proxies.size(); ++i)
    cache.addOverlappingPair(&proxies[0], &proxies[i]);
  for (std::size_t i = 1; i < proxies.size(); ++i)
    cache.removeOverlappingPair(&proxies[0], &proxies[i], &dispatcher);
}

// The joints' readings after a step are shared with the islands' helper in blocks of
// this many joints (Simulation::share): each joint reads its two bodies and writes
// only its own readings.
constexpr int kJointsPerItem = 32;

}  // namespace

Simulation::Simulation(const Model& model, double dt_s)
    : data_(std::make_unique<Data>(model, dt_s)) {
  reuse_bullet_scratch();
  Data& d = *data_;
  const int bodies = static_cast<int>(model.bodies.size() + model.soft_bodies.size());
  reserve_overlapping_pairs(*d.broadphase.getOverlappingPairCache(), d.dispatcher,
                            std::max(4096, 8 * bodies));
  d.broadphase.getOverlappingPairCache()->setOverlapFilterCallback(&d.filter);
  d.world.setGravity(to_bt(model.world.gravity_mps2));
  d.world.getWorldInfo().m_gravity = to_bt(model.world.gravity_mps2);
  d.world.getWorldInfo().m_sparsesdf.Initialize();
  d.world.getSolverInfo().m_numIterations = model.world.max_iterations;
  // No body is swept for continuous collision (none has a CCD motion threshold), so
  // its bounds need not reach its predicted pose: the narrow phase meets contacts at
  // the bodies' poses, within the 2 cm Bullet adds to every bound. Without it the
  // poses Bullet predicts for it alone are not computed (ReservedWorld).
  d.world.getDispatchInfo().m_useContinuous = false;
  // Bullet's broadphase looks for each added body's overlaps at once, walking every
  // body it overlaps: bodies piled at one point made loading cubic (8000 took over
  // 100 s, 10 000 held 2.8 GB of pairs). Deferred, the first step finds them all in
  // one pass over the tree, then step() turns the search per moved body back on.
  d.broadphase.m_deferedcollide = true;
  d.build_bodies();
  d.build_joints();
  d.build_soft_bodies();
  d.build_sensors();
  d.build_actuators();
  d.build_world_objects();
  d.build_bounds();
  d.joint_driver.assign(model.joints.size(), -1);
  d.read_sensors();
  d.keep_good_state();
}

Simulation::~Simulation() = default;

const Model& Simulation::model() const noexcept {
  return data_->model;
}
double Simulation::dt_s() const noexcept {
  return data_->dt_s;
}
std::uint64_t Simulation::step_count() const noexcept {
  return data_->steps;
}
std::uint64_t Simulation::islands_solved_by_helper() const noexcept {
  return data_->world.islands_solved_by_helper();
}
std::uint64_t Simulation::items_shared_with_helper() const noexcept {
  return data_->world.items_shared_with_helper();
}
void Simulation::share(int count, SharedWork& work) noexcept {
  data_->world.share(count, work);
}
double Simulation::time_s() const noexcept {
  return static_cast<double>(data_->steps) * data_->dt_s;
}

const Pid& Simulation::joint_gains(std::size_t joint) const noexcept {
  return data_->joints[joint]->gains();
}
double Simulation::joint_damping(std::size_t joint) const noexcept {
  return data_->joints[joint]->damping();
}
const std::vector<std::string>& Simulation::parted_overlaps() const noexcept {
  return data_->parted_overlaps;
}
std::vector<std::string> Simulation::gain_notes() const {
  std::vector<std::string> notes;
  for (const auto& joint : data_->joints)
    if (!joint->gain_note().empty()) notes.push_back(joint->gain_note());
  return notes;
}

void Simulation::step() noexcept {
  Data& d = *data_;
  for (BodyData& body : d.bodies) d.apply_cartesian(body);
  // A URDF <mimic> joint follows its leader's latest position, over any command.
  for (auto& joint : d.joints)
    if (const std::optional<Mimic>& mimic = joint->spec().mimic)
      joint->command(JointMode::kPosition,
                     mimic->multiplier * d.joints[mimic->joint]->position() + mimic->offset);
  for (auto& joint : d.joints) joint->apply_control();
  d.world.stepSimulation(d.dt_s, 1, d.dt_s);
  d.broadphase.m_deferedcollide = false;  // the first step met the initial overlaps
  ++d.steps;
  d.mirror_chains();
  d.recover_non_finite();
  d.sum_contacts();
  share_each(d.world, static_cast<int>(d.joints.size()), kJointsPerItem,
             [&d](int j, int) { d.joints[j]->update_readings(); });
  d.read_sensors();
}

void Simulation::reset() noexcept {
  Data& d = *data_;
  for (BodyData& body : d.bodies) {
    btRigidBody& rb = *body.body;
    rb.setWorldTransform(body.initial_com);
    rb.setInterpolationWorldTransform(body.initial_com);
    rb.setLinearVelocity(btVector3(0, 0, 0));
    rb.setAngularVelocity(btVector3(0, 0, 0));
    rb.clearForces();
    body.contact_force.setZero();
    body.contact_moment_at_origin.setZero();
    body.contact_count = 0;
  }
  for (ChainData& chain : d.chains) {
    chain.body->setBaseWorldTransform(d.bodies[chain.base].body->getWorldTransform());
    d.place_chain(chain, chain.initial_q);
  }
  for (std::size_t b = 0; b < d.bodies.size(); ++b) clear_input(b);
  for (auto& joint : d.joints) joint->release();
  std::fill(d.joint_driver.begin(), d.joint_driver.end(), -1);
  for (ActuatorData& actuator : d.actuators) d.actuate(actuator, false);
  for (SoftBodyData& soft : d.soft_bodies)
    for (int n = 0; n < soft.body->m_nodes.size(); ++n) {
      soft.body->m_nodes[n].m_x = soft.initial_positions[n];
      soft.body->m_nodes[n].m_v = btVector3(0, 0, 0);
    }
  for (auto& joint : d.joints) joint->restart_readings();
  d.keep_good_state();
  d.steps = 0;
}

}  // namespace afhub::physics
