// The viewer's reading of the hub (see pose_feed.hpp).
#include "afhub/viewer/pose_feed.hpp"

#include <cstring>
#include <unordered_set>

#include "afhub/hub/json_writer.hpp"
#include "afhub/shm_layout/channel_names.hpp"

namespace afhub::viewer {
namespace {

template <class T>
void put(std::vector<std::uint8_t>& out, T value) {
  const std::size_t at = out.size();
  out.resize(at + sizeof value);
  std::memcpy(out.data() + at, &value, sizeof value);  // x86 and ARM Linux: little-endian
}

static_assert(kMaxSceneBodies <= 65535 && kMaxJointsPerBody <= 65535,
              "a joint block's index and count are 16 bits");

}  // namespace

PoseFeed::PoseFeed(const std::string& world)
    : scene_reader_({std::string(kService), world, std::string(kSceneEvent)}),
      world_reader_({std::string(kService), world, std::string(kStateEvent)}),
      scene_(std::make_shared<ViewScene>()) {
  catalog_.wait(std::chrono::milliseconds(2000));
}

void PoseFeed::refresh_readers(const BodyList& catalog) {
  std::unordered_set<std::string> listed;
  catalog_bodies_ = 0;
  JsonWriter joints;
  joints.begin_object();
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    if (catalog.bodies[i].kind != ChannelKind::kBody) continue;
    ++catalog_bodies_;
    listed.insert(catalog.bodies[i].channel.data());
    joints.key(catalog.bodies[i].channel.data()).begin_array();
    for (const std::string& name : joint_names_of(catalog, catalog.bodies[i])) joints.value(name);
    joints.end_array();
  }
  joints.end_object();
  joints_changed_ = joints.str() != joints_json_;
  joints_json_ = joints.str();
  states_.resize(scene_->channels.size());
  for (std::size_t b = 0; b < states_.size(); ++b) {
    const bool live = listed.count(scene_->channels[b]) != 0;
    if (live && !states_[b])
      states_[b] =
          std::make_unique<LatestReader<BodyState>>(body_state_channel(scene_->channels[b]));
    else if (!live)
      states_[b].reset();
  }
}

std::shared_ptr<const ViewScene> PoseFeed::update(std::vector<std::uint8_t>& frame) {
  std::shared_ptr<const ViewScene> changed;
  joints_changed_ = false;
  const SceneDescription* scene = scene_reader_.latest();
  bool rebuild = scene && scene_reader_.updated();
  if (rebuild) {
    soft_.clear();
    for (std::uint32_t s = 0; s < scene->soft_body_count; ++s) {
      const std::string channel = scene->soft_bodies[s].channel.data();
      soft_.push_back({std::make_unique<LatestReader<SoftBodyMesh>>(
                           ChannelId{std::string(kService), channel, std::string(kSoftFacesEvent)}),
                       std::make_unique<LatestReader<SoftBodyMesh>>(ChannelId{
                           std::string(kService), channel, std::string(kSoftNodesEvent)})});
    }
  }
  // A soft body's faces come on their own channel, after the scene: a new scene then.
  std::vector<const SoftBodyMesh*> faces;
  for (SoftReaders& soft : soft_) {
    faces.push_back(soft.faces->latest());
    rebuild = rebuild || (faces.back() && soft.faces->updated());
  }
  if (rebuild) {
    // A restarted physics starts its sequence again: the viewer counts instead.
    scene_ =
        std::make_shared<const ViewScene>(view_scene_of(*scene, scene_->generation + 1, faces));
    states_.clear();
    catalog_sequence_ = 0;  // readers for the new scene's bodies
    changed = scene_;
  }
  const BodyList& catalog = catalog_.latest();
  if (catalog.header.sequence != catalog_sequence_) {
    catalog_sequence_ = catalog.header.sequence;
    refresh_readers(catalog);
  }
  if (const WorldState* world = world_reader_.latest()) {
    sim_time_s_ = world->header.sim_time_s;
    paused_ = world->paused != 0;
  }
  frame.clear();
  put(frame, kFrameMagic);
  put(frame, scene_->generation);
  put(frame, std::uint32_t{0});  // the entry count, set below
  put(frame, std::uint32_t{paused_ ? 1U : 0U});
  put(frame, sim_time_s_);
  put(frame, catalog_bodies_);
  put(frame, std::uint32_t{0});  // the joint block count, set below
  std::uint32_t entries = 0, blocks = 0;
  joint_blocks_.clear();
  for (std::size_t b = 0; b < states_.size(); ++b) {
    if (!states_[b]) continue;
    const BodyState* state = states_[b]->latest();
    if (!state) continue;
    const Pose& pose = state->pose;
    put(frame, static_cast<std::uint32_t>(b));
    for (double v : {pose.position_m.x, pose.position_m.y, pose.position_m.z, pose.orientation.x,
                     pose.orientation.y, pose.orientation.z, pose.orientation.w})
      put(frame, static_cast<float>(v));
    ++entries;
    if (state->joint_count == 0) continue;
    // Scene bodies (kMaxSceneBodies) and joints (kMaxJointsPerBody) fit 16 bits.
    put(joint_blocks_, static_cast<std::uint16_t>(b));
    put(joint_blocks_, static_cast<std::uint16_t>(state->joint_count));
    for (std::uint32_t j = 0; j < state->joint_count; ++j)
      put(joint_blocks_, static_cast<float>(state->joints[j].position));
    ++blocks;
  }
  frame.insert(frame.end(), joint_blocks_.begin(), joint_blocks_.end());
  std::memcpy(frame.data() + 8, &entries, sizeof entries);
  std::memcpy(frame.data() + 28, &blocks, sizeof blocks);
  const std::size_t soft_count_at = frame.size();
  put(frame, std::uint32_t{0});  // the soft-body block count, set below
  std::uint32_t soft_blocks = 0;
  for (std::size_t s = 0; s < soft_.size(); ++s) {
    const SoftBodyMesh* nodes = soft_[s].nodes->latest();
    if (!nodes) continue;
    put(frame, static_cast<std::uint32_t>(s));
    put(frame, nodes->node_count);
    const std::size_t at = frame.size();
    frame.resize(at + nodes->node_count * sizeof nodes->nodes[0]);
    std::memcpy(frame.data() + at, nodes->nodes.data(), nodes->node_count * sizeof nodes->nodes[0]);
    ++soft_blocks;
  }
  std::memcpy(frame.data() + soft_count_at, &soft_blocks, sizeof soft_blocks);
  return changed;
}

}  // namespace afhub::viewer
