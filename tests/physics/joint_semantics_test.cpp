// Joints as a robotics engineer expects them: commands only to joints with an
// axis, passive joints out of the lists, continuous joints counting turns, a
// slider's velocity right on a turning parent, limits and effort caps that hold,
// a PID without derivative kick or wind-up whose lowered gains are said, inertia
// from a mesh on its principal axes, and gravity by AMBF's rule.
#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/physics/simulation.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

using afhub::testing::kMultiBodies;

// A static base and a 1 kg arm, 0.2 m long along x, on joint `j` at the base's
// origin about y; `extra` adds to the joint's block, `header` to the file's.
std::string arm_model(const std::string& type, const std::string& extra,
                      const std::string& header = "gravity: {x: 0, y: 0, z: 0}\n") {
  return "bodies: [BODY base, BODY arm]\njoints: [JOINT j]\n" + header +
         "BODY base:\n  name: base\n  mass: 0\n"
         "BODY arm:\n  name: arm\n  mass: 1\n  shape: box\n  geometry: {x: 0.2, y: 0.02, z: "
         "0.02}\n  damping: {linear: 0, angular: 0}\n"
         "  location: {position: {x: 0.1, y: 0, z: 0}}\n"
         "JOINT j:\n  name: j\n  parent: BODY base\n  child: BODY arm\n"
         "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
         "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n  type: " +
         type + "\n" + extra;
}

BodyInput one_joint(JointMode mode, double value) {
  BodyInput input{};
  input.joint_count = 1;
  input.joint_modes[0] = mode;
  input.joint_values[0] = value;
  return input;
}

double spin(const Simulation& sim, std::size_t body) {
  BodyReading reading{};
  sim.read_body(body, reading);
  const Vec3& w = reading.twist.angular_radps;
  return std::sqrt(w.x * w.x + w.y * w.y + w.z * w.z);
}

// A joint without an axis takes no command: its entry is refused (named), and the
// arm it holds stays still instead of turning about an arbitrary axis.
TEST(JointSemantics, JointsWithoutAnAxisRefuseCommands) {
  for (const std::string type : {"fixed", "p2p", "six dof"}) {
    testing::ModelFolder folder;
    const Model model = load_adf_files({folder.write("arm.yaml", arm_model(type, ""))});
    for (JointMode mode : {JointMode::kEffort, JointMode::kVelocity, JointMode::kPosition}) {
      Simulation sim(model, 0.001);
      const BodyInput input = one_joint(mode, 2.0);
      ASSERT_EQ(sim.input_problem(0, input), nullptr) << type;
      const char* refused = sim.axisless_entry(0, input);
      ASSERT_NE(refused, nullptr) << type;
      EXPECT_NE(std::string(refused).find("joint 0 (j) is " + type), std::string::npos) << refused;
      sim.set_input(0, input);
      EXPECT_EQ(sim.joint_driver(0), -1) << type;
      for (int i = 0; i < 200; ++i) sim.step();
      EXPECT_LT(spin(sim, 1), 0.01) << type << " mode " << static_cast<int>(mode);
    }
    // A 0, what a full-length command (or a hold at its reading) carries for it, asks nothing.
    Simulation sim(model, 0.001);
    for (JointMode mode : {JointMode::kEffort, JointMode::kVelocity, JointMode::kPosition})
      EXPECT_EQ(sim.axisless_entry(0, one_joint(mode, 0.0)), nullptr);
  }
  // A revolute joint takes all three.
  testing::ModelFolder folder;
  const Model hinge = load_adf_files({folder.write("arm.yaml", arm_model("revolute", ""))});
  Simulation sim(hinge, 0.001);
  EXPECT_EQ(sim.axisless_entry(0, one_joint(JointMode::kPosition, 1.0)), nullptr);
}

// As AMBF's active child-joint list: a passive joint is in no body's joint list
// (so not in its state, its directory names or its commands); the joints below it
// still are.
TEST(JointSemantics, PassiveJointsStayOutOfJointLists) {
  testing::ModelFolder folder;
  auto box = [](const std::string& name, double x) {
    return "BODY " + name + ":\n  name: " + name +
           "\n  mass: 1\n  shape: box\n  geometry: {x: 0.2, y: 0.02, z: 0.02}\n"
           "  location: {position: {x: " +
           std::to_string(x) + ", y: 0, z: 0}}\n";
  };
  auto joint = [](const std::string& name, const std::string& parent, const std::string& child,
                  bool passive) {
    return "JOINT " + name + ":\n  name: " + name + "\n  parent: BODY " + parent +
           "\n  child: BODY " + child +
           "\n  parent pivot: {x: 0.1, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
           "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n"
           "  type: revolute\n  passive: " +
           (passive ? "true" : "false") + "\n";
  };
  const Model model = load_adf_files(
      {folder.write("chain.yaml",
                    "bodies: [BODY base, BODY a, BODY b]\njoints: [JOINT base-a, JOINT a-b]\n"
                    "BODY base:\n  name: base\n  mass: 0\n" +
                        box("a", 0.2) + box("b", 0.4) + joint("base-a", "base", "a", true) +
                        joint("a-b", "a", "b", false))});
  ASSERT_EQ(model.joints.size(), 2u);
  EXPECT_EQ(model.descendant_joints[0], std::vector<int>{1});  // base: a-b only
  EXPECT_EQ(model.descendant_joints[1], std::vector<int>{1});
  Simulation sim(model, 0.001);
  BodyReading reading{};
  sim.read_body(0, reading);
  EXPECT_EQ(reading.joint_count, 1u);
}

// The da Vinci ECM marks its parallelogram's mirror joints passive: only the four
// joints a controller drives are listed, so no two PIDs fight about one loop.
TEST(JointSemantics, TheEcmListsOnlyItsActiveJoints) {
  SKIP_WITHOUT_SHARED_MODELS();
  const Model model = load_adf_files({kMultiBodies + "robots/blender-ecm.yaml"});
  std::size_t base = 0;
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].name == "baselink") base = b;
  std::vector<std::string> names;
  for (int j : model.descendant_joints[base]) {
    EXPECT_FALSE(model.joints[j].passive) << model.joints[j].name;
    names.push_back(model.joints[j].name);
  }
  EXPECT_EQ(names.size(), 4u) << ::testing::PrintToString(names);
}

// A continuous joint turning at 10 rad/s for 2 s reports 20 rad, not an angle
// wrapped at +-pi; a reset starts its count again.
TEST(JointSemantics, ContinuousJointsCountTurns) {
  testing::ModelFolder folder;
  const Model model = load_adf_files(
      {folder.write("wheel.yaml", arm_model("continuous", "  max motor impulse: 1\n"))});
  Simulation sim(model, 0.001);
  sim.set_input(0, one_joint(JointMode::kVelocity, 10.0));
  double previous = sim.joint_position(0);
  for (int i = 0; i < 2000; ++i) {
    sim.step();
    EXPECT_LT(std::abs(sim.joint_position(0) - previous), 0.1) << "a jump at step " << i;
    previous = sim.joint_position(0);
  }
  EXPECT_NEAR(sim.joint_position(0), 20.0, 0.3);
  // Holding it where it is stays a valid command after many turns.
  EXPECT_EQ(sim.input_problem(0, one_joint(JointMode::kPosition, 1000.0)), nullptr);
  // A position command is absolute: it takes the joint back through the turns to
  // 0.5 rad, not to the nearest equal angle (0.5 + 6 pi).
  sim.set_input(0, one_joint(JointMode::kPosition, 0.5));
  for (int i = 0; i < 5000; ++i) sim.step();
  EXPECT_NEAR(sim.joint_position(0), 0.5, 0.05);
  // A reset starts the count again.
  sim.reset();
  EXPECT_NEAR(sim.joint_position(0), 0.0, 1e-9);
}

// A slider on a turntable, locked at zero travel (limits 0, 0): it does not slide,
// so its velocity reads zero while the turntable turns, though its centre of mass
// moves along the slide's axis relative to the turntable's.
TEST(JointSemantics, PrismaticVelocityIsMeasuredAtThePivot) {
  testing::ModelFolder folder;
  const Model model = load_adf_files({folder.write(
      "turntable.yaml",
      "bodies: [BODY base, BODY table, BODY slider]\njoints: [JOINT turn, JOINT slide]\n"
      "gravity: {x: 0, y: 0, z: 0}\nignore inter-collision: true\n"
      "BODY base:\n  name: base\n  mass: 0\n"
      "BODY table:\n  name: table\n  mass: 2\n  shape: cylinder\n"
      "  geometry: {radius: 0.3, height: 0.02, axis: Z}\n  damping: {linear: 0, angular: 0}\n"
      "BODY slider:\n  name: slider\n  mass: 0.5\n  shape: box\n"
      "  geometry: {x: 0.1, y: 0.05, z: 0.05}\n  damping: {linear: 0, angular: 0}\n"
      "  location: {position: {x: 0, y: 0.5, z: 0}}\n"
      "JOINT turn:\n  name: turn\n  parent: BODY base\n  child: BODY table\n"
      "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 0, z: 1}\n"
      "  child pivot: {x: 0, y: 0, z: 0}\n  child axis: {x: 0, y: 0, z: 1}\n"
      "  type: continuous\n  max motor impulse: 10\n"
      "JOINT slide:\n  name: slide\n  parent: BODY table\n  child: BODY slider\n"
      "  parent pivot: {x: 0, y: 0.5, z: 0}\n  parent axis: {x: 1, y: 0, z: 0}\n"
      "  child pivot: {x: 0, y: 0, z: 0}\n  child axis: {x: 1, y: 0, z: 0}\n"
      "  joint limits: {low: 0, high: 0}\n  type: prismatic\n")});
  Simulation sim(model, 0.001);
  sim.set_input(0, one_joint(JointMode::kVelocity, 2.0));  // the turntable, 2 rad/s
  double largest = 0.0;
  for (int i = 0; i < 1000; ++i) {
    sim.step();
    if (i > 200) largest = std::max(largest, std::abs(sim.joint_velocity(1)));
  }
  EXPECT_GT(std::abs(sim.joint_velocity(0)), 1.5);  // the table does turn
  EXPECT_LT(std::abs(sim.joint_position(1)), 0.002);
  EXPECT_LT(largest, 0.02) << "a slider held at zero travel reads a velocity";
}

// A position command beyond a limit stops at the limit, even on a light link with a
// stiff PID, which reaches the limit fast: the joint does not go a step's travel past.
TEST(JointSemantics, PositionCommandsBeyondALimitStopAtIt) {
  testing::ModelFolder folder;
  std::string model_text = arm_model(
      "revolute", "  joint limits: {low: -1, high: 1}\n  controller: {P: 10000, I: 0, D: 0.5}\n");
  const std::string heavy = "  mass: 1\n";
  model_text.replace(model_text.find(heavy, model_text.find("BODY arm:")), heavy.size(),
                     "  mass: 0.1\n");
  const Model model = load_adf_files({folder.write("arm.yaml", model_text)});
  Simulation sim(model, 0.001);
  sim.set_input(0, one_joint(JointMode::kPosition, 3.0));
  double highest = -10.0;
  for (int i = 0; i < 3000; ++i) {
    sim.step();
    highest = std::max(highest, sim.joint_position(0));
  }
  std::printf("light arm commanded to 3 rad: highest %.4f rad (limit 1)\n", highest);
  EXPECT_GT(highest, 0.99);
  EXPECT_LT(highest, 1.005) << "the limit is 1 rad";
}

// The KUKA's position command of 3.0 rad on a joint limited to 2.094 went 0.09 rad past.
TEST(JointSemantics, KukaJointStopsAtItsLimit) {
  SKIP_WITHOUT_SHARED_MODELS();
  const Model model = load_adf_files({kMultiBodies + "robots/blender-kuka.yaml"});
  std::size_t base = 0;
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].name == "base") base = b;
  const int joint = model.descendant_joints[base][0];
  ASSERT_NEAR(*model.joints[joint].limit_high, 2.094, 1e-9);
  Simulation sim(model, 0.001);
  sim.set_input(base, one_joint(JointMode::kPosition, 3.0));
  double highest = -10.0;
  for (int i = 0; i < 3000; ++i) {
    sim.step();
    highest = std::max(highest, sim.joint_position(joint));
  }
  std::printf("KUKA base-link1 commanded to 3.0 rad: highest %.4f rad (limit 2.094)\n", highest);
  EXPECT_GT(highest, 2.0);
  EXPECT_LT(highest, 2.094 + 0.01);
}

// An effort beyond the joint's max effort (max motor impulse / dt) is capped: the
// arm accelerates as under the cap, not under what was asked.
TEST(JointSemantics, EffortsAreCappedToTheMaxMotorImpulse) {
  testing::ModelFolder folder;
  const Model model = load_adf_files(
      {folder.write("arm.yaml", arm_model("revolute", "  max motor impulse: 0.002\n"))});
  Simulation sim(model, 0.001);  // cap: 2 N m
  sim.set_input(0, one_joint(JointMode::kEffort, 50.0));
  for (int i = 0; i < 100; ++i) sim.step();
  // About the pivot, the arm's inertia is m L^2 / 3 plus its thickness: ~0.0134 kg m^2.
  const double inertia = 1.0 * (0.2 * 0.2 + 0.02 * 0.02) / 12 + 1.0 * 0.1 * 0.1;
  EXPECT_NEAR(std::abs(sim.joint_velocity(0)), 2.0 / inertia * 0.1, 0.1 * 2.0 / inertia * 0.1);
}

// A step in the target moves the joint by P alone: D acts on the measured velocity,
// which is zero at the step, so there is no derivative kick.
TEST(JointSemantics, ATargetStepGivesNoDerivativeKick) {
  testing::ModelFolder folder;
  const Model model = load_adf_files(
      {folder.write("arm.yaml", arm_model("revolute", "  controller: {P: 10, I: 0, D: 5}\n"))});
  Simulation sim(model, 0.001);
  sim.set_input(0, one_joint(JointMode::kPosition, 0.0));
  for (int i = 0; i < 100; ++i) sim.step();
  ASSERT_LT(std::abs(sim.joint_velocity(0)), 1e-6);
  sim.set_input(0, one_joint(JointMode::kPosition, 0.5));
  sim.step();
  sim.step();
  // P alone: 5 N m on ~0.0134 kg m^2 for 2 ms is 0.75 rad/s; a kick of D * 0.5 / dt
  // (2500 N m, or the 100 N m cap) would be far more.
  EXPECT_LT(std::abs(sim.joint_velocity(0)), 1.0);
}

// An arm pressed against an obstacle for 3 s: its integral is clamped (I times it
// within the effort cap), so once the target is back in free space the arm leaves
// the obstacle at once instead of after the wound-up integral unwinds.
TEST(JointSemantics, TheIntegralDoesNotWindUp) {
  testing::ModelFolder folder;
  // Static blocks 0.5 rad either way of the arm's tip, 0.15 m out.
  auto block = [](const std::string& name, double angle) {
    return "BODY " + name + ":\n  name: " + name +
           "\n  mass: 0\n  shape: box\n  geometry: {x: 0.04, y: 0.1, z: 0.04}\n"
           "  location: {position: {x: " +
           std::to_string(0.15 * std::cos(angle)) +
           ", y: 0, z: " + std::to_string(0.15 * std::sin(angle) + (angle > 0 ? 0.03 : -0.03)) +
           "}}\n";
  };
  std::string text =
      arm_model("revolute", "  controller: {P: 10, I: 50, D: 0.5}\n  max motor impulse: 0.005\n");
  text.replace(text.find("bodies: [BODY base, BODY arm]"), 29,
               "bodies: [BODY base, BODY arm, BODY up, BODY down]");
  text += block("up", 0.5) + block("down", -0.5);
  const Model model = load_adf_files({folder.write("arm.yaml", text)});
  Simulation sim(model, 0.001);  // cap 5 N m
  sim.set_input(0, one_joint(JointMode::kPosition, 1.0));
  for (int i = 0; i < 3000; ++i) sim.step();
  const double blocked = sim.joint_position(0);
  ASSERT_GT(std::abs(blocked), 0.2) << "the arm reached a block";
  ASSERT_LT(std::abs(blocked), 0.6) << "and was stopped by it";
  sim.set_input(0, one_joint(JointMode::kPosition, 0.0));
  for (int i = 0; i < 1000; ++i) sim.step();
  std::printf("pressed at %.3f rad; 1 s after a target of 0: %.3f rad\n", blocked,
              sim.joint_position(0));
  EXPECT_LT(std::abs(sim.joint_position(0)), 0.1) << "the wound-up integral held it";
}

// Gains beyond what one step carries are lowered, said with the values used;
// explicit damping counts in D's bound.
TEST(JointSemantics, LoweredGainsAreSaidAndDampingCounts) {
  testing::ModelFolder folder;
  // The arm's ~0.0134 kg m^2 at dt 1 ms: P <= 1337, D + damping <= 6.7.
  const Model model = load_adf_files({folder.write(
      "arm.yaml",
      arm_model("revolute", "  controller: {P: 1000000, I: 0, D: 5}\n  damping: 4\n"))});
  Simulation sim(model, 0.001);
  const Pid& used = sim.joint_gains(0);
  EXPECT_LT(used.p, 1.4e3);
  EXPECT_GT(used.p, 1.3e3);
  EXPECT_NEAR(sim.joint_damping(0), 4.0, 1e-12);
  EXPECT_LT(used.d + sim.joint_damping(0), 6.8);
  const std::vector<std::string> notes = sim.gain_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("joint 'j'"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("P 1e+06 lowered to 1337"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("D 5 lowered to"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("arm.yaml:"), std::string::npos) << notes[0];
  // Gains within the bound are left alone, and said nothing of.
  const Model gentle = load_adf_files(
      {folder.write("gentle.yaml", arm_model("revolute", "  controller: {P: 100, I: 0, D: 1}\n"))});
  Simulation fine(gentle, 0.001);
  EXPECT_TRUE(fine.gain_notes().empty());
  EXPECT_EQ(fine.joint_gains(0).p, 100.0);
}

// A joint built outside its limits (the Allegro hand's thumb, as its URDF places it) is
// said at load; a sender holding it where it is was named for a target past its limits
// when it commanded another joint.
TEST(JointSemantics, AJointBuiltOutsideItsLimitsIsSaidAndItsHoldIsNoMistake) {
  testing::ModelFolder folder;
  const Model model = load_adf_files(
      {folder.write("arm.yaml", arm_model("revolute", "  joint limits: {low: 0.3, high: 1.0}\n"))});
  Simulation sim(model, 0.001);
  const std::vector<std::string> said = sim.joints_outside_limits();
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("arm.yaml:"), std::string::npos) << said[0];
  EXPECT_NE(said[0].find("warning: joint 'j' is built at 0.0000 rad, outside its limits [0.3, 1]"),
            std::string::npos)
      << said[0];
  EXPECT_EQ(sim.beyond_limits_entry(0, one_joint(JointMode::kPosition, sim.joint_position(0))),
            nullptr);
  const char* far = sim.beyond_limits_entry(0, one_joint(JointMode::kPosition, 57.0));
  ASSERT_NE(far, nullptr);
  EXPECT_NE(std::string(far).find("joint 0 (j): position target 57 is outside its limits [0.3, 1]"),
            std::string::npos)
      << far;
  // Within them, or a velocity, nothing.
  EXPECT_EQ(sim.beyond_limits_entry(0, one_joint(JointMode::kPosition, 0.5)), nullptr);
  EXPECT_EQ(sim.beyond_limits_entry(0, one_joint(JointMode::kVelocity, 57.0)), nullptr);
  const Model inside = load_adf_files({folder.write(
      "inside.yaml", arm_model("revolute", "  joint limits: {low: -1.0, high: 1.0}\n"))});
  EXPECT_TRUE(Simulation(inside, 0.001).joints_outside_limits().empty());
}

// A joint is capped for the inertia it drives, not for its own light link alone: a light
// hub carrying a 2 kg weight 0.5 m out (0.5 kg m^2 about the axis) was capped for the
// hub's 5e-5 kg m^2, P 200 lowered to 5.3 and D 20 to 0.03, and took seconds to ring
// down where the file's gains are critically damped (the UR5's shoulder pan overshot 62 %).
TEST(JointSemantics, AJointIsCappedForTheInertiaItDrives) {
  testing::ModelFolder folder;
  // The weight held by `held_type`, its centre `offset` m beyond the hinge's pivot.
  const auto hub_model = [&](const std::string& held_type, double offset = 0.0) {
    return load_adf_files({folder.write(
        "hub_" + held_type + std::to_string(offset) + ".yaml",
        "gravity: {x: 0, y: 0, z: 0}\n"
        "bodies: [BODY base, BODY hub, BODY weight]\njoints: [JOINT j, JOINT held]\n"
        "BODY base:\n  name: base\n  mass: 0\n"
        "BODY hub:\n  name: hub\n  mass: 0.2\n  shape: box\n  geometry: {x: 0.04, y: 0.04, "
        "z: 0.04}\n  damping: {linear: 0, angular: 0}\n"
        "BODY weight:\n  name: weight\n  mass: 2\n  shape: box\n  geometry: {x: 0.05, y: "
        "0.05, z: 0.05}\n  damping: {linear: 0, angular: 0}\n"
        "  location: {position: {x: " +
            std::to_string(0.5 + offset) +
            ", y: 0, z: 0}}\n"
            "JOINT j:\n  name: j\n  parent: BODY base\n  child: BODY hub\n"
            "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
            "  child pivot: {x: 0, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n  type: "
            "revolute\n"
            "  controller: {P: 200, I: 0, D: 20}\n  max motor impulse: 1\n"
            "JOINT held:\n  name: held\n  parent: BODY hub\n  child: BODY weight\n"
            "  parent pivot: {x: 0.5, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
            "  child pivot: {x: " +
            std::to_string(-offset) +
            ", y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n  type: " + held_type + "\n")});
  };
  // Fixed to the hub, or on a hinge through its centre parallel to j's: either way j
  // carries its mass round (on the hinge, its turn about its centre stays free).
  for (const std::string held : {"fixed", "revolute"}) {
    SCOPED_TRACE(held);
    const Model model = hub_model(held);
    Simulation sim(model, 0.001);
    EXPECT_EQ(sim.joint_gains(0).p, 200.0);
    EXPECT_EQ(sim.joint_gains(0).d, 20.0);
    for (const std::string& note : sim.gain_notes())
      EXPECT_EQ(note.find("joint 'j'"), std::string::npos) << note;
    sim.set_input(0, one_joint(JointMode::kPosition, 0.5));
    double highest = 0.0;
    for (int i = 0; i < 1500; ++i) {
      sim.step();
      highest = std::max(highest, sim.joint_position(0));
    }
    std::printf("weight %s: step of 0.5 rad: highest %.4f rad, after 1.5 s %.4f rad\n",
                held.c_str(), highest, sim.joint_position(0));
    EXPECT_LT(highest, 0.5 * 1.05) << "overshoot";
    EXPECT_NEAR(sim.joint_position(0), 0.5, 0.01);
    EXPECT_TRUE(sim.all_finite());
  }
  // Its centre 0.3 m past that hinge, the weight swings about it, and j drives little of
  // it: lowered, though above the hub's own cap (P 5.3).
  Simulation swinging(hub_model("revolute", 0.3), 0.001);
  EXPECT_LT(swinging.joint_gains(0).p, 100.0);
  EXPECT_GT(swinging.joint_gains(0).p, 6.0);
}

// A box 0.4 x 0.1 x 0.1 m turned 30 degrees about z in its mesh: its principal
// moments are the box's, whatever the turn (the products of inertia count).
TEST(JointSemantics, MeshInertiaIsTheFullTensorOnPrincipalAxes) {
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    const double x = (i & 1 ? 0.2 : -0.2), y = (i & 2 ? 0.05 : -0.05), z = (i & 4 ? 0.05 : -0.05);
    mesh.vertices.push_back({c * x - s * y + 1.0, s * x + c * y, z});
  }
  // Outward faces of the cube's corners 0..7 (bit 0: x, bit 1: y, bit 2: z).
  const unsigned faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (const auto& f : faces) mesh.triangles.push_back({f[0], f[1], f[2]});
  const MeshMassProperties properties = mass_properties(mesh);
  EXPECT_NEAR(properties.centroid_m[0], 1.0, 1e-12);
  EXPECT_GT(std::abs(properties.inertia_per_kg[1]), 1e-4);  // a product of inertia
  const Matrix3 identity = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const PrincipalInertia principal = principal_inertia(properties, properties.centroid_m, identity);
  std::vector<double> moments(principal.moments_per_kg.begin(), principal.moments_per_kg.end());
  std::sort(moments.begin(), moments.end());
  EXPECT_NEAR(moments[0], (0.01 + 0.01) / 12, 1e-9);
  EXPECT_NEAR(moments[1], (0.16 + 0.01) / 12, 1e-9);
  EXPECT_NEAR(moments[2], (0.16 + 0.01) / 12, 1e-9);
  // The smallest moment's axis is the box's long axis, turned 30 degrees.
  const auto& a = principal.axes;
  int smallest = 0;
  for (int k = 1; k < 3; ++k)
    if (principal.moments_per_kg[k] < principal.moments_per_kg[smallest]) smallest = k;
  EXPECT_NEAR(std::abs(a[0 + smallest]), c, 1e-9);
  EXPECT_NEAR(std::abs(a[3 + smallest]), s, 1e-9);

  // In a simulated body: its reported principal inertia is the box's, times its mass.
  testing::ModelFolder folder;
  std::string obj;
  for (const auto& v : mesh.vertices)
    obj += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) +
           "\n";
  for (const auto& f : faces)
    obj += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " +
           std::to_string(f[2] + 1) + "\n";
  folder.write("box.obj", obj);
  const Model model = load_adf_files(
      {folder.write("box.yaml",
                    "bodies: [BODY box]\ngravity: {x: 0, y: 0, z: 0}\nBODY box:\n  name: box\n"
                    "  mass: 2\n  mesh: box.obj\n  collision mesh type: CONVEX_HULL\n")});
  Simulation sim(model, 0.001);
  BodyReading reading{};
  sim.read_body(0, reading);
  std::vector<double> body = {reading.principal_inertia_kgm2.x, reading.principal_inertia_kgm2.y,
                              reading.principal_inertia_kgm2.z};
  std::sort(body.begin(), body.end());
  EXPECT_NEAR(body[0], 2 * moments[0], 1e-5);
  EXPECT_NEAR(body[2], 2 * moments[2], 1e-5);
  // The mesh frame stays where it was put: the body did not turn to its axes.
  EXPECT_NEAR(reading.pose.orientation.w, 1.0, 1e-9);
  EXPECT_NEAR(reading.pose.position_m.x, 0.0, 1e-9);
}

// AMBF's rule: a body's or its file's gravity wins over the world's; --gravity
// (override_gravity) wins over both.
TEST(JointSemantics, GravityFollowsAmbfsRuleAndTheOverride) {
  testing::ModelFolder folder;
  const std::string ball =
      "bodies: [BODY ball]\ngravity: {x: 0, y: 0, z: 0}\nBODY ball:\n  name: ball\n  mass: 1\n"
      "  shape: sphere\n  geometry: {radius: 0.05}\n  damping: {linear: 0, angular: 0}\n";
  Model model = load_adf_files({folder.write("ball.yaml", ball)});
  model.world.gravity_mps2 = {0, 0, -9.81};  // as a world file sets it
  EXPECT_EQ(effective_gravity(model, 0).z, 0.0);
  {
    Simulation sim(model, 0.001);
    for (int i = 0; i < 500; ++i) sim.step();
    EXPECT_NEAR(sim.body_pose(0).position_m.z, 0.0, 1e-9) << "the file's gravity 0 wins";
  }
  override_gravity(model, {0, 0, -3.0});
  EXPECT_EQ(effective_gravity(model, 0).z, -3.0);
  Simulation sim(model, 0.001);
  for (int i = 0; i < 1000; ++i) sim.step();
  EXPECT_NEAR(sim.body_pose(0).position_m.z, -1.5, 0.01);
}

TEST(JointSemantics, TheKukaFallsUnderAnOverriddenGravity) {
  SKIP_WITHOUT_SHARED_MODELS();
  Model model = load_adf_files({kMultiBodies + "robots/blender-kuka.yaml"});
  EXPECT_EQ(effective_gravity(model, 1).z, 0.0);  // the file says 0
  override_gravity(model, {0, 0, -9.81});
  Simulation sim(model, 0.001);
  const double before = sim.joint_position(1);
  for (int i = 0; i < 1000; ++i) sim.step();
  EXPECT_GT(std::abs(sim.joint_position(1) - before), 0.05) << "the arm sags";
}

}  // namespace
}  // namespace afhub::physics
