// What the viewer reads through the hub, at display rate: the scene description,
// the catalog, and the physics' pose feed (ScenePoses: every body's pose and joints
// in one payload, published at display rate only while read, so that a viewer adds
// no reader to any 1 kHz state channel), packed into one binary pose frame per tick
// for the scene bodies the catalog lists (never JSON per frame). Bodies that appear
// or vanish in the catalog come and go in the next frame; a new scene description
// (physics restarted, another model) gets a new generation, and the page reloads it.
//
// Frame, little-endian:
//   u32 magic 'AFV1' (0x31564641), u32 scene generation (the viewer counts the scenes),
//   u32 entry count, u32 flags (bit 0: paused; bit 1: the hub is lost, and the viewer
//   waits for it to come back: hub_lost_frame()), f64 simulation time,
//   u32 bodies in the catalog, u32 joint blocks;
//   then per entry (a scene body the catalog lists): u32 scene index,
//   f32 position x y z, f32 orientation x y z w;
//   then per joint block (an entry whose body has joints, in the entries' order):
//   u16 scene index, u16 joint count N, N x f32 joint position (rad or m);
//   then u32 soft-body blocks, and per block (a scene soft body with node positions):
//   u32 soft-body index, u32 node count N, N x f32 x y z (world frame, m).
// The arm's 7 joints add 32 bytes: every body's joints travel, so the page can
// inspect and plot any body without asking the server for it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/channel.hpp"
#include "afhub/hub/copying_reader.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub/shm_layout/soft_body.hpp"
#include "afhub/shm_layout/world.hpp"
#include "afhub/viewer/view_scene.hpp"

namespace afhub::viewer {

inline constexpr std::uint32_t kFrameMagic = 0x31564641;
inline constexpr std::size_t kFrameHeaderBytes = 32;
inline constexpr std::size_t kFrameEntryBytes = 32;
inline constexpr std::uint32_t kFramePaused = 1, kFrameHubLost = 2;

// What the page is sent while the viewer has no hub (hub_loss.hpp): no bodies, the
// hub-lost flag.
std::vector<std::uint8_t> hub_lost_frame();

class PoseFeed {
 public:
  // Needs connect_to_hub(); `world` is the world's channel instance (world_instance()).
  explicit PoseFeed(const std::string& world);

  // Reads what is new and writes the frame; returns the scene when it changed
  // (nullptr otherwise).
  std::shared_ptr<const ViewScene> update(std::vector<std::uint8_t>& frame);
  // The joint names of every body the catalog lists, {"CHANNEL": ["joint", ...]}, as
  // of the last update(); joints_changed() says whether that update changed them.
  const std::string& joints_json() const { return joints_json_; }
  bool joints_changed() const { return joints_changed_; }
  // The bodies the catalog lists, as of the last update() (they change with the joints).
  const std::vector<std::string>& catalog_channels() const { return catalog_channels_; }

 private:
  void refresh_live(const BodyList& catalog);

  // What the physics wrote, copied before it is checked: any member of the hub's group
  // can change a chunk after its check, and a count read twice must not differ.
  CopiedReader<SceneDescription> scene_reader_;
  CopiedReader<WorldState> world_reader_;
  CopiedReader<ScenePoses> poses_reader_;
  CatalogReader catalog_;
  std::shared_ptr<const ViewScene> scene_;
  std::uint32_t scene_pid_ = 0;  // the physics that published it: its poses only
  std::uint64_t catalog_sequence_ = 0;
  std::uint32_t catalog_bodies_ = 0;
  // Per scene body: the catalog lists it (a live body: drawn at its pose).
  std::vector<bool> live_;
  // Per scene soft body, its faces (read once per scene) and its node positions.
  struct SoftReaders {
    std::unique_ptr<CopiedReader<SoftBodyMesh>> faces, nodes;
  };
  std::vector<SoftReaders> soft_;
  std::vector<std::uint8_t> joint_blocks_;  // reused: no allocation once grown
  std::string joints_json_ = "{}";
  std::vector<std::string> catalog_channels_;
  bool joints_changed_ = false;
  double sim_time_s_ = 0.0;
  bool paused_ = false;
};

}  // namespace afhub::viewer
