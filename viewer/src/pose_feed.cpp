// The viewer's reading of the hub (see pose_feed.hpp).
#include "afhub/viewer/pose_feed.hpp"

#include <algorithm>
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

std::vector<std::uint8_t> hub_lost_frame() {
  std::vector<std::uint8_t> frame;
  put(frame, kFrameMagic);
  put(frame, std::uint32_t{0});  // no scene
  put(frame, std::uint32_t{0});  // no entries
  put(frame, kFrameHubLost);
  put(frame, 0.0);               // no simulation time
  put(frame, std::uint32_t{0});  // no catalog
  put(frame, std::uint32_t{0});  // no joint blocks
  put(frame, std::uint32_t{0});  // no soft bodies
  return frame;
}

PoseFeed::PoseFeed(const std::string& world)
    : scene_reader_({std::string(kService), world, std::string(kSceneEvent)}),
      world_reader_({std::string(kService), world, std::string(kStateEvent)}),
      poses_reader_({std::string(kService), world, std::string(kScenePosesEvent)}),
      scene_(std::make_shared<ViewScene>(no_scene())) {
  catalog_.wait(std::chrono::milliseconds(2000));
}

void PoseFeed::refresh_live(const BodyList& catalog) {
  std::unordered_set<std::string> listed;
  catalog_bodies_ = 0;
  catalog_channels_.clear();
  JsonWriter joints;
  joints.begin_object();
  for (std::uint32_t i = 0; i < catalog.body_count; ++i) {
    if (catalog.bodies[i].kind != ChannelKind::kBody) continue;
    ++catalog_bodies_;
    listed.insert(catalog.bodies[i].channel.data());
    catalog_channels_.emplace_back(catalog.bodies[i].channel.data());
    joints.key(catalog.bodies[i].channel.data()).begin_array();
    for (const std::string& name : joint_names_of(catalog, catalog.bodies[i])) joints.value(name);
    joints.end_array();
  }
  joints.end_object();
  joints_changed_ = joints.str() != joints_json_;
  joints_json_ = joints.str();
  live_.assign(scene_->channels.size(), false);
  for (std::size_t b = 0; b < live_.size(); ++b) live_[b] = listed.count(scene_->channels[b]) != 0;
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
      soft_.push_back({std::make_unique<CopiedReader<SoftBodyMesh>>(
                           ChannelId{std::string(kService), channel, std::string(kSoftFacesEvent)}),
                       std::make_unique<CopiedReader<SoftBodyMesh>>(ChannelId{
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
    scene_pid_ = scene->header.publisher_pid;
    catalog_sequence_ = 0;  // which of the new scene's bodies are live
    changed = scene_;
  }
  const BodyList& catalog = catalog_.latest();
  if (catalog.header.sequence != catalog_sequence_) {
    catalog_sequence_ = catalog.header.sequence;
    refresh_live(catalog);
  }
  if (const WorldState* world = world_reader_.latest()) {
    sim_time_s_ = world->header.sim_time_s;
    paused_ = world->paused != 0;
  }
  frame.clear();
  put(frame, kFrameMagic);
  put(frame, scene_->generation);
  put(frame, std::uint32_t{0});  // the entry count, set below
  put(frame, paused_ ? kFramePaused : 0U);
  put(frame, sim_time_s_);
  put(frame, catalog_bodies_);
  put(frame, std::uint32_t{0});  // the joint block count, set below
  std::uint32_t entries = 0, blocks = 0;
  joint_blocks_.clear();
  // The newest poses of the physics that published the scene (a restarted one's
  // last sample stays readable until the new one publishes).
  const ScenePoses* poses = poses_reader_.latest();
  if (poses && poses->header.publisher_pid != scene_pid_) poses = nullptr;
  const std::uint32_t count =
      poses ? std::min<std::uint32_t>(poses->body_count, static_cast<std::uint32_t>(live_.size()))
            : 0;
  for (std::uint32_t b = 0; b < count; ++b) {
    if (!live_[b]) continue;
    const ScenePose& pose = poses->bodies[b];
    put(frame, b);
    for (float v : pose.position_m) put(frame, v);
    for (float v : pose.orientation_xyzw) put(frame, v);
    ++entries;
    if (pose.joint_count == 0) continue;
    // Scene bodies (kMaxSceneBodies) and joints (kMaxJointsPerBody) fit 16 bits.
    put(joint_blocks_, static_cast<std::uint16_t>(b));
    put(joint_blocks_, static_cast<std::uint16_t>(pose.joint_count));
    for (std::uint32_t j = 0; j < pose.joint_count; ++j)
      put(joint_blocks_, joint_positions_in(*poses)[pose.first_joint + j]);
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
