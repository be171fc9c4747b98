// The Bullet simulation against physics and against the real AMBF models:
// free fall, a pendulum's period, joint PID on the KUKA, closed loops holding
// together (the four-bar, a slider-crank with a prismatic joint), soft bodies,
// proximity sensors, and the command checks.
#include "afhub/physics/simulation.hpp"

#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <functional>
#include <vector>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/shm_layout/error.hpp"
#include "model_files.hpp"
#include "reserved_world.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

using afhub::testing::kMultiBodies;
constexpr double kGravity = 9.81;

int body_index(const Model& model, const std::string& name) {
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].name == name) return static_cast<int>(b);
  ADD_FAILURE() << "no body " << name;
  return 0;
}

// Steps `seconds` of simulated time; returns the largest pivot gap seen.
double run_for(Simulation& sim, double seconds) {
  double largest = 0.0;
  const auto steps = static_cast<int>(std::lround(seconds / sim.dt_s()));
  for (int i = 0; i < steps; ++i) {
    sim.step();
    for (std::size_t j = 0; j < sim.model().joints.size(); ++j)
      largest = std::max(largest, sim.joint_pivot_gap_m(j));
    if (!sim.all_finite()) {
      ADD_FAILURE() << "NaN at step " << sim.step_count();
      break;
    }
  }
  return largest;
}

TEST(Simulation, FreeFallMatchesHalfGTSquared) {
  testing::ModelFolder folder;
  const Model model = load_adf_files(
      {folder.write("ball.yaml",
                    "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 2.0\n  shape: sphere\n"
                    "  geometry: {radius: 0.05}\n  damping: {linear: 0, angular: 0}\n"
                    "  location: {position: {x: 0, y: 0, z: 10}}\n")});
  Simulation sim(model, 0.001);
  for (double t : {0.5, 1.0, 2.0}) {
    run_for(sim, t - sim.time_s());
    const double fallen = 10.0 - sim.body_pose(0).position_m.z;
    const double expected = kGravity * t * t / 2;
    EXPECT_NEAR(fallen, expected, 0.01 * expected) << "at t = " << t;
  }
}

// Lights and cameras look along their direction (their x axis) with `up` as their
// z axis; one with a parent body is carried by it.
TEST(Simulation, LightsAndCamerasLookAlongTheirDirectionAndFollowTheirParent) {
  testing::ModelFolder folder;
  Model model = load_adf_files(
      {folder.write("ball.yaml",
                    "bodies: [BODY ball]\nBODY ball:\n  name: ball\n  mass: 1.0\n  shape: sphere\n"
                    "  geometry: {radius: 0.05}\n  location: {position: {x: 0, y: 0, z: 1}}\n")});
  WorldObjectSpec camera;
  camera.name = "ambf/env/main_camera";
  camera.position_m = {2, 0, 1};
  camera.direction = {-1, 0, 0};  // looking back at the origin's x
  model.world.cameras.push_back(camera);
  WorldObjectSpec light;
  light.name = "ambf/env/lamp";
  light.position_m = {0, 0, 0.5};  // in the ball's frame
  light.direction = {0, 0, -1};
  light.parent = "/ambf/env/BODY ball";
  model.world.lights.push_back(light);
  Simulation sim(model, 0.001);

  auto rotate = [](const Quaternion& q, double x, double y, double z) {
    const btVector3 v = quatRotate(btQuaternion(q.x, q.y, q.z, q.w), btVector3(x, y, z));
    return Vec3{v.x(), v.y(), v.z()};
  };
  const Pose seen_by = sim.camera_pose(0);
  EXPECT_NEAR(seen_by.position_m.x, 2.0, 1e-12);
  const Vec3 forward = rotate(seen_by.orientation, 1, 0, 0);
  const Vec3 up = rotate(seen_by.orientation, 0, 0, 1);
  EXPECT_NEAR(forward.x, -1.0, 1e-12);
  EXPECT_NEAR(up.z, 1.0, 1e-12);

  EXPECT_NEAR(sim.light_pose(0).position_m.z, 1.5, 1e-9);
  EXPECT_NEAR(rotate(sim.light_pose(0).orientation, 1, 0, 0).z, -1.0, 1e-12);
  run_for(sim, 0.5);
  const double fallen = 1.0 - sim.body_pose(0).position_m.z;
  EXPECT_GT(fallen, 0.5);
  EXPECT_NEAR(sim.light_pose(0).position_m.z, 1.5 - fallen, 1e-9);  // carried by the ball
}

TEST(Simulation, PendulumPeriodMatchesTheAnalyticValue) {
  // A 1 kg ball of radius 2 cm on a 0.5 m massless arm, released 0.05 rad from vertical.
  const double length = 0.5, radius = 0.02, start = 0.05;
  const double inertia = 0.4 * radius * radius;
  testing::ModelFolder folder;
  const std::string x = std::to_string(length * std::sin(start));
  const std::string z = std::to_string(-length * std::cos(start));
  const std::string pivot = "{x: " + std::to_string(-length * std::sin(start)) +
                            ", y: 0, z: " + std::to_string(length * std::cos(start)) + "}";
  const Model model = load_adf_files({folder.write(
      "pendulum.yaml",
      "bodies: [BODY base, BODY bob]\njoints: [JOINT swing]\n"
      "BODY base:\n  name: base\n  mass: 0\n"
      "BODY bob:\n  name: bob\n  mass: 1\n  shape: sphere\n  geometry: {radius: 0.02}\n"
      "  inertia: {ix: " +
          std::to_string(inertia) + ", iy: " + std::to_string(inertia) +
          ", iz: " + std::to_string(inertia) +
          "}\n  damping: {linear: 0, angular: 0}\n"
          "  location: {position: {x: " +
          x + ", y: 0, z: " + z +
          "}}\n"
          "JOINT swing:\n  name: swing\n  parent: BODY base\n  child: BODY bob\n"
          "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
          "  child pivot: " +
          pivot + "\n  child axis: {x: 0, y: 1, z: 0}\n  type: continuous\n")});
  Simulation sim(model, 0.001);
  std::vector<double> crossings;  // times the bob passes x = 0 (interpolated)
  double previous_x = sim.body_pose(1).position_m.x;
  while (sim.time_s() < 10.0) {
    sim.step();
    const double now_x = sim.body_pose(1).position_m.x;
    if ((previous_x > 0) != (now_x > 0))
      crossings.push_back(sim.time_s() - sim.dt_s() * now_x / (now_x - previous_x));
    previous_x = now_x;
  }
  ASSERT_GE(crossings.size(), 10u);
  const double measured = 2 * (crossings.back() - crossings.front()) / (crossings.size() - 1);
  const double expected = 2 * M_PI * std::sqrt((inertia + length * length) / (kGravity * length)) *
                          (1 + start * start / 16);
  EXPECT_NEAR(measured, expected, 0.02 * expected);
}

// `reduced`: the arm a chain in reduced coordinates (reduced_coordinates_test.cpp).
void expect_kuka_reaches_its_targets(bool reduced) {
  Model model = load_adf_files({kMultiBodies + "robots/blender-kuka.yaml"});
  model.world.reduced_coordinates = reduced;
  Simulation sim(model, 0.001);
  EXPECT_EQ(sim.links_in_reduced_coordinates() >= 7, reduced);
  const std::array<double, 7> targets = {0.5, -0.4, 0.3, 0.6, -0.5, 0.4, 0.7};
  BodyInput command{};
  command.joint_count = 7;
  for (std::size_t j = 0; j < 7; ++j) {
    command.joint_values[j] = targets[j];
    command.joint_modes[j] = JointMode::kPosition;
  }
  ASSERT_EQ(input_problem(command, 7), nullptr);
  sim.set_input(body_index(model, "base"), command);
  const double gap = run_for(sim, 2.0);
  const std::vector<int>& joints = model.descendant_joints[body_index(model, "base")];
  for (std::size_t j = 0; j < 7; ++j)
    EXPECT_NEAR(sim.joint_position(joints[j]), targets[j], 0.01) << model.joints[joints[j]].name;
  EXPECT_LT(gap, 0.002);
}

TEST(Simulation, KukaJointsReachTheirTargetsUnderTheirPid) {
  SKIP_WITHOUT_SHARED_MODELS();
  expect_kuka_reaches_its_targets(false);
}

TEST(Simulation, KukaJointsReachTheirTargetsInReducedCoordinates) {
  SKIP_WITHOUT_SHARED_MODELS();
  expect_kuka_reaches_its_targets(true);
}

// The watchdog's two policies after the KUKA was driven to a pose: zero effort lets
// the arm fall under gravity; hold keeps every joint where it was.
TEST(Simulation, WatchdogPoliciesZeroEffortOrHoldPosition) {
  SKIP_WITHOUT_SHARED_MODELS();
  const Model model = load_adf_files({kMultiBodies + "robots/blender-kuka.yaml"});
  const int base = body_index(model, "base");
  const std::vector<int>& joints = model.descendant_joints[base];
  BodyInput command{};
  command.joint_count = 7;
  for (std::size_t j = 0; j < 7; ++j) {
    command.joint_values[j] = 0.6;
    command.joint_modes[j] = JointMode::kPosition;
  }
  double largest_drift[2] = {0.0, 0.0};
  for (const bool hold : {false, true}) {
    Simulation sim(model, 0.001);
    sim.set_input(base, command);
    run_for(sim, 1.5);
    std::array<double, 7> before{};
    for (std::size_t j = 0; j < 7; ++j) before[j] = sim.joint_position(joints[j]);
    if (hold)
      sim.hold_joints(base);
    else
      sim.clear_input(base);
    run_for(sim, 3.0);
    for (std::size_t j = 0; j < 7; ++j)
      largest_drift[hold] =
          std::max(largest_drift[hold], std::abs(sim.joint_position(joints[j]) - before[j]));
  }
  std::printf("largest joint drift in 3 s: zero effort %.4f rad, hold %.6f rad\n",
              largest_drift[false], largest_drift[true]);
  EXPECT_GT(largest_drift[false], 0.02) << "with zero effort the arm should sag under gravity";
  EXPECT_LT(largest_drift[true], 0.001) << "holding, every joint should stay where it was";
}

TEST(Simulation, RealModelsRunTenSecondsHoldingTogether) {
  SKIP_WITHOUT_SHARED_MODELS();
  for (const char* file : {"robots/blender-kuka.yaml", "puzzles/parallel_structure.yaml"}) {
    const Model model = load_adf_files({kMultiBodies + file});
    Simulation sim(model, 0.001);
    const double gap = run_for(sim, 10.0);
    EXPECT_TRUE(sim.all_finite()) << file;
    EXPECT_LT(gap, 0.002) << file;
  }
}

TEST(Simulation, FourBarLoopStaysClosedUnderGravity) {
  SKIP_WITHOUT_SHARED_MODELS();
  Model model = load_adf_files({kMultiBodies + "puzzles/parallel_structure.yaml"});
  ASSERT_EQ(model.closed_loop_count, 1);
  Simulation sim(model, 0.001);
  run_for(sim, 10.0);
  const std::size_t loop_joint = 4;  // JOINT l1-l4 closes the loop
  ASSERT_EQ(model.joints[loop_joint].name, "l1-l4");
  EXPECT_LT(sim.joint_pivot_gap_m(loop_joint), 0.002);
  // It did move: gravity swings the linkage away from where it was drawn.
  EXPECT_GT(std::abs(sim.joint_position(1)), 0.1);
}

// Crank r = 0.1 m turning about z at the origin, rod l = 0.3 m, and a slider on
// the x axis: the slider's joint follows x = r cos(q) + sqrt(l^2 - r^2 sin^2(q)).
TEST(Simulation, PrismaticJointInsideAClosedLoopFollowsTheSliderCrank) {
  testing::ModelFolder folder;
  auto box = [](const std::string& name, double x, double length) {
    return "BODY " + name + ":\n  name: " + name + "\n  mass: 0.5\n  shape: box\n" +
           "  geometry: {x: " + std::to_string(length) + ", y: 0.02, z: 0.02}\n" +
           "  damping: {linear: 0, angular: 0}\n  location: {position: {x: " + std::to_string(x) +
           ", y: 0, z: 0}}\n";
  };
  auto joint = [](const std::string& name, const std::string& parent, const std::string& child,
                  const std::string& parent_pivot, const std::string& child_pivot,
                  const std::string& type, const std::string& axis) {
    return "JOINT " + name + ":\n  name: " + name + "\n  parent: BODY " + parent +
           "\n  child: BODY " + child + "\n  parent pivot: " + parent_pivot +
           "\n  child pivot: " + child_pivot + "\n  parent axis: " + axis +
           "\n  child axis: " + axis + "\n  type: " + type + "\n  max motor impulse: 1.0\n";
  };
  const std::string z = "{x: 0, y: 0, z: 1}", x = "{x: 1, y: 0, z: 0}";
  const Model model = load_adf_files({folder.write(
      "slider_crank.yaml",
      "bodies: [BODY base, BODY crank, BODY rod, BODY slider]\n"
      "joints: [JOINT base-crank, JOINT crank-rod, JOINT rod-slider, JOINT base-slider]\n"
      "gravity: {x: 0, y: 0, z: 0}\nignore inter-collision: true\n"
      "BODY base:\n  name: base\n  mass: 0\n" +
          box("crank", 0.05, 0.1) + box("rod", 0.25, 0.3) + box("slider", 0.4, 0.04) +
          joint("base-crank", "base", "crank", "{x: 0, y: 0, z: 0}", "{x: -0.05, y: 0, z: 0}",
                "continuous", z) +
          joint("crank-rod", "crank", "rod", "{x: 0.05, y: 0, z: 0}", "{x: -0.15, y: 0, z: 0}",
                "continuous", z) +
          joint("rod-slider", "rod", "slider", "{x: 0.15, y: 0, z: 0}", "{x: 0, y: 0, z: 0}",
                "continuous", z) +
          joint("base-slider", "base", "slider", "{x: 0.4, y: 0, z: 0}", "{x: 0, y: 0, z: 0}",
                "prismatic", x))});
  ASSERT_EQ(model.closed_loop_count, 1);
  Simulation sim(model, 0.001);
  BodyInput command{};
  command.joint_count = 1;  // the crank, turning at 2 rad/s
  command.joint_values[0] = 2.0;
  command.joint_modes[0] = JointMode::kVelocity;
  sim.set_input(0, command);
  double worst_error = 0.0, largest_gap = 0.0, turned = 0.0;
  for (int i = 0; i < 3000; ++i) {
    sim.step();
    const double q = sim.joint_position(0);
    const double expected = 0.1 * std::cos(q) + std::sqrt(0.09 - 0.01 * std::sin(q) * std::sin(q));
    worst_error = std::max(worst_error, std::abs(sim.joint_position(3) + 0.4 - expected));
    for (std::size_t j = 0; j < 4; ++j)
      largest_gap = std::max(largest_gap, sim.joint_pivot_gap_m(j));
    turned = std::max(turned, std::abs(q));
  }
  EXPECT_GT(turned, 2.0);  // the crank went well round
  EXPECT_LT(worst_error, 0.002);
  EXPECT_LT(largest_gap, 0.002);
}

// Every joint type builds, holds its bodies together under gravity, and stays finite.
TEST(Simulation, EveryJointTypeHoldsTogether) {
  const std::vector<std::pair<std::string, std::string>> types = {
      {"revolute", "  joint limits: {low: -1, high: 1}\n"},
      {"continuous", ""},
      {"prismatic", "  joint limits: {low: -0.1, high: 0.1}\n"},
      {"fixed", ""},
      {"p2p", ""},
      {"linear spring", "  stiffness: 200\n  damping: 2\n  joint limits: {low: -0.2, high: 0.2}\n"},
      {"torsion spring", "  stiffness: 20\n  damping: 0.2\n  joint limits: {low: -1, high: 1}\n"},
      {"cone twist", "  joint limits: {x: 0.5, y: 0.5, z: 0.5}\n"},
      {"six dof",
       "  joint limits: {linear: {low: {x: 0, y: 0, z: -0.05}, high: {x: 0, y: 0, z: 0.05}},\n"
       "                 angular: {low: {x: 0, y: 0, z: -1}, high: {x: 0, y: 0, z: 1}}}\n"},
      {"six dof spring",
       "  stiffness: 100\n  damping: 1\n"
       "  joint limits: {linear: {low: {x: 0, y: 0, z: -0.05}, high: {x: 0, y: 0, z: 0.05}},\n"
       "                 angular: {low: {x: 0, y: 0, z: -1}, high: {x: 0, y: 0, z: 1}}}\n"},
  };
  for (const auto& [type, extra] : types) {
    testing::ModelFolder folder;
    const Model model = load_adf_files({folder.write(
        "joint.yaml",
        "bodies: [BODY base, BODY arm]\njoints: [JOINT j]\n"
        "BODY base:\n  name: base\n  mass: 0\n"
        "BODY arm:\n  name: arm\n  mass: 1\n  shape: box\n  geometry: {x: 0.2, y: 0.02, z: 0.02}\n"
        "  location: {position: {x: 0.1, y: 0, z: 0}}\n"
        "JOINT j:\n  name: j\n  parent: BODY base\n  child: BODY arm\n"
        "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
        "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n  type: " +
            type + "\n" + extra)});
    Simulation sim(model, 0.001);
    const double gap = run_for(sim, 2.0);
    EXPECT_TRUE(sim.all_finite()) << type;
    // The gap leaves out a joint's free directions (a slider's or a spring's travel).
    EXPECT_LT(gap, 0.002) << type;
  }
}

// A body's pose command through its Cartesian controller, as AMBF loads it: with no
// `controller` in its file, a velocity with P 10 and no D; with gains in its file, a
// force. Before, both drove a velocity with D 1 by default: a free box went to 8e9 m,
// and the PR2 gripper's palm (P 200, D 20) to 1e260 m.
TEST(Simulation, APoseCommandReachesItsTargetWithTheFilesControllerOrAmbfsDefault) {
  const struct {
    const char* controller;
    ControllerOutput linear, angular;
  } cases[] = {
      {"", ControllerOutput::kVelocity, ControllerOutput::kVelocity},
      {"  controller: {linear: {P: 200, D: 20}, angular: {P: 2, D: 0.2}}\n",
       ControllerOutput::kForce, ControllerOutput::kForce},
      {"  controller: {linear: {P: 200, D: 20}}\n", ControllerOutput::kForce,
       ControllerOutput::kVelocity},
      {"  controller: {linear: {P: 20, D: 0.5}, angular: {P: 20, D: 0.5}}\n"
       "  controller output type: VELOCITY\n",
       ControllerOutput::kVelocity, ControllerOutput::kVelocity},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.controller);
    testing::ModelFolder folder;
    Model model = load_adf_files({folder.write(
        "box.yaml",
        std::string("bodies: [BODY box]\nBODY box:\n  name: box\n  mass: 0.6\n  shape: box\n"
                    "  geometry: {x: 0.1, y: 0.1, z: 0.1}\n"
                    "  location: {position: {x: 2, y: 0, z: 1}}\n") +
            c.controller)});
    EXPECT_TRUE(model.warnings.empty()) << model.warnings.front();
    EXPECT_EQ(model.bodies[0].linear_output, c.linear);
    EXPECT_EQ(model.bodies[0].angular_output, c.angular);
    model.world.gravity_mps2 = {0.0, 0.0, 0.0};
    Simulation sim(model, 0.001);
    BodyInput command{};
    command.cartesian = CartesianMode::kPosition;
    command.target_pose.position_m = {2.3, 0.2, 1.1};                              // 0.37 m away
    command.target_pose.orientation = {0.0, 0.0, std::sin(0.25), std::cos(0.25)};  // 0.5 rad
    for (int step = 0; step < 3000; ++step) {
      sim.set_input(0, command);
      sim.step();
    }
    ASSERT_TRUE(sim.all_finite());
    const Pose pose = sim.body_pose(0);
    EXPECT_NEAR(pose.position_m.x, 2.3, 1e-3);
    EXPECT_NEAR(pose.position_m.y, 0.2, 1e-3);
    EXPECT_NEAR(pose.position_m.z, 1.1, 1e-3);
    EXPECT_NEAR(std::abs(pose.orientation.z), std::sin(0.25), 1e-3);
  }
}

// A velocity output with D from 1 diverges: said at load, with what to do.
TEST(Simulation, AVelocityControllerWithADOfOneOrMoreIsAWarning) {
  testing::ModelFolder folder;
  const Model model = load_adf_files(
      {folder.write("box.yaml",
                    "bodies: [BODY box]\nBODY box:\n  name: box\n  mass: 1\n"
                    "  controller: {linear: {P: 10, D: 1}, angular: {P: 10, D: 0.5}}\n"
                    "  controller output type: VELOCITY\n")});
  ASSERT_EQ(model.warnings.size(), 1u);
  EXPECT_NE(model.warnings[0].find("box.yaml:5:15: warning: controller.linear D 1 with VELOCITY"),
            std::string::npos)
      << model.warnings[0];
  EXPECT_NE(model.warnings[0].find("give D below 1, or `controller output type: FORCE`"),
            std::string::npos)
      << model.warnings[0];
  // FORCE with no gains would turn the preset (P 10, no D) into an undamped spring: as in
  // AMBF, the output type goes with gains only.
  const Model bare =
      load_adf_files({folder.write("bare.yaml",
                                   "bodies: [BODY box]\nBODY box:\n  name: box\n  mass: 1\n"
                                   "  controller output type: FORCE\n")});
  EXPECT_EQ(bare.bodies[0].linear_output, ControllerOutput::kVelocity);
  ASSERT_EQ(bare.warnings.size(), 1u);
  EXPECT_NE(bare.warnings[0].find(
                "bare.yaml:5:27: warning: 'controller output type' is ignored without a "
                "'controller' block"),
            std::string::npos)
      << bare.warnings[0];
}

TEST(Simulation, ModelSplitOverTwoFilesSimulates) {
  testing::ModelFolder folder;
  const std::string bodies = folder.write(
      "bodies.yaml",
      "bodies: [BODY base, BODY arm]\nBODY base:\n  name: base\n  mass: 0\n"
      "BODY arm:\n  name: arm\n  mass: 1\n  shape: box\n  geometry: {x: 0.2, y: 0.02, z: 0.02}\n"
      "  location: {position: {x: 0.1, y: 0, z: 0}}\n");
  const std::string joints = folder.write(
      "joints.yaml",
      "joints: [JOINT hinge]\nJOINT hinge:\n  name: hinge\n  parent: BODY base\n"
      "  child: BODY arm\n  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 0}\n"
      "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 0}\n  type: revolute\n");
  const Model model = load_adf_files({bodies, joints});
  Simulation sim(model, 0.001);
  const double gap = run_for(sim, 1.0);
  EXPECT_LT(gap, 0.002);
  // Hinged at the origin, the arm swings down instead of falling away.
  const Pose arm = sim.body_pose(1);
  EXPECT_NEAR(std::hypot(arm.position_m.x, arm.position_m.z), 0.1, 0.002);
  EXPECT_LT(arm.position_m.z, -0.05);
}

TEST(Simulation, ClothWithFixedCornersHangsInsteadOfFalling) {
  testing::ModelFolder folder;
  std::string obj;
  const int n = 11;  // an 11 x 11 grid over 1 m x 1 m in the xy plane
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      obj += "v " + std::to_string(j * 0.1) + " " + std::to_string(i * 0.1) + " 0\n";
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      const int a = i * n + j + 1, b = a + 1, c = a + n, d = c + 1;  // OBJ is 1-based
      obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + "\n";
      obj += "f " + std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(c) + "\n";
    }
  folder.write("sheet.obj", obj);
  const Model model = load_adf_files(
      {folder.write("cloth.yaml",
                    "soft bodies: [SOFTBODY cloth]\nSOFTBODY cloth:\n  name: cloth\n  mass: 0.5\n"
                    "  mesh: sheet.obj\n  location: {position: {x: 0, y: 0, z: 1}}\n"
                    "  config: {kLST: 0.9, kDP: 0.01, piterations: 10, bending constraint: 2,\n"
                    "           fixed nodes: [0, 10]}\n")});
  ASSERT_EQ(model.soft_bodies.size(), 1u);
  Simulation sim(model, 0.001);
  BodyReading start{}, end{};
  sim.read_soft_body(0, start);
  run_for(sim, 2.0);
  sim.read_soft_body(0, end);
  ASSERT_TRUE(sim.all_finite());
  const double drop = start.pose.position_m.z - end.pose.position_m.z;
  EXPECT_GT(drop, 0.05);  // it sags
  EXPECT_LT(drop, 1.0);   // but hangs from its corners: free fall would be 19.6 m
}

// 65 x 65 = 4225 nodes, just past kMaxSoftBodyNodes (4096); 220 x 220 = 48 400, past
// where Bullet's builder overflows its nodes x nodes table (a crash before the check
// came first).
TEST(Simulation, ASoftBodyWithMoreNodesThanAViewerTakesIsRefusedAtLoad) {
  for (const int n : {65, 220}) {
    testing::ModelFolder folder;
    std::string obj;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        obj += "v " + std::to_string(j * 0.01) + " " + std::to_string(i * 0.01) + " 0\n";
    for (int i = 0; i + 1 < n; ++i)
      for (int j = 0; j + 1 < n; ++j) {
        const int a = i * n + j + 1, b = a + 1, c = a + n;  // OBJ is 1-based
        obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
        obj +=
            "f " + std::to_string(b) + " " + std::to_string(c + 1) + " " + std::to_string(c) + "\n";
      }
    folder.write("big.obj", obj);
    const Model model =
        load_adf_files({folder.write("big.yaml",
                                     "soft bodies: [SOFTBODY big]\nSOFTBODY big:\n  name: big\n"
                                     "  mass: 0.5\n  mesh: big.obj\n")});
    const std::string nodes = "has " + std::to_string(n * n) + " nodes";
    auto expect_refused = [&](const std::function<void()>& load, const char* what) {
      try {
        load();
        ADD_FAILURE() << what << " took a soft body of " << n * n << " nodes";
      } catch (const afhub::Error& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find("big.yaml:"), std::string::npos) << message;
        EXPECT_NE(message.find(nodes), std::string::npos) << message;
        EXPECT_NE(message.find("at most 4096 nodes"), std::string::npos) << message;
      }
    };
    expect_refused([&] { check_meshes(model); }, "check_meshes");
    expect_refused([&] { Simulation sim(model, 0.001); }, "Simulation");
  }
}

TEST(Simulation, ProximitySensorMeasuresTheDistanceToABody) {
  testing::ModelFolder folder;
  const Model model = load_adf_files({folder.write(
      "sensor.yaml",
      "bodies: [BODY probe, BODY wall]\nsensors: [SENSOR range]\n"
      "BODY probe:\n  name: probe\n  mass: 0\n  shape: sphere\n  geometry: {radius: 0.05}\n"
      "BODY wall:\n  name: wall\n  mass: 0\n  shape: box\n  geometry: {x: 0.2, y: 1, z: 1}\n"
      "  location: {position: {x: 1, y: 0, z: 0}}\n"
      "SENSOR range:\n  name: range\n  type: Proximity\n  parent: BODY probe\n  range: 2.0\n"
      "  array:\n  - {offset: {x: 0, y: 0, z: 0}, direction: {x: 1, y: 0, z: 0}}\n"
      "  - {offset: {x: 0, y: 0, z: 0}, direction: {x: -1, y: 0, z: 0}}\n")});
  Simulation sim(model, 0.001);
  sim.step();
  BodyReading state{};
  sim.read_body(0, state);
  ASSERT_EQ(state.ray_count, 2u);
  EXPECT_NEAR(state.ray_distances_m[0], 0.9, 0.005);  // the wall's near face
  EXPECT_EQ(state.ray_distances_m[1], -1.0);          // nothing behind
}

TEST(Simulation, ConstraintActuatorHoldsWhatTouchesItAndLetsGo) {
  testing::ModelFolder folder;
  const Model model = load_adf_files({folder.write(
      "gripper.yaml",
      "bodies: [BODY gripper, BODY ball, BODY far]\nactuators: [ACTUATOR grip]\n"
      "BODY gripper:\n  name: gripper\n  mass: 0\n"
      "BODY ball:\n  name: ball\n  mass: 1\n  shape: sphere\n  geometry: {radius: 0.05}\n"
      "  location: {position: {x: 0, y: 0, z: -0.045}}\n"
      "BODY far:\n  name: far\n  mass: 0\n"
      "  location: {position: {x: 5, y: 0, z: 0}}\n"
      "ACTUATOR grip:\n  name: grip\n  type: Constraint\n  parent: BODY gripper\n"
      "  max impulse: 10\n  tau: 1\n")});
  Simulation sim(model, 0.001);
  BodyInput command{};
  command.actuator_count = 1;
  command.engage[0] = true;
  ASSERT_EQ(input_problem(command, 0, 1), nullptr);
  EXPECT_NE(input_problem(command, 0, 0), nullptr);  // a body without actuators
  sim.set_input(0, command);
  ASSERT_TRUE(sim.actuator_engaged(0));
  run_for(sim, 1.0);
  EXPECT_NEAR(sim.body_pose(1).position_m.z, -0.045, 0.005);  // held against gravity
  command.engage[0] = false;
  sim.set_input(0, command);
  EXPECT_FALSE(sim.actuator_engaged(0));
  run_for(sim, 0.5);
  EXPECT_LT(sim.body_pose(1).position_m.z, -1.0);  // let go: it falls
  command.engage[0] = true;
  sim.set_input(0, command);  // nothing touches it any more
  EXPECT_FALSE(sim.actuator_engaged(0));
}

TEST(Simulation, CommandsWithNanOrBadJointsAreRefused) {
  BodyInput good{};
  good.joint_count = 2;
  EXPECT_EQ(input_problem(good, 2), nullptr);
  BodyInput too_many = good;
  too_many.joint_count = 3;
  EXPECT_NE(input_problem(too_many, 2), nullptr);
  BodyInput nan_joint = good;
  nan_joint.joint_values[1] = std::nan("");
  EXPECT_NE(input_problem(nan_joint, 2), nullptr);
  BodyInput inf_force = good;
  inf_force.wrench.force_n.y = INFINITY;
  EXPECT_NE(input_problem(inf_force, 2), nullptr);
  BodyInput bad_type = good;
  bad_type.cartesian = static_cast<CartesianMode>(7);
  EXPECT_NE(input_problem(bad_type, 2), nullptr);
}

TEST(Simulation, ResetReturnsToTheStart) {
  SKIP_WITHOUT_SHARED_MODELS();
  const Model model = load_adf_files({kMultiBodies + "puzzles/parallel_structure.yaml"});
  Simulation sim(model, 0.001);
  const double start = sim.joint_position(1);
  run_for(sim, 1.0);
  EXPECT_GT(std::abs(sim.joint_position(1) - start), 0.05);
  sim.reset();
  EXPECT_EQ(sim.step_count(), 0u);
  EXPECT_NEAR(sim.joint_position(1), start, 1e-9);
}

// Effort, velocity and position commands move a joint the way its position counts.
TEST(Simulation, JointCommandsFollowTheSignOfThePosition) {
  for (const std::string type : {"revolute", "prismatic"}) {
    testing::ModelFolder folder;
    const Model model = load_adf_files({folder.write(
        "arm.yaml",
        "bodies: [BODY base, BODY arm]\njoints: [JOINT j]\ngravity: {x: 0, y: 0, z: 0}\n"
        "BODY base:\n  name: base\n  mass: 0\n"
        "BODY arm:\n  name: arm\n  mass: 1\n  shape: box\n  geometry: {x: 0.2, y: 0.02, z: 0.02}\n"
        "  location: {position: {x: 0.1, y: 0, z: 0}}\n"
        "JOINT j:\n  name: j\n  parent: BODY base\n  child: BODY arm\n"
        "  parent pivot: {x: 0, y: 0, z: 0}\n  parent axis: {x: 0, y: 1, z: 1}\n"
        "  child pivot: {x: -0.1, y: 0, z: 0}\n  child axis: {x: 0, y: 1, z: 1}\n"
        "  controller: {P: 20, I: 0, D: 2}\n  max motor impulse: 1\n  type: " +
            type + "\n")});
    for (JointMode kind : {JointMode::kEffort, JointMode::kVelocity, JointMode::kPosition}) {
      Simulation sim(model, 0.001);
      BodyInput command{};
      command.joint_count = 1;
      command.joint_modes[0] = kind;
      command.joint_values[0] = 0.3;
      sim.set_input(0, command);
      run_for(sim, 0.5);
      EXPECT_GT(sim.joint_position(0), 0.02) << type << " command " << static_cast<int>(kind);
      EXPECT_LT(sim.joint_pivot_gap_m(0), 0.002) << type;
    }
  }
}

}  // namespace
}  // namespace afhub::physics

namespace afhub::physics {
namespace {

const std::string kArm = AFHUB_EXAMPLE_MODELS "/arm7.yaml";

int arm_body(const Model& model, const std::string& name) {
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].name == name) return static_cast<int>(b);
  ADD_FAILURE() << "no body " << name;
  return 0;
}

// A finite but extreme command (1e308) passes the NaN check, yet makes the world NaN
// within a step: each field is bounded by the model (InputBounds) and refused,
// naming the field, its value and the bound.
TEST(CommandBounds, FiniteExtremeCommandsAreRefusedNamingTheField) {
  const Model model = load_adf_files({kArm});
  Simulation sim(model, 0.001);
  const std::size_t base = arm_body(model, "base");
  const InputBounds& bounds = sim.input_bounds(base);
  // The arm7's base carries 23.3 kg, reaching 1.3 m: 100 g of force on it, ten
  // times its shoulder's gravity load, and the motor's 0.18 N m s per step.
  EXPECT_GT(bounds.force_n, 20'000.0);
  EXPECT_LT(bounds.force_n, 30'000.0);
  EXPECT_GE(bounds.joint_effort[0], 180.0);
  EXPECT_LT(bounds.joint_effort[0], 5'000.0);
  EXPECT_GT(bounds.joint_effort[6], 100.0);  // the wrist: its motor's, or 10 g R on 1 kg
  EXPECT_LT(bounds.joint_effort[6], bounds.joint_effort[0]);
  struct Case {
    const char* field;
    std::function<void(BodyInput&)> set;
  };
  const std::vector<Case> cases = {
      {"joint 0 (base-link1) effort",
       [](BodyInput& in) {
         in.joint_count = 1;
         in.joint_modes[0] = JointMode::kEffort;
         in.joint_values[0] = 1e308;
       }},
      {"joint 2 (link2-link3) velocity",
       [](BodyInput& in) {
         in.joint_count = 3;
         in.joint_modes[2] = JointMode::kVelocity;
         in.joint_values[2] = -1e308;
       }},
      {"joint 1 (link1-link2) position",
       [](BodyInput& in) {
         in.joint_count = 2;
         in.joint_modes[1] = JointMode::kPosition;
         in.joint_values[1] = 1e308;
       }},
      {"force", [](BodyInput& in) { in.wrench.force_n.x = 1e308; }},
      {"torque", [](BodyInput& in) { in.wrench.torque_nm.z = 1e308; }},
      {"linear velocity", [](BodyInput& in) { in.twist.linear_mps.y = 1e308; }},
      {"angular velocity", [](BodyInput& in) { in.twist.angular_radps.x = 1e308; }},
      {"pose position", [](BodyInput& in) { in.target_pose.position_m.z = 1e308; }},
      {"pose orientation", [](BodyInput& in) { in.target_pose.orientation.w = 1e308; }},
      // Zero (an unfilled ROS Pose) was taken as the identity.
      {"pose orientation (0, 0, 0, 0) is no rotation",
       [](BodyInput& in) {
         in.cartesian = CartesianMode::kPosition;
         in.target_pose.orientation = {0.0, 0.0, 0.0, 0.0};
       }},
  };
  for (const Case& c : cases) {
    BodyInput input{};
    c.set(input);
    EXPECT_EQ(input_problem(input, 7), nullptr) << c.field << ": finite, so the NaN check passes";
    const char* problem = sim.input_problem(base, input);
    ASSERT_NE(problem, nullptr) << c.field;
    EXPECT_NE(std::string(problem).find(c.field), std::string::npos) << problem;
  }
  // Ordinary commands pass: 50 N m on a joint, 100 N, a pose in reach, 1 rad/s.
  BodyInput fine{};
  fine.joint_count = 7;
  fine.joint_modes[0] = JointMode::kEffort;
  fine.joint_values[0] = 50.0;
  fine.joint_modes[1] = JointMode::kVelocity;
  fine.joint_values[1] = 1.0;
  fine.wrench.force_n = {100.0, 0.0, 0.0};
  fine.target_pose.position_m = {0.5, 0.2, 1.0};
  fine.target_pose.orientation = {0.0, 0.0, 0.0, 1.0};
  EXPECT_EQ(sim.input_problem(base, fine), nullptr) << sim.input_problem(base, fine);
  // A pose left zero where no pose is applied (a sender that fills none) passes.
  fine.target_pose.orientation = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(sim.input_problem(base, fine), nullptr) << sim.input_problem(base, fine);
}

// Two bodies command joints below both (an ancestor's list covers a descendant's):
// each joint follows the body that commanded it last, and one body's watchdog
// releases only the joints it drives.
TEST(CommandBounds, AWatchdogReleasesOnlyWhatItsBodyCommanded) {
  const Model model = load_adf_files({kArm});
  Simulation sim(model, 0.001);
  const std::size_t base = arm_body(model, "base");
  const std::size_t link3 = arm_body(model, "link3");
  const std::vector<int>& below_base = model.descendant_joints[base];
  const std::vector<int>& below_link3 = model.descendant_joints[link3];
  ASSERT_EQ(below_base.size(), 7u);
  ASSERT_EQ(below_link3.size(), 4u);  // link3-link4 .. link6-link7
  BodyInput all{};
  all.joint_count = 7;
  for (std::size_t j = 0; j < 7; ++j) all.joint_modes[j] = JointMode::kPosition;
  sim.set_input(base, all);
  BodyInput wrist{};
  wrist.joint_count = 4;
  for (std::size_t j = 0; j < 4; ++j) {
    wrist.joint_modes[j] = JointMode::kPosition;
    wrist.joint_values[j] = 0.3;
  }
  sim.set_input(link3, wrist);
  for (int joint : below_link3) EXPECT_EQ(sim.joint_driver(joint), static_cast<int>(link3));
  EXPECT_EQ(sim.joint_driver(below_base[0]), static_cast<int>(base));
  // The base's watchdog: its own three joints are released, the wrist's four stay
  // with link3's controller and reach its targets.
  sim.clear_input(base);
  for (int joint : below_link3) EXPECT_EQ(sim.joint_driver(joint), static_cast<int>(link3));
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(sim.joint_driver(below_base[k]), -1);
  for (int i = 0; i < 2000; ++i) sim.step();
  for (int joint : below_link3) EXPECT_NEAR(sim.joint_position(joint), 0.3, 0.02);
  // The hold policy holds what no other body drives, and leaves link3's joints alone.
  sim.hold_joints(base);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_EQ(sim.joint_driver(below_base[k]), static_cast<int>(base));
  for (int joint : below_link3) EXPECT_EQ(sim.joint_driver(joint), static_cast<int>(link3));
  // link3's watchdog releases its four, not the base's held three.
  sim.clear_input(link3);
  for (int joint : below_link3) EXPECT_EQ(sim.joint_driver(joint), -1);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_EQ(sim.joint_driver(below_base[k]), static_cast<int>(base));
}

// The damping of every step, with one power per distinct damping, is Bullet's own bit
// for bit: bodies of several dampings (the defaults, none, heavy), in an order that
// changes the power kept, against btRigidBody::applyDamping on a twin.
TEST(BodyDampingTest, IsBulletsApplyDampingBitForBit) {
  btSphereShape shape(0.1);
  const btScalar dampings[][2] = {{0.04, 0.1}, {0.0, 0.0}, {0.5, 0.9}, {0.04, 0.1}, {0.3, 0.1}};
  BodyDamping damping;
  for (const btScalar dt : {btScalar(0.001), btScalar(0.0005)})
    for (int i = 0; i < 5; ++i) {
      btRigidBody::btRigidBodyConstructionInfo info(1.0, nullptr, &shape,
                                                    btVector3(0.01, 0.01, 0.01));
      info.m_linearDamping = dampings[i][0];
      info.m_angularDamping = dampings[i][1];
      btRigidBody ours(info), bullets(info);
      const btVector3 v(1.5 + i, -2.25, 0.125 * i), w(-0.5, 3.0 + i, 7.0);
      for (btRigidBody* body : {&ours, &bullets}) {
        body->setLinearVelocity(v);
        body->setAngularVelocity(w);
      }
      damping.apply(ours, dt);
      bullets.applyDamping(dt);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(ours.getLinearVelocity()[k], bullets.getLinearVelocity()[k]) << i << " " << k;
        EXPECT_EQ(ours.getAngularVelocity()[k], bullets.getAngularVelocity()[k]) << i << " " << k;
      }
      if (dampings[i][0] > 0) {
        EXPECT_LT(ours.getLinearVelocity().length(), v.length()) << i;
      }
    }
}

}  // namespace
}  // namespace afhub::physics
