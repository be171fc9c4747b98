// A loaded file placed where the user wants it (issue 31): `afhub run --at
// FILE=x,y,z[,r,p,y]` and a launch file's `at:` move every body of that file
// rigidly, so that its joints still meet; other files stay; bad values are refused
// naming the option or the file and line. No hub.
#include <gtest/gtest.h>

#include <cmath>

#include "afhub/physics/scene_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/error.hpp"
#include "frames.hpp"
#include "model_files.hpp"
#include "text_contains.hpp"

namespace afhub::physics {
namespace {

using afhub::test::contains;

// A base and a link turned about z, on a hinge about z: its pivots meet as written.
const char* const kHinge =
    "bodies: [BODY base, BODY link]\n"
    "joints: [JOINT base-link]\n"
    "BODY base:\n  name: base\n  mass: 0\n"
    "  location: {position: {x: 0.1, y: 0.2, z: 0.3}, orientation: {r: 0, p: 0, y: 0}}\n"
    "BODY link:\n  name: link\n  mass: 1\n  shape: box\n  geometry: {x: 0.1, y: 0.1, z: 0.4}\n"
    "  location: {position: {x: 0.1, y: 0.2, z: 0.6}, orientation: {r: 0, p: 0, y: 0.5}}\n"
    "JOINT base-link:\n  name: base-link\n  parent: BODY base\n  child: BODY link\n"
    "  parent pivot: {x: 0, y: 0, z: 0.1}\n  parent axis: {x: 0, y: 0, z: 1}\n"
    "  child pivot: {x: 0, y: 0, z: -0.2}\n  child axis: {x: 0, y: 0, z: 1}\n"
    "  type: revolute\n";

const char* const kBall =
    "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1\n"
    "  location: {position: {x: 1, y: 2, z: 3}}\n";

std::string error_of(const SceneRequest& request) {
  try {
    load_scene(request);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST(FilePlacement, AtParsesAFileAndAPositionWithAnOptionalTurn) {
  const FilePlacement moved = parse_file_placement("robots/my arm.yaml=1,-2,0.5");
  EXPECT_EQ(moved.file, "robots/my arm.yaml");
  EXPECT_EQ(moved.placement.position_m.x, 1.0);
  EXPECT_EQ(moved.placement.position_m.y, -2.0);
  EXPECT_EQ(moved.placement.position_m.z, 0.5);
  EXPECT_EQ(moved.placement.rpy_rad.z, 0.0);
  const FilePlacement turned = parse_file_placement("a.yaml=0,0,0,0.1,0.2,1.5");
  EXPECT_EQ(turned.placement.rpy_rad.x, 0.1);
  EXPECT_EQ(turned.placement.rpy_rad.y, 0.2);
  EXPECT_EQ(turned.placement.rpy_rad.z, 1.5);
  for (const char* bad : {"a.yaml", "=1,2,3", "a.yaml=", "a.yaml=1,2", "a.yaml=1,2,3,4",
                          "a.yaml=1,x,3", "a.yaml=1,2,3,", "a.yaml=nan,0,0", "a.yaml=1e9,0,0"}) {
    try {
      parse_file_placement(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& error) {
      EXPECT_TRUE(contains(error.what(), "--at takes FILE=x,y,z or FILE=x,y,z,r,p,y"))
          << error.what();
      EXPECT_TRUE(contains(error.what(), std::string("got '") + bad + "'")) << error.what();
    }
  }
}

// Every body of the placed file moves by the same rigid motion, so its joints read
// as before and its pivots still meet; the other file stays where it was.
TEST(FilePlacement, EveryBodyOfThePlacedFileMovesRigidlyAndTheOthersStay) {
  testing::ModelFolder folder;
  SceneRequest request;
  request.adf_files = {folder.write("hinge.yaml", kHinge), folder.write("ball.yaml", kBall)};
  const Model before = load_scene(request);
  const Placement at{{3.0, -1.0, 0.5}, {0.2, -0.4, 1.2}};
  // The same file by another spelling of its path.
  request.placements = {{(folder.dir() / "." / "hinge.yaml").string(), at}};
  const Model after = load_scene(request);

  const btTransform move = to_transform(at);
  for (std::size_t b = 0; b < 2; ++b) {
    const btTransform expected = move * to_transform(before.bodies[b].location);
    const btTransform placed = to_transform(after.bodies[b].location);
    EXPECT_LT((placed.getOrigin() - expected.getOrigin()).length(), 1e-12) << b;
    EXPECT_LT(std::abs(std::abs(placed.getRotation().dot(expected.getRotation())) - 1), 1e-12) << b;
  }
  const Vec3& ball = after.bodies[2].location.position_m;
  EXPECT_EQ(ball.x, 1.0);
  EXPECT_EQ(ball.y, 2.0);
  EXPECT_EQ(ball.z, 3.0);

  const Simulation still(before, 0.001), placed(after, 0.001);
  EXPECT_LT(placed.joint_pivot_gap_m(0), 1e-9);
  EXPECT_NEAR(placed.joint_position(0), still.joint_position(0), 1e-9);
}

// A file loaded twice: each placement naming it places the next copy.
TEST(FilePlacement, EachPlacementOfAFileLoadedTwicePlacesTheNextCopy) {
  testing::ModelFolder folder;
  SceneRequest request;
  const std::string ball = folder.write("ball.yaml", kBall);
  request.adf_files = {ball, ball};
  request.placements = {{ball, {{0, 0, 0}, {}}}, {ball, {{1.5, 0, 0}, {}}}};
  const Model model = load_scene(request);
  ASSERT_EQ(model.bodies.size(), 2u);
  EXPECT_EQ(model.bodies[0].location.position_m.x, 1.0);
  EXPECT_EQ(model.bodies[1].location.position_m.x, 2.5);
  request.placements.push_back({ball, {{3, 0, 0}, {}}});
  const std::string error = error_of(request);
  EXPECT_TRUE(contains(error, "more times than it is loaded: each --at places one copy")) << error;
}

TEST(FilePlacement, AtNamingAFileNotLoadedSaysWhichAreLoaded) {
  testing::ModelFolder folder;
  SceneRequest request;
  request.adf_files = {folder.write("ball.yaml", kBall)};
  request.placements = {{"robot.yaml", {{1, 0, 0}, {}}}};
  const std::string error = error_of(request);
  EXPECT_TRUE(contains(error, "--at names 'robot.yaml', which is not a loaded file")) << error;
  EXPECT_TRUE(contains(error, "ball.yaml")) << error;
}

// The launch file's `at:` (an afhub key that AMBF ignores): by the path its
// `multibody configs` list, for the models picked with -l.
TEST(FilePlacement, ALaunchFilePlacesItsModelsWithAt) {
  testing::ModelFolder folder;
  folder.write("hinge.yaml", kHinge);
  folder.write("ball.yaml", kBall);
  const std::string configs = "multibody configs: [./hinge.yaml, ./ball.yaml]\n";
  SceneRequest request;
  request.launch_file =
      folder.write("launch.yaml", configs +
                                      "at:\n  ./ball.yaml: [0, 0, -3]\n  ./hinge.yaml: "
                                      "[1, 0, 0, 0, 0, 3.14159265358979]\n");
  request.launch_indices = {1};  // the ball only: the hinge's `at` waits until it is picked
  const Model ball = load_scene(request);
  ASSERT_EQ(ball.bodies.size(), 1u);
  EXPECT_EQ(ball.bodies[0].location.position_m.z, 0.0);
  request.launch_indices = {0, 1};
  const Model both = load_scene(request);
  EXPECT_NEAR(both.bodies[0].location.position_m.x, 0.9, 1e-12);  // base at x 0.1, turned
  EXPECT_NEAR(both.bodies[0].location.position_m.y, -0.2, 1e-12);
  EXPECT_EQ(both.bodies[2].location.position_m.z, 0.0);

  struct Bad {
    const char* at;
    const char* error;
  };
  for (const Bad& bad : {
           Bad{"at: [1, 2, 3]\n", "launch.yaml:2:5: error: 'at' must map model paths"},
           Bad{"at:\n  ./ball.yaml: [1, 2]\n", "launch.yaml:3:16: error: 'at' takes [x, y, z]"},
           Bad{"at:\n  ./ball.yaml: [1, a, 2]\n", "launch.yaml:3:20: error:"},
           Bad{"at:\n  ./hinge.yaml: [1, 2, 3]\n  ./floor.yaml: [0, 0, 0]\n",
               "launch.yaml:4:3: error: 'at' names './floor.yaml', which is not in 'multibody "
               "configs'"},
           Bad{"at:\n  ./ball.yaml: [1e9, 0, 0]\n", "launch.yaml:3:17: error:"},
       }) {
    folder.write("floor.yaml", kBall);  // exists, but is not among the configs
    request.launch_file = folder.write("launch.yaml", configs + bad.at);
    const std::string error = error_of(request);
    EXPECT_TRUE(contains(error, bad.error)) << bad.at << "\n" << error;
  }
}

}  // namespace
}  // namespace afhub::physics
