// The ADF loader on the real AMBF models in ../shared/ambf_models, and on broken
// files: every problem is reported as "file:line:col: error: ...".
#include "afhub/physics/adf_loader.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "afhub/shm_layout/error.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

using afhub::testing::kMultiBodies;

std::vector<std::string> joint_names_below(const Model& model, const std::string& channel) {
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    if (model.bodies[b].channel != channel) continue;
    std::vector<std::string> names;
    for (int j : model.descendant_joints[b]) names.push_back(model.joints[j].name);
    return names;
  }
  return {};
}

TEST(AdfLoader, LoadsTheKuka) {
  SKIP_WITHOUT_SHARED_MODELS();
  Model model = load_adf_files({kMultiBodies + "robots/blender-kuka.yaml"});
  ASSERT_EQ(model.bodies.size(), 8u);
  ASSERT_EQ(model.joints.size(), 7u);
  EXPECT_EQ(model.bodies[0].channel, "ambf/env/base");
  EXPECT_EQ(model.bodies[0].mass_kg, 0.0);
  EXPECT_TRUE(fs::exists(model.bodies[3].visual_mesh)) << model.bodies[3].visual_mesh;
  EXPECT_NE(model.bodies[3].collision_mesh.find("low_res/link3.STL"), std::string::npos);
  EXPECT_DOUBLE_EQ(model.bodies[1].location.position_m.z, -1.197);
  EXPECT_EQ(model.joints[0].type, JointType::kRevolute);
  EXPECT_DOUBLE_EQ(*model.joints[0].limit_high, 2.094);
  EXPECT_DOUBLE_EQ(model.joints[0].controller.p, 1000.0);
  EXPECT_EQ(joint_names_below(model, "ambf/env/base"),
            (std::vector<std::string>{"base-link1", "link1-link2", "link2-link3", "link3-link4",
                                      "link4-link5", "link5-link6", "link6-link7"}));
  EXPECT_EQ(model.closed_loop_count, 0);
  EXPECT_TRUE(model.warnings.empty());
}

TEST(AdfLoader, FourBarKeepsItsLoopJointOnceInFileOrder) {
  SKIP_WITHOUT_SHARED_MODELS();
  Model model = load_adf_files({kMultiBodies + "puzzles/parallel_structure.yaml"});
  EXPECT_EQ(model.closed_loop_count, 1);
  EXPECT_EQ(joint_names_below(model, "ambf/env/l1"),
            (std::vector<std::string>{"l1-l2", "l2-l3", "l3-l4", "l1-l4"}));
  EXPECT_EQ(model.joints[4].type, JointType::kContinuous);
  ASSERT_EQ(model.warnings.size(), 1u);  // an unknown key 'redundant', located
  EXPECT_NE(
      model.warnings[0].find("parallel_structure.yaml:131:3: warning: unknown key 'redundant'"),
      std::string::npos)
      << model.warnings[0];
}

// Writes `text` to a fresh file and loads it; returns the error message ("" if none).
class BrokenFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("afhub_adf_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    std::ofstream(dir_ / "box.STL") << "solid box\nendsolid box\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string error_of(const std::string& text, const std::string& name = "model.yaml") {
    std::ofstream(dir_ / name) << text;
    try {
      load_adf_files({(dir_ / name).string()});
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  }
  fs::path dir_;
};

const char* kGoodBody = "BODY a:\n  name: a\n  mass: 1.0\n";

TEST_F(BrokenFiles, EachProblemIsLocatedAndExplained) {
  struct Case {
    std::string text, expected;
  };
  const std::vector<Case> cases = {
      {"", "model.yaml:1:1: error: the file holds nothing"},
      {"bodies: [BODY a\n", "model.yaml:2:1: error: YAML syntax"},
      {"- a\n- b\n", "error: expected an ADF file"},
      {"bodies: BODY a\n", "model.yaml:1:9: error: 'bodies' must be a list"},
      // A second document went unread, without a word.
      {"bodies: [BODY a]\nBODY a: {name: a, mass: 1}\n---\nbodies: [BODY b]\n",
       "model.yaml:3: error: a second YAML document begins here"},
      {"adf version: [9]\nbodies: [BODY a]\nBODY a: {name: a, mass: 1}\n",
       "model.yaml:1:14: error: 'adf version' must be text, not a list"},
      {"bodies: [BODY a]\n",
       "model.yaml:1:10: error: 'BODY a' is listed in 'bodies' but the file has no"},
      {"bodies: [BODY a]\nBODY a:\n  mass: 1.0\n", "model.yaml:3:3: error: missing 'name'"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n", "model.yaml:3:3: error: 'BODY a' has no 'mass'"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: heavy\n",
       "model.yaml:4:9: error: 'mass' must be a number, got 'heavy'"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: -2\n",
       "model.yaml:4:9: error: 'mass' must not be negative"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: .nan\n",
       "model.yaml:4:9: error: 'mass' must be finite"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: {x: 1}\n",
       "'mass' must be a number, not a map"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  scale: 0\n",
       "model.yaml:5:10: error: 'scale' must be positive"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  mesh: nothere.STL\n",
       "model.yaml:5:9: error: mesh 'nothere.STL' is not a readable file:"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  shape: blob\n  geometry: {}\n",
       "model.yaml:5:10: error: unknown shape 'blob'"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  location: {position: {x: 1, y: 2}}\n",
       "error: 'location.position' is missing 'z'"},
      // yaml-cpp took the first of two, most readers the last.
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 0.25\n  mass: 99\n",
       "model.yaml:5:3: error: 'mass' is written twice in BODY a"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  color rgba: {r: 1e8}\n",
       "model.yaml:5:19: error: 'color rgba.r' is 1e8; a component is from 0 to 1"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  collision margin: 1e8\n",
       "model.yaml:5:21: error: 'collision margin' is 1e8, beyond the bound of"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  collision groups: [1000]\n",
       "model.yaml:5:22: error: collision groups are integers from 0 to 999"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  inertia: {ix: 1, iy: -1, iz: 1}\n",
       "error: 'inertia' components must not be negative"},
      {"bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n  friction: 3\n",
       "model.yaml:5:13: error: 'friction' must be a map such as {static: 0.5, rolling: 0.01}"},
      {std::string("bodies: [BODY a]\nBODY a:\n  name: ") + std::string(101, 'n') + "\n  mass: 1\n",
       "characters; iceoryx allows at most 100"},
  };
  for (const Case& c : cases) {
    std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "file:\n"
                                                           << c.text << "\nmessage: " << message;
  }
}

// Principal inertias no body has (one larger than the other two together) load, with a
// warning at them; a flat plate's (one equal to the others' sum) loads without.
TEST_F(BrokenFiles, InertiasNoRigidBodyHasAreAWarning) {
  const auto warnings_of = [&](const std::string& inertia) {
    std::ofstream(dir_ / "model.yaml") << "bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n"
                                          "  inertia: "
                                       << inertia << "\n";
    return load_adf_files({(dir_ / "model.yaml").string()}).warnings;
  };
  const std::vector<std::string> impossible = warnings_of("{ix: 1, iy: 0.001, iz: 0.001}");
  ASSERT_EQ(impossible.size(), 1u);
  EXPECT_NE(impossible[0].find("model.yaml:5:12: warning: 'inertia' (1, 0.001, 0.001) has one "
                               "component larger than the other two together"),
            std::string::npos)
      << impossible[0];
  EXPECT_TRUE(warnings_of("{ix: 0.5, iy: 0.5, iz: 1}").empty());
}

// Values in the wrong unit load, with a warning at them: gravity in mm/s^2 fell a
// thousand times too fast, limits in degrees were no limits, and a zero inertia froze an
// axis, all without a word. Each sound value beside them says nothing.
TEST_F(BrokenFiles, ValuesInTheWrongUnitAreAWarning) {
  const auto warnings_of = [&](const std::string& text) {
    std::ofstream(dir_ / "model.yaml") << text;
    return load_adf_files({(dir_ / "model.yaml").string()}).warnings;
  };
  const auto model = [](const std::string& gravity, const std::string& inertia,
                        const std::string& limits) {
    return "gravity: " + gravity +
           "\nbodies: [BODY a, BODY b]\njoints: [JOINT j]\nBODY a:\n  name: a\n  mass: 0\n"
           "  inertia: {ix: 0, iy: 0, iz: 0}\nBODY b:\n  name: b\n  mass: 1\n  inertia: " +
           inertia +
           "\nJOINT j:\n  name: j\n  parent: BODY a\n  child: BODY b\n"
           "  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
           "  parent axis: {x: 0, y: 0, z: 1}\n  child axis: {x: 0, y: 0, z: 1}\n"
           "  type: revolute\n  joint limits: " +
           limits + "\n";
  };
  EXPECT_TRUE(warnings_of(model("{x: 0, y: 0, z: -9.81}", "{ix: 0.1, iy: 0.1, iz: 0.1}",
                                "{low: -6.2832, high: 6.2832}"))
                  .empty());
  const std::vector<std::string> wrong = warnings_of(
      model("{x: 0, y: 0, z: -9810}", "{ix: 0.1, iy: 0, iz: 0.1}", "{low: -90, high: 90}"));
  ASSERT_EQ(wrong.size(), 3u);
  EXPECT_NE(wrong[0].find("model.yaml:1:10: warning: 'gravity' is 9810 m/s^2, more than 10 g"),
            std::string::npos)
      << wrong[0];
  EXPECT_NE(wrong[1].find("model.yaml:11:12: warning: 'inertia' has a zero component: Bullet "
                          "takes it as infinite"),
            std::string::npos)
      << wrong[1];
  EXPECT_NE(wrong[2].find("warning: 'joint limits' {low: -90, high: 90} reach past a full turn: "
                          "ADF gives them in radians"),
            std::string::npos)
      << wrong[2];
}

// AMBF takes the spaces out of bodies' and joints' names: its scripts name the ECM's
// 'base link-yaw link' as 'baselink-yawlink', which afhub refused.
TEST_F(BrokenFiles, NamesLoseTheirSpacesAsInAmbf) {
  std::ofstream(dir_ / "model.yaml")
      << "bodies: [BODY a, BODY b]\njoints: [JOINT j]\nBODY a:\n  name: base link\n  mass: 0\n"
         "BODY b:\n  name: yaw link\n  mass: 1\nJOINT j:\n  name: base link-yaw link\n"
         "  parent: BODY a\n  child: BODY b\n  parent pivot: {x: 0, y: 0, z: 0}\n"
         "  child pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 0, z: 1}\n"
         "  child axis: {x: 0, y: 0, z: 1}\n  type: revolute\n";
  const Model model = load_adf_files({(dir_ / "model.yaml").string()});
  EXPECT_EQ(model.bodies[1].name, "yawlink");
  EXPECT_EQ(model.joints[0].name, "baselink-yawlink");
  EXPECT_EQ(model.joints[0].channel, "ambf/env/baselink-yawlink");
}

TEST_F(BrokenFiles, ShapeSensorSoftBodyAndActuatorProblemsAreLocatedAndExplained) {
  const std::string body = "bodies: [BODY a]\nBODY a:\n  name: a\n  mass: 1\n";
  struct Case {
    std::string text, expected;
  };
  const std::vector<Case> cases = {
      {body + "  shape: box\n  geometry: {x: 1, y: 1}\n",
       "model.yaml:6:13: error: 'geometry' of a box needs 'z'"},
      {body + "  shape: sphere\n  geometry: {radius: -1}\n",
       "model.yaml:6:22: error: 'geometry.radius' must be positive"},
      {body + "  shape: cylinder\n  geometry: {radius: 1, height: 1, axis: W}\n",
       "error: 'geometry.axis' must be X, Y or Z"},
      {body + "  compound shape: 3\n", "model.yaml:5:19: error: 'compound shape' must be a"},
      {body + "  mesh: box.STL\n  collision mesh type: BLOB\n",
       "model.yaml:6:24: error: unknown collision mesh type 'BLOB'"},
      {body + "  controller output type: TORQUE\n",
       "error: 'controller output type' must be FORCE or VELOCITY"},
      {body + "sensors: [SENSOR s]\nSENSOR s:\n  name: s\n  type: Sonar\n  parent: BODY a\n",
       "model.yaml:8:9: error: unknown sensor type 'Sonar'"},
      {body + "sensors: [SENSOR s]\nSENSOR s:\n  name: s\n  type: Proximity\n  parent: BODY a\n",
       "model.yaml:7:3: error: 'SENSOR s' needs 'array' or 'parametric'"},
      {body + "actuators: [ACTUATOR c]\nACTUATOR c:\n  name: c\n  type: Constraint\n"
              "  parent: BODY z\n",
       "model.yaml:9:11: error: parent 'BODY z' of ACTUATOR c is not a loaded body"},
      {"soft bodies: [SOFTBODY s]\nSOFTBODY s:\n  name: s\n  mass: 1\n",
       "model.yaml:3:3: error: missing 'mesh'"},
  };
  for (const Case& c : cases) {
    std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "file:\n"
                                                           << c.text << "\nmessage: " << message;
  }
}

TEST_F(BrokenFiles, JointProblemsAreLocatedAndExplained) {
  const std::string bodies = std::string("bodies: [BODY a, BODY b]\njoints: [JOINT j]\n") +
                             kGoodBody + "BODY b:\n  name: b\n  mass: 1.0\n";
  const std::string joint_head = "JOINT j:\n  name: j\n  parent: BODY a\n";
  const std::string pivots =
      "  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
      "  parent axis: {x: 0, y: 0, z: 1}\n";
  struct Case {
    std::string joint, expected;
  };
  const std::vector<Case> cases = {
      {joint_head + "  child: BODY c\n" + pivots +
           "  child axis: {x: 0, y: 0, z: 1}\n  type: revolute\n",
       "model.yaml:12:10: error: child 'BODY c' of JOINT j is not a loaded body"},
      {joint_head + "  child: BODY b\n" + pivots +
           "  child axis: {x: 0, y: 0, z: 0}\n  type: revolute\n",
       "model.yaml:16:15: error: 'child axis' has zero length"},
      {joint_head + "  child: BODY b\n" + pivots +
           "  child axis: {x: 0, y: 0, z: 1}\n  type: wobbly\n",
       "model.yaml:17:9: error: unknown joint type 'wobbly'"},
      {joint_head + "  child: BODY b\n" + pivots + "  type: revolute\n",
       "error: missing 'child axis'"},
      {joint_head + "  child: BODY a\n" + pivots +
           "  child axis: {x: 0, y: 0, z: 1}\n  type: revolute\n",
       "joins 'BODY a' to itself"},
      {joint_head + "  child: BODY b\n" + pivots +
           "  child axis: {x: 0, y: 0, z: 1}\n  type: revolute\n  joint limits: {low: 1, high: "
           "-1}\n",
       "model.yaml:18:17: error: 'joint limits' has low 1 above high -1"},
  };
  for (const Case& c : cases) {
    std::string message = error_of(bodies + c.joint);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "joint:\n"
                                                           << c.joint << "\nmessage: " << message;
  }
}

TEST_F(BrokenFiles, ModelSplitOverTwoFilesLoadsAndUnlistedBlocksAreSkipped) {
  std::ofstream(dir_ / "bodies.yaml")
      << "bodies: [BODY a, BODY b]\n"
      << kGoodBody << "BODY b:\n  name: b\n  mass: 2.0\nBODY c:\n  name: c\n  mass: oops\n";
  std::ofstream(dir_ / "joints.yaml")
      << "joints: [JOINT j]\nJOINT j:\n  name: j\n  parent: BODY a\n  child: BODY b\n"
         "  parent pivot: {x: 0, y: 0, z: 0}\n  child pivot: {x: 0, y: 0, z: 0}\n"
         "  parent axis: {x: 1, y: 0, z: 0}\n  child axis: {x: 1, y: 0, z: 0}\n  type: prismatic\n";
  Model model = load_adf_files({(dir_ / "bodies.yaml").string(), (dir_ / "joints.yaml").string()});
  EXPECT_EQ(model.bodies.size(), 2u);  // BODY c is not listed: not loaded, not checked
  ASSERT_EQ(model.joints.size(), 1u);
  EXPECT_EQ(model.joints[0].type, JointType::kPrismatic);
  EXPECT_EQ(model.bodies[model.joints[0].child].name, "b");
}

}  // namespace
}  // namespace afhub::physics
