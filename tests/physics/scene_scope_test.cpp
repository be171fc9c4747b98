// Several robots in one world (issue 18): block names scoped per file as in AMBF,
// references across files resolved when unique, ambiguous ones refused with the
// candidates, qualified references, the same model loaded twice as a copy with its
// own channels, and launch files picking several models. No hub.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/shm_layout/error.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"
#include "text_contains.hpp"

namespace afhub::physics {
namespace {

using afhub::testing::kMultiBodies;
const std::string kSmallGripper = kMultiBodies + "grippers/pr2 gripper small.yaml";
const std::string kSmallRedGripper = kMultiBodies + "grippers/pr2 gripper small red.yaml";

using afhub::test::contains;

// An arm as AMBF's da Vinci files write them: the same block names in every robot
// ("BODY base link", "BODY tool link"), each file in its own namespace. With a
// sensor and an actuator whose parent is written qualified, as the PR2 grippers do.
std::string arm(const std::string& name_space, const std::string& qualified_parent) {
  return "bodies: [BODY base link, BODY tool link]\n"
         "joints: [JOINT base-tool]\n"
         "sensors: [SENSOR range]\n"
         "actuators: [ACTUATOR grip]\n"
         "namespace: " +
         name_space +
         "\n"
         "BODY base link:\n  name: base link\n  mass: 0\n  shape: box\n"
         "  geometry: {x: 0.1, y: 0.1, z: 0.1}\n"
         "BODY tool link:\n  name: tool link\n  mass: 1\n  shape: sphere\n"
         "  geometry: {radius: 0.05}\n"
         "JOINT base-tool:\n  name: base-tool\n  parent: BODY base link\n  child: BODY tool link\n"
         "  parent pivot: {x: 0, y: 0, z: 0.1}\n  child pivot: {x: 0, y: 0, z: 0}\n"
         "  parent axis: {x: 0, y: 0, z: 1}\n  child axis: {x: 0, y: 0, z: 1}\n"
         "  type: revolute\n"
         "SENSOR range:\n  name: range\n  type: Proximity\n  parent: " +
         qualified_parent +
         "\n  array: [{offset: {x: 0, y: 0, z: 0}, direction: {x: 1, y: 0, z: 0}}]\n"
         "ACTUATOR grip:\n  name: grip\n  type: Constraint\n  parent: " +
         qualified_parent + "\n";
}

// A file of joints only (AMBF's distributed definition), in the default namespace.
std::string joint_between(const std::string& parent, const std::string& child) {
  return "joints: [JOINT bridge]\n"
         "JOINT bridge:\n  name: bridge\n  parent: " +
         parent + "\n  child: " + child +
         "\n  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
         "  parent axis: {x: 0, y: 0, z: 1}\n  child axis: {x: 0, y: 0, z: 1}\n"
         "  type: fixed\n";
}

std::string scene_error_of(const std::vector<std::string>& paths) {
  try {
    load_adf_files(paths);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

int body_by_channel(const Model& model, const std::string& channel) {
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].channel == channel) return static_cast<int>(b);
  return -1;
}

class SceneScope : public ::testing::Test {
 protected:
  afhub::testing::ModelFolder folder_;
  std::string psm_ = folder_.write("psm.yaml", arm("/ambf/env/psm/", "BODY tool link"));
  std::string ecm_ =
      folder_.write("ecm.yaml", arm("/ambf/env/ecm/", "/ambf/env/ecm/BODY tool link"));
};

TEST_F(SceneScope, TwoRobotsWithTheSameBlockNamesLoadEachInItsOwnScope) {
  const Model model = load_adf_files({psm_, ecm_});
  ASSERT_EQ(model.bodies.size(), 4u);
  ASSERT_EQ(model.joints.size(), 2u);
  EXPECT_EQ(model.bodies[0].channel, "ambf/env/psm/baselink");
  EXPECT_EQ(model.bodies[2].channel, "ambf/env/ecm/baselink");
  // Each joint joins its own file's bodies.
  EXPECT_EQ(model.joints[0].parent, 0);
  EXPECT_EQ(model.joints[0].child, 1);
  EXPECT_EQ(model.joints[1].parent, 2);
  EXPECT_EQ(model.joints[1].child, 3);
  // Sensors and actuators too, written plain or qualified.
  ASSERT_EQ(model.sensors.size(), 2u);
  EXPECT_EQ(model.sensors[0].parent, 1);
  EXPECT_EQ(model.sensors[1].parent, 3);
  EXPECT_EQ(model.actuators[0].parent, 1);
  EXPECT_EQ(model.actuators[1].parent, 3);
  EXPECT_TRUE(model.warnings.empty()) << model.warnings.front();
}

TEST_F(SceneScope, AReferenceAcrossFilesResolvesWhenUnique) {
  // Qualified: names one body although both robots have a 'BODY tool link'.
  const std::string bridge =
      folder_.write("bridge.yaml", joint_between("/ambf/env/ecm/BODY tool link", "BODY ball"));
  const std::string ball =
      folder_.write("ball.yaml",
                    "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1\n  shape: sphere\n"
                    "  geometry: {radius: 0.01}\n");
  const Model model = load_adf_files({psm_, ecm_, ball, bridge});
  ASSERT_EQ(model.joints.size(), 3u);
  EXPECT_EQ(model.bodies[model.joints[2].parent].channel, "ambf/env/ecm/toollink");
  EXPECT_EQ(model.bodies[model.joints[2].child].channel, "ambf/env/ball");
}

// A recording names the files a run came from: one holding only a joint, a sensor, an
// actuator or a soft body is one of them.
TEST_F(SceneScope, TheModelsFilesAreEveryFileABlockCameFromEachOnce) {
  const std::string bridge = folder_.write(
      "bridge.yaml", joint_between("/ambf/env/ecm/BODY tool link", "/ambf/env/psm/BODY tool link"));
  const std::string sensor =
      folder_.write("sensor.yaml",
                    "sensors: [SENSOR far]\nSENSOR far:\n  name: far\n  type: Proximity\n"
                    "  parent: /ambf/env/psm/BODY base link\n"
                    "  array: [{offset: {x: 0, y: 0, z: 0}, direction: {x: 0, y: 1, z: 0}}]\n");
  const std::string actuator =
      folder_.write("actuator.yaml",
                    "actuators: [ACTUATOR hold]\nACTUATOR hold:\n  name: hold\n"
                    "  type: Constraint\n  parent: /ambf/env/ecm/BODY base link\n");
  const std::string cloth = AFHUB_EXAMPLE_MODELS "/cloth.yaml";
  const Model model = load_adf_files({psm_, ecm_, bridge, sensor, actuator, cloth});
  std::vector<std::string> expected{psm_, ecm_, bridge, sensor, actuator, cloth};
  for (std::string& file : expected)
    file = std::filesystem::absolute(file).lexically_normal().string();
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(model_files(model), expected);
}

TEST_F(SceneScope, AnAmbiguousReferenceIsALocatedErrorListingTheCandidates) {
  const std::string bridge =
      folder_.write("bridge.yaml", joint_between("BODY base link", "/ambf/env/psm/BODY tool link"));
  const std::string message = scene_error_of({psm_, ecm_, bridge});
  EXPECT_TRUE(contains(message,
                       "bridge.yaml:4:11: error: parent 'BODY base link' of JOINT "
                       "bridge is ambiguous: 2 loaded bodies match it"))
      << message;
  for (const char* candidate :
       {"'/ambf/env/psm/BODY base link' (channel 'ambf/env/psm/baselink', ",
        "'/ambf/env/ecm/BODY base link' (channel 'ambf/env/ecm/baselink', "})
    EXPECT_TRUE(contains(message, candidate)) << candidate << " in " << message;
  EXPECT_TRUE(contains(message, "psm.yaml:7:3)")) << message;
  EXPECT_TRUE(contains(message, "ecm.yaml:7:3)")) << message;
  // Still an error within one file: a block listed twice.
  const std::string twice =
      folder_.write("twice.yaml", "bodies: [BODY a, BODY a]\nBODY a:\n  name: a\n  mass: 1\n");
  EXPECT_TRUE(contains(scene_error_of({twice}), "twice.yaml:1:18: error: 'BODY a' is listed twice"))
      << scene_error_of({twice});
}

TEST_F(SceneScope, TheSameModelLoadedTwiceGetsItsOwnChannelsNamedAsAmbfNamesCopies) {
  const Model model = load_adf_files({psm_, psm_, psm_});
  ASSERT_EQ(model.bodies.size(), 6u);
  for (const char* channel : {"ambf/env/psm/baselink", "ambf/env/psm/baselink1",
                              "ambf/env/psm/baselink2", "ambf/env/psm/toollink2"})
    EXPECT_GE(body_by_channel(model, channel), 0) << channel;
  EXPECT_EQ(model.bodies[2].name, "baselink1");
  // Each copy's joint, sensor and actuator belong to that copy.
  ASSERT_EQ(model.joints.size(), 3u);
  for (int copy = 0; copy < 3; ++copy) {
    EXPECT_EQ(model.joints[copy].parent, 2 * copy);
    EXPECT_EQ(model.joints[copy].child, 2 * copy + 1);
    EXPECT_EQ(model.joints[copy].name, "base-tool");  // the body's joint list reads the same
    EXPECT_EQ(model.sensors[copy].parent, 2 * copy + 1);
    EXPECT_EQ(model.actuators[copy].parent, 2 * copy + 1);
  }
  // Clients find sensors and actuators by name in their body's namespace: named as
  // copies too (each copy's was "range" and "grip": one name for three).
  EXPECT_EQ(model.sensors[0].name, "range");
  EXPECT_EQ(model.sensors[1].name, "range1");
  EXPECT_EQ(model.sensors[2].name, "range2");
  EXPECT_EQ(model.actuators[2].name, "grip2");
  // In other namespaces the same names are other names: kept.
  const Model two = load_adf_files({psm_, ecm_});
  EXPECT_EQ(two.sensors[1].name, "range");
  EXPECT_NE(model.joints[0].channel, model.joints[1].channel);
  ASSERT_EQ(model.warnings.size(), 2u);
  EXPECT_TRUE(contains(model.warnings[0],
                       "psm.yaml:1:1: warning: 3 channel(s) of this file are already used"))
      << model.warnings[0];
  EXPECT_TRUE(contains(model.warnings[0], "'ambf/env/psm/baselink' (first at "))
      << model.warnings[0];
  EXPECT_TRUE(contains(model.warnings[0], "is 'ambf/env/psm/baselink1' here")) << model.warnings[0];

  // A copy's qualified name takes its index, as AMBF's world names it; the plain
  // qualified name then means several bodies.
  const std::string to_copy =
      folder_.write("to_copy.yaml", joint_between("/ambf/env/psm/BODY tool link1", "BODY ball"));
  const std::string ball =
      folder_.write("ball.yaml", "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1\n");
  const Model linked = load_adf_files({psm_, psm_, ball, to_copy});
  EXPECT_EQ(linked.bodies[linked.joints.back().parent].channel, "ambf/env/psm/toollink1");
  const std::string to_either =
      folder_.write("to_either.yaml", joint_between("/ambf/env/psm/BODY tool link", "BODY ball"));
  const std::string message = scene_error_of({psm_, psm_, ball, to_either});
  EXPECT_TRUE(contains(message, "is ambiguous")) << message;
  EXPECT_TRUE(contains(message,
                       "'/ambf/env/psm/BODY tool link1' (channel "
                       "'ambf/env/psm/toollink1'"))
      << message;
}

TEST_F(SceneScope, ALaunchFilesIndicesLoadSeveralRobotsEachInItsNamespace) {
  const std::string launch =
      folder_.write("launch.yaml", "multibody configs:\n  - ./psm.yaml\n  - ./ecm.yaml\n");
  SceneRequest request;
  request.launch_file = launch;
  request.launch_indices = {0, 1};
  const Model both = load_scene(request);
  ASSERT_EQ(both.bodies.size(), 4u);
  EXPECT_EQ(both.bodies[1].channel, "ambf/env/psm/toollink");
  EXPECT_EQ(both.bodies[3].channel, "ambf/env/ecm/toollink");
  request.launch_indices = {1, 1};  // one robot twice
  const Model twice = load_scene(request);
  EXPECT_EQ(twice.bodies[3].channel, "ambf/env/ecm/toollink1");
  EXPECT_EQ(twice.joints[1].child, 3);
}

// The real files: two AMBF robots, the PR2 grippers that share block names and
// namespace and name their sensors' parents qualified, and input_devices.yaml's
// binding of one gripper file to two devices.
TEST(SceneScopeSharedModels, TheEcmTwiceAndBesideTheKukaLoads) {
  SKIP_WITHOUT_SHARED_MODELS();
  const std::string ecm = kMultiBodies + "robots/blender-ecm.yaml";
  const Model one = load_adf_files({ecm});
  const Model two = load_adf_files({ecm, ecm});
  ASSERT_EQ(two.bodies.size(), 2 * one.bodies.size());
  ASSERT_EQ(two.joints.size(), 2 * one.joints.size());
  EXPECT_EQ(two.closed_loop_count, 2 * one.closed_loop_count);
  for (std::size_t j = 0; j < one.joints.size(); ++j) {
    const auto copy = j + one.joints.size();
    EXPECT_EQ(two.joints[copy].parent, one.joints[j].parent + static_cast<int>(one.bodies.size()));
    EXPECT_EQ(two.joints[copy].child, one.joints[j].child + static_cast<int>(one.bodies.size()));
  }
  const Model with_kuka = load_adf_files({ecm, kMultiBodies + "robots/blender-kuka.yaml"});
  EXPECT_EQ(with_kuka.bodies.size(), one.bodies.size() + 8);
}

TEST(SceneScopeSharedModels, ThePr2GrippersLoadAloneTogetherAndTwice) {
  SKIP_WITHOUT_SHARED_MODELS();
  const Model small = load_adf_files({kSmallGripper});
  ASSERT_EQ(small.sensors.size(), 1u);  // its header lists one of its three
  const int palm = body_by_channel(small, "ambf/env/r_gripper_palm_link");
  ASSERT_GE(palm, 0);
  EXPECT_EQ(small.sensors[0].parent, palm);  // "/ambf/env/BODY r_gripper_palm_link"
  EXPECT_EQ(small.actuators[0].parent, palm);

  const Model both = load_adf_files({kSmallGripper, kSmallRedGripper});
  ASSERT_EQ(both.bodies.size(), 2 * small.bodies.size());
  const int red_palm = body_by_channel(both, "ambf/env/r_gripper_palm_link1");
  ASSERT_GE(red_palm, 0);
  EXPECT_EQ(both.sensors.back().parent, red_palm);
  EXPECT_EQ(both.actuators.back().parent, red_palm);

  // input_devices.yaml binds "pr2 gripper small red.yaml" to MTML and to MTMR.
  const Model devices = load_adf_files({kSmallRedGripper, kSmallRedGripper});
  EXPECT_GE(body_by_channel(devices, "ambf/env/r_gripper_palm_link"), 0);
  EXPECT_EQ(devices.actuators[1].parent, body_by_channel(devices, "ambf/env/r_gripper_palm_link1"));
}

}  // namespace
}  // namespace afhub::physics
