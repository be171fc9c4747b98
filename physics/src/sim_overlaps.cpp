// Bodies that overlap as built. Of different files: two robots loaded at one place (AMBF
// draws every model at the origin) are pushed apart at the first step with forces that
// can blow one up, and nothing said why. Of one robot: its links, drawn touching. Looked
// for once, after the build, pair by pair only where their bounding boxes meet.
#include <algorithm>
#include <cstdio>
#include <map>

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

// Pairs of moving bodies (or a moving and a static one) whose shapes overlap by more
// than `depth_m` as built, among those `wanted` takes and the step would let collide,
// looked for where their bounding boxes meet along x, within the bounds above: false
// when these stopped the search.
bool Simulation::Data::find_overlaps(const std::function<bool(int, int)>& wanted, double depth_m,
                                     std::vector<Overlap>& found, std::size_t& looked_at) {
  struct Object {
    btCollisionObject* object;
    btVector3 low, high;
  };
  std::vector<Object> objects;
  const btCollisionObjectArray& all = world.getCollisionObjectArray();
  for (int i = 0; i < all.size(); ++i) {
    btCollisionObject* object = all[i];
    if (object->getUserIndex() < 0 || !object->getBroadphaseHandle() ||
        !object->hasContactResponse())
      continue;  // a soft body, or a body nothing collides with
    Object entry{object, {}, {}};
    object->getCollisionShape()->getAabb(object->getWorldTransform(), entry.low, entry.high);
    objects.push_back(entry);
  }
  std::sort(objects.begin(), objects.end(),
            [](const Object& x, const Object& y) { return x.low.x() < y.low.x(); });
  std::size_t tested = 0;
  looked_at = 0;
  for (std::size_t i = 0; i < objects.size(); ++i)
    for (std::size_t j = i + 1; j < objects.size() && objects[j].low.x() <= objects[i].high.x();
         ++j) {
      if (++looked_at > kMaxPairsLookedAt || tested == kMaxPairsTested) return false;
      btCollisionObject* a = objects[i].object;
      btCollisionObject* b = objects[j].object;
      const int ia = a->getUserIndex(), ib = b->getUserIndex();
      if (!wanted(ia, ib)) continue;
      if (a->isStaticOrKinematicObject() && b->isStaticOrKinematicObject()) continue;
      if (!TestAabbAgainstAabb2(objects[i].low, objects[i].high, objects[j].low, objects[j].high))
        continue;
      // As the step would: bodies a joint or their groups keep apart are no overlap.
      if (!a->checkCollideWith(b) || !b->checkCollideWith(a) ||
          !filter.needBroadphaseCollision(a->getBroadphaseHandle(), b->getBroadphaseHandle()))
        continue;
      ++tested;
      DeepestContact contact;
      contact.m_collisionFilterGroup = contact.m_collisionFilterMask = btBroadphaseProxy::AllFilter;
      world.contactPairTest(a, b, contact);
      // Beyond the shapes' margins, which Bullet counts in: links built touching overlap
      // by them.
      const double margins =
          a->getCollisionShape()->getMargin() + b->getCollisionShape()->getMargin();
      if (contact.depth_m > depth_m + margins) found.push_back({a, b, contact.depth_m});
    }
  return true;
}

// A robot's links are drawn touching and overlapping each other: the Allegro hand's
// thumb, as its URDF builds it, sits inside its palm, and contacts held its joints up to
// 0.25 rad past their limits, and pulled it apart under higher damping. As MoveIt does for a
// robot's default pose, bodies of such a file that overlap as built do not collide with each other.
void Simulation::Data::part_overlaps() {
  if (std::none_of(model.file_parts_overlaps.begin(), model.file_parts_overlaps.end(),
                   [](bool parts) { return parts; }))
    return;
  std::vector<Overlap> found;
  std::size_t looked_at = 0;
  const bool whole = find_overlaps(
      [&](int a, int b) {
        const int file = model.bodies[a].file_index;
        return file == model.bodies[b].file_index && model.file_parts_overlaps[file];
      },
      0.0, found, looked_at);
  std::map<int, std::vector<const Overlap*>> by_file;
  for (const Overlap& overlap : found) {
    filter.part(overlap.a->getUserIndex(), overlap.b->getUserIndex());
    by_file[model.bodies[overlap.a->getUserIndex()].file_index].push_back(&overlap);
  }
  // The broadphase met them as they were added: those pairs go.
  struct Refused : btOverlapCallback {
    const CollisionFilter& filter;
    explicit Refused(const CollisionFilter& f) : filter(f) {}
    bool processOverlap(btBroadphasePair& pair) override {
      return !filter.needBroadphaseCollision(pair.m_pProxy0, pair.m_pProxy1);
    }
  } refused(filter);
  if (!found.empty()) world.getPairCache()->processAllOverlappingPairs(&refused, &dispatcher);
  const auto name = [&](const btCollisionObject* object) {
    return model.bodies[object->getUserIndex()].name;
  };
  for (const auto& [file, overlaps] : by_file) {
    std::string some;
    for (std::size_t k = 0; k < overlaps.size() && k < kPairsShown; ++k)
      some += std::string(k ? ", " : "") + name(overlaps[k]->a) + " and " + name(overlaps[k]->b);
    if (overlaps.size() > kPairsShown) some += ", ...";
    parted_overlaps.push_back(
        model.bodies[overlaps.front()->a->getUserIndex()].where.file +
        ": links that overlap as built do not collide with each other: " + some + " (" +
        std::to_string(overlaps.size()) + (overlaps.size() == 1 ? " pair)" : " pairs)"));
  }
  if (!whole)
    parted_overlaps.push_back("the search for links that overlap as built stopped after " +
                              std::to_string(looked_at - 1) + " pairs; more may collide");
}

std::vector<std::string> Simulation::overlaps_between_files() const {
  const Model& model = data_->model;
  if (std::all_of(model.bodies.begin(), model.bodies.end(), [&](const BodySpec& body) {
        return body.file_index == model.bodies.front().file_index;
      }))
    return {};
  std::vector<Data::Overlap> found;
  std::size_t looked_at = 0;
  const bool whole = data_->find_overlaps(
      [&](int a, int b) { return model.bodies[a].file_index != model.bodies[b].file_index; },
      kOverlapM, found, looked_at);
  std::sort(found.begin(), found.end(),
            [](const Data::Overlap& x, const Data::Overlap& y) { return x.depth_m > y.depth_m; });
  std::vector<std::string> warnings;
  for (std::size_t k = 0; k < found.size() && k < kPairsShown; ++k) {
    const BodySpec& a = model.bodies[found[k].a->getUserIndex()];
    const BodySpec& b = model.bodies[found[k].b->getUserIndex()];
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
  if (!whole)
    warnings.push_back("warning: the check for overlapping files stopped after " +
                       std::to_string(looked_at - 1) +
                       " pairs of bodies; more of them may overlap");
  return warnings;
}

}  // namespace afhub::physics
