// The viewer's pose feed (ScenePoses): what the physics publishes for a viewer at
// display rate instead of a viewer reading every body's 1 kHz state channel.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <thread>

#include "afhub/hub/channel.hpp"
#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/sim_channels.hpp"
#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/scene_poses.hpp"
#include "afhub_process.hpp"

namespace afhub::test {
namespace {

using namespace std::chrono_literals;

const ChannelId kPoses{std::string(kService), world_instance(), std::string(kScenePosesEvent)};

// The physics loop at 1 kHz of wall time, as `afhub run` calls it.
struct Loop {
  physics::Simulation& sim;
  physics::SimChannels& channels;
  int cycle = 0;
  void run(int cycles, LatestReader<ScenePoses>* viewer = nullptr, int* updates = nullptr) {
    for (int i = 0; i < cycles; ++i, ++cycle) {
      channels.apply_commands(monotonic_ns());
      sim.step();
      channels.publish({cycle * 1e-3, 1000.0, false});
      channels.publish_view(std::int64_t{cycle} * 1'000'000);
      if (viewer && viewer->latest() && viewer->updated()) ++*updates;
    }
  }
};

std::uint64_t sequence_seen_by_a_new_reader() {
  LatestReader<ScenePoses> reader(kPoses);
  const ScenePoses* poses = nullptr;
  EXPECT_TRUE(wait_until([&] { return (poses = reader.latest()) != nullptr; }, 5s));
  return poses ? poses->header.sequence : 0;
}

TEST(ScenePoses, AtDisplayRateOnlyWhileReadWithEveryBodysPoseAndJoints) {
  const physics::Model model = physics::load_adf_files({AFHUB_EXAMPLE_MODELS "/arm7.yaml"});
  physics::Simulation sim(model, 0.001);
  physics::SimChannels channels(sim, 0.5);
  Loop loop{sim, channels};

  // Unread: published once (a viewer joining later gets it from the history), then not.
  loop.run(1000);
  EXPECT_EQ(sequence_seen_by_a_new_reader(), 1u);

  // Read: about 60 a second, each the bodies' poses and joints of the step it went out.
  auto viewer = std::make_unique<LatestReader<ScenePoses>>(kPoses);
  ASSERT_TRUE(wait_until([&] { return viewer->raw().subscribed(); }, 5s));
  viewer->latest();  // the history sample
  int updates = 0;
  loop.run(1000, viewer.get(), &updates);
  std::printf("scene poses: %d in 1000 steps of 1 ms\n", updates);
  EXPECT_GE(updates, 55);  // every 17th step of 1 ms: 58.8 a second
  EXPECT_LE(updates, 61);
  // Wait for one, then compare it with the world it describes (not stepped since).
  int fresh = 0;
  while (fresh == 0) loop.run(1, viewer.get(), &fresh);
  const ScenePoses& poses = *viewer->latest();
  EXPECT_EQ(poses.header.sim_step, sim.step_count());
  ASSERT_EQ(poses.body_count, model.bodies.size());
  std::uint32_t joints = 0;
  for (std::uint32_t b = 0; b < poses.body_count; ++b) {
    const Pose expected = sim.body_pose(b);
    const ScenePose& pose = poses.bodies[b];
    EXPECT_NEAR(pose.position_m[0], expected.position_m.x, 1e-6) << model.bodies[b].name;
    EXPECT_NEAR(pose.position_m[2], expected.position_m.z, 1e-6) << model.bodies[b].name;
    EXPECT_NEAR(pose.orientation_xyzw[3], expected.orientation.w, 1e-6) << model.bodies[b].name;
    const std::vector<int>& below = model.descendant_joints[b];
    ASSERT_EQ(pose.joint_count, model.bodies[b].passive ? 0u : below.size());
    for (std::uint32_t j = 0; j < pose.joint_count; ++j)
      EXPECT_NEAR(joint_positions_in(poses)[pose.first_joint + j], sim.joint_position(below[j]),
                  1e-6);
    joints += pose.joint_count;
  }
  EXPECT_EQ(poses.joint_value_count, joints);
  EXPECT_GT(joints, 0u);

  // Read no more: nothing more goes out.
  const std::uint64_t last = poses.header.sequence;
  viewer.reset();
  std::this_thread::sleep_for(500ms);  // RouDi sees the reader go (its discovery loop)
  loop.run(1000);
  EXPECT_EQ(sequence_seen_by_a_new_reader(), last);
}

}  // namespace
}  // namespace afhub::test
