// Bodies of different files that overlap as built: two robots loaded at one place (AMBF
// draws every model at the origin) are pushed apart at the first step with forces that
// can blow one up, and nothing said why. Checked once, after the build, pair by pair
// only where their bounding boxes meet.
#include <algorithm>
#include <cstdio>

#include "simulation_data.hpp"

namespace afhub::physics {
namespace {

// Deeper than this is no resting contact (a robot standing on another file's floor
// settles within a millimetre or two).
constexpr double kOverlapM = 0.005;
// Bounds the work for scenes of thousands of bodies, all at one point: pairs whose boxes
// are compared, and pairs whose shapes are.
constexpr std::size_t kMaxPairsLookedAt = 4'000'000;
constexpr std::size_t kMaxPairsTested = 20'000;
constexpr std::size_t kPairsShown = 3;

struct DeepestContact : btCollisionWorld::ContactResultCallback {
  double depth_m = 0.0;
  btScalar addSingleResult(btManifoldPoint& point, const btCollisionObjectWrapper*, int, int,
                           const btCollisionObjectWrapper*, int, int) override {
    depth_m = std::max(depth_m, -static_cast<double>(point.getDistance()));
    return 0;
  }
};

struct Overlap {
  int a, b;
  double depth_m;
};

// A joint from one file's body to the other's, or nullptr: moving either file would not
// part them, the joint holds them where they are.
const JointSpec* joint_between(const Model& model, int file_a, int file_b) {
  for (const JointSpec& joint : model.joints) {
    const int parent = model.bodies[joint.parent].file_index;
    const int child = model.bodies[joint.child].file_index;
    if ((parent == file_a && child == file_b) || (parent == file_b && child == file_a))
      return &joint;
  }
  return nullptr;
}

std::string advice(const Model& model, const BodySpec& a, const BodySpec& b) {
  if (const JointSpec* joint = joint_between(model, a.file_index, b.file_index))
    return "the joint '" + joint->name + "' (" + joint->where.str() +
           ") holds the two files together, so placing one elsewhere would not part them: move "
           "that joint's pivot, or keep the two bodies from colliding (`collision groups`)";
  return "place one file elsewhere with --at FILE=x,y,z (of a file loaded twice, each --at "
         "naming it places the next copy)";
}

}  // namespace

std::vector<std::string> Simulation::overlaps_between_files() const {
  Data& d = *data_;
  const Model& model = d.model;
  struct Object {
    btCollisionObject* object;
    btVector3 low, high;
  };
  std::vector<Object> objects;
  const btCollisionObjectArray& all = d.world.getCollisionObjectArray();
  for (int i = 0; i < all.size(); ++i) {
    btCollisionObject* object = all[i];
    if (object->getUserIndex() < 0 || !object->getBroadphaseHandle() ||
        !object->hasContactResponse())
      continue;  // a soft body, or a body nothing collides with
    Object entry{object, {}, {}};
    object->getCollisionShape()->getAabb(object->getWorldTransform(), entry.low, entry.high);
    objects.push_back(entry);
  }
  const bool one_file = std::all_of(objects.begin(), objects.end(), [&](const Object& o) {
    return model.bodies[o.object->getUserIndex()].file_index ==
           model.bodies[objects.front().object->getUserIndex()].file_index;
  });
  if (one_file) return {};
  // Sweep along x: a pair is looked at only when its boxes meet along x.
  std::sort(objects.begin(), objects.end(),
            [](const Object& x, const Object& y) { return x.low.x() < y.low.x(); });
  std::vector<Overlap> found;
  std::size_t looked_at = 0, tested = 0;
  bool stopped = false;
  for (std::size_t i = 0; i < objects.size() && !stopped; ++i)
    for (std::size_t j = i + 1; j < objects.size() && objects[j].low.x() <= objects[i].high.x();
         ++j) {
      if (++looked_at > kMaxPairsLookedAt || tested == kMaxPairsTested) {
        stopped = true;
        break;
      }
      btCollisionObject* a = objects[i].object;
      btCollisionObject* b = objects[j].object;
      const int ia = a->getUserIndex(), ib = b->getUserIndex();
      if (model.bodies[ia].file_index == model.bodies[ib].file_index) continue;
      if (a->isStaticOrKinematicObject() && b->isStaticOrKinematicObject()) continue;
      if (!TestAabbAgainstAabb2(objects[i].low, objects[i].high, objects[j].low, objects[j].high))
        continue;
      // As the step would: bodies a joint or their groups keep apart are no overlap.
      if (!a->checkCollideWith(b) || !b->checkCollideWith(a) ||
          !d.filter.needBroadphaseCollision(a->getBroadphaseHandle(), b->getBroadphaseHandle()))
        continue;
      ++tested;
      DeepestContact contact;
      contact.m_collisionFilterGroup = contact.m_collisionFilterMask = btBroadphaseProxy::AllFilter;
      d.world.contactPairTest(a, b, contact);
      if (contact.depth_m > kOverlapM) found.push_back({ia, ib, contact.depth_m});
    }
  std::sort(found.begin(), found.end(),
            [](const Overlap& x, const Overlap& y) { return x.depth_m > y.depth_m; });
  std::vector<std::string> warnings;
  for (std::size_t k = 0; k < found.size() && k < kPairsShown; ++k) {
    const BodySpec& a = model.bodies[found[k].a];
    const BodySpec& b = model.bodies[found[k].b];
    char depth[32];
    std::snprintf(depth, sizeof depth, "%.0f mm", found[k].depth_m * 1e3);
    warnings.push_back(a.where.str() + ": warning: body '" + a.channel + "' overlaps body '" +
                       b.channel + "' of another loaded file (" + b.where.str() + ") by " + depth +
                       " as loaded: the first step pushes them apart, hard enough to " +
                       "blow a robot up; " + advice(model, a, b));
  }
  if (found.size() > kPairsShown)
    warnings.push_back("warning: " + std::to_string(found.size() - kPairsShown) +
                       " more pairs of bodies of different loaded files overlap as loaded");
  if (stopped)
    warnings.push_back("warning: the check for overlapping files stopped after " +
                       std::to_string(looked_at - 1) +
                       " pairs of bodies; more of them may overlap");
  return warnings;
}

}  // namespace afhub::physics
